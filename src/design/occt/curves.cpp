// NURBS section curves through OCCT: end points, arc length, and samples at even arc spacing.
#include <GeomAdaptor_Curve.hxx>
#include <GeomConvert_CompCurveToBSplineCurve.hxx>
#include <algorithm>
#include <array>
#include <cmath>
#include <list>
#include <memory>
#include <mutex>
#include <string>

#include "occt.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::design::occt {

void ends(const Section& s, Eigen::Vector3d& first, Eigen::Vector3d& last) {
  Handle(Geom_BSplineCurve) c = curve(s);
  first = vec(c->StartPoint());
  last = vec(c->EndPoint());
}

namespace {

// The arc length of a curve as a function of its parameter, piece by piece: on each piece, the
// speed |C'(t)| at the 8 Gauss–Legendre nodes as a Legendre series of degree 7, whose integral
// is the 8-point quadrature over the whole piece and, integrated term by term, the arc to any
// parameter inside it. Pieces: the knot spans, cut to no more than 2 mm long, and halved
// until the quadrature of each half and the series' integral to the midpoint agree with the
// whole within 1e-12 mm. A parameter at a given arc is then found by Newton's method on the
// series (no curve evaluations), kept in its piece by bisection.
class ArcTable {
 public:
  ArcTable(const GeomAdaptor_Curve& a, const Geom_BSplineCurve& c) : a_(a) {
    constexpr double kPiece = 2;  // mm
    for (int i = c.FirstUKnotIndex(); i < c.LastUKnotIndex(); ++i) {
      const double ka = c.Knot(i), kb = c.Knot(i + 1);
      if (!(kb > ka)) continue;
      const double est = fit(ka, kb).length();
      const int m = std::max(1, static_cast<int>(std::ceil(est / kPiece)));
      for (int k = 0; k < m; ++k) add(ka + (kb - ka) * k / m, ka + (kb - ka) * (k + 1) / m, 0);
    }
    if (pieces_.empty()) pieces_.push_back(fit(c.FirstParameter(), c.LastParameter()));
  }
  double total() const { return pieces_.back().arc0 + pieces_.back().length(); }
  // The parameter at arc length `s` (0 ≤ s ≤ total).
  double parameter(double s) const {
    const auto after = std::upper_bound(pieces_.begin(), pieces_.end(), s,
                                        [](double v, const Piece& q) { return v < q.arc0; });
    const Piece& p = after == pieces_.begin() ? pieces_.front() : *(after - 1);
    const double rem = s - p.arc0, len = p.length();
    if (rem <= 0) return p.t0;
    if (rem >= len) return p.t1;
    double lo = -1, hi = 1, x = 2 * rem / len - 1;
    for (int it = 0; it < 60; ++it) {
      double speed = 0;
      const double f = p.arc_to(x, &speed) - rem;
      if (std::abs(f) <= 1e-14) break;
      (f > 0 ? hi : lo) = x;
      double nx = speed > 0 ? x - f / speed : 0.5 * (lo + hi);
      if (!(nx > lo && nx < hi)) nx = 0.5 * (lo + hi);
      if (nx == x || hi - lo < 1e-15) break;
      x = nx;
    }
    return p.mid() + p.half() * x;
  }

 private:
  static constexpr int kNodes = 8;
  struct Piece {
    double t0 = 0, t1 = 0, arc0 = 0;
    std::array<double, kNodes> c{};  // Legendre coefficients of the speed (mm per unit of x)
    double mid() const { return 0.5 * (t0 + t1); }
    double half() const { return 0.5 * (t1 - t0); }
    double length() const { return 2 * half() * c[0]; }
    // Arc from the piece's start to x ∈ [−1, 1] (t = mid + half·x), and its derivative in x.
    double arc_to(double x, double* dx = nullptr) const {
      // ∫₋₁ˣ P₀ = x + 1; ∫₋₁ˣ Pₖ = (Pₖ₊₁(x) − Pₖ₋₁(x)) / (2k + 1).
      std::array<double, kNodes + 1> P{};
      P[0] = 1;
      P[1] = x;
      for (int k = 1; k < kNodes; ++k) P[k + 1] = ((2 * k + 1) * x * P[k] - k * P[k - 1]) / (k + 1);
      double sum = c[0] * (x + 1), d = c[0];
      for (int k = 1; k < kNodes; ++k) {
        sum += c[k] * (P[k + 1] - P[k - 1]) / (2 * k + 1);
        d += c[k] * P[k];
      }
      if (dx) *dx = half() * d;
      return half() * sum;
    }
  };
  const GeomAdaptor_Curve& a_;
  std::vector<Piece> pieces_;

