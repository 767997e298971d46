// trueaxis::io — the virtual machine's JSON description and point lists (sim/machine.hpp).
//
// machine.json (units: mm for positions, µm for linear errors, µrad for angular errors):
//   {"name": "...", "chain": "FYXZ",
//    "ranges": {"x": [min, max], "y": [min, max], "z": [min, max]},
//    "offset": [x, y, z],
//    "errors": {"EXX": <function>, "EYX": ..., ..., "ECZ": ...,        (18 axis errors, ISO 230-1)
//               "EC0Y": µrad, "EB0Z": µrad, "EA0Z": µrad}}             (3 squareness errors)
// <function> = {"polynomial": [c0, c1, ...]   (c_k multiplies (u / 1000 mm)^k; µm or µrad),
//               "sines": [{"amplitude": µm|µrad, "period": mm, "phase": rad}, ...],
//               "table": {"u": [mm, ...], "value": [µm|µrad, ...]}}  (any combination, summed).
// Missing errors are zero; "chain" defaults to FYXZ and "offset" to [0, 0, 0]. Unknown keys in
// "errors" are refused (a typo must not silently zero an error). Errors name file:line:col.
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>

#include "trueaxis/io/json.hpp"
#include "trueaxis/sim/machine.hpp"

namespace trueaxis::io {

sim::Machine read_machine(const std::string& path);
void write_machine(const std::string& path, const sim::Machine& machine);
// The same from / to a parsed document (other top-level keys are ignored on reading, so a file
// may carry more, e.g. a parametric model's identification).
sim::Machine read_machine(const JsonFile& file);
nlohmann::ordered_json machine_json(const sim::Machine& machine);

// A CSV with columns x, y, z (mm; other columns ignored) as a 3 × n matrix. Errors name
// file:line:col. If `machine` is given, points outside its ranges are refused the same way.
Eigen::Matrix3Xd read_points(const std::string& path, const sim::Machine* machine = nullptr);
// The CSV read_points reads: header x,y,z, one point (mm) per row; "-" writes to stdout.
void write_points(const std::string& path, const Eigen::Matrix3Xd& points);

}  // namespace trueaxis::io
