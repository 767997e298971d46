// Design data: checks, lengths and samples of planar section curves (evaluated by OCCT).
#include "trueaxis/design/design.hpp"

#include <fmt/format.h>

#include <GCPnts_AbscissaPoint.hxx>
#include <GCPnts_UniformAbscissa.hxx>
#include <GeomAdaptor_Curve.hxx>
#include <cmath>
#include <vector>

#include "occt.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::design {
namespace {

constexpr double kMaxCoordinate = 1e6;  // mm: beyond any machine
constexpr int kMaxDegree = 25;          // OCCT's limit

std::optional<Problem> check_points(const Eigen::Matrix3Xd& pts, const Plane& plane,
                                    const std::string& field) {
  for (Eigen::Index i = 0; i < pts.cols(); ++i) {
    if (!pts.col(i).allFinite() || pts.col(i).cwiseAbs().maxCoeff() > kMaxCoordinate)
      return Problem{field, i,
                     fmt::format("a coordinate is not a number within ±{:g} mm", kMaxCoordinate)};
    const double off = (pts.col(i) - plane.origin).dot(plane.normal);
    if (std::abs(off) > kPlanarTolerance)
      return Problem{field, i,
                     fmt::format("the point is {:.4g} mm off the section plane (allowed {:g} mm): "
                                 "a section curve must lie in its plane",
                                 off, kPlanarTolerance)};
  }
  return std::nullopt;
}

}  // namespace

const char* to_string(Side s) {
  return s == Side::Left ? "left" : "right";
}

std::optional<Problem> check(const Section& s) {
  if (!s.plane.origin.allFinite() || s.plane.origin.cwiseAbs().maxCoeff() > kMaxCoordinate)
    return Problem{"plane/origin", -1, "the plane origin is not a point within ±1e6 mm"};
  if (!s.plane.normal.allFinite() || !(s.plane.normal.norm() > 1e-9))
    return Problem{"plane/normal", -1, "the plane normal has no direction (zero length)"};
  Plane plane = s.plane;
  plane.normal.normalize();
  if (s.nurbs && s.polyline.cols())
    return Problem{"curve", -1, "a section has one curve: either 'nurbs' or 'polyline'"};
  Eigen::Vector3d first, last;
  if (s.nurbs) {
    const Nurbs& n = *s.nurbs;
    const long np = static_cast<long>(n.control_points.cols());
    if (n.degree < 1 || n.degree > kMaxDegree)
      return Problem{"curve/nurbs/degree", -1,
                     fmt::format("degree {} is outside 1..{}", n.degree, kMaxDegree)};
    if (np < n.degree + 1)
      return Problem{"curve/nurbs/control_points", -1,
                     fmt::format("{} control points are too few for degree {} (at least {})", np,
                                 n.degree, n.degree + 1)};
    if (n.weights.size() != np)
      return Problem{"curve/nurbs/weights", -1,
                     fmt::format("{} weights for {} control points", n.weights.size(), np)};
    for (Eigen::Index i = 0; i < n.weights.size(); ++i)
      if (!std::isfinite(n.weights[i]) || !(n.weights[i] > 0) || n.weights[i] > 1e6)
        return Problem{"curve/nurbs/weights", i, "weights must be positive (and at most 1e6)"};
    if (n.knots.size() != np + n.degree + 1)
      return Problem{"curve/nurbs/knots", -1,
                     fmt::format("{} knots; a degree-{} curve with {} control points needs {} "
                                 "(control points + degree + 1)",
                                 n.knots.size(), n.degree, np, np + n.degree + 1)};
    for (Eigen::Index i = 0; i < n.knots.size(); ++i) {
      if (!std::isfinite(n.knots[i]) || std::abs(n.knots[i]) > 1e9)
        return Problem{"curve/nurbs/knots", i, "a knot is not a finite number"};
      if (i > 0 && n.knots[i] < n.knots[i - 1])
        return Problem{
            "curve/nurbs/knots", i,
            fmt::format("knots must not decrease ({:g} after {:g})", n.knots[i], n.knots[i - 1])};
    }
    // Multiplicities: at most the degree inside the curve (else it falls apart there), at most
    // degree + 1 at the ends (a clamped curve).
    for (Eigen::Index i = 0, j; i < n.knots.size(); i = j) {
      for (j = i; j < n.knots.size() && n.knots[j] == n.knots[i];) ++j;
      const bool end = i == 0 || j == n.knots.size();
      const long limit = end ? n.degree + 1 : n.degree;
      if (j - i > limit)
        return Problem{
            "curve/nurbs/knots", j - 1,
            fmt::format("knot {:g} is repeated {} times; at most {} {}", n.knots[i], j - i, limit,
                        end ? "at an end (degree + 1)" : "inside the curve (the degree)")};
    }
    if (!(n.knots[n.knots.size() - 1] > n.knots[0]))
      return Problem{"curve/nurbs/knots", -1, "all knots are equal: the curve has no extent"};
    if (auto p = check_points(n.control_points, plane, "curve/nurbs/control_points")) return p;
    try {
      Handle(Geom_BSplineCurve) c = occt::curve(s);
      first = occt::vec(c->StartPoint());
      last = occt::vec(c->EndPoint());
    } catch (const Error& e) {
      return Problem{"curve/nurbs", -1, e.what()};
    }
  } else {
    const Eigen::Matrix3Xd& p = s.polyline;
    if (p.cols() < 2)
      return Problem{"curve/polyline", -1,
                     fmt::format("{} point(s): a polyline needs at least 2", p.cols())};
    if (auto pr = check_points(p, plane, "curve/polyline")) return pr;
    for (Eigen::Index i = 1; i < p.cols(); ++i)
      if ((p.col(i) - p.col(i - 1)).norm() < 1e-9)
        return Problem{"curve/polyline", i, "the point repeats the one before it"};
    first = p.col(0);
    last = p.col(p.cols() - 1);
  }
  if (s.closed && (last - first).norm() > kClosureTolerance)
    return Problem{"closed", -1,
                   fmt::format("the curve is marked closed but ends {:.4g} mm from its start "
                               "(allowed {:g} mm): repeat the first point at the end, or set "
                               "\"closed\": false",
                               (last - first).norm(), kClosureTolerance)};
  return std::nullopt;
}

