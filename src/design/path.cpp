// The stylus-centre path of design-value scanning: options, segments and paths, and the path of a
// space curve. A plane section's path (an offset of its curve) is made by Open CASCADE Technology
// in libtrueaxis_occt.so (occt/path.cpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "occt_api.hpp"
#include "trueaxis/design/design.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::design {
namespace {

// Measured contours (a section overwritten by an autonomous scan) have nanometre kinks between
// otherwise collinear points; OCCT 7.6's offset fails on chains of such nearly tangent edges.
// Points that lie within `eps` of the chord between their kept neighbours carry no shape and
// are dropped (eps well inside the chordal tolerance; greedy: a point is dropped while every point
// since the last kept one stays within eps of the chord from it to the next point).
Eigen::Matrix3Xd drop_collinear(const Eigen::Matrix3Xd& p, double eps) {
  const Eigen::Index n = p.cols();
  if (n < 3) return p;
  std::vector<Eigen::Index> keep{0};
  for (Eigen::Index j = 2; j < n; ++j) {
    const Eigen::Vector3d a = p.col(keep.back()), b = p.col(j);
    const Eigen::Vector3d ab = b - a;
    const double l2 = ab.squaredNorm();
    bool fits = l2 > 0;
    fits = fits && j - keep.back() < 1000;  // bounded work on long straight runs
    for (Eigen::Index i = keep.back() + 1; fits && i < j; ++i) {
      const double t = (p.col(i) - a).dot(ab) / l2;
      fits = t > 0 && t < 1 && (p.col(i) - a - t * ab).norm() <= eps;
    }
    if (!fits) keep.push_back(j - 1);
  }
  keep.push_back(n - 1);
  Eigen::Matrix3Xd out(3, static_cast<Eigen::Index>(keep.size()));
  for (std::size_t k = 0; k < keep.size(); ++k)
    out.col(static_cast<Eigen::Index>(k)) = p.col(keep[k]);
  return out;
}

}  // namespace

void PathOptions::validate() const {
  auto bad = [](const char* name, double v, const char* why) {
    throw Error(fmt::format("{} = {:g}: {}", name, v, why));
  };
  if (!(tip_radius > 0 && tip_radius <= 50)) bad("tip radius", tip_radius, "must be in (0, 50] mm");
  if (!(pushing >= 0 && pushing < tip_radius))
    bad("pushing amount", pushing, "must be at least 0 and less than the tip radius (mm)");
  if (!(chordal_tolerance >= 1e-7 && chordal_tolerance <= 1))
    bad("chordal tolerance", chordal_tolerance, "must be in [1e-7, 1] mm");
  if (!(max_speed > 0 && max_speed <= 1000))
    bad("maximum speed", max_speed, "must be in (0, 1000] mm/s");
  if (!(min_speed > 0 && min_speed <= max_speed))
    bad("minimum speed", min_speed, "must be positive and at most the maximum speed (mm/s)");
  if (!(max_normal_acceleration > 0 && max_normal_acceleration <= 1e6))
    bad("maximum normal acceleration", max_normal_acceleration, "must be in (0, 1e6] mm/s²");
}

namespace {
// Arc length of a segment from u = 0 to u (5-point Gauss–Legendre on |p'|, as its length).
double arc_to(const PccSegment& g, double u) {
  static const double x[5] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831,
                              0.9061798459386640};
  static const double w[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889,
                              0.4786286704993665, 0.2369268850561891};
  double l = 0;
  for (int i = 0; i < 5; ++i) l += w[i] * g.tangent(0.5 * u * (x[i] + 1)).norm();
  return 0.5 * u * l;
}
// The parameter at arc length `a` along the segment (Newton's method from the linear guess): a
// cubic's parameter need not run evenly with its arc, and a scan that takes it for arc length
// commands a carriage that runs ahead of or behind its feed.
double u_at(const PccSegment& g, double a) {
  double u = std::clamp(a / g.length, 0.0, 1.0);
  for (int it = 0; it < 6; ++it) {
    const double speed = g.tangent(u).norm();
    if (!(speed > 0)) break;
    const double step = (arc_to(g, u) - a) / speed;
    u = std::clamp(u - step, 0.0, 1.0);
    if (std::abs(step) < 1e-12) break;
  }
  return u;
}
}  // namespace

