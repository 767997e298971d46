// trueaxis::geometry — flatness of a surface given as heights z over plane coordinates (x, y).
//
// Units: x, y and z in one unit (mm in the library). The reference plane is z = a + b·x + c·y and
// deviations are measured along z. For a measured surface (deviations of micrometres over
// hundreds of millimetres) this equals the perpendicular distance to within a relative 1e-10.
#pragma once

#include <Eigen/Core>

namespace trueaxis::geometry {

struct HeightPlane {
  double a = 0, b = 0, c = 0;  // z = a + b·x + c·y
  double width = 0;            // max − min of z − plane over the points (the flatness)
  double operator()(double x, double y) const { return a + b * x + c * y; }
};

// Least-squares plane (ISO 12781 LS reference plane) and the peak-to-valley about it.
// Precondition: at least three points, not all on one line in (x, y); throws Error otherwise.
HeightPlane ls_plane(const Eigen::VectorXd& x, const Eigen::VectorXd& y, const Eigen::VectorXd& z);

// Minimum-zone flatness: the plane that minimises the peak-to-valley (Chebyshev fit), solved
// exactly as a linear programme (GLPK simplex on centred, scaled data).
// Same preconditions as ls_plane.
HeightPlane min_zone_plane(const Eigen::VectorXd& x, const Eigen::VectorXd& y,
                           const Eigen::VectorXd& z);

}  // namespace trueaxis::geometry
