// trueaxis::io — readers and writers for the straightness separation (probes.csv and its result).
//
// probes.csv: header row; first column `x` (mm, strictly increasing, equal steps); then one
// column per probe (µm) in the order of the offsets; optionally an angle column (µrad) named by
// the caller. Every violation is reported as "file:line:column: what is wrong".
//
// result.json: see write_result(). Units in files: mm for positions, µm for profiles and
// uncertainties, µrad for pitch.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "trueaxis/separation/separation.hpp"

namespace trueaxis::io {

struct ProbeReadOptions {
  // Probe offsets (mm) from probe A; empty: 0, h, 2h, ... in column order.
  std::vector<double> offsets;
  // Name of the angle column (µrad), if any. It is not counted as a probe.
  std::optional<std::string> angle_column;
  // Names of the probe columns, in the order of the offsets. Empty: every column after `x` but
  // the angle column; then a column whose name reads as an angle (`angle`, `pitch`, `*_urad`) is
  // refused rather than taken for a probe, and so is a column beyond the given offsets.
  std::vector<std::string> probe_columns;
  // Negate probe readings (probes that read the gap).
  bool invert = false;
  // Fewest stations accepted.
  long min_stations = 3;
};

// Reads probes.csv into library units (mm, rad). Throws Error naming file, line and column.
separation::ProbeData read_probes(const std::string& path, const ProbeReadOptions& options = {});

// Writes probes.csv (and the angle column if present) from library units.
void write_probes(const std::string& path, const separation::ProbeData& data,
                  const std::string& angle_column = "angle");

// result.json: {"method", "reference", "gauge", "unobservable": [...],
//   "workpiece": {"x": [mm], "value": [µm], "uncertainty": [µm]?}, "guide": {...},
//   "pitch": {"x": [mm], "value": [µrad], "uncertainty": [µrad]?}?,
//   "straightness": {"workpiece": {"ls": µm, "min_zone": µm, "U_um": µm|null,
//                                  "resolved": bool|null}, "guide": {...}},
//   "sigma_um": µm|null, "no_uncertainty"?: why no uncertainty is stated, "noise_gain"?,
//   "sigma_estimated", "dof", "residual_rms_um"}
void write_result(const std::string& path, const separation::Result& result);
// Reads a result.json written by write_result (or by hand in the same shape); validates it.
separation::Result read_result(const std::string& path);
// result.csv: x,workpiece_um[,workpiece_u_um],guide_um[,guide_u_um][,pitch_urad[,pitch_u_urad]];
// rows on the workpiece grid, empty fields where a curve is not defined.
void write_result_csv(const std::string& path, const separation::Result& result);

}  // namespace trueaxis::io
