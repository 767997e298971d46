// trueaxis::io — design data for scanning (design.json).
//
// design.json: {"sections": [{"name": str, "plane": {"origin": [x, y, z], "normal": [i, j, k]},
//   "closed": bool, "curve": {"nurbs": {"degree": int, "knots": [...], "weights": [...],
//   "control_points": [[x, y, z], ...]}} or {"polyline": [[x, y, z], ...]},
//   "material": "left" | "right"}, ...]}
// mm, part coordinates. "weights" may be left out (all 1). The material side is seen from the
// plane's normal, walking along the curve. Every problem design::check() finds, and every
// structural one (a missing key, a wrong type, an unknown key, a duplicate section name), is
// refused with file:line:col of the offending value.
#pragma once

#include <string>

#include "trueaxis/design/design.hpp"

namespace trueaxis::io {

design::Design read_design(const std::string& path);
// Parses text (`path` names it in messages).
design::Design parse_design(std::string text, const std::string& path);
void write_design(const std::string& path, const design::Design& design);

}  // namespace trueaxis::io
