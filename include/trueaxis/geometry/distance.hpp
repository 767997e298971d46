// trueaxis::geometry — distances between simple elements (mm).
#pragma once

#include <Eigen/Core>

namespace trueaxis::geometry {

// The squared distance between the segments p1–q1 and p2–q2 (either may be a point): the
// closest points' parameters clamped to the segments (Ericson, Real-Time Collision Detection,
// 2005, 5.1.9).
double segment_distance2(const Eigen::Vector3d& p1, const Eigen::Vector3d& q1,
                         const Eigen::Vector3d& p2, const Eigen::Vector3d& q2);

}  // namespace trueaxis::geometry
