// trueaxis::io — a circular test's compensation (circular/compensation.hpp) written for the
// controllers (io/compensation/parameters.hpp, io/compensation/controller.hpp), each file read
// back and compared with what was meant, and summarised in compensation.json.
//
// Files in the output folder:
// - linuxcnc-backlash.ini, heidenhain-backlash.mp, fanuc-backlash.txt, siemens-backlash.ini:
//   the backlash of the plane's two axes;
// - with the second axis' travel given, the squareness as a cross-axis table (the correction
//   added to the first axis over the second's position): siemens-squareness.ini (sag and
//   angularity compensation) and heidenhain-squareness.com (nonlinear axis error compensation,
//   the first axis' column over the second axis' positions; assign it in the *.CMA file). LinuxCNC
//   has no cross-axis compensation, and FANUC's straightness compensation option is not
//   written: both are listed as not written, with the reason.
// compensation.json (`"kind": "circular compensation"`): the plane, per axis
// `backlash_um: {<axis>: {"value", "active", "diagnosed", "u", "changed", "reason"}}`,
// `squareness_um_per_m` the same, `files` (controller, what, file, read_back, max_difference in
// µm or µm/m) and `not_written` (controller, what, reason).
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "trueaxis/circular/compensation.hpp"
#include "trueaxis/sim/circular.hpp"

namespace trueaxis::io {

struct CompensationFilesOptions {
  // mm: the second axis' travel, the span of the squareness tables; none: no table is written.
  std::optional<std::array<double, 2>> travel;
  int table_points = 11;               // points of a squareness table, >= 2
  double fanuc_detection_unit = 1e-3;  // mm
};

struct CompensationFiles {
  struct Written {
    std::string controller, what, path;
    double max_difference = 0;  // read back against what was meant: mm (backlash) or rad
  };
  struct NotWritten {
    std::string controller, what, reason;
  };
  std::vector<Written> written;
  std::vector<NotWritten> not_written;
  std::string json_path;
};

// Creates `folder` if needed. Throws Error when a file cannot be written, or reads back other than
// meant (beyond the format's resolution).
CompensationFiles write_compensation_files(const std::string& folder,
                                           const circular::Compensation& compensation,
                                           const CompensationFilesOptions& options = {});

// compensation.json read back: what a controller loaded with it applies.
struct AppliedCompensation {
  circular::Plane plane;
  std::array<double, 2> backlash{0, 0};  // mm, axes a, b
  double squareness = 0;                 // rad: a's correction = squareness·b
  std::string path;                      // the file it was read from
  // Loads it in the virtual machine's controller for a test of `options`' plane; throws Error
  // (naming the file) when the planes differ.
  void apply(sim::CircularOptions& options) const;
};
AppliedCompensation read_compensation_json(const std::string& path);

}  // namespace trueaxis::io
