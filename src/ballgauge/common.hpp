// Private helpers shared by the ball-gauge map and the parametric identification.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace trueaxis::ballgauge::detail {

struct Centre {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();  // fitted centre (mm)
  Eigen::Vector3d u = Eigen::Vector3d::Zero();  // its standard uncertainty (mm)
  double diameter = 0;                          // fitted diameter of the tip-centre sphere
  // Wrong touches left out (with drop_outliers): "point k (1-based) was 11.2 mm off ...".
  std::vector<std::string> dropped;
};

// Least-squares sphere fit of probed tip centres (3 × n, mm), with the centre's uncertainty from
// the residuals: cov = s²·(JᵀJ)⁻¹, s² = Σr² / (n − 4). Throws Error for degenerate sets.
// Wrong touches: while a residual exceeds `outlier_tolerance` (mm), the point whose removal
// leaves the others within the tolerance is an outlier; it is refused (Error naming it) or, with
// `drop_outliers`, left out and listed in `dropped`. At least 5 points stay.
Centre fit_ball(const Eigen::Matrix3Xd& points, double outlier_tolerance = 0.02,
                bool drop_outliers = false);

// Closed-form least-squares rigid registration X ≈ R·U + t (Kabsch, via SVD; a proper rotation).
void kabsch(const std::vector<Eigen::Vector3d>& U, const std::vector<Eigen::Vector3d>& X,
            Eigen::Matrix3d& R, Eigen::Vector3d& t);

// Clusters of coordinate values within `tol` of their sorted neighbour: the clusters' means
// (ascending) and, per value, its cluster index in `which`.
std::vector<double> clusters(const std::vector<double>& v, double tol, std::vector<int>& which);

}  // namespace trueaxis::ballgauge::detail
