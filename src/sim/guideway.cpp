#include "trueaxis/sim/guideway.hpp"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "common.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::sim {
void GuidewayOptions::validate() const {
  if (axis < 0 || axis > 2) throw Error("guideway simulation: axis must be 0, 1 or 2 (X, Y, Z)");
  if (positions < 2) throw Error("guideway simulation: need at least 2 positions");
  for (double v : {pointing_noise, noise, angle_noise, quantisation, current_noise})
    if (!(v >= 0) || !std::isfinite(v))
      throw Error("guideway simulation: noise levels and quantisation must be >= 0");
  if (!(spot_radius > 0)) throw Error("guideway simulation: spot radius must be > 0");
}

Eigen::Matrix3d carriage_axes(int axis) {
  return guideway::carriage_axes(axis);
}

GuidewayCampaign simulate_guideway(const Machine& machine, const guideway::Layout& layout,
                                   const GuidewayOptions& o) {
  o.validate();
  machine.validate();
  layout.validate();
  const auto& range = machine.range[static_cast<std::size_t>(o.axis)];
  const auto& fns = machine.errors[static_cast<std::size_t>(o.axis)];
  const Eigen::Matrix3d M = carriage_axes(o.axis);
  const long n = o.positions;
  const auto m = static_cast<Eigen::Index>(layout.detectors.size());
  GuidewayCampaign c;
  c.s = Eigen::VectorXd::LinSpaced(n, range[0], range[1]);
  for (auto& t : c.truth) t.resize(n);
  Eigen::MatrixXd spots(n, 2 * m);
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> N(0.0, 1.0);
  for (Eigen::Index k = 0; k < n; ++k) {
    const double u = c.s[k];
    Eigen::Vector3d dm, em;
    for (int j = 0; j < 3; ++j) {
      const auto& ft = fns[static_cast<std::size_t>(j)];
      const auto& fr = fns[static_cast<std::size_t>(j + 3)];
      dm[j] = ft.empty() ? 0.0 : ft(u);
      em[j] = fr.empty() ? 0.0 : fr(u);
    }
    const Eigen::Vector3d d = M.transpose() * dm, e = M.transpose() * em;
    c.truth[0][k] = d.x();
    c.truth[1][k] = d.y();
    c.truth[2][k] = e.x();
    c.truth[3][k] = e.y();
    c.truth[4][k] = e.z();
    const Eigen::Matrix3d R = detail::rotation(e);
    for (Eigen::Index i = 0; i < m; ++i) {
      const auto& det = layout.detectors[static_cast<std::size_t>(i)];
      Eigen::Vector2d r;
      if (det.kind == guideway::Kind::Angle) {
        if (o.exact) {
          const Eigen::Vector3d b = R.transpose() * Eigen::Vector3d::UnitZ();  // beam, lens frame
          r = -det.focal_length * Eigen::Vector2d(b.x() / b.z(), b.y() / b.z());
        } else {
          r = det.focal_length * Eigen::Vector2d(e.y(), -e.x());
        }
        r += det.focal_length * o.angle_noise * Eigen::Vector2d(N(rng), N(rng));
      } else {
        const Eigen::Vector3d& p = det.position;
        if (o.exact) {
          const Eigen::Vector3d centre = d + R * p, normal = R.col(2);
          // The beam (p.x, p.y, t) meets the detector plane through `centre` with `normal`.
          const double t =
              (centre.dot(normal) - p.x() * normal.x() - p.y() * normal.y()) / normal.z();
          const Eigen::Vector3d rel = Eigen::Vector3d(p.x(), p.y(), t) - centre;
          r = {rel.dot(R.col(0)), rel.dot(R.col(1))};
        } else {
          r = {-(d.x() + e.y() * p.z() - e.z() * p.y()), -(d.y() + e.z() * p.x() - e.x() * p.z())};
        }
        r += o.pointing_noise * Eigen::Vector2d(N(rng), N(rng));
      }
      r += o.noise * Eigen::Vector2d(N(rng), N(rng));
      if (o.quantisation > 0) r = (r / o.quantisation).array().round().matrix() * o.quantisation;
      spots(k, 2 * i) = r.x();
      spots(k, 2 * i + 1) = r.y();
    }
  }
  if (!o.currents) {
    c.spots = std::move(spots);
    return c;
  }
  c.currents.resize(n, 4 * m);
  for (Eigen::Index k = 0; k < n; ++k)
    for (Eigen::Index i = 0; i < m; ++i) {
      // Fractions of a Gaussian spot right of and above the detector's centre lines.
      const double pr = 0.5 * (1 + guideway::gaussian_signal(spots(k, 2 * i), o.spot_radius));
      const double pu = 0.5 * (1 + guideway::gaussian_signal(spots(k, 2 * i + 1), o.spot_radius));
      const double q[4] = {pr * pu, (1 - pr) * pu, (1 - pr) * (1 - pu), pr * (1 - pu)};
      for (int j = 0; j < 4; ++j) c.currents(k, 4 * i + j) = q[j] * (1 + o.current_noise * N(rng));
    }
  return c;
}

}  // namespace trueaxis::sim
