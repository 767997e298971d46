// trueaxis::geometry — straightness evaluation of a profile.
//
// Units: all lengths (positions and profile values) in the same unit, mm in the library.
// A profile is a set of points (x_i, y_i); x need not be sorted unless stated.
#pragma once

#include <Eigen/Core>

namespace trueaxis::geometry {

// y = intercept + slope * x.
struct Line {
  double intercept = 0;
  double slope = 0;
  double operator()(double x) const { return intercept + slope * x; }
};

// Least-squares line (ISO 12780-1 LS reference line) through (x, y). Precondition: at least two
// distinct x. Computed about the centroid, so large x offsets do not cost precision.
Line fit_line(const Eigen::VectorXd& x, const Eigen::VectorXd& y);

// Residuals y - line(x).
Eigen::VectorXd residuals(const Eigen::VectorXd& x, const Eigen::VectorXd& y, const Line& line);
// The same in place: y -= line(x) (no copy of a long profile).
void subtract_line(const Eigen::VectorXd& x, Eigen::VectorXd& y, const Line& line);

// Peak-to-valley of the residuals about the least-squares line.
double ls_straightness(const Eigen::VectorXd& x, const Eigen::VectorXd& y);

// Minimum-zone result: the minimum width of the point set, measured perpendicular to the pair of
// parallel lines that enclose it, and the middle line of that zone.
struct MinZone {
  double width = 0;
  Line middle;  // reference line halfway between the two enclosing lines
};

// Exact minimum zone (minimum width of the convex hull, rotating calipers). O(n) when x is
// sorted ascending (as profiles are), O(n log n) otherwise. Precondition: n >= 2.
MinZone min_zone(const Eigen::VectorXd& x, const Eigen::VectorXd& y);

// ISO 16610-21 Gaussian profile filter: returns the mean line (long-wave part) of y sampled at
// equal spacing `dx`, with cut-off wavelength `cutoff` (50 % amplitude transmission there).
// End handling: the weighting function is truncated at the profile ends and renormalised to unit
// sum (so a constant or a straight-line profile is reproduced up to the ends' curvature bias);
// the kernel is cut at +-cutoff where its weight is below 1e-6 of the peak.
// Preconditions: dx > 0, cutoff > 0.
Eigen::VectorXd gaussian_filter(const Eigen::VectorXd& y, double dx, double cutoff);

}  // namespace trueaxis::geometry
