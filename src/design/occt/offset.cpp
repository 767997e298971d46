// The planar offset of a section curve: the path of a ball of radius d that rolls along the curve
// on the free side without entering the material anywhere.
//
// The classic construction of tool-path offsetting (e.g. Held, "On the Computational Geometry of
// Pocket Machining", 1991): offset each smooth piece exactly (c(t) + d·n(t), Geom_OffsetCurve),
// join the pieces at convex corners with arcs of radius d about the corner, then keep only the
// points whose distance from the whole curve is at least d. What is cut away is where the offset
// runs into a concave corner, a bend tighter than d, or the far side of a slot or neck. The kept
// stretches are joined at their intersections; if two consecutive stretches do not meet, the ball
// cannot pass there, and the refusal says where.
//
// The distance test runs against the curve as a fine polyline (chords within 1e-5 mm of it) in a
// uniform grid: cheap enough to test every point at a quarter of d along the offset, and exact to
// well within the 1e-3 mm the path is fitted to; the joins are then found exactly, by Newton's
// method on the two offset curves.
#include <fmt/format.h>

#include <GCPnts_TangentialDeflection.hxx>
#include <GC_MakeArcOfCircle.hxx>
#include <GC_MakeSegment.hxx>
#include <GeomAdaptor_Curve.hxx>
#include <Geom_OffsetCurve.hxx>
#include <Geom_TrimmedCurve.hxx>
#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

#include "occt.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::design::occt {
namespace {

constexpr double kSagitta = 1e-5;      // mm: the polyline's chords from the curve
constexpr double kLongestChord = 1.0;  // mm: no chord longer (a chord checked at its quarter
                                       // points can still hide a wiggle between them)
constexpr double kTolerance = 2e-5;    // mm: a point this much inside d still counts as clear
constexpr double kSameGap = 1e-9;      // mm: stretch ends this close are one point
constexpr double kBridgeGap = 1e-4;    // mm: joined by a straight bridge if Newton fails

// The section curve as a polyline in plane coordinates, with a uniform grid of its segments.
class Outline {
 public:
  Outline(const std::vector<Handle(Geom_BSplineCurve)>& pieces, const Eigen::Vector3d& origin,
          const Eigen::Vector3d& e1, const Eigen::Vector3d& e2, double cell)
      : origin_(origin), e1_(e1), e2_(e2) {
    for (const auto& piece : pieces) {
      // Tangential deflection gives a first polyline; every chord is then split until it is at
      // most kLongestChord long and its quarter points lie within kSagitta of it (the first pass
      // only estimates its deflection, and misses wiggles of approximated section curves).
      // Points come from the adaptor, which keeps the knot span's polynomial between calls.
      GeomAdaptor_Curve a(piece);
      GCPnts_TangentialDeflection td(a, 0.2, kSagitta, 2);
      const std::size_t first = pts_.size();
      auto add = [&](const Eigen::Vector3d& p3) {
        const Eigen::Vector2d p = to2(p3);
        if (pts_.size() == first || (p - pts_.back()).norm() > 1e-12) pts_.push_back(p);
      };
      std::function<void(double, double, const Eigen::Vector3d&, const Eigen::Vector3d&, int)>
          refine = [&](double ta, double tb, const Eigen::Vector3d& pa, const Eigen::Vector3d& pb,
                       int depth) {
            const Eigen::Vector3d chord = pb - pa;
            const double len2 = chord.squaredNorm();
            double worst = 0;
            for (double f : {0.25, 0.5, 0.75}) {
              const Eigen::Vector3d q = vec(a.Value(ta + f * (tb - ta)));
              const double t = len2 > 0 ? std::clamp((q - pa).dot(chord) / len2, 0.0, 1.0) : 0.0;
              worst = std::max(worst, (q - pa - t * chord).norm());
            }
            if ((worst > kSagitta || len2 > kLongestChord * kLongestChord) && depth < 30) {
              const double tm = 0.5 * (ta + tb);
              const Eigen::Vector3d pm = vec(a.Value(tm));
              refine(ta, tm, pa, pm, depth + 1);
              refine(tm, tb, pm, pb, depth + 1);
              return;
            }
            add(pb);
          };
      std::vector<double> ts;
      for (int i = 1; i <= td.NbPoints(); ++i) ts.push_back(td.Parameter(i));
      if (ts.size() < 2) ts = {piece->FirstParameter(), piece->LastParameter()};
      add(vec(a.Value(ts.front())));
      for (std::size_t i = 0; i + 1 < ts.size(); ++i)
        refine(ts[i], ts[i + 1], vec(a.Value(ts[i])), vec(a.Value(ts[i + 1])), 0);
      for (std::size_t i = first; i + 1 < pts_.size(); ++i) seg_.push_back(static_cast<int>(i));
    }
    lo_ = hi_ = pts_.front();
    for (const auto& p : pts_) {
      lo_ = lo_.cwiseMin(p);
      hi_ = hi_.cwiseMax(p);
    }
    const Eigen::Vector2d ext = hi_ - lo_;
    h_ = std::max({cell, ext.maxCoeff() / 1024, 1e-6});
    nx_ = static_cast<int>(ext.x() / h_) + 1;
    ny_ = static_cast<int>(ext.y() / h_) + 1;
    start_.assign(static_cast<std::size_t>(nx_) * ny_ + 1, 0);
    auto cells = [&](int s, auto&& fn) {
      const Eigen::Vector2d a = pts_[s], b = pts_[s + 1];
      const int x0 = cx(std::min(a.x(), b.x())), x1 = cx(std::max(a.x(), b.x()));
      const int y0 = cy(std::min(a.y(), b.y())), y1 = cy(std::max(a.y(), b.y()));
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) fn(static_cast<std::size_t>(y) * nx_ + x);
    };
    for (int s : seg_) cells(s, [&](std::size_t c) { ++start_[c + 1]; });
    for (std::size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
    items_.resize(static_cast<std::size_t>(start_.back()));
    std::vector<int> fill(start_.begin(), start_.end() - 1);
    for (int s : seg_) cells(s, [&](std::size_t c) { items_[fill[c]++] = s; });
  }

