// trueaxis::io — design data for scanning (design.json) and simulated parts (part.json).
//
// design.json: {"sections": [{"name": str, "plane": {"origin": [x, y, z], "normal": [i, j, k]},
//   "closed": bool, "curve": {"nurbs": {"degree": int, "knots": [...], "weights": [...],
//   "control_points": [[x, y, z], ...]}} or {"polyline": [[x, y, z], ...]},
//   "material": "left" | "right", "joined_gap_mm": the largest gap closed to join the edges of
//   a cut from CAD (optional, 0 to 1 mm), "probe": {"a_deg", "b_deg"} (optional: the probe
//   head's orientation for this section, default vertical)}, ...],
//   "solid": {"step": "part.stp"}}  (optional: the part's STEP file, relative to design.json's
//   folder, which scanning plans its moves against; it must exist)
// mm, part coordinates. A space curve (a scan path that need not lie in a plane, e.g. a spiral
// over a sphere) is written instead as {"name", "closed", "curve": {"polyline": [...]},
// "normals": [[i, j, k], ...]}: one surface normal per point, away from the material, and no
// plane or material side. "weights" may be left out (all 1). The material side is seen from the
// plane's normal, walking along the curve. Every problem design::check() finds, and every
// structural one (a missing key, a wrong type, an unknown key, a duplicate section name), is
// refused with file:line:col of the offending value.
#pragma once

#include <string>

#include "trueaxis/design/design.hpp"
#include "trueaxis/sim/part.hpp"

namespace trueaxis::io {

design::Design read_design(const std::string& path);
// Parses text (`path` names it in messages).
design::Design parse_design(std::string text, const std::string& path);
void write_design(const std::string& path, const design::Design& design);

// part.json: {"design": {design.json's content}, "deviation": {"scale", "scale_about": [mm],
//   "scale_direction": [..], "directional_scale", "rotation_deg": [ax, ay, az], "translation":
//   [mm], "bumps": [{"section", "arc_mm", "height_mm", "width_mm"}], "noise_um", "seed"}}
// (every deviation optional; see sim/part.hpp). Refusals name file:line:col.
sim::Part read_part(const std::string& path);
sim::Part parse_part(std::string text, const std::string& path);
void write_part(const std::string& path, const sim::Part& part);

}  // namespace trueaxis::io
