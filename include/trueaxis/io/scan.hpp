// trueaxis::io — results of a scanning run.
//
// scan.json: {"kind": "scan", "strategy", "tolerance_mm", "ok", "summary", "machine_time_s": {"total", "design",
//   "touch", "autonomous", "moves"}, "sections": [{"name", "status" ("ok" | "error"), "reason",
//   "machine_time_s": {…}, "corrections": [{"type", "parameters": {name: value}, "accepted",
//   "residual_before_mm", "residual_after_mm"}], "autonomous_count", "trajectory_errors",
//   "points": [[x, y, z], …]}]}
// points.csv: section,x,y,z,nx,ny,nz,t — workpiece surface points (mm, tip-compensated), the
//   measured normal, machine time (s).
// events.csv: t,section,arc_mm,delta_l_mm,mode,event,decision — every decision of the flow.
#pragma once

#include <string>

#include "trueaxis/scan/controller.hpp"

namespace trueaxis::io {

void write_scan(const std::string& path, const scan::Result& result,
                const scan::ControllerOptions& options);
void write_scan_points(const std::string& path, const scan::Result& result);
void write_scan_events(const std::string& path, const scan::Result& result);

}  // namespace trueaxis::io
