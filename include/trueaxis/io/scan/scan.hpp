// trueaxis::io — results of a scanning run.
//
// scan.json: {"kind": "scan", "strategy", "tolerance_mm", "ok", "summary", "stopped" (why the
//   run stopped early, e.g. a collision, or null), "cmm": {"tip_radius_mm", "probe_noise_um",
//   "geometric_errors" (the machine's name, or null), "part_origin_mm" ([x, y, z] in machine
//   coordinates, with geometric errors)}, "machine_time_s": {"total", "design", "touch",
//   "autonomous", "moves"}, "sections": [{"name", "stretch_of" (the section a reachable stretch
//   was cut from; only for stretches), "status" ("ok" | "error" | "not_reachable"), "reason",
//   "machine_time_s": {…}, "corrections": [{"type", "parameters": {name: value}, "accepted",
//   "residual_before_mm", "residual_after_mm"}], "autonomous_count", "trajectory_errors",
//   "points": [[x, y, z], …], "normals": [[i, j, k], …], "times_s": [t, …], "traces": [{"label",
//   "completed", "arc_mm": […], "delta_l_mm": […]}]}], "not_reachable": [{"section",
//   "from_arc_mm", "to_arc_mm", "start_mm", "end_mm", "reason"}], "events": [{"t_s", "section",
//   "arc_mm", "delta_l_mm", "mode", "event", "decision"}], "planned_design" and
//   "corrected_design" (design.json's object)}: written also when the run stops early, with what
//   was measured until then.
// points.csv: section,x,y,z,nx,ny,nz,t — workpiece surface points (mm, tip-compensated), the
//   measured normal, machine time (s).
// events.csv: t,section,arc_mm,delta_l_mm,mode,event,decision — every decision of the flow.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>

#include "trueaxis/scan/controller.hpp"

namespace trueaxis::io {

// The CMM a scan ran on, as recorded in scan.json.
struct ScanCmm {
  double tip_radius = 0, probe_noise_um = 0;
  std::string machine;                         // the geometric-error model's name ("" = none)
  std::optional<Eigen::Vector3d> part_origin;  // mm, machine coordinates
};

void write_scan(const std::string& path, const scan::Result& result,
                const scan::ControllerOptions& options, const ScanCmm& cmm = {});
// scan.json read back with what its report needs (trueaxis report scan.json). Throws Error
// naming file:line:col of a missing or bad value.
struct ScanFile {
  scan::Result result;
  double tolerance = 0;  // the run's trajectory tolerance (mm)
};
ScanFile read_scan(const std::string& path);
void write_scan_points(const std::string& path, const scan::Result& result);
void write_scan_events(const std::string& path, const scan::Result& result);

}  // namespace trueaxis::io