  Piece fit(double t0, double t1) const {
    static constexpr double x[kNodes] = {
        -0.9602898564975363, -0.7966664774136267, -0.5255324099163290, -0.1834346424956498,
        0.1834346424956498,  0.5255324099163290,  0.7966664774136267,  0.9602898564975363};
    static constexpr double w[kNodes] = {0.1012285362903763, 0.2223810344533745, 0.3137066458778873,
                                         0.3626837833783620, 0.3626837833783620, 0.3137066458778873,
                                         0.2223810344533745, 0.1012285362903763};
    Piece p;
    p.t0 = t0;
    p.t1 = t1;
    gp_Pnt pt;
    gp_Vec d1;
    for (int i = 0; i < kNodes; ++i) {
      a_.D1(p.mid() + p.half() * x[i], pt, d1);
      const double f = d1.Magnitude();
      // cₖ = (2k + 1)/2 Σᵢ wᵢ f(xᵢ) Pₖ(xᵢ): exact for the degree-7 interpolant.
      double P0 = 1, P1 = x[i];
      p.c[0] += 0.5 * w[i] * f;
      p.c[1] += 1.5 * w[i] * f * P1;
      for (int k = 1; k + 1 < kNodes; ++k) {
        const double P2 = ((2 * k + 1) * x[i] * P1 - k * P0) / (k + 1);
        p.c[k + 1] += 0.5 * (2 * k + 3) * w[i] * f * P2;
        P0 = P1;
        P1 = P2;
      }
    }
    return p;
  }
  void add(double t0, double t1, int depth) {
    Piece whole = fit(t0, t1);
    const double tm = 0.5 * (t0 + t1);
    const double l = fit(t0, tm).length(), r = fit(tm, t1).length();
    constexpr double kExact = 1e-12;  // mm
    if ((std::abs(l + r - whole.length()) > kExact || std::abs(whole.arc_to(0) - l) > kExact) &&
        depth < 40) {
      add(t0, tm, depth + 1);
      add(tm, t1, depth + 1);
      return;
    }
    whole.arc0 = pieces_.empty() ? 0 : pieces_.back().arc0 + pieces_.back().length();
    pieces_.push_back(whole);
  }
};

}  // namespace

double length(const Section& s) {
  Handle(Geom_BSplineCurve) c = curve(s);
  GeomAdaptor_Curve a(c);
  return ArcTable(a, *c).total();
}

