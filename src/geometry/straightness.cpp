#include "trueaxis/geometry/straightness.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <vector>

#include "trueaxis/error.hpp"

namespace trueaxis::geometry {

Line fit_line(const Eigen::VectorXd& x, const Eigen::VectorXd& y) {
  if (x.size() != y.size() || x.size() < 2) throw Error("fit_line: need at least two points");
  const double mx = x.mean(), my = y.mean();
  double sxx = 0, sxy = 0;
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    const double dx = x[i] - mx;
    sxx += dx * dx;
    sxy += dx * (y[i] - my);
  }
  if (!(sxx > 0)) throw Error("fit_line: all x are equal");
  const double slope = sxy / sxx;
  return {my - slope * mx, slope};
}

Eigen::VectorXd residuals(const Eigen::VectorXd& x, const Eigen::VectorXd& y, const Line& l) {
  Eigen::VectorXd r = y;
  subtract_line(x, r, l);
  return r;
}

void subtract_line(const Eigen::VectorXd& x, Eigen::VectorXd& y, const Line& l) {
  y.array() -= l.intercept + l.slope * x.array();
}

double ls_straightness(const Eigen::VectorXd& x, const Eigen::VectorXd& y) {
  const Line l = fit_line(x, y);
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    const double r = y[i] - l.intercept - l.slope * x[i];
    lo = std::min(lo, r);
    hi = std::max(hi, r);
  }
  return hi - lo;
}

