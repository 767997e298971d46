// trueaxis::io — the CMM acceptance test's files (ISO 10360-2 and -5): the artefacts' set-up and
// the results.
//
// acceptance.json (`"kind": "acceptance-setup"`), as the user sets the artefacts up, in the
// machine's coordinates (mm):
//   {"temperature_C": 20.1, "u_temperature_K": 0.2, "u_alignment_um": 0.05,
//    "block_width_mm": 35, "block_height_mm": 9, "approach_mm": 5, "repetitions": 3,
//    "blocks": [{"id": "G0100", "length_mm": 100.00012, "u_um": 0.04,
//                "alpha_per_K": 11.5e-6, "u_alpha_per_K": 1e-6}, ...],
//    "placements": [{"block": "G0100", "position": "diagonal 1", "centre": [x, y, z],
//                    "direction": [dx, dy, dz]}, ...],
//    "sphere": {"centre": [x, y, z], "diameter_mm": 25.0004, "u_um": 0.1, "form_um": 0.05,
//               "pole": [0, 0, 1]}}
// Only "blocks" and "placements" (for E0) or "sphere" (for probing) are needed; the rest has
// the defaults of acceptance::Setup. A direction need not be of unit length; "position" may be
// left out (the line is then named from its direction). Errors name file:line:col.
//
// e0.json (`"kind": "acceptance-e0"`): "mpe", "E0_max_um", "R0_max_um", "pass" (conformance
// proven), "verdict", "rule", "complete" (and "stopped"), "positions", "r0", and every length:
// {"position", "block", "repetition", "nominal_mm", "measured_mm", "error_um", "mpe_um", "U_um",
// "endpoints": [[x, y, z], [x, y, z]]}.
// probing.json (`"kind": "acceptance-probing"`): "PForm_um", "PSize_um", "diameter_mm",
// "centre", their MPEs and verdicts, "pass", and the 25 points with their radial deviations.
#pragma once

#include <string>

#include "trueaxis/acceptance/acceptance.hpp"

namespace trueaxis::io {

acceptance::Setup read_acceptance_setup(const std::string& path);
void write_acceptance_setup(const std::string& path, const acceptance::Setup& setup);
void write_e0_result(const std::string& path, const acceptance::E0Result& result);
void write_probing_result(const std::string& path, const acceptance::ProbingResult& result);
// The results read back (for reports and records). Refused with file:line:col: a field of the
// wrong type, a verdict that is not one, a length whose error is not its measured less its
// nominal, an E0_max_um or PForm_um that its lengths or points do not give.
acceptance::E0Result read_e0_result(const std::string& path);
acceptance::ProbingResult read_probing_result(const std::string& path);

}  // namespace trueaxis::io
