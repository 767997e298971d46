#include "trueaxis/geometry/straightness.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <vector>

#include "trueaxis/error.hpp"

namespace trueaxis::geometry {

Line fit_line(const Eigen::VectorXd& x, const Eigen::VectorXd& y) {
  if (x.size() != y.size() || x.size() < 2) throw Error("fit_line: need at least two points");
  const double mx = x.mean(), my = y.mean();
  const Eigen::ArrayXd dx = x.array() - mx;
  const double sxx = dx.square().sum();
  if (!(sxx > 0)) throw Error("fit_line: all x are equal");
  const double slope = (dx * (y.array() - my)).sum() / sxx;
  return {my - slope * mx, slope};
}

Eigen::VectorXd residuals(const Eigen::VectorXd& x, const Eigen::VectorXd& y, const Line& l) {
  return (y.array() - l.intercept - l.slope * x.array()).matrix();
}

double ls_straightness(const Eigen::VectorXd& x, const Eigen::VectorXd& y) {
  const Eigen::VectorXd r = residuals(x, y, fit_line(x, y));
  return r.maxCoeff() - r.minCoeff();
}

namespace {

struct P {
  double x, y;
};

double cross(const P& o, const P& a, const P& b) {
  return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

// Andrew's monotone chain on points sorted by (x, y). Returns the hull counter-clockwise
// without repeating the first point; collinear points dropped.
std::vector<P> hull_sorted(const std::vector<P>& p) {
  const std::size_t n = p.size();
  if (n < 3) return p;
  std::vector<P> h(2 * n);
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (std::size_t i = n - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  h.resize(k - 1);
  return h;
}

}  // namespace

MinZone min_zone(const Eigen::VectorXd& x, const Eigen::VectorXd& y) {
  if (x.size() != y.size() || x.size() < 2) throw Error("min_zone: need at least two points");
  // Work about the centroid: widths are tiny compared with lengths.
  const double cx = x.mean(), cy = y.mean();
  std::vector<P> p(static_cast<std::size_t>(x.size()));
  for (Eigen::Index i = 0; i < x.size(); ++i)
    p[static_cast<std::size_t>(i)] = {x[i] - cx, y[i] - cy};
  auto less = [](const P& a, const P& b) { return a.x < b.x || (a.x == b.x && a.y < b.y); };
  if (!std::is_sorted(p.begin(), p.end(), less)) std::sort(p.begin(), p.end(), less);
  const std::vector<P> h = hull_sorted(p);
  const std::size_t m = h.size();
  if (m < 3) {
    // All points collinear: zero width along the line through them.
    const P a = p.front(), b = p.back();
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
