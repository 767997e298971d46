// trueaxis::io — positioning runs (laser interferometer, ISO 230-2) and their evaluation.
//
// runs.csv: a header row naming the columns (any order, case-insensitive), then one reading per
// line; blank lines and lines starting with '#' are skipped.
//   target_mm        commanded target position (mm)
//   cycle            cycle number, an integer from 1
//   direction        '+' (approach moving in the positive direction; also "up") or '-' ("down")
//   deviation_um     actual − target (µm), the laser's reading minus the commanded position
//   material_temp_c  optional: the machine's (material) temperature (°C) at the reading
//   air_temp_c       optional: the air temperature (°C), recorded only
// Rows may come in any order. Unknown columns, missing fields, non-numbers, cycles that are not
// positive integers, unknown directions, implausible temperatures (outside −50 .. 100 °C) and
// the same target, cycle and direction twice are refused with "file:line:col: why".
//
// positioning.json (µm): {"kind": "positioning", "standard": "ISO 230-2:2014" | "VDI/DGQ 3441",
//   "A", "A_up", "A_down", "E", "E_up", "E_down", "M", "R", "R_up", "R_down", "B", "B_mean"
//   (ISO), or "P", "Pa", "Ps", "Ps_mean", "U", "U_mean" (VDI) — null where not defined;
//   "cycles", "directions": ["+", "-"], "targets": [{"position" (mm), "n_up", "n_down",
//   "mean_up", "mean_down", "s_up", "s_down", "B", "R" (ISO) or "U", "Ps" (VDI), ...}],
//   "temperature": {"material": [min, max] | null, "air": [min, max] | null, "corrected": bool,
//   "expansion_coefficient", "datum_mm", "max_correction_um"}, "tolerances": {name: {"limit",
//   "value", "pass"}}, "pass": bool | null, "warnings": [...], "readings": {"target_mm": [...],
//   "cycle": [...], "direction": "+-..." (one character per reading), "deviation_um": [...]
//   (as evaluated: corrected to 20 °C when "corrected")}}.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "trueaxis/positioning/positioning.hpp"

namespace trueaxis::io {

struct PositioningRuns {
  std::vector<positioning::Reading> readings;
  std::vector<std::size_t> lines;  // 1-based line of each reading
  bool has_material = false, has_air = false;
};

// Parses `text` (`path` names it in messages).
PositioningRuns parse_runs(std::string text, const std::string& path);
PositioningRuns read_runs(const std::string& path);

// An interferometer log: CSV with columns time_s (s, strictly increasing) and reading_mm (the
// laser's reading, mm); errors name file:line:col.
positioning::Log read_log(const std::string& path);
void write_log(const std::string& path, const positioning::Log& log);
// True when the file's header row names the two columns of such a log (time and reading, in
// either order, with any unit suffix), so that one --input takes runs and logs alike.
bool is_log_file(const std::string& path);

// Writes readings in the runs.csv form above (temperature columns when any reading has one).
void write_runs(const std::string& path, const std::vector<positioning::Reading>& readings);

void write_positioning_result(const std::string& path, const positioning::Result& result,
                              positioning::Standard standard,
                              const std::vector<positioning::Verdict>& verdicts = {});

// A positioning.json read back (for 'trueaxis report'): the parameters of its standard (the
// other standard's are NaN), the targets, readings, warnings and verdicts. Errors name
// file:line:col.
struct PositioningFile {
  positioning::Result result;
  positioning::Standard standard = positioning::Standard::Iso230_2;
  std::vector<positioning::Verdict> verdicts;
};
PositioningFile read_positioning_result(const std::string& path);

}  // namespace trueaxis::io