  Eigen::Vector2d to2(const Eigen::Vector3d& p) const {
    return {(p - origin_).dot(e1_), (p - origin_).dot(e2_)};
  }

  // Which side of the curve q lies on, as the segment nearest to it (within r) says: +1 the
  // side its right-hand normal points to, −1 the other; 0 when the nearest point is a segment's
  // end (a corner, where either side may be meant) or no segment lies within r.
  int side(const Eigen::Vector2d& q, double r) const {
    double best = r * r, best_t = 0;
    int best_s = -1;
    near(q, r, [&](int s, double t, double d2) {
      if (d2 < best) {
        best = d2;
        best_t = t;
        best_s = s;
      }
      return false;
    });
    if (best_s < 0 || best_t <= 1e-9 || best_t >= 1 - 1e-9) return 0;
    const Eigen::Vector2d a = pts_[best_s], d = pts_[best_s + 1] - a;
    return (q - a).dot(Eigen::Vector2d(d.y(), -d.x())) > 0 ? 1 : -1;
  }

  // True when some point of the curve lies closer than r to q.
  bool closer_than(const Eigen::Vector2d& q, double r) const {
    return near(q, r, [r2 = r * r](int, double, double d2) { return d2 < r2; });
  }

 private:
  // Calls fn(segment, t, squared distance of q from the segment's point at t, its nearest) for
  // the segments in the grid cells within r of q, until fn returns true; returns whether it did.
  template <class Fn>
  bool near(const Eigen::Vector2d& q, double r, Fn&& fn) const {
    const int x0 = cx(q.x() - r), x1 = cx(q.x() + r), y0 = cy(q.y() - r), y1 = cy(q.y() + r);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const std::size_t c = static_cast<std::size_t>(y) * nx_ + x;
        for (int k = start_[c]; k < start_[c + 1]; ++k) {
          const Eigen::Vector2d a = pts_[items_[k]], d = pts_[items_[k] + 1] - a;
          const double t = std::clamp((q - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
          if (fn(items_[k], t, (q - a - t * d).squaredNorm())) return true;
        }
      }
    return false;
  }

  int cx(double x) const { return std::clamp(static_cast<int>((x - lo_.x()) / h_), 0, nx_ - 1); }
  int cy(double y) const { return std::clamp(static_cast<int>((y - lo_.y()) / h_), 0, ny_ - 1); }
  Eigen::Vector3d origin_, e1_, e2_;
  std::vector<Eigen::Vector2d> pts_;
  std::vector<int> seg_;  // segment s runs from pts_[s] to pts_[s + 1]
  Eigen::Vector2d lo_, hi_;
  double h_ = 1;
  int nx_ = 1, ny_ = 1;
  std::vector<int> start_, items_;
};

// A piece of the offset: an exact offset of a smooth piece of the curve, or a corner's arc.
struct Link {
  Handle(Geom_Curve) curve;
  double a = 0, b = 0;
};

// A kept stretch of one link.
struct Stretch {
  std::size_t link = 0;
  double a = 0, b = 0;
  bool from_start = false, to_end = false;  // it begins (ends) where its link does
};

Eigen::Vector3d unit_tangent(const Handle(Geom_Curve) & c, double t) {
  gp_Pnt p;
  gp_Vec v;
  c->D1(t, p, v);
  const Eigen::Vector3d d = vec(v);
  return d.norm() > 0 ? Eigen::Vector3d(d.normalized()) : d;
}

// The point where links A and B cross near A(ta) and B(tb), by Newton's method in the plane;
// false if it does not converge there.
bool intersect(const Link& A, const Link& B, const Eigen::Vector3d& n, double& ta, double& tb) {
  const Eigen::Vector3d ax =
      std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d e1 = (ax - ax.dot(n) * n).normalized(), e2 = n.cross(e1);
  double t = ta, u = tb;
  for (int it = 0; it < 60; ++it) {
    gp_Pnt pa, pb;
    gp_Vec va, vb;
    A.curve->D1(t, pa, va);
    B.curve->D1(u, pb, vb);
    const Eigen::Vector3d f = vec(pa) - vec(pb);
    const Eigen::Vector2d F(f.dot(e1), f.dot(e2));
    if (F.norm() < 1e-11) {
      ta = t;
      tb = u;
      return true;
    }
    Eigen::Matrix2d J;
    J << vec(va).dot(e1), -vec(vb).dot(e1), vec(va).dot(e2), -vec(vb).dot(e2);
    if (std::abs(J.determinant()) < 1e-14 * (1 + J.squaredNorm())) return false;
    const Eigen::Vector2d step = J.fullPivLu().solve(-F);
    t = std::clamp(t + step.x(), A.a, A.b);
    u = std::clamp(u + step.y(), B.a, B.b);
  }
  return false;
}

}  // namespace

std::vector<OffsetSpan> offset_curve(const Section& s, const Handle(Geom_BSplineCurve) & c,
                                     double d) {
  const Eigen::Vector3d n = s.plane.normal.normalized();
  // The smooth pieces: the curve split at its C0 knots (multiplicity ≥ degree), where tangent
  // direction or parametric speed may jump.
  std::vector<double> cuts{c->FirstParameter()};
  for (int i = c->FirstUKnotIndex() + 1; i < c->LastUKnotIndex(); ++i)
    if (c->Multiplicity(i) >= c->Degree()) cuts.push_back(c->Knot(i));
  cuts.push_back(c->LastParameter());
  std::vector<Handle(Geom_BSplineCurve)> pieces;
  for (std::size_t i = 0; i + 1 < cuts.size(); ++i) {
    Handle(Geom_BSplineCurve) p = Handle(Geom_BSplineCurve)::DownCast(c->Copy());
    if (cuts.size() > 2) p->Segment(cuts[i], cuts[i + 1]);
    pieces.push_back(p);
  }
  if (d == 0) {
    std::vector<OffsetSpan> out;
    for (const auto& p : pieces)
      out.push_back({Handle(Geom_Curve)(p), p->FirstParameter(), p->LastParameter()});
    return out;
  }
  // Geom_OffsetCurve moves a point by d along T × V: with V the plane normal that is the right
  // of the direction of travel, away from the material when it lies on the left.
  const double signed_d = s.material == Side::Left ? d : -d;
  auto away = [&](const Eigen::Vector3d& t) {
    const Eigen::Vector3d right = t.cross(n);
    return s.material == Side::Left ? right : Eigen::Vector3d(-right);
  };
  std::vector<Link> links;
  const std::size_t m = pieces.size();
  for (std::size_t k = 0; k < m; ++k) {
    const auto& p = pieces[k];
    links.push_back(
        {new Geom_OffsetCurve(p, signed_d, dir(n)), p->FirstParameter(), p->LastParameter()});
    if (k + 1 == m && !s.closed) break;
    const auto& q = pieces[(k + 1) % m];
    const Eigen::Vector3d t1 = unit_tangent(p, p->LastParameter());
    const Eigen::Vector3d t2 = unit_tangent(q, q->FirstParameter());
    const Eigen::Vector3d corner = vec(q->StartPoint());
    const Eigen::Vector3d q1 = vec(p->EndPoint()) + d * away(t1), q2 = corner + d * away(t2);
    // A convex corner (the curve turns towards the material): the ball rolls round it.
    if ((q2 - q1).norm() > kSameGap && away(t1).dot(t2) < 0) {
      GC_MakeArcOfCircle arc(pnt(q1), gp_Vec(t1.x(), t1.y(), t1.z()), pnt(q2));
      if (arc.IsDone()) {
        Handle(Geom_TrimmedCurve) a = arc.Value();
        links.push_back({a, a->FirstParameter(), a->LastParameter()});
      }
    }
  }

  // Which points of the offset are clear of the whole curve.
  const Eigen::Vector3d ax =
      std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d e1 = (ax - ax.dot(n) * n).normalized(), e2 = n.cross(e1);
  const Outline outline(pieces, s.plane.origin, e1, e2, std::max(d, 0.05));
  const double clear = d - kTolerance - 1e-9 * d;
  auto ok = [&](const Link& l, double t) {
    return !outline.closer_than(outline.to2(vec(l.curve->Value(t))), clear);
  };
  const double step = std::clamp(d / 4, 0.005, 0.5);
  std::vector<Stretch> kept;
  for (std::size_t i = 0; i < links.size(); ++i) {
    const Link& l = links[i];
    double len = 0;
    {
      Eigen::Vector3d prev = vec(l.curve->Value(l.a));
      for (int j = 1; j <= 16; ++j) {
        const Eigen::Vector3d p = vec(l.curve->Value(l.a + (l.b - l.a) * j / 16));
        len += (p - prev).norm();
        prev = p;
      }
    }
    const int ns = std::max(8, static_cast<int>(std::ceil(len / step)));
    auto param = [&](int j) { return l.a + (l.b - l.a) * j / ns; };
    // Bisection between a clear and a blocked parameter, to the boundary.
    auto boundary = [&](double good, double bad) {
      for (int it = 0; it < 60 && std::abs(bad - good) > 1e-15 * (1 + std::abs(good)); ++it) {
        const double mid = 0.5 * (good + bad);
        (ok(l, mid) ? good : bad) = mid;
      }
      return good;
    };
    bool in = ok(l, l.a);
    double begin = l.a;
    for (int j = 1; j <= ns; ++j) {
      const double t = param(j);
      const bool now = ok(l, t);
      if (now && !in) begin = boundary(t, param(j - 1));
      if (!now && in) kept.push_back({i, begin, boundary(param(j - 1), t), begin == l.a, false});
      in = now;
    }
    if (in) kept.push_back({i, begin, l.b, begin == l.a, true});
  }
  auto where = [](const Eigen::Vector3d& p) {
    return fmt::format("({:.3f}, {:.3f}, {:.3f})", p.x(), p.y(), p.z());
  };
  // An offset that crossed a slit narrower than the tip lands in the material beyond it (both
  // flanks' offsets do), clear of the curve: a stretch whose middle lies on the material side of
  // the curve there is dropped, and the offsets on either side of the slit are bridged below.
  const int away_side = s.material == Side::Left ? 1 : -1;
  std::erase_if(kept, [&](const Stretch& k) {
    const Link& l = links[k.link];
    return outline.side(outline.to2(vec(l.curve->Value(0.5 * (k.a + k.b)))), 4 * d) == -away_side;
  });
  if (kept.empty())
    throw Error(fmt::format(
        "section '{}': no scanning path at {:g} mm from the surface (tip radius less pushing "
        "amount): the tip does not fit anywhere along this contour (it is narrower than {:g} mm "
        "everywhere)",
        s.name, d, 2 * d));

  // Join the kept stretches in order: consecutive links that were not cut meet as they are; cut
  // ones meet where the two offsets cross.
  std::vector<Stretch> joined;
  const std::size_t nk = kept.size();
  const std::size_t pairs = s.closed ? nk : nk - 1;
  std::vector<bool> bridge(nk, false);
  for (std::size_t j = 0; j < pairs; ++j) {
    Stretch& A = kept[j];
    Stretch& B = kept[(j + 1) % nk];
    const Link& la = links[A.link];
    const Link& lb = links[B.link];
    const Eigen::Vector3d pa = vec(la.curve->Value(A.b)), pb = vec(lb.curve->Value(B.a));
    const bool natural =
        A.to_end && B.from_start && (B.link == (A.link + 1) % links.size() || links.size() == 1);
    if ((pb - pa).norm() <= kSameGap && natural) continue;
    double ta = A.b, tb = B.a;
    if (intersect(la, lb, n, ta, tb) && ta >= A.a - 1e-12 && tb <= B.b + 1e-12 &&
        (vec(la.curve->Value(ta)) - pa).norm() < std::max(d, 0.05) &&
        (vec(lb.curve->Value(tb)) - pb).norm() < std::max(d, 0.05)) {
      A.b = std::max(ta, A.a);
      B.a = std::min(tb, B.b);
      continue;
    }
    // A gap narrower than the tip between two kept stretches (the mouth of a slit it does not
    // enter) is bridged straight when the bridge keeps the offset from the curve all along.
    auto bridge_clear = [&] {
      const double gap = (pb - pa).norm();
      if (gap > 2 * d) return false;
      const int k = std::max(4, static_cast<int>(std::ceil(gap / step)));
      for (int i = 1; i < k; ++i)
        if (outline.closer_than(outline.to2(pa + (pb - pa) * i / k), clear)) return false;
      return true;
    };
    if ((pb - pa).norm() < kBridgeGap || bridge_clear()) {
      bridge[j] = true;
      continue;
    }
    throw Error(fmt::format(
        "section '{}': no scanning path at {:g} mm from the surface (tip radius less pushing "
        "amount) all the way along: the path breaks off at {} and resumes at {} mm, so the tip "
        "does not fit between them (a slot, neck or concave bend narrower than {:g} mm)",
        s.name, d, where(pa), where(pb), 2 * d));
  }
  std::vector<OffsetSpan> out;
  for (std::size_t j = 0; j < nk; ++j) {
    const Stretch& k = kept[j];
    const Link& l = links[k.link];
    if (k.b - k.a > 1e-14 * (1 + std::abs(k.a))) out.push_back({l.curve, k.a, k.b});
    if (bridge[j]) {
      const Stretch& nx = kept[(j + 1) % nk];
      const gp_Pnt p0 = l.curve->Value(k.b), p1 = links[nx.link].curve->Value(nx.a);
      GC_MakeSegment seg(p0, p1);
      if (seg.IsDone()) {
        Handle(Geom_TrimmedCurve) g = seg.Value();
        out.push_back({g, g->FirstParameter(), g->LastParameter()});
      }
    }
  }
  return out;
}

}  // namespace trueaxis::design::occt
