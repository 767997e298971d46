// The moving parts of a virtual scanning CMM: servo, section contour, probe.
#include "trueaxis/sim/cmm.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

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
    p_.conservativeResize(3, p_.cols() - 1);
  if (p_.cols() < 2 || !p_.allFinite()) throw Error("contour: needs at least 2 finite points");
  const Eigen::Index n = p_.cols(), segs = closed_ ? n : n - 1;
  arc_.resize(segs + 1);
  normals_.resize(3, segs);
  arc_[0] = 0;
  for (Eigen::Index i = 0; i < segs; ++i) {
    const Eigen::Vector3d d = p_.col((i + 1) % n) - p_.col(i);
    const double len = d.norm();
    if (!(len > 0)) throw Error(fmt::format("contour: points {} and {} coincide", i, (i + 1) % n));
    arc_[i + 1] = arc_[i] + len;
    const Eigen::Vector3d left = n_.cross(d / len);
    normals_.col(i) = left_ ? -left : left;
  }
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

Contour::Nearest Contour::nearest(const Eigen::Vector3d& q0) const {
  const Eigen::Vector3d q = q0 - (q0 - p_.col(0)).dot(n_) * n_;
  const Eigen::Index segs = normals_.cols();
  auto search = [&](Eigen::Index from, Eigen::Index count, Eigen::Index& best_i) {
    Nearest best;
    double best_d = 1e300;
    for (Eigen::Index k = 0; k < count; ++k) {
      Eigen::Index i = from + k;
      if (closed_)
        i = ((i % segs) + segs) % segs;
      else if (i < 0 || i >= segs)
        continue;
      const Nearest r = at_segment(i, q);
      if (std::abs(r.distance) < best_d - 1e-12) {
        best_d = std::abs(r.distance);
        best = r;
        best_i = i;
      }
    }
    return best;
  };
  constexpr Eigen::Index kWindow = 8;
  if (hint_ >= 0 && segs > 4 * kWindow) {
    Eigen::Index bi = -1;
    Nearest r = search(hint_ - kWindow, 2 * kWindow + 1, bi);
    // Accept a minimum strictly inside the window; at its edge the probe has moved far.
    Eigen::Index off = bi - hint_;
    if (closed_) off = ((off + segs + segs / 2) % segs) - segs / 2;
    if (bi >= 0 && std::abs(off) < kWindow) {
      hint_ = bi;
      return r;
    }
  }
  Eigen::Index bi = 0;
  Nearest r = search(0, segs, bi);
  hint_ = bi;
  return r;
}

// -------------------------------------------------------------------------------------------

void ProbeOptions::validate() const {
  if (!(tip_radius > 0 && tip_radius <= 50))
    throw Error(fmt::format("probe tip radius = {:g}: must be in (0, 50] mm", tip_radius));
  if (!(range > 0 && range <= 10))
    throw Error(fmt::format("probe range = {:g}: must be in (0, 10] mm", range));
  if (!(noise >= 0 && noise <= 0.1))
    throw Error(fmt::format("probe noise = {:g} mm: must be in [0, 0.1] mm", noise));
}

Probe::Probe(const ProbeOptions& options) : o_(options), rng_(options.seed) {
  o_.validate();
}

ProbeReading Probe::read(const Eigen::Vector3d& position, const Contour& part) {
  ProbeReading r;
  r.surface = part.nearest(position);
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