double length(const Section& s) {
  if (!s.nurbs) {
    double l = 0;
    for (Eigen::Index i = 1; i < s.polyline.cols(); ++i)
      l += (s.polyline.col(i) - s.polyline.col(i - 1)).norm();
    return l;
  }
  GeomAdaptor_Curve a(occt::curve(s));
  return GCPnts_AbscissaPoint::Length(a);
}

namespace {
// A polyline sampled directly (exact, and far faster than integrating its B-spline form): each
// segment divided evenly at no more than `spacing`, so that every vertex is a sample.
Samples sample_polyline(const Section& s, double spacing) {
  const Eigen::Matrix3Xd& p = s.polyline;
  const Eigen::Index m = p.cols();
  std::vector<int> pieces(static_cast<std::size_t>(m - 1));
  int count = 1;
  for (Eigen::Index i = 0; i + 1 < m; ++i) {
    const double len = (p.col(i + 1) - p.col(i)).norm();
    pieces[static_cast<std::size_t>(i)] =
        std::max(1, static_cast<int>(std::ceil(len / spacing - 1e-9)));
    count += pieces[static_cast<std::size_t>(i)];
  }
  if (s.closed) --count;  // the end repeats the start
  Samples out;
  out.points.resize(3, count);
  out.normals.resize(3, count);
  out.arc.resize(count);
  const Eigen::Vector3d pn = s.plane.normal.normalized();
  int k = 0;
  double arc = 0;
  for (Eigen::Index i = 0; i + 1 < m && k < count; ++i) {
    const Eigen::Vector3d d = p.col(i + 1) - p.col(i);
    const double len = d.norm();
    const Eigen::Vector3d left = pn.cross(d / len);
    const Eigen::Vector3d normal = s.material == Side::Left ? Eigen::Vector3d(-left) : left;
    const int n = pieces[static_cast<std::size_t>(i)];
    for (int j = 0; j < n && k < count; ++j, ++k) {
      out.points.col(k) = p.col(i) + d * (static_cast<double>(j) / n);
      out.normals.col(k) = normal;
      out.arc[k] = arc + len * j / n;
    }
    arc += len;
  }
  if (k < count) {  // an open polyline: its last point
    const Eigen::Vector3d d = p.col(m - 1) - p.col(m - 2);
    const Eigen::Vector3d left = pn.cross(d.normalized());
    out.points.col(k) = p.col(m - 1);
    out.normals.col(k) = s.material == Side::Left ? Eigen::Vector3d(-left) : left;
    out.arc[k] = arc;
  }
  return out;
}
}  // namespace

Samples sample(const Section& s, double spacing) {
  if (!(spacing > 0)) throw Error("the sample spacing must be positive (mm)");
  if (!s.nurbs) return sample_polyline(s, spacing);
  Handle(Geom_BSplineCurve) c = occt::curve(s);
  GeomAdaptor_Curve a(c);
  const double total = GCPnts_AbscissaPoint::Length(a);
  const int n = std::max(2, static_cast<int>(std::ceil(total / spacing)) + 1);
  GCPnts_UniformAbscissa ua(a, n);
  if (!ua.IsDone()) throw Error("cannot sample the section curve '" + s.name + "'");
  const int m = s.closed ? ua.NbPoints() - 1 : ua.NbPoints();
  Samples out;
  out.points.resize(3, m);
  out.normals.resize(3, m);
  out.arc.resize(m);
  Section unit = s;
  unit.plane.normal.normalize();
  for (int i = 0; i < m; ++i) {
    const double t = ua.Parameter(i + 1);
    out.points.col(i) = occt::vec(c->Value(t));
    out.normals.col(i) = occt::away_from_material(unit, *c, t);
    out.arc[i] = total * i / (ua.NbPoints() - 1);
  }
  return out;
}

}  // namespace trueaxis::design