namespace {

struct P {
  double x, y;
};

double cross(const P& o, const P& a, const P& b) {
  return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

// Andrew's monotone chain on points sorted by (x, y), given as point(i) for i < n, skipping the
// points for which skip_lower(i, point(i)) (skip_upper) says they cannot be vertices of the lower
// (upper) chain; the first and last points must not be skipped. Returns the hull
// counter-clockwise without repeating the first point; collinear points dropped. The work array
// is left uninitialised: a profile's hull has few vertices, so few of its pages are touched.
template <class Point, class SkipLower, class SkipUpper>
std::vector<P> hull_chains(std::size_t n, Point point, SkipLower skip_lower, SkipUpper skip_upper) {
  const auto h = std::make_unique_for_overwrite<P[]>(2 * n);
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const P q = point(i);
    if (skip_lower(i, q)) continue;
    while (k >= 2 && cross(h[k - 2], h[k - 1], q) <= 0) --k;
    h[k++] = q;
  }
  for (std::size_t i = n - 1, t = k + 1; i-- > 0;) {
    const P q = point(i);
    if (skip_upper(i, q)) continue;
    while (k >= t && cross(h[k - 2], h[k - 1], q) <= 0) --k;
    h[k++] = q;
  }
  return std::vector<P>(h.get(), h.get() + (k - 1));
}

// The hull of points sorted by (x, y), given as point(i) for i < n.
template <class Point>
std::vector<P> hull_sorted(std::size_t n, Point point) {
  if (n < 3) {
    std::vector<P> h;
    for (std::size_t i = 0; i < n; ++i) h.push_back(point(i));
    return h;
  }
  const auto skip_none = [](std::size_t, const P&) { return false; };
  return hull_chains(n, point, skip_none, skip_none);
}

// One chain of points sorted by x, as a polyline in increasing x: the lower (upper) hull.
std::vector<P> chain(const std::vector<P>& v, bool upper) {
  std::vector<P> h;
  for (const P& q : v) {
    while (h.size() >= 2 && (upper ? -1 : 1) * cross(h[h.size() - 2], h.back(), q) <= 0)
      h.pop_back();
    h.push_back(q);
  }
  return h;
}

// The hull of a profile (x strictly increasing), point(i) for i < n. On noisy data the monotone
// chain's pops are unpredictable branches (~7 ns a point), so most points are ruled out first by
// a test that is cheap and predictable: the hull of the highest points of blocks of kBlock
// points is made of points of the set, so a point strictly below it lies inside the hull and is
// no vertex of the upper chain; likewise above the hull of the blocks' lowest points for the
// lower chain. What is left is a few points near each hull vertex.
template <class Point>
std::vector<P> hull_profile(std::size_t n, Point point) {
  constexpr std::size_t kBlock = 64;
  const std::size_t nb = (n + kBlock - 1) / kBlock;
  if (nb < 8) return hull_sorted(n, point);
  std::vector<P> top(nb), bottom(nb);
  for (std::size_t b = 0; b < nb; ++b) {
    const std::size_t end = std::min(n, (b + 1) * kBlock);
    std::size_t hi = b * kBlock, lo = hi;
    double yhi = point(hi).y, ylo = yhi;
    for (std::size_t i = b * kBlock + 1; i < end; ++i) {
      const double y = point(i).y;
      hi = y > yhi ? i : hi;
      yhi = y > yhi ? y : yhi;
      lo = y < ylo ? i : lo;
      ylo = y < ylo ? y : ylo;
    }
    top[b] = point(hi);
    bottom[b] = point(lo);
  }
  const std::vector<P> roof = chain(top, true), floor = chain(bottom, false);
  // Whole blocks first: the roof is concave, so over a block's x range it is lowest at one of
  // the ends; a block whose highest point lies below both (by more than the interpolation's
  // rounding) lies below the roof, and likewise above the convex floor.
  std::vector<unsigned char> under(nb, 0), over(nb, 0);
  auto height = [](const std::vector<P>& c, std::size_t& j, double x) {
    while (x > c[j + 1].x) ++j;
    return c[j].y + (c[j + 1].y - c[j].y) * ((x - c[j].x) / (c[j + 1].x - c[j].x));
  };
  constexpr double kRounding = 16 * std::numeric_limits<double>::epsilon();
  std::size_t ja = 0, jb = 0;
  for (std::size_t b = 0; b < nb; ++b) {
    const double xa = point(b * kBlock).x, xb = point(std::min(n, (b + 1) * kBlock) - 1).x;
    if (xa > roof.front().x && xb < roof.back().x) {
      const double ha = height(roof, ja, xa);
      std::size_t j = ja;
      const double hb = height(roof, j, xb);
      const double margin = kRounding * (std::abs(ha) + std::abs(hb) + std::abs(top[b].y));
      under[b] = top[b].y < std::min(ha, hb) - margin;
    }
    if (xa > floor.front().x && xb < floor.back().x) {
      const double ha = height(floor, jb, xa);
      std::size_t j = jb;
      const double hb = height(floor, j, xb);
      const double margin = kRounding * (std::abs(ha) + std::abs(hb) + std::abs(bottom[b].y));
      over[b] = bottom[b].y > std::max(ha, hb) + margin;
    }
  }
  // Segment pointers: the lower chain visits x increasing, the upper one decreasing.
  std::size_t jl = 0, ju = roof.size() - 2;
  return hull_chains(
      n, point,
      [&](std::size_t i, const P& q) {
        if (over[i / kBlock]) return true;
        if (q.x <= floor.front().x || q.x >= floor.back().x) return false;
        while (q.x > floor[jl + 1].x) ++jl;
        return cross(floor[jl], floor[jl + 1], q) > 0;  // strictly above the floor
      },
      [&](std::size_t i, const P& q) {
        if (under[i / kBlock]) return true;
        if (q.x <= roof.front().x || q.x >= roof.back().x) return false;
        while (q.x < roof[ju].x) --ju;
        return cross(roof[ju], roof[ju + 1], q) < 0;  // strictly below the roof
      });
}

}  // namespace

