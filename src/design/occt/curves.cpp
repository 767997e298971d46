// NURBS section curves through OCCT: end points, arc length, and samples at even arc spacing.
#include <GCPnts_AbscissaPoint.hxx>
#include <GeomAdaptor_Curve.hxx>
#include <GeomConvert_CompCurveToBSplineCurve.hxx>
#include <algorithm>
#include <cmath>
#include <list>
#include <memory>
#include <mutex>

#include "occt.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::design::occt {

void ends(const Section& s, Eigen::Vector3d& first, Eigen::Vector3d& last) {
  Handle(Geom_BSplineCurve) c = curve(s);
  first = vec(c->StartPoint());
  last = vec(c->EndPoint());
}

double length(const Section& s) {
  GeomAdaptor_Curve a(curve(s));
  return GCPnts_AbscissaPoint::Length(a);
}

Section piece(const Section& s, double from, double to) {
  Handle(Geom_BSplineCurve) c = curve(s);
  GeomAdaptor_Curve a(c);
  const double total = GCPnts_AbscissaPoint::Length(a);
  auto param = [&](double arc) {
    GCPnts_AbscissaPoint ap(a, arc, c->FirstParameter());
    if (!ap.IsDone()) throw Error("cannot find arc length " + std::to_string(arc) + " mm");
    return ap.Parameter();
  };
  Handle(Geom_BSplineCurve) out;
  if (to <= total + 1e-9) {
    out = Handle(Geom_BSplineCurve)::DownCast(c->Copy());
    out->Segment(param(from), param(std::min(to, total)));
  } else {  // across the start of a closed curve
    Handle(Geom_BSplineCurve) tail = Handle(Geom_BSplineCurve)::DownCast(c->Copy());
    tail->Segment(param(from), c->LastParameter());
    Handle(Geom_BSplineCurve) head = Handle(Geom_BSplineCurve)::DownCast(c->Copy());
    head->Segment(c->FirstParameter(), param(to - total));
    GeomConvert_CompCurveToBSplineCurve joined(tail);
    if (!joined.Add(head, 1e-6, Standard_True))
      throw Error("the stretch across the curve's start does not join");
    out = joined.BSplineCurve();
  }
  Section p = s;
  p.closed = false;
  p.nurbs = nurbs(*out);
  return p;
}

namespace {

// The curve as a polyline: every knot a point; between knots, even parameter steps no longer
// than `spacing`, each chord split until its quarter points lie within `tolerance` of the curve.
struct Dense {
  std::vector<double> t;
  std::vector<Eigen::Vector3d> p;
  std::vector<double> arc;  // along the polyline
};

Dense dense(const Geom_BSplineCurve& c, double spacing, double tolerance) {
  Dense d;
  auto refine = [&](auto&& self, double ta, double tb, const Eigen::Vector3d& pa,
                    const Eigen::Vector3d& pb, int depth) -> void {
    const Eigen::Vector3d chord = pb - pa;
    const double len2 = chord.squaredNorm();
    double worst = 0;
    for (double f : {0.25, 0.5, 0.75}) {
      const Eigen::Vector3d q = vec(c.Value(ta + f * (tb - ta)));
      const double t = len2 > 0 ? std::clamp((q - pa).dot(chord) / len2, 0.0, 1.0) : 0.0;
      worst = std::max(worst, (q - pa - t * chord).norm());
    }
    if ((worst > tolerance || len2 > spacing * spacing) && depth < 40) {
      const double tm = 0.5 * (ta + tb);
      const Eigen::Vector3d pm = vec(c.Value(tm));
      self(self, ta, tm, pa, pm, depth + 1);
      self(self, tm, tb, pm, pb, depth + 1);
      return;
    }
    d.arc.push_back(d.arc.back() + std::sqrt(len2));
    d.t.push_back(tb);
    d.p.push_back(pb);
  };
  d.t.push_back(c.FirstParameter());
  d.p.push_back(vec(c.StartPoint()));
  d.arc.push_back(0);
  for (int i = c.FirstUKnotIndex(); i < c.LastUKnotIndex(); ++i) {
    const double ka = c.Knot(i), kb = c.Knot(i + 1);
    if (!(kb > ka)) continue;
    double est = 0;
    Eigen::Vector3d prev = vec(c.Value(ka));
    for (int k = 1; k <= 8; ++k) {
      const Eigen::Vector3d q = vec(c.Value(ka + (kb - ka) * k / 8));
      est += (q - prev).norm();
      prev = q;
    }
    const int m = std::max(1, static_cast<int>(std::ceil(est / spacing)));
    for (int k = 0; k < m; ++k) {
      const double ta = ka + (kb - ka) * k / m, tb = ka + (kb - ka) * (k + 1) / m;
      refine(refine, ta, tb, vec(c.Value(ta)), vec(c.Value(tb)), 0);
    }
  }
  return d;
}

// The dense polyline of a section's curve, remembered for the last few curves: a scan samples
// the same design curve many times (touch points, corrections, paths, the simulated part), and
// building the polyline to 1e-7 mm was most of a scan's computing time.
std::shared_ptr<const Dense> cached_dense(const Section& s, const Geom_BSplineCurve& c,
                                          double spacing, double tolerance) {
  std::vector<double> key;
  const Nurbs& nu = *s.nurbs;
  key.reserve(
      static_cast<std::size_t>(4 + nu.knots.size() + nu.weights.size() + nu.control_points.size()));
  key.insert(key.end(), {static_cast<double>(nu.degree), spacing, tolerance});
  key.insert(key.end(), nu.knots.data(), nu.knots.data() + nu.knots.size());
  key.insert(key.end(), nu.weights.data(), nu.weights.data() + nu.weights.size());
  key.insert(key.end(), nu.control_points.data(),
             nu.control_points.data() + nu.control_points.size());
  static std::mutex mutex;
  static std::list<std::pair<std::vector<double>, std::shared_ptr<const Dense>>> recent;
  {
    std::lock_guard<std::mutex> lock(mutex);
    for (auto it = recent.begin(); it != recent.end(); ++it)
      if (it->first == key) {
        recent.splice(recent.begin(), recent, it);
        return recent.front().second;
      }
  }
  auto d = std::make_shared<const Dense>(dense(c, spacing, tolerance));
  std::lock_guard<std::mutex> lock(mutex);
  recent.emplace_front(std::move(key), d);
  constexpr std::size_t kRemembered = 32;
  if (recent.size() > kRemembered) recent.pop_back();
  return d;
}

}  // namespace

