#include "trueaxis/geometry/straightness.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <optional>
#include <vector>

#include "profile_min_zone.hpp"
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
// (upper) chain, and, in blocks of `block` points, whole blocks b with over[b] (under[b]) set
// (null: none); the first and last points must not be skipped. Returns the hull
// counter-clockwise without repeating the first point; collinear points dropped. The work array
// is left uninitialised: a profile's hull has few vertices, so few of its pages are touched.
template <class Point, class SkipLower, class SkipUpper>
std::vector<P> hull_chains(std::size_t n, Point point, SkipLower skip_lower, SkipUpper skip_upper,
                           std::size_t block = 1, const unsigned char* over = nullptr,
                           const unsigned char* under = nullptr) {
  const auto h = std::make_unique_for_overwrite<P[]>(2 * n);
  std::size_t k = 0;
  auto add = [&](std::size_t i, std::size_t t, auto skip) {
    const P q = point(i);
    if (skip(i, q)) return;
    while (k >= t && cross(h[k - 2], h[k - 1], q) <= 0) --k;
    h[k++] = q;
  };
  for (std::size_t b0 = 0; b0 < n; b0 += block) {
    if (over && over[b0 / block]) continue;
    for (std::size_t i = b0, end = std::min(n, b0 + block); i < end; ++i) add(i, 2, skip_lower);
  }
  // The upper chain backwards from point n − 2, block by block.
  const std::size_t t = k + 1;
  for (std::size_t b0 = (n - 2) / block * block + block; b0 > 0;) {
    b0 -= block;
    if (under && under[b0 / block]) continue;
    for (std::size_t i = std::min(n - 1, b0 + block); i-- > b0;) add(i, t, skip_upper);
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

// The hull of a profile, or nothing when x is not strictly increasing (with check_order, checked
// on the way, NaN counting as not increasing; without, the caller vouches for the order). On noisy
// data the monotone chain's pops are unpredictable branches (~7 ns a point), so most points are
// ruled out first by a test that is cheap and predictable: the hull of the highest points of blocks
// of kBlock points is made of points of the set, so a point strictly below it lies inside the hull
// and is no vertex of the upper chain; likewise above the hull of the blocks' lowest points for the
// lower chain. What is left is a few points near each hull vertex. Points are taken about (cx, cy).
std::optional<std::vector<P>> hull_profile(const double* x, const double* y, std::size_t n,
                                           double cx, double cy, bool check_order) {
  const auto point = [&](std::size_t i) { return P{x[i] - cx, y[i] - cy}; };
  constexpr std::size_t kBlock = 64, kLanes = 8, kRows = kBlock / kLanes;
  const std::size_t nb = (n + kBlock - 1) / kBlock;
  // The order check, one vectorised pass without an early exit; the count is a double (the
  // lanes' width).
  auto not_rising = [&](std::size_t from, std::size_t to) {
    double bad = 0;
#pragma omp simd reduction(+ : bad)
    for (std::size_t i = from; i < to; ++i) bad += x[i] > x[i - 1] ? 0.0 : 1.0;
    return bad;
  };
  if (nb < 8) {
    if (check_order && not_rising(1, n) > 0) return std::nullopt;
    return hull_sorted(n, point);
  }
  // Each block's highest and lowest point, in the same pass as the order check: a whole block's
  // extremes by lanes of every kLanes-th point (vectorised), then the point of the lane that
  // attains each; the last, partial block point by point. The heights are compared before cy is
  // subtracted: rounding is monotone, so the highest y is also a highest y − cy.
  std::vector<P> top(nb), bottom(nb);
  double bad = 0;
  for (std::size_t b = 0; b < nb; ++b) {
    const std::size_t b0 = b * kBlock, m = std::min(n, b0 + kBlock) - b0;
    if (check_order) bad += not_rising(std::max<std::size_t>(b0, 1), b0 + m);
    const double* yb = y + b0;
    std::size_t hi = 0, lo = 0;
    if (m == kBlock) {
      std::array<double, kLanes> lmax, lmin;
      for (std::size_t c = 0; c < kLanes; ++c) lmax[c] = lmin[c] = yb[c];
      for (std::size_t r = 1; r < kRows; ++r)
        for (std::size_t c = 0; c < kLanes; ++c) {
          const double v = yb[r * kLanes + c];
          lmax[c] = std::max(lmax[c], v);
          lmin[c] = std::min(lmin[c], v);
        }
      const double yhi = *std::max_element(lmax.begin(), lmax.end());
      const double ylo = *std::min_element(lmin.begin(), lmin.end());
      // (A NaN never matches: the loops stop at the last candidate.)
      std::size_t ch = 0, cl = 0;
      while (ch + 1 < kLanes && !(lmax[ch] == yhi)) ++ch;
      while (cl + 1 < kLanes && !(lmin[cl] == ylo)) ++cl;
      hi = ch;
      lo = cl;
      while (hi + kLanes < kBlock && !(yb[hi] == yhi)) hi += kLanes;
      while (lo + kLanes < kBlock && !(yb[lo] == ylo)) lo += kLanes;
    } else {
      for (std::size_t i = 1; i < m; ++i) {
        hi = yb[i] > yb[hi] ? i : hi;
        lo = yb[i] < yb[lo] ? i : lo;
      }
    }
    top[b] = point(b0 + hi);
    bottom[b] = point(b0 + lo);
  }
  if (bad > 0) return std::nullopt;
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
      [&](std::size_t, const P& q) {
        if (q.x <= floor.front().x || q.x >= floor.back().x) return false;
        while (q.x > floor[jl + 1].x) ++jl;
        return cross(floor[jl], floor[jl + 1], q) > 0;  // strictly above the floor
      },
      [&](std::size_t, const P& q) {
        if (q.x <= roof.front().x || q.x >= roof.back().x) return false;
        while (q.x < roof[ju].x) --ju;
        return cross(roof[ju], roof[ju + 1], q) < 0;  // strictly below the roof
      },
      kBlock, over.data(), under.data());
}

// min_zone, with x's order checked on the way (check_order) or known to be strictly increasing.
MinZone min_zone_impl(const Eigen::VectorXd& x, const Eigen::VectorXd& y, bool check_order) {
  if (x.size() != y.size() || x.size() < 2) throw Error("min_zone: need at least two points");
  const std::size_t n = static_cast<std::size_t>(x.size());
  std::optional<std::vector<P>> profile_hull =
      hull_profile(x.data(), y.data(), n, 0.5 * (x[0] + x[x.size() - 1]), y[0], check_order);
  const bool increasing = profile_hull.has_value();
  const double cx = increasing ? 0.5 * (x[0] + x[x.size() - 1]) : x.mean();
  const double cy = increasing ? y[0] : y.mean();
  if (!increasing) {
    std::vector<P> p(n);
    for (std::size_t i = 0; i < n; ++i) {
      const auto e = static_cast<Eigen::Index>(i);
      p[i] = {x[e] - cx, y[e] - cy};
    }
    auto less = [](const P& a, const P& b) { return a.x < b.x || (a.x == b.x && a.y < b.y); };
    std::sort(p.begin(), p.end(), less);
    profile_hull = hull_sorted(n, [&](std::size_t i) { return p[i]; });
  }
  const std::vector<P>& h = *profile_hull;
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

}  // namespace

MinZone min_zone(const Eigen::VectorXd& x, const Eigen::VectorXd& y) {
  return min_zone_impl(x, y, true);
}

MinZone detail::min_zone_of_increasing(const Eigen::VectorXd& x, const Eigen::VectorXd& y) {
  return min_zone_impl(x, y, false);
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
