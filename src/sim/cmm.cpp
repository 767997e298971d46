// The moving parts of a virtual scanning CMM: servo, section contour, probe.
#include "trueaxis/sim/cmm.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "trueaxis/error.hpp"

namespace trueaxis::sim {

void ServoOptions::validate() const {
  auto bad = [](const char* name, double v, const char* why) {
    throw Error(fmt::format("servo {} = {:g}: {}", name, v, why));
  };
  if (!(rate_hz >= 10 && rate_hz <= 1e5)) bad("rate", rate_hz, "must be 10 Hz to 100 kHz");
  if (!(max_velocity > 0 && max_velocity <= 1e4))
    bad("max velocity", max_velocity, "must be in (0, 1e4] mm/s");
  if (!(max_acceleration > 0 && max_acceleration <= 1e6))
    bad("max acceleration", max_acceleration, "must be in (0, 1e6] mm/s²");
  if (!(lag >= 2 * dt() && lag < 1)) bad("lag", lag, "must be at least two ticks and below 1 s");
  if (!(position_gain > 0 && position_gain * lag <= 0.5))
    bad("position gain", position_gain, "must be positive with gain × lag ≤ 0.5 (a stable loop)");
}

Servo::Servo(const ServoOptions& options, const Eigen::Vector3d& start)
    : o_(options), position_(start) {
  o_.validate();
  if (!start.allFinite()) throw Error("servo start position is not finite");
}

void Servo::step(const Eigen::Vector3d& target, const Eigen::Vector3d& feed) {
  const double dt = o_.dt();
  const double alpha = 1 - std::exp(-dt / o_.lag);
  const double dv_max = o_.max_acceleration * dt;
  for (int k = 0; k < 3; ++k) {
    const double cmd = std::clamp(feed[k] + o_.position_gain * (target[k] - position_[k]),
                                  -o_.max_velocity, o_.max_velocity);
    const double dv = std::clamp(alpha * (cmd - velocity_[k]), -dv_max, dv_max);
    velocity_[k] += dv;
    position_[k] += velocity_[k] * dt;
  }
  time_ = static_cast<double>(++ticks_) * dt;
}

// -------------------------------------------------------------------------------------------

Contour::Contour(Eigen::Matrix3Xd points, const Eigen::Vector3d& plane_normal, bool closed,
                 bool material_left)
    : p_(std::move(points)), n_(plane_normal), closed_(closed), left_(material_left) {
  if (!(n_.norm() > 0)) throw Error("contour: the plane normal is zero");
  n_.normalize();
  if (closed_ && p_.cols() > 2 && (p_.col(0) - p_.col(p_.cols() - 1)).norm() < 1e-12)
    p_ = p_.leftCols(p_.cols() - 1).eval();  // the repeated closing point dropped
  if (p_.cols() < 2 || !p_.allFinite()) throw Error("contour: needs at least 2 finite points");
  const Eigen::Index n = p_.cols(), segs = closed_ ? n : n - 1;
  arc_.resize(segs + 1);
  normals_.resize(3, segs);
  dir_.resize(3, segs);
  inv_len2_.resize(segs);
  arc_[0] = 0;
  for (Eigen::Index i = 0; i < segs; ++i) {
    const Eigen::Vector3d d = p_.col((i + 1) % n) - p_.col(i);
    const double len = d.norm();
    if (!(len > 0)) throw Error(fmt::format("contour: points {} and {} coincide", i, (i + 1) % n));
    arc_[i + 1] = arc_[i] + len;
    dir_.col(i) = d;
    inv_len2_[i] = 1 / (len * len);
    const Eigen::Vector3d left = n_.cross(d / len);
    normals_.col(i) = left_ ? -left : left;
  }
  // The grid: about 64 cells along the larger side, each cell listing the segments whose
  // bounding box touches it.
  const Eigen::Vector3d a =
      std::abs(n_.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  e1_ = (a - a.dot(n_) * n_).normalized();
  e2_ = n_.cross(e1_);
  Eigen::Matrix2Xd q(2, n);
  for (Eigen::Index i = 0; i < n; ++i) q.col(i) << p_.col(i).dot(e1_), p_.col(i).dot(e2_);
  lo_ = q.rowwise().minCoeff();
  const Eigen::Vector2d ext = q.rowwise().maxCoeff() - lo_;
  h_ = std::max(ext.maxCoeff() / 64, 1e-3);
  nx_ = static_cast<int>(ext.x() / h_) + 1;
  ny_ = static_cast<int>(ext.y() / h_) + 1;
  // Cells per segment (bounding box), counted, then filled (compressed rows).
  const std::size_t ncell = static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_);
  cell_start_.assign(ncell + 1, 0);
  auto each_cell = [&](Eigen::Index i, auto&& fn) {
    const Eigen::Vector2d u = q.col(i), v = q.col((i + 1) % n);
    const int x0 = std::max(0, static_cast<int>((std::min(u.x(), v.x()) - lo_.x()) / h_));
    const int x1 = std::min(nx_ - 1, static_cast<int>((std::max(u.x(), v.x()) - lo_.x()) / h_));
    const int y0 = std::max(0, static_cast<int>((std::min(u.y(), v.y()) - lo_.y()) / h_));
    const int y1 = std::min(ny_ - 1, static_cast<int>((std::max(u.y(), v.y()) - lo_.y()) / h_));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) fn(static_cast<std::size_t>(y) * nx_ + x);
  };
  for (Eigen::Index i = 0; i < segs; ++i)
    each_cell(i, [&](std::size_t c) { ++cell_start_[c + 1]; });
  for (std::size_t c = 0; c < ncell; ++c) cell_start_[c + 1] += cell_start_[c];
  cell_items_.resize(static_cast<std::size_t>(cell_start_[ncell]));
  std::vector<int> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (Eigen::Index i = 0; i < segs; ++i)
    each_cell(i, [&](std::size_t c) {
      cell_items_[static_cast<std::size_t>(fill[c]++)] = static_cast<int>(i);
    });
}