Samples sample_fine(const Section& s, double spacing, double tolerance) {
  Handle(Geom_BSplineCurve) c = curve(s);
  Section unit = s;
  unit.plane.normal.normalize();
  const auto dp = cached_dense(s, *c, spacing, tolerance);
  const Dense& d = *dp;
  const std::size_t n = s.closed && d.p.size() > 1 ? d.p.size() - 1 : d.p.size();
  Samples out;
  out.points.resize(3, static_cast<Eigen::Index>(n));
  out.normals.resize(3, static_cast<Eigen::Index>(n));
  out.arc.resize(static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) {
    out.points.col(static_cast<Eigen::Index>(i)) = d.p[i];
    out.normals.col(static_cast<Eigen::Index>(i)) = away_from_material(unit, *c, d.t[i]);
    out.arc[static_cast<Eigen::Index>(i)] = d.arc[i];
  }
  return out;
}

Samples sample(const Section& s, double spacing) {
  // Even arc steps, found on a polyline whose chords are within 1e-7 mm of the curve (their
  // lengths then within 1e-12 of the arcs): the parameter between its points by linear
  // interpolation, the point and its normal on the curve itself.
  Handle(Geom_BSplineCurve) c = curve(s);
  const auto dp = cached_dense(s, *c, std::min(spacing, 1.0), 1e-7);
  const Dense& d = *dp;
  const double total = d.arc.back();
  const int n = std::max(2, static_cast<int>(std::ceil(total / spacing)) + 1);
  const int m = s.closed ? n - 1 : n;
  Samples out;
  out.points.resize(3, m);
  out.normals.resize(3, m);
  out.arc.resize(m);
  Section unit = s;
  unit.plane.normal.normalize();
  std::size_t j = 0;
  for (int i = 0; i < m; ++i) {
    const double target = total * i / (n - 1);
    while (j + 2 < d.arc.size() && d.arc[j + 1] < target) ++j;
    const double span = d.arc[j + 1] - d.arc[j];
    const double f = span > 0 ? std::clamp((target - d.arc[j]) / span, 0.0, 1.0) : 0.0;
    const double t = d.t[j] + f * (d.t[j + 1] - d.t[j]);
    out.points.col(i) = vec(c->Value(t));
    out.normals.col(i) = away_from_material(unit, *c, t);
    out.arc[i] = target;
  }
  return out;
}

}  // namespace trueaxis::design::occt
