// The stylus-centre path of a plane section: the section curve offset away from the material
// (offset.cpp: convex corners rounded with arcs, concave ones trimmed), then approximated by
// cubic Hermite segments within a chordal tolerance.
#include <fmt/format.h>

#include <GeomAdaptor_Curve.hxx>
#include <Geom_Circle.hxx>
#include <Geom_TrimmedCurve.hxx>
#include <algorithm>
#include <cmath>

#include "occt.hpp"
#include "trueaxis/design/design.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::design::occt {
namespace {

struct Eval {
  Eigen::Vector3d p, d1, d2;
};

Eval eval(const GeomAdaptor_Curve& c, double t) {
  gp_Pnt p;
  gp_Vec v1, v2;
  c.D2(t, p, v1, v2);
  return {vec(p), vec(v1), vec(v2)};
}

// Cubic Hermite segment from the curve between parameters ta and tb.
Eigen::Matrix<double, 3, 4> hermite(const GeomAdaptor_Curve& c, double ta, double tb) {
  const Eval e0 = eval(c, ta), e1 = eval(c, tb);
  const Eigen::Vector3d m0 = e0.d1 * (tb - ta), m1 = e1.d1 * (tb - ta);
  Eigen::Matrix<double, 3, 4> k;
  k.col(0) = e0.p;
  k.col(1) = m0;
  k.col(2) = 3 * (e1.p - e0.p) - 2 * m0 - m1;
  k.col(3) = 2 * (e0.p - e1.p) + m0 + m1;
  return k;
}

Eigen::Vector3d at(const Eigen::Matrix<double, 3, 4>& k, double u) {
  return k.col(0) + u * (k.col(1) + u * (k.col(2) + u * k.col(3)));
}

// Distance between the segment and the curve at `m` interior parameters (parametric
// correspondence: an upper bound on the distance between the two curves).
double deviation(const GeomAdaptor_Curve& c, double ta, double tb,
                 const Eigen::Matrix<double, 3, 4>& k, int m) {
  double worst = 0;
  for (int i = 1; i < m; ++i) {
    const double u = static_cast<double>(i) / m;
    worst = std::max(worst, (at(k, u) - vec(c.Value(ta + u * (tb - ta)))).norm());
  }
  return worst;
}

double curvature(const Eval& e) {
  const double s = e.d1.norm();
  return s > 0 ? e.d1.cross(e.d2).norm() / (s * s * s) : 0.0;
}

// Halves [ta, tb] until the Hermite segment is within the tolerance at 8 points; appends the
// segments and the chordal error of each, checked at 16 points.
void fit(const GeomAdaptor_Curve& c, double ta, double tb, int depth, const PathOptions& o,
         std::vector<PccSegment>& out, double& chordal_error) {
  const auto k = hermite(c, ta, tb);
  if (depth < 40 && deviation(c, ta, tb, k, 8) > o.chordal_tolerance) {
    const double tm = 0.5 * (ta + tb);
    fit(c, ta, tm, depth + 1, o, out, chordal_error);
    fit(c, tm, tb, depth + 1, o, out, chordal_error);
    return;
  }
  chordal_error = std::max(chordal_error, deviation(c, ta, tb, k, 16));
  PccSegment s;
  s.coeff = k;
  // Arc length by 5-point Gauss–Legendre on |p'(u)|.
  static const double x[5] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831,
                              0.9061798459386640};
  static const double w[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889,
                              0.4786286704993665, 0.2369268850561891};
  for (int i = 0; i < 5; ++i) s.length += 0.5 * w[i] * s.tangent(0.5 * (x[i] + 1)).norm();
  for (int i = 0; i <= 4; ++i)
    s.curvature = std::max(s.curvature, curvature(eval(c, ta + (tb - ta) * i / 4)));
  const double v =
      s.curvature > 0 ? std::sqrt(o.max_normal_acceleration / s.curvature) : o.max_speed;
  s.speed = std::clamp(v, o.min_speed, o.max_speed);
  out.push_back(s);
}

}  // namespace

