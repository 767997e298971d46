// trueaxis::io — error-space files: plan.json, space.json, the generic CSV table and the
// LinuxCNC per-joint compensation file.
//
// plan.json (every key optional): {"spacing": mm, "probes": "three-point" | "two-point",
//   "probe_noise_um": µm, "laser_noise_um": µm, "profile_um": µm, "diagonals": true,
//   "monte_carlo": n, "seed": n}. Unknown keys are refused (file:line:col).
// space.json: {"frame", "reference", "unobservable": [...], "gauge", "plan": {...},
//   "grid": {"x": [mm], "y": [mm], "z": [mm], "layout": "...", "ex": [µm], "ey", "ez",
//            "ux"?, "uy"?, "uz"? (standard uncertainty, µm)},
//   "surfaces": [{"component", "level", "closure_rms", "flatness_ls"}],
//   "truth": {"rms", "max"}, "verification"?: {...}}; node n = i + nx·(j + ny·k).
#pragma once

#include <optional>
#include <string>

#include "trueaxis/map/error_map.hpp"
#include "trueaxis/surface/space.hpp"

namespace trueaxis::io {

surface::SpacePlan read_plan(const std::string& path);
void write_space(const std::string& path, const surface::SpaceResult& space,
                 const surface::SpacePlan& plan,
                 const std::optional<surface::Verification>& verification = std::nullopt);
// The "grid" of a space.json (or any JSON file with such a grid). Errors name file:line:col.
map::ErrorMap read_error_map(const std::string& path);

// Generic table: x,y,z (mm), ex,ey,ez (µm)[, ux,uy,uz (µm)], one row per node.
void write_map_csv(const std::string& path, const map::ErrorMap& map);

// LinuxCNC [JOINT_n] COMP_FILE for the joint of `axis` (0, 1, 2): one line "nominal forward
// reverse" per grid node along the axis, on the grid line through `at` (the other two
// coordinates, mm; interpolated). Type 0: actual positions (nominal + error along the axis);
// type 1: trims (nominal − actual). No header or comments (LinuxCNC stops at the first line that
// is not three numbers); nominals strictly increasing; at most 256 lines. The map has no
// reversal error, so forward == reverse. Returns the number of lines.
int write_linuxcnc(const std::string& path, const map::ErrorMap& map, int axis,
                   const Eigen::Vector3d& at, int type);

}  // namespace trueaxis::io