double Contour::dist2(Eigen::Index i, const Eigen::Vector3d& q) const {
  const Eigen::Vector3d a = p_.col(i), d = dir_.col(i);
  const double t = std::clamp((q - a).dot(d) * inv_len2_[i], 0.0, 1.0);
  return (q - a - t * d).squaredNorm();
}

Contour::Nearest Contour::at_segment(Eigen::Index i, const Eigen::Vector3d& q) const {
  const Eigen::Index n = p_.cols(), segs = normals_.cols();
  const Eigen::Vector3d a = p_.col(i), b = p_.col((i + 1) % n);
  const Eigen::Vector3d d = b - a;
  const double len2 = d.squaredNorm();
  const double t = std::clamp((q - a).dot(d) / len2, 0.0, 1.0);
  Nearest r;
  r.point = a + t * d;
  r.arc = arc_[i] + t * std::sqrt(len2);
  const Eigen::Vector3d off = q - r.point;
  const double dist = off.norm();
  // At a vertex the side comes from the mean of the two segment normals (the vertex
  // pseudo-normal), so that signs agree on both sides of a corner.
  Eigen::Vector3d pseudo = normals_.col(i);
  if (t <= 0 && (closed_ || i > 0)) pseudo += normals_.col((i + segs - 1) % segs);
  if (t >= 1 && (closed_ || i + 1 < segs)) pseudo += normals_.col((i + 1) % segs);
  const double side = off.dot(pseudo) >= 0 ? 1.0 : -1.0;
  r.distance = side * dist;
  if (t > 0 && t < 1)
    r.normal = normals_.col(i);
  else if (dist > 1e-12)
    r.normal = side * off / dist;
  else
    r.normal = pseudo.normalized();
  return r;
}

Contour::Nearest Contour::nearest(const Eigen::Vector3d& q) const {
  return *nearest_within(q, std::numeric_limits<double>::infinity());
}

std::optional<Contour::Nearest> Contour::nearest_within(const Eigen::Vector3d& q0,
                                                        double radius) const {
  const Eigen::Vector3d q = q0 - (q0 - p_.col(0)).dot(n_) * n_;
  const Eigen::Index segs = normals_.cols();
  // A first bound from the segments around the one found last (a probe moving along the contour
  // finds its minimum there), then the grid: rings of cells outward from the query until no cell
  // can hold a closer segment. A cell in ring r lies at least (r − 1)·h from the query, and at
  // least as far as the query is outside the grid.
  double best_d = radius;
  Eigen::Index best_i = -1;
  if (hint_ >= 0) {
    constexpr Eigen::Index kWindow = 2;
    for (Eigen::Index k = -kWindow; k <= kWindow; ++k) {
      Eigen::Index i = hint_ + k;
      if (closed_)
        i = ((i % segs) + segs) % segs;
      else if (i < 0 || i >= segs)
        continue;
      const double d = std::sqrt(dist2(i, q));
      if (d < best_d) {
        best_d = d;
        best_i = i;
      }
    }
  }
  const Eigen::Vector2d g((q.dot(e1_) - lo_.x()) / h_, (q.dot(e2_) - lo_.y()) / h_);
  const int cx = std::clamp(static_cast<int>(std::floor(g.x())), 0, nx_ - 1);
  const int cy = std::clamp(static_cast<int>(std::floor(g.y())), 0, ny_ - 1);
  const double outside =
      h_ * std::hypot(std::max({0.0, -g.x(), g.x() - nx_}), std::max({0.0, -g.y(), g.y() - ny_}));
  double best_d2 = best_d * best_d * (1 - 1e-12);
  const int rings = std::max(nx_, ny_);
  for (int r = 0; r <= rings; ++r) {
    if (best_d <= std::max(outside, (r - 1) * h_)) break;
    for (int y = cy - r; y <= cy + r; ++y) {
      if (y < 0 || y >= ny_) continue;
      const bool edge_row = y == cy - r || y == cy + r;
      for (int x = cx - r; x <= cx + r; x += (edge_row || r == 0) ? 1 : 2 * r) {
        if (x < 0 || x >= nx_) continue;
        const std::size_t cell = static_cast<std::size_t>(y) * nx_ + x;
        for (int k = cell_start_[cell]; k < cell_start_[cell + 1]; ++k) {
          const int i = cell_items_[static_cast<std::size_t>(k)];
          const double d2 = dist2(i, q);
          // Ties (a vertex shared by two segments) keep the first found: both agree.
          if (d2 < best_d2) {
            best_d2 = d2;
            best_d = std::sqrt(d2);
            best_i = i;
          }
        }
      }
    }
  }
  if (best_i < 0) return std::nullopt;
  hint_ = best_i;
  return at_segment(best_i, q);
}