ScanPath plane_path(const Section& s, const PathOptions& o) {
  const double d = o.tip_radius - o.pushing;
  Handle(Geom_BSplineCurve) c = curve(s);
  ScanPath path;
  path.section = s.name;
  path.plane = s.plane;
  path.closed = s.closed;
  path.material = s.material;
  path.offset = d;
  // The spans' segments, and for the arcs the ball rolls on round convex corners (circles of
  // radius d about a corner of the section) their radius and turn.
  struct Span {
    std::size_t first = 0, end = 0;
    double radius = 0, turn = 0;  // 0: not a corner's arc
  };
  std::vector<Span> spans;
  for (const OffsetSpan& sp : offset_curve(s, c, std::max(d, 0.0))) {
    GeomAdaptor_Curve a(sp.curve, sp.a, sp.b);
    Span k{path.segments.size(), 0};
    fit(a, sp.a, sp.b, 0, o, path.segments, path.chordal_error);
    k.end = path.segments.size();
    const auto trimmed = Handle(Geom_TrimmedCurve)::DownCast(sp.curve);
    const auto circle = trimmed.IsNull() ? Handle(Geom_Circle)()
                                         : Handle(Geom_Circle)::DownCast(trimmed->BasisCurve());
    if (!circle.IsNull()) {
      k.radius = circle->Radius();
      k.turn = std::abs(sp.b - sp.a);  // a circle's parameter is its angle
    }
    if (k.end > k.first) spans.push_back(k);
  }
  // Sharp corners of the path (where the offset is trimmed in a concave corner): the ball turns
  // there as on an arc of radius R that cuts the corner by δ = pushing / 3, R = δ / (1/cos(θ/2)
  // − 1) for a turn of θ, at no more than the speed v = √(a R) of the normal-acceleration limit.
  // The arc must also fit on the segments it joins (its tangent length R·tan(θ/2) at most half
  // of each): a concave fillet given as many short chords (a measured contour) turns 90° within
  // half a millimetre in 10° steps, each harmless alone, and is taken at the speed of its radius.
  auto& g = path.segments;
  const double delta = o.pushing / 3;
  for (std::size_t i = 0; i < g.size(); ++i) {
    if (i == 0 && !s.closed) continue;
    const PccSegment& before = g[(i + g.size() - 1) % g.size()];
    const Eigen::Vector3d t0 = before.tangent(1).normalized(), t1 = g[i].tangent(0).normalized();
    const double theta = std::acos(std::clamp(t0.dot(t1), -1.0, 1.0));
    if (!(theta > 1e-3)) continue;
    const double half = 0.5 * std::min(theta, 3.0);
    const double R = std::min(delta / (1 / std::cos(half) - 1),
                              0.5 * std::min(before.length, g[i].length) / std::tan(half));
    g[i].corner_speed =
        std::clamp(std::sqrt(o.max_normal_acceleration * R), o.min_speed, o.max_speed);
  }
  // Convex corners by the same rule: the ball rolls round the corner on an arc of radius ρ = d,
  // and the machine may take it on a wider arc of radius R ≥ ρ through the same two tangents, as
  // long as that cuts in by at most δ, (R − ρ)(1/cos(θ/2) − 1) ≤ δ, and fits on half of each
  // neighbouring span, (R − ρ)·tan(θ/2). At a sharp 90° corner of a 0.7 mm offset that is 0.94 mm
  // instead of 0.7; at the 3° corners between the chords of a fillet or a measured contour (a
  // polyline) it is about the fillet's radius, where v²/ρ alone held the path to 26 mm/s round
  // every chord's end.
  auto span_length = [&](const Span& k) {
    double L = 0;
    for (std::size_t i = k.first; i < k.end; ++i) L += g[i].length;
    return L;
  };
  for (std::size_t j = 0; j < spans.size(); ++j) {
    const Span& k = spans[j];
    const bool first = j == 0, last = j + 1 == spans.size();
    if (!(k.radius > 0 && k.turn > 1e-9) || ((first || last) && !s.closed)) continue;
    const double half = 0.5 * std::min(k.turn, 3.0);
    const double room = std::min(span_length(spans[first ? spans.size() - 1 : j - 1]),
                                 span_length(spans[last ? 0 : j + 1]));
    const double R =
        k.radius + std::min(delta / (1 / std::cos(half) - 1), 0.5 * room / std::tan(half));
    const double v = std::clamp(std::sqrt(o.max_normal_acceleration * R), o.min_speed, o.max_speed);
    for (std::size_t i = k.first; i < k.end; ++i) g[i].speed = std::max(g[i].speed, v);
  }
  return path;
}

}  // namespace trueaxis::design::occt
