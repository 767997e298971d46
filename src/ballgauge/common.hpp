// Private helpers shared by the ball-gauge map and the parametric identification.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace trueaxis::ballgauge::detail {

struct Centre {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();  // fitted centre (mm)
  Eigen::Vector3d u = Eigen::Vector3d::Zero();  // its standard uncertainty (mm)
  double diameter = 0;                          // fitted diameter of the tip-centre sphere
};

// Least-squares sphere fit of probed tip centres (3 × n, mm), with the centre's uncertainty from
// the residuals: cov = s²·(JᵀJ)⁻¹, s² = Σr² / (n − 4). Throws Error for degenerate sets.
Centre fit_ball(const Eigen::Matrix3Xd& points);

// Closed-form least-squares rigid registration X ≈ R·U + t (Kabsch, via SVD; a proper rotation).
void kabsch(const std::vector<Eigen::Vector3d>& U, const std::vector<Eigen::Vector3d>& X,
            Eigen::Matrix3d& R, Eigen::Vector3d& t);

// Clusters of coordinate values within `tol` of their sorted neighbour: the clusters' means
// (ascending) and, per value, its cluster index in `which`.
std::vector<double> clusters(const std::vector<double>& v, double tol, std::vector<int>& which);

}  // namespace trueaxis::ballgauge::detail