Section piece(const Section& s, double from, double to) {
  Handle(Geom_BSplineCurve) c = curve(s);
  GeomAdaptor_Curve a(c);
  const ArcTable table(a, *c);
  const double total = table.total();
  auto param = [&](double arc) { return table.parameter(std::clamp(arc, 0.0, total)); };
  // A stretch that wraps round a closed curve's start by less than a micrometre either way is
  // taken without that sliver: OCCT cannot cut a B-spline to a span of no length (it threw
  // "NCollection_Array1::Create" for the DaimlerChrysler part cut at x = 0).
  constexpr double kSliver = 1e-6;  // mm
  if (to > total && to - total < kSliver) to = total;
  if (to > total && from > total - kSliver) {
    from -= total;
    to -= total;
  }
  if (!(to - from >= kSliver))
    throw Error("a piece of the curve from " + std::to_string(from) + " to " + std::to_string(to) +
                " mm along it has no length");
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

// Points and first derivatives are evaluated through GeomAdaptor_Curve, which keeps the
// polynomial of the knot span last used (BSplCLib_Cache): a B-spline's Value() would locate the
// span and rebuild its basis at every call, most of the time of sampling a curve densely.
Dense dense(const Handle(Geom_BSplineCurve) & curve, double spacing, double tolerance) {
  const Geom_BSplineCurve& c = *curve;
  GeomAdaptor_Curve a(curve);
  auto at = [&](double t) { return vec(a.Value(t)); };
  Dense d;
  auto refine = [&](auto&& self, double ta, double tb, const Eigen::Vector3d& pa,
                    const Eigen::Vector3d& pb, int depth) -> void {
    const Eigen::Vector3d chord = pb - pa;
    const double len2 = chord.squaredNorm();
    double worst = 0;
    for (double f : {0.25, 0.5, 0.75}) {
      const Eigen::Vector3d q = at(ta + f * (tb - ta));
      const double t = len2 > 0 ? std::clamp((q - pa).dot(chord) / len2, 0.0, 1.0) : 0.0;
      worst = std::max(worst, (q - pa - t * chord).norm());
    }
    if ((worst > tolerance || len2 > spacing * spacing) && depth < 40) {
      const double tm = 0.5 * (ta + tb);
      const Eigen::Vector3d pm = at(tm);
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
    Eigen::Vector3d prev = at(ka);
    for (int k = 1; k <= 8; ++k) {
      const Eigen::Vector3d q = at(ka + (kb - ka) * k / 8);
      est += (q - prev).norm();
      prev = q;
    }
    const int m = std::max(1, static_cast<int>(std::ceil(est / spacing)));
    for (int k = 0; k < m; ++k) {
      const double ta = ka + (kb - ka) * k / m, tb = ka + (kb - ka) * (k + 1) / m;
      refine(refine, ta, tb, at(ta), at(tb), 0);
    }
  }
  return d;
}

// The dense polyline of a section's curve, remembered for the last few curves: a scan asks for
// the same design curve's polyline many times (touch points, corrections, the simulated part).
std::shared_ptr<const Dense> cached_dense(const Section& s, const Handle(Geom_BSplineCurve) & c,
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
  GeomAdaptor_Curve a(c);
  const auto dp = cached_dense(s, c, spacing, tolerance);
  const Dense& d = *dp;
  const std::size_t n = s.closed && d.p.size() > 1 ? d.p.size() - 1 : d.p.size();
  Samples out;
  out.points.resize(3, static_cast<Eigen::Index>(n));
  out.normals.resize(3, static_cast<Eigen::Index>(n));
  out.arc.resize(static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) {
    out.points.col(static_cast<Eigen::Index>(i)) = d.p[i];
    gp_Pnt p;
    gp_Vec d1;
    a.D1(d.t[i], p, d1);
    out.normals.col(static_cast<Eigen::Index>(i)) = away_from_material(unit, vec(d1));
    out.arc[static_cast<Eigen::Index>(i)] = d.arc[i];
  }
  return out;
}

Samples sample(const Section& s, double spacing) {
  // Even arc steps: the curve's arc length by Gauss–Legendre quadrature of |C'(t)| between
  // breakpoints (ArcTable), the parameter of each step by a safeguarded Newton iteration on it,
  // the point and its normal on the curve itself.
  Handle(Geom_BSplineCurve) c = curve(s);
  GeomAdaptor_Curve a(c);
  const ArcTable table(a, *c);
  const double total = table.total();
  const int n = std::max(2, static_cast<int>(std::ceil(total / spacing)) + 1);
  const int m = s.closed ? n - 1 : n;
  Samples out;
  out.points.resize(3, m);
  out.normals.resize(3, m);
  out.arc.resize(m);
  Section unit = s;
  unit.plane.normal.normalize();
  for (int i = 0; i < m; ++i) {
    const double target = total * i / (n - 1);
    const double t = table.parameter(target);
    gp_Pnt p;
    gp_Vec d1;
    a.D1(t, p, d1);
    out.points.col(i) = vec(p);
    out.normals.col(i) = away_from_material(unit, vec(d1));
    out.arc[i] = target;
  }
  return out;
}

}  // namespace trueaxis::design::occt
