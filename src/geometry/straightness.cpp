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
// points for which skip_lower(i) (skip_upper(i)) says they cannot be vertices of the lower
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
  const auto keep = [](std::size_t, const P&) { return false; };
  return hull_chains(n, point, keep, keep);
}

// The hull of a profile (x strictly increasing), point(i) for i < n. On noisy data the monotone
// chain's pops are unpredictable branches (~7 ns a point), so most points are ruled out first by
// a test that is cheap and, on such data, predictable: in blocks of kBlock points, a point
// strictly below the chord between the highest points of the blocks either side of its own lies
// inside the hull, and so does one strictly above the chord between their lowest points for the
// lower chain. The first and last blocks are kept whole. A smooth profile (many points on its
// hull, and no mispredicted pops) gains nothing from the test: a sample of blocks decides.
template <class Point>
std::vector<P> hull_profile(std::size_t n, Point point) {
  constexpr std::size_t kBlock = 64, kSampleBlocks = 16;
  const std::size_t nb = (n + kBlock - 1) / kBlock;
  if (nb < 4 * kSampleBlocks) return hull_sorted(n, point);
  std::vector<P> top(nb), bottom(nb);
  auto extremes = [&](std::size_t b) {
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
  };
  auto skip_lower = [&](std::size_t b, const P& q) {
    return cross(bottom[b - 1], bottom[b + 1], q) > 0;  // above the neighbours' lowest points
  };
  auto skip_upper = [&](std::size_t b, const P& q) {
    return cross(top[b - 1], top[b + 1], q) < 0;  // below the neighbours' highest points
  };
  // The sample: every (nb / kSampleBlocks)-th inner block with its neighbours.
  std::size_t kept = 0, seen = 0;
  for (std::size_t s = 0; s < kSampleBlocks; ++s) {
    const std::size_t b = 1 + s * (nb - 2) / kSampleBlocks;
    for (std::size_t c = b - 1; c <= b + 1; ++c) extremes(c);
    for (std::size_t i = b * kBlock; i < (b + 1) * kBlock; ++i, ++seen) {
      const P q = point(i);
      kept += !skip_lower(b, q) + !skip_upper(b, q);
    }
  }
  if (2 * kept > seen) return hull_sorted(n, point);  // more than a quarter per chain survive
  for (std::size_t b = 0; b < nb; ++b) extremes(b);
  auto inner_block = [nb](std::size_t i) {
    const std::size_t b = i / kBlock;
    return b > 0 && b + 1 < nb ? b : 0;
  };
  return hull_chains(
      n, point,
      [&](std::size_t i, const P& q) {
        const std::size_t b = inner_block(i);
        return b && skip_lower(b, q);
      },
      [&](std::size_t i, const P& q) {
        const std::size_t b = inner_block(i);
        return b && skip_upper(b, q);
      });
}

}  // namespace

MinZone min_zone(const Eigen::VectorXd& x, const Eigen::VectorXd& y) {
  if (x.size() != y.size() || x.size() < 2) throw Error("min_zone: need at least two points");
  // Work about the centroid: widths are tiny compared with lengths.
  const double cx = x.mean(), cy = y.mean();
  const std::size_t n = static_cast<std::size_t>(x.size());
  auto less = [](const P& a, const P& b) { return a.x < b.x || (a.x == b.x && a.y < b.y); };
  std::vector<P> p;  // a sorted copy, only when x is not strictly increasing (a profile is)
  bool increasing = true;
  for (Eigen::Index i = 1; i < x.size() && increasing; ++i) increasing = x[i - 1] < x[i];
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
