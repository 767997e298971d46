// Internal to trueaxis::geometry: what every fit of geometry/fit.hpp checks first (the points'
// count, coordinates and spread) and the principal axes it starts from, shared by the
// least-squares fits (fit.cpp) and the minimum-zone fits (fit_min_zone.cpp).
#pragma once

#include <Eigen/Core>

#include "trueaxis/geometry/fit.hpp"

namespace trueaxis::geometry::detail {

inline constexpr double kDegenerate =
    1e-9;  // relative singular value below which a set is degenerate
inline constexpr double kMaxCoordinate = 1e9;  // mm: 1000 km, beyond any machine

struct Pca {
  Eigen::Vector3d centroid;
  Eigen::Matrix3d axes;    // columns: principal directions, largest spread first
  Eigen::Vector3d spread;  // singular values of the centred points
  double extent = 0;       // mm: the largest distance of a point from the centroid
};

// With `exact_axes` false (the axes are only start values, or unused) the spreads and axes come
// from the 3 × 3 scatter matrix in one pass when the cloud is far from flat: its eigenvalues are
// the squared singular values, and only a spread near the degeneracy threshold needs the SVD's
// accuracy (an SVD of the 3 × n points costs ~40 passes over them).
Pca pca(const Eigen::Matrix3Xd& p, const Eigen::Vector3d& centroid, bool exact_axes = true);

// Before anything touches the points: a count, and coordinates a machine can have. The same
// pass gives their centroid and largest absolute coordinate. Throws Error saying what is wrong.
struct Scanned {
  Eigen::Vector3d centroid;
  double largest = 0;  // mm
};
Scanned check_points(Element e, const Eigen::Matrix3Xd& p);

// Enough points for the element, and spread enough to define it (not coincident, not collinear
// for a surface or circle, not coplanar for a sphere). Throws Error saying which.
void check(Element e, const Eigen::Matrix3Xd& p, const Pca& s);

// A circle in a plane's 2-D frame (mm).
struct Circle2 {
  Eigen::Vector2d c;
  double r;
};

}  // namespace trueaxis::geometry::detail