MinZone min_zone(const Eigen::VectorXd& x, const Eigen::VectorXd& y) {
  if (x.size() != y.size() || x.size() < 2) throw Error("min_zone: need at least two points");
  const std::size_t n = static_cast<std::size_t>(x.size());
  auto less = [](const P& a, const P& b) { return a.x < b.x || (a.x == b.x && a.y < b.y); };
  std::vector<P> p;  // a sorted copy, only when x is not strictly increasing (a profile is)
  // One vectorised pass (NaN compares false: not increasing).
  const bool increasing = ((x.tail(x.size() - 1) - x.head(x.size() - 1)).array() > 0).all();
  // Work about a point within the data (widths are tiny compared with lengths): a profile's
  // mid-range and first height, which costs no pass; otherwise the centroid.
  const double cx = increasing ? 0.5 * (x[0] + x[x.size() - 1]) : x.mean();
  const double cy = increasing ? y[0] : y.mean();
  if (!increasing) {
    p.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const auto e = static_cast<Eigen::Index>(i);
      p[i] = {x[e] - cx, y[e] - cy};
    }
    std::sort(p.begin(), p.end(), less);
  }
  const std::vector<P> h = increasing ? hull_profile(n,
                                                     [&](std::size_t i) {
                                                       const auto e = static_cast<Eigen::Index>(i);
                                                       return P{x[e] - cx, y[e] - cy};
                                                     })
                                      : hull_sorted(n, [&](std::size_t i) { return p[i]; });
  const std::size_t m = h.size();
  if (m < 3) {
    // All points collinear: zero width along the line through them.
    const P a = h.front(), b = h.back();
    const double slope = b.x != a.x ? (b.y - a.y) / (b.x - a.x) : 0.0;
    return {0.0, {cy + a.y - slope * (a.x) - slope * cx, slope}};
  }
  // Rotating calipers: for each hull edge, the farthest vertex (antipodal pointer advances
  // monotonically). The minimum width is attained with one side flush with a hull edge.
  double best = std::numeric_limits<double>::infinity();
  std::size_t best_i = 0, best_j = 0;
  std::size_t j = 1;
  for (std::size_t i = 0; i < m; ++i) {
    const P& a = h[i];
    const P& b = h[(i + 1) % m];
    while (std::abs(cross(a, b, h[(j + 1) % m])) > std::abs(cross(a, b, h[j]))) j = (j + 1) % m;
    const double len = std::hypot(b.x - a.x, b.y - a.y);
    const double w = std::abs(cross(a, b, h[j])) / len;
    if (w < best) {
      best = w;
      best_i = i;
      best_j = j;
    }
  }
  const P& a = h[best_i];
  const P& b = h[(best_i + 1) % m];
  const P& c = h[best_j];
  // Middle line: parallel to edge ab, halfway to c. Profiles never have vertical edges as the
  // minimum-width direction unless degenerate; guard anyway.
  double slope = 0, icpt = 0;
  if (b.x != a.x) {
    slope = (b.y - a.y) / (b.x - a.x);
    const double ia = a.y - slope * a.x, ic = c.y - slope * c.x;
    icpt = 0.5 * (ia + ic);
  }
  return {best, {icpt + cy - slope * cx, slope}};
}

Eigen::VectorXd gaussian_filter(const Eigen::VectorXd& y, double dx, double cutoff) {
  if (!(dx > 0) || !(cutoff > 0)) throw Error("gaussian_filter: dx and cutoff must be positive");
  const double alpha = std::sqrt(std::log(2.0) / M_PI);
  const double ac = alpha * cutoff;
  const Eigen::Index half = static_cast<Eigen::Index>(std::ceil(cutoff / dx));
  Eigen::VectorXd k(2 * half + 1);
  for (Eigen::Index i = -half; i <= half; ++i) {
    const double u = static_cast<double>(i) * dx / ac;
    k[i + half] = std::exp(-M_PI * u * u);
  }
  const Eigen::Index n = y.size();
  Eigen::VectorXd out(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index lo = std::max<Eigen::Index>(0, i - half);
    const Eigen::Index hi = std::min<Eigen::Index>(n - 1, i + half);
    const auto kk = k.segment(lo - i + half, hi - lo + 1);
    out[i] = kk.dot(y.segment(lo, hi - lo + 1)) / kk.sum();
  }
  return out;
}

}  // namespace trueaxis::geometry
