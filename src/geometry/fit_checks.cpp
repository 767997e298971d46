// The checks every fit makes first, and the principal axes it starts from (fit_checks.hpp).
#include "fit_checks.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <cmath>

#include "../common/eigen_instances.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::geometry::detail {

Pca pca(const Eigen::Matrix3Xd& p, const Eigen::Vector3d& centroid, bool exact_axes) {
  Pca r;
  r.centroid = centroid;
  if (!exact_axes) {
    double xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0, far = 0;
    const double cx = centroid.x(), cy = centroid.y(), cz = centroid.z();
    for (Eigen::Index i = 0; i < p.cols(); ++i) {
      const double x = p(0, i) - cx, y = p(1, i) - cy, z = p(2, i) - cz;
      xx += x * x;
      xy += x * y;
      xz += x * z;
      yy += y * y;
      yz += y * z;
      zz += z * z;
      far = std::max(far, x * x + y * y + z * z);
    }
    r.extent = std::sqrt(far);
    Eigen::Matrix3d M;
    M << xx, xy, xz, xy, yy, yz, xz, yz, zz;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(M);
    const Eigen::Vector3d ev = es.eigenvalues();  // ascending
    constexpr double kScatterSpreadRatio = 1e-4;  // far above kDegenerate: safe to decide here
    if (es.info() == Eigen::Success && ev[0] > kScatterSpreadRatio * kScatterSpreadRatio * ev[2]) {
      r.spread = ev.reverse().cwiseSqrt();
      r.axes = es.eigenvectors().rowwise().reverse();
      return r;
    }
  }
  const Eigen::Matrix3Xd c = p.colwise() - r.centroid;
  r.extent = std::sqrt(c.colwise().squaredNorm().maxCoeff());
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(c, Eigen::ComputeFullU);
  r.axes = svd.matrixU();
  r.spread = svd.singularValues();
  return r;
}

Scanned check_points(Element e, const Eigen::Matrix3Xd& p) {
  const Eigen::Index n = p.cols();
  if (n == 0) throw Error(fmt::format("{} fit: no points", to_string(e)));
  double sx = 0, sy = 0, sz = 0, largest = 0;
  bool ok = true;  // every coordinate finite and within kMaxCoordinate (NaN compares false)
  for (Eigen::Index i = 0; i < n; ++i) {
    const double x = p(0, i), y = p(1, i), z = p(2, i);
    sx += x;
    sy += y;
    sz += z;
    const double ax = std::abs(x), ay = std::abs(y), az = std::abs(z);
    ok &= (ax <= kMaxCoordinate) & (ay <= kMaxCoordinate) & (az <= kMaxCoordinate);
    largest = std::max(largest, std::max(ax, std::max(ay, az)));
  }
  if (!ok) {
    if (!p.allFinite())
      throw Error(fmt::format("{} fit: coordinates must be finite", to_string(e)));
    throw Error(
        fmt::format("{} fit: a coordinate of {:g} mm is beyond any machine (at most "
                    "{:g} mm)",
                    to_string(e), p.cwiseAbs().maxCoeff(), kMaxCoordinate));
  }
  const double inv = 1 / static_cast<double>(n);
  return {Eigen::Vector3d(sx * inv, sy * inv, sz * inv), largest};
}

void check(Element e, const Eigen::Matrix3Xd& p, const Pca& s) {
  const long need[] = {2, 3, 3, 4, 5, 6};
  const long n = p.cols();
  if (n < need[static_cast<int>(e)])
    throw Error(fmt::format("{} fit: need at least {} points, got {}", to_string(e),
                            need[static_cast<int>(e)], n));
  if (!(s.spread[0] > 0))
    throw Error(fmt::format("{} fit: all {} points coincide", to_string(e), n));
  if (e != Element::Line && !(s.spread[1] > kDegenerate * s.spread[0]))
    throw Error(fmt::format("{} fit: the points are collinear: no {} is defined", to_string(e),
                            to_string(e)));
  if (e == Element::Sphere && !(s.spread[2] > kDegenerate * s.spread[0]))
    throw Error("sphere fit: the points are coplanar: the sphere is not defined");
}

}  // namespace trueaxis::geometry::detail
