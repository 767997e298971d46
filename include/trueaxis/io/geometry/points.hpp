// trueaxis::io — point sets for the geometric fits (points.csv).
//
// NIST .ds (ASME B89.4.10 reference data): the first line is the number of points; every further
// line holds x y z separated by spaces or tabs ("\r\n" accepted). Errors name file:line:col
// (non-numbers, missing or extra coordinates, a count that does not match the points).
#pragma once

#include <Eigen/Core>
#include <string>

#include "trueaxis/geometry/fit.hpp"

namespace trueaxis::io {

Eigen::Matrix3Xd read_ds(const std::string& path);

// A .ds file (by its extension, case-insensitive), or a CSV with columns x, y, z (mm).
Eigen::Matrix3Xd read_point_set(const std::string& path);

// fit.json: {"element", "points": n, "center" (circle, sphere) or "point" ([x, y, z] mm),
// "normal" (plane, circle) or "direction" (line, cylinder, cone; unit), "diameter" (circle,
// sphere, cylinder; mm), "distance" (cone: from "point" to the surface, mm), "apex_angle_deg"
// (cone), "zone" (minimum-zone fits: the zone's width, mm), "rms", "max" (residuals, mm),
// "iterations"}. `form`: the element's form figure (geometry::form_of), written as "form": {"name",
// "reference", "value", "U" (95 %, null when not stated), "resolved", "no_uncertainty"} (mm).
void write_fit(const std::string& path, const geometry::Fit& fit, const geometry::Form& form);

}  // namespace trueaxis::io
