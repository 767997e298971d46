// trueaxis::io — guideway files : layout.json, spots.csv and result.json.
//
// layout.json: {"detectors": [{"name": "a", "kind": "position", "position": [x, y, z]}, ...,
//                             {"name": "f", "kind": "angle", "focal_length": mm}],
//               "qpd": {"gain_um": µm per unit signal, "min_sum": current,
//                       "max_signal": 0.9,
//                       "table": {"signal": [...], "displacement_um": [...]}}}   ("qpd" optional)
// Carriage frame, mm: z along the travel, x horizontal, y vertical. Errors name file:line:col.
//
// spots.csv: header; first column `s` (carriage position, mm); then for every detector either
// `<name>_dx,<name>_dy` (spot displacement, µm) or `<name>_i1..<name>_i4` (quadrant currents,
// converted with the layout's "qpd"). Unknown detector names, missing or ambiguous columns and
// rejected samples (spot lost, out of range) name file:line:col.
//
// result.json: {"s": [mm], "horizontal": [µm] | null, "vertical", "pitch": [µrad] | null, "yaw",
//   "roll", "residual": [µm], "straightness": {"horizontal": [µm] | null, "vertical"} (against
//   the LS line), "observable": {"horizontal": bool, ...}, "condition_number",
//   "singular_values", "sigma_um", "sigma_estimated", "uncertainty": {name: µm | µrad | null},
//   "summary": {name: {"pv", "rms"} | null}, "message"}.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "trueaxis/guideway/guideway.hpp"

namespace trueaxis::io {

struct GuidewayLayout {
  guideway::Layout layout;
  std::optional<guideway::Qpd> qpd;
};

GuidewayLayout read_layout(const std::string& path);

struct Spots {
  Eigen::VectorXd s;      // mm
  Eigen::MatrixXd spots;  // positions × 2m, mm (dx, dy per detector in layout order)
  // Samples dropped with skip_bad: "file:line:col: detector 'a': why", one per dropped position.
  std::vector<std::string> skipped;
};

// With `skip_bad`, rejected current samples drop their position (listed in `skipped`) instead
// of failing.
Spots read_spots(const std::string& path, const GuidewayLayout& layout, bool skip_bad = false);

void write_guideway_result(const std::string& path, const guideway::Result& result);

// layout.json (detectors only) and spots.csv with displacements (s mm, dx/dy µm).
void write_layout(const std::string& path, const guideway::Layout& layout);
void write_spots(const std::string& path, const guideway::Layout& layout, const Eigen::VectorXd& s,
                 const Eigen::MatrixXd& spots);

}  // namespace trueaxis::io