// -------------------------------------------------------------------------------------------

void ProbeOptions::validate() const {
  if (!(tip_radius > 0 && tip_radius <= 50))
    throw Error(fmt::format("probe tip radius = {:g}: must be in (0, 50] mm", tip_radius));
  if (!(range > 0 && range <= 10))
    throw Error(fmt::format("probe range = {:g}: must be in (0, 10] mm", range));
  if (!(noise >= 0 && noise <= 0.1))
    throw Error(fmt::format("probe noise = {:g} mm: must be in [0, 0.1] mm", noise));
  if (!(lobing >= 0 && lobing <= 0.1))
    throw Error(fmt::format("probe lobing = {:g} mm: must be in [0, 0.1] mm", lobing));
}

double pretravel_lobing(double lobing, const Eigen::Vector3d& d) {
  if (lobing == 0) return 0;
  const Eigen::Vector3d u = d.normalized();
  return lobing * std::cos(3 * std::atan2(u.y(), u.x())) * (1 - u.z() * u.z());
}

double Box::top() const {
  return centre.z() + axes.row(2).cwiseAbs().dot(half);
}

Contour::Nearest Box::nearest(const Eigen::Vector3d& x) const {
  const Eigen::Vector3d q = axes.transpose() * (x - centre);  // in the box's frame
  const Eigen::Vector3d excess = q.cwiseAbs() - half;
  Contour::Nearest n;
  if ((excess.array() > 0).any()) {  // outside: the closest point of the box
    const Eigen::Vector3d inner = q.cwiseMax(-half).cwiseMin(half);
    const Eigen::Vector3d v = q - inner;
    n.distance = v.norm();
    n.point = centre + axes * inner;
    n.normal = axes * (v / n.distance);
    return n;
  }
  int k = 0;  // inside: the nearest face
  excess.maxCoeff(&k);
  Eigen::Vector3d inner = q;
  inner[k] = q[k] >= 0 ? half[k] : -half[k];
  n.distance = excess[k];  // ≤ 0
  n.point = centre + axes * inner;
  n.normal = axes.col(k) * (q[k] >= 0 ? 1.0 : -1.0);
  return n;
}

SpaceCurve::SpaceCurve(Eigen::Matrix3Xd points, Eigen::Matrix3Xd normals)
    : p_(std::move(points)), n_(std::move(normals)) {
  if (p_.cols() < 2 || n_.cols() != p_.cols())
    throw Error("a space curve needs at least 2 points and one normal per point");
  for (Eigen::Index i = 0; i < n_.cols(); ++i) {
    if (!(n_.col(i).norm() > 0)) throw Error("a space curve's normal has no direction");
    n_.col(i).normalize();
  }
  arc_.resize(p_.cols());
  arc_[0] = 0;
  for (Eigen::Index i = 1; i < p_.cols(); ++i)
    arc_[i] = arc_[i - 1] + (p_.col(i) - p_.col(i - 1)).norm();
}

Contour::Nearest SpaceCurve::nearest(const Eigen::Vector3d& q) const {
  double best = INFINITY;
  Contour::Nearest out;
  for (Eigen::Index i = 0; i + 1 < p_.cols(); ++i) {
    const Eigen::Vector3d a = p_.col(i), d = p_.col(i + 1) - a;
    const double l2 = d.squaredNorm();
    const double t = l2 > 0 ? std::clamp((q - a).dot(d) / l2, 0.0, 1.0) : 0.0;
    const Eigen::Vector3d f = a + t * d;
    const double d2 = (q - f).squaredNorm();
    if (d2 < best) {
      best = d2;
      out.point = f;
      out.normal = ((1 - t) * n_.col(i) + t * n_.col(i + 1)).normalized();
      out.arc = arc_[i] + t * std::sqrt(l2);
    }
  }
  out.distance = (q - out.point).dot(out.normal);
  return out;
}

Probe::Probe(const ProbeOptions& options) : o_(options), rng_(options.seed) {
  o_.validate();
}

ProbeReading Probe::read(const Eigen::Vector3d& position, const Contour& part) {
  return read(part.nearest(position));
}

ProbeReading Probe::read(const Contour::Nearest& surface) {
  ProbeReading r;
  r.surface = surface;
  const double penetration = o_.tip_radius - r.surface.distance;
  if (penetration > 0) {
    r.contact = true;
    r.true_deflection = penetration * r.surface.normal;
    r.overtravel = penetration > o_.range;
  }
  r.deflection = r.true_deflection;
  if (o_.noise > 0)
    for (int k = 0; k < 3; ++k) r.deflection[k] += o_.noise * gauss_(rng_);
  return r;
}

}  // namespace trueaxis::sim
