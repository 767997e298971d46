// The stylus-centre path of a plane section: the section curve offset away from the material
// (OCCT's planar wire offset, which rounds convex corners with arcs and trims concave ones), then
// approximated by cubic Hermite segments within a chordal tolerance.
#include <fmt/format.h>

#include <BRepAdaptor_Curve.hxx>
#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepOffsetAPI_MakeOffset.hxx>
#include <BRepTools_WireExplorer.hxx>
#include <BRep_Tool.hxx>
#include <GeomAPI_ProjectPointOnCurve.hxx>
#include <Geom_OffsetCurve.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <algorithm>
#include <cmath>
#include <gp_Pln.hxx>
#include <optional>

#include "occt.hpp"
#include "trueaxis/design/design.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::design::occt {
namespace {

// A piece of the offset curve, walked from parameter `a` to `b` (b < a walks backwards).
struct Span {
  TopoDS_Edge edge;
  double a = 0, b = 0;
};

struct Eval {
  Eigen::Vector3d p, d1, d2;
};

Eval eval(const BRepAdaptor_Curve& c, double t) {
  gp_Pnt p;
  gp_Vec v1, v2;
  c.D2(t, p, v1, v2);
  return {vec(p), vec(v1), vec(v2)};
}

// Cubic Hermite segment from the curve between parameters ta and tb.
Eigen::Matrix<double, 3, 4> hermite(const BRepAdaptor_Curve& c, double ta, double tb) {
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
double deviation(const BRepAdaptor_Curve& c, double ta, double tb,
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
void fit(const BRepAdaptor_Curve& c, double ta, double tb, int depth, const PathOptions& o,
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

std::vector<Span> spans_of(const TopoDS_Wire& w) {
  std::vector<Span> out;
  for (BRepTools_WireExplorer ex(w); ex.More(); ex.Next()) {
    const TopoDS_Edge& e = ex.Current();
    BRepAdaptor_Curve c(e);
    Span s{e, c.FirstParameter(), c.LastParameter()};
    if (e.Orientation() == TopAbs_REVERSED) std::swap(s.a, s.b);
    if (c.Value(s.a).Distance(c.Value(s.b)) < 1e-9 && !BRep_Tool::IsClosed(e)) {
      // A degenerate sliver the offset may leave between two corners.
      const gp_Pnt m = c.Value(0.5 * (s.a + s.b));
      if (m.Distance(c.Value(s.a)) < 1e-9) continue;
    }
    out.push_back(s);
  }
  return out;
}

// Signed distance of the offset wire from the design curve, on the side away from the material:
// the mean over the middles of up to five edges whose nearest design point is not a corner
// (beside a corner the offset is an arc about it, and the side is ambiguous).
double side_distance(const std::vector<Span>& spans, const Section& s,
                     const Handle(Geom_BSplineCurve) & c) {
  std::vector<Eigen::Vector3d> corner_points;
  for (double u : corners(*c, s.closed)) corner_points.push_back(vec(c->Value(u)));
  double sum = 0;
  int n = 0;
  for (std::size_t i = 0; i < spans.size() && n < 5; ++i) {
    BRepAdaptor_Curve a(spans[i].edge);
    const gp_Pnt p = a.Value(0.5 * (spans[i].a + spans[i].b));
    GeomAPI_ProjectPointOnCurve pr(p, c);
    if (pr.NbPoints() == 0) continue;
    const double t = pr.LowerDistanceParameter();
    bool corner = false;
    for (const auto& k : corner_points)
      corner = corner || (k - vec(p)).norm() < pr.LowerDistance() * (1 + 1e-9) + 1e-9;
    if (corner) continue;
    sum += (vec(p) - vec(c->Value(t))).dot(away_from_material(s, *c, t));
    ++n;
  }
  return n ? sum / n : 0.0;
}

std::optional<std::vector<Span>> offset_wire(const TopoDS_Wire& w, const Plane& plane, double d,
                                             bool open) {
  auto one = [&](BRepOffsetAPI_MakeOffset& mo) -> std::optional<std::vector<Span>> {
    mo.Perform(d);
    if (!mo.IsDone()) return std::nullopt;
    std::vector<TopoDS_Wire> wires;
    for (TopExp_Explorer e(mo.Shape(), TopAbs_WIRE); e.More(); e.Next())
      wires.push_back(TopoDS::Wire(e.Current()));
    if (wires.size() != 1) return std::nullopt;
    auto spans = spans_of(wires[0]);
    if (spans.empty()) return std::nullopt;
    return spans;
  };
  try {
    BRepOffsetAPI_MakeOffset mo(w, GeomAbs_Arc, open);
    if (auto r = one(mo)) return r;
    if (open) return std::nullopt;
    // OCCT sometimes finds no inward offset of a lone closed edge from the wire alone; from a
    // planar face bounded by it, it does.
    BRepBuilderAPI_MakeFace mf(gp_Pln(pnt(plane.origin), dir(plane.normal)), w, true);
    if (!mf.IsDone()) return std::nullopt;
    BRepOffsetAPI_MakeOffset mo2(mf.Face(), GeomAbs_Arc, false);
    return one(mo2);
  } catch (const Standard_Failure&) {
    return std::nullopt;
  }
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

  std::vector<Span> spans;
  if (d > 0) {
    const TopoDS_Wire w = wire(s);
    // OCCT offsets a closed wire outwards for a positive distance. Try the side away from the
    // material first, check it, and fall back to the other sign if OCCT saw it differently.
    double first = 1;
    if (s.closed) {
      const bool ccw = signed_area(*c, s.plane.normal) > 0;
      const bool material_inside = ccw == (s.material == Side::Left);
      first = material_inside ? 1 : -1;
    }
    for (double sign : {first, -first}) {
      auto r = offset_wire(w, s.plane, sign * d, !s.closed);
      if (!r) continue;
      const double dist = side_distance(*r, s, c);
      if (std::abs(dist - d) < 1e-3 * std::max(1.0, d)) {
        spans = std::move(*r);
        break;
      }
    }
    if (spans.empty() && !s.closed && c->Continuity() >= GeomAbs_C1) {
      // An open smooth curve OCCT cannot put in a plane by itself (a straight line).
      Handle(Geom_OffsetCurve) oc =
          new Geom_OffsetCurve(c, s.material == Side::Left ? d : -d, dir(s.plane.normal));
      spans.push_back(
          {BRepBuilderAPI_MakeEdge(oc).Edge(), c->FirstParameter(), c->LastParameter()});
    }
    if (spans.empty())
      throw Error(
          fmt::format("section '{}': no scanning path at {:g} mm from the surface (tip "
                      "radius less pushing amount): the tip does not fit a concave corner, "
                      "slot or narrow part of this section",
                      s.name, d));
  } else {
    spans.push_back({BRepBuilderAPI_MakeEdge(c).Edge(), c->FirstParameter(), c->LastParameter()});
  }

  // Walk in the design curve's direction.
  {
    BRepAdaptor_Curve a(spans.front().edge);
    const double t0 = spans.front().a, t1 = spans.front().b;
    const double tm = t0 + 0.5 * (t1 - t0);
    const Eigen::Vector3d dir = vec(a.DN(tm, 1)) * (t1 > t0 ? 1 : -1);
    GeomAPI_ProjectPointOnCurve pr(a.Value(tm), c);
    gp_Pnt p;
    gp_Vec v;
    c->D1(pr.NbPoints() ? pr.LowerDistanceParameter() : c->FirstParameter(), p, v);
    if (dir.dot(vec(v)) < 0) {
      std::reverse(spans.begin(), spans.end());
      for (auto& sp : spans) std::swap(sp.a, sp.b);
    }
  }
  // A closed path starts beside the design curve's start.
  if (s.closed && d > 0) {
    const double t0 = c->FirstParameter();
    const gp_Pnt start = pnt(vec(c->Value(t0)) + d * away_from_material(s, *c, t0));
    std::size_t best = 0;
    double best_d = 1e300, best_t = spans[0].a;
    for (std::size_t i = 0; i < spans.size(); ++i) {
      double f = 0, l = 0;
      Handle(Geom_Curve) g = BRep_Tool::Curve(spans[i].edge, f, l);
      GeomAPI_ProjectPointOnCurve pr(start, g, f, l);
      if (pr.NbPoints() && pr.LowerDistance() < best_d) {
        best_d = pr.LowerDistance();
        best = i;
        best_t = pr.LowerDistanceParameter();
      }
    }
    std::vector<Span> rotated;
    const Span& k = spans[best];
    const double eps = 1e-9 * (1 + std::abs(k.b - k.a));
    if (std::abs(best_t - k.b) > eps) rotated.push_back({k.edge, best_t, k.b});
    for (std::size_t i = 1; i < spans.size(); ++i)
      rotated.push_back(spans[(best + i) % spans.size()]);
    if (std::abs(best_t - k.a) > eps) rotated.push_back({k.edge, k.a, best_t});
    spans = std::move(rotated);
  }

  for (const Span& sp : spans) {
    BRepAdaptor_Curve a(sp.edge);
    fit(a, sp.a, sp.b, 0, o, path.segments, path.chordal_error);
  }
  return path;
}

}  // namespace trueaxis::design::occt