double ScanPath::length() const {
  double l = 0;
  for (const auto& s : segments) l += s.length;
  return l;
}
PathPoint ScanPath::at(double s) const {
  if (segments.empty()) throw Error("the scanning path is empty");
  if (cumulative_.size() != segments.size() + 1) {
    cumulative_.assign(1, 0.0);
    for (const auto& g : segments) cumulative_.push_back(cumulative_.back() + g.length);
    last_ = 0;
  }
  s = std::clamp(s, 0.0, cumulative_.back());
  // Scans walk forward: start from the last segment found.
  if (last_ >= segments.size() || s < cumulative_[last_]) last_ = 0;
  while (last_ + 1 < segments.size() && s >= cumulative_[last_ + 1]) ++last_;
  const PccSegment& g = segments[last_];
  const double u = g.length > 0 ? u_at(g, s - cumulative_[last_]) : 0.0;
  PathPoint r;
  r.p = g.point(u);
  r.tangent = g.tangent(u).normalized();
  if (space()) {
    r.normal = ((1 - u) * space_normals[last_] + u * space_normals[last_ + 1]).normalized();
  } else {
    const Eigen::Vector3d left = plane.normal.cross(r.tangent);
    r.normal = material == Side::Left ? Eigen::Vector3d(-left) : left;
  }
  r.speed = g.speed;
  return r;
}

double ScanPath::nominal_time() const {
  double t = 0;
  for (const auto& s : segments) t += s.length / s.speed;
  return t;
}

// A space curve's path: each point moved along its surface normal, straight between them.
ScanPath space_path(const Section& s, const PathOptions& o) {
  const double d = o.tip_radius - o.pushing;
  const Eigen::Index n = s.polyline.cols();
  ScanPath path;
  path.section = s.name;
  path.closed = s.closed;
  path.offset = d;
  std::vector<Eigen::Vector3d> p(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d nn = s.normals.col(i).normalized();
    p[static_cast<std::size_t>(i)] = s.polyline.col(i) + d * nn;
    path.space_normals.push_back(nn);
  }
  // Curvature at a vertex: the turning angle over the mean of the two segment lengths.
  auto turn = [&](std::size_t i) {
    if (i == 0 || i + 1 >= p.size()) {
      if (!s.closed || p.size() < 3) return 0.0;
      // A closed curve turns at its start (= end) point too.
      const Eigen::Vector3d a = p[0] - p[p.size() - 2], b = p[1] - p[0];
      return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) /
             (0.5 * (a.norm() + b.norm()));
    }
    const Eigen::Vector3d a = p[i] - p[i - 1], b = p[i + 1] - p[i];
    return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) /
           (0.5 * (a.norm() + b.norm()));
  };
  for (std::size_t i = 0; i + 1 < p.size(); ++i) {
    PccSegment g;
    g.coeff.setZero();
    g.coeff.col(0) = p[i];
    g.coeff.col(1) = p[i + 1] - p[i];
    g.length = (p[i + 1] - p[i]).norm();
    if (!(g.length > 0))
      throw Error(
          fmt::format("section '{}': two points of the path coincide after the offset "
                      "along the normals (point {})",
                      s.name, i + 1));
    g.curvature = std::max(turn(i), turn(i + 1));
    g.speed = g.curvature > 0 ? std::sqrt(o.max_normal_acceleration / g.curvature) : o.max_speed;
    g.speed = std::clamp(g.speed, o.min_speed, o.max_speed);
    path.segments.push_back(g);
  }
  return path;
}

ScanPath make_path(const Section& s0, const PathOptions& o) {
  o.validate();
  if (auto p = check(s0))
    throw Error(fmt::format("section '{}': {}: {}", s0.name, p->field, p->what));
  if (s0.space_curve()) return space_path(s0, o);
  Section s = s0;
  s.plane.normal.normalize();
  if (!s.nurbs) s.polyline = drop_collinear(s.polyline, std::min(1e-4, 0.1 * o.chordal_tolerance));
  ScanPath path;
  const std::string why = detail::occt_api().plane_path(s, o, path);
  if (!why.empty()) throw Error(why);
  return path;
}

}  // namespace trueaxis::design
