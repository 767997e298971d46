// trueaxis::geometry — least-squares (Gaussian, ISO 10360-6) fits of geometric elements to 3-D
// points: line, plane, circle, sphere, cylinder and cone.
//
// Residuals are orthogonal distances (mm) from each point to the element. Lines and planes are
// solved exactly (centroid and SVD). Circles follow NIST's convention (and common CMM practice):
// the least-squares plane, then a 2-D circle fit of the projected points. Spheres, circles,
// cylinders and cones start from algebraic fits (linear least squares; cylinders and cones from
// each principal direction of the point cloud) and are refined by Gauss–Newton with
// Levenberg–Marquardt damping on the geometric distances, in a local frame re-centred on the
// current estimate at every step (Shakarji 1998, the NIST Algorithm Testing System).
//
// Reported like NIST's reference fits: a point and a unit direction (line: along it; plane and
// circle: normal; cylinder and cone: axis), and the diameter (circle, sphere, cylinder). The point
// on an axis is the foot of the perpendicular from the centroid of the data. A cone's direction
// points towards increasing radius; its size is the orthogonal distance from the reported axis
// point to the surface, and its apex angle is the full angle.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

namespace trueaxis::geometry {

enum class Element { Line, Plane, Circle, Sphere, Cylinder, Cone };

const char* to_string(Element e);
Element element_from_string(const std::string& s);  // "line", "plane", ...; throws Error

struct Fit {
  Element element = Element::Line;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  // centre, or a point on the line/axis/plane
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();  // unit: line/axis direction, or normal
  double diameter = 0;                                   // circle, sphere, cylinder (mm)
  double distance = 0;        // cone: orthogonal distance from `point` to the surface (mm)
  double apex_angle = 0;      // cone: full apex angle (rad)
  Eigen::VectorXd residuals;  // signed orthogonal distances (mm), one per point
  double rms = 0, max = 0;    // of |residuals|
  int iterations = 0;         // Gauss–Newton steps (0 for closed-form fits)
  double zone = 0;            // minimum-zone fits: the width of the zone (mm), else 0

  // Least-squares fits: standard uncertainties of the reported quantities, from the Jacobian at
  // the solution scaled by the residual variance (s² = Σr²/dof), i.e. assuming independent
  // errors of equal variance in every point. Each component of `point` and `direction` on its
  // own (mm; direction: unitless, ≈ rad); size in mm; apex angle in rad. Only when
  // has_uncertainty (the data are redundant: dof > 0).
  bool has_uncertainty = false;
  Eigen::Vector3d u_point = Eigen::Vector3d::Zero(), u_direction = Eigen::Vector3d::Zero();
  double u_diameter = 0, u_distance = 0, u_apex_angle = 0;
  long dof = 0;                 // residuals − parameters
  double condition_number = 0;  // of the Jacobian with unit columns at the solution
  // Plain-language warnings: a poorly determined size (standard uncertainty above 1 % of it),
  // a cone that cannot be told from a cylinder, an ill-conditioned fit (condition > 1e10).
  std::vector<std::string> warnings;
};

// Least-squares fit of `element` to the points (3 × n, mm). Preconditions (else Error): finite
// coordinates within 1e9 mm; at least 2 distinct points (line), 3 non-collinear (plane,
// circle), 4 non-coplanar (sphere), 5 (cylinder), 6 (cone). A diameter whose standard
// uncertainty exceeds a quarter of it (a sphere fitted to a nearly flat patch) is refused: the
// points do not determine it. The Gauss–Newton iteration stops when its step, and the distance
// its rate of convergence leaves to go, are at round-off; Newton steps in 80-bit arithmetic then
// reach the minimum to round-off of the result (circle, sphere, cylinder, cone). A fit that
// finds no minimum (Gauss–Newton still descending after 500 steps and Newton not settling, as on
// a small sector of a wide cone with noise) is refused with an Error.
Fit fit(Element element, const Eigen::Matrix3Xd& points);

// Minimum-zone (Chebyshev) fits: the element in the middle of the thinnest zone that contains
// all points, and that zone's width (Fit::zone).
//  - line: two parallel lines in the points' least-squares plane (2-D straightness; exact, by
//    rotating calipers on the convex hull);
//  - plane: two parallel planes (exact LP on heights in the plane's own frame, re-solved in the
//    frame of the new normal until it stops moving, so the width is perpendicular);
//  - circle: two concentric circles in the least-squares plane (LP on the linearised radial
//    distances, re-linearised at the new centre until it stops moving; from the LS centre).
// Residuals are distances to the middle element, so max − min of them equals the zone.
Fit fit_min_zone(Element element, const Eigen::Matrix3Xd& points);

// Orthogonal distances from points to a fitted element: signed (outside positive; along the
// normal for a plane) except for a line, where they are unsigned.
Eigen::VectorXd distances(const Fit& f, const Eigen::Matrix3Xd& points);

// The form of a fitted element, a peak-to-valley figure of its residuals: straightness (line),
// flatness (plane), roundness (circle), sphericity (sphere), cylindricity (cylinder), conicity
// (cone). About a least-squares element it is the range of the signed residuals (ISO 12781-1,
// 12181-1, 12180-1: the least-squares reference; a line: the diameter of the cylinder about it,
// twice the largest distance); of a minimum-zone fit, the zone.
struct Form {
  std::string name;       // "flatness", ...
  std::string reference;  // "about the least-squares plane", "minimum zone"
  double value = 0;       // mm
  // Expanded uncertainty (95 %, mm) from the points' own standard uncertainty along the surface
  // normal (the residuals alone cannot tell form from the points' noise):
  // detail::peak_to_valley_U(point_u, points), as every peak-to-valley figure. Unset when the
  // points' uncertainty is not stated; `no_uncertainty` says why.
  std::optional<double> U;
  std::string no_uncertainty;
  std::optional<bool> resolved() const {
    if (!U) return std::nullopt;
    return *U < value;
  }
  // In words, µm, to the resolution U supports: "flatness (about the least-squares plane): 2.3
  // um, U = 0.80 um (95 %)", "... not resolved (U = ...)", or the value with why no U.
  std::string summary() const;
};
// `point_u`: the points' standard uncertainty along the normal (mm), > 0; NaN when not stated.
// Throws Error for a point_u that is not a positive number or NaN.
Form form_of(const Fit& f, double point_u);

}  // namespace trueaxis::geometry
