// Bowyer–Watson Delaunay insertion, contour segments and linear interpolation over the
// triangles (see the header for the references).
#include "trueaxis/geometry/triangulation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

namespace trueaxis::geometry {
namespace {

struct Tri {
  std::array<int, 3> v;
  double cx, cy, r2;  // circumcircle
};

// The circumcircle of a, b, c; false when they are (nearly) on one line.
bool circumcircle(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                  Tri& t) {
  const double d =
      2 * (a.x() * (b.y() - c.y()) + b.x() * (c.y() - a.y()) + c.x() * (a.y() - b.y()));
  if (std::abs(d) < 1e-14) return false;
  const double a2 = a.squaredNorm(), b2 = b.squaredNorm(), c2 = c.squaredNorm();
  t.cx = (a2 * (b.y() - c.y()) + b2 * (c.y() - a.y()) + c2 * (a.y() - b.y())) / d;
  t.cy = (a2 * (c.x() - b.x()) + b2 * (a.x() - c.x()) + c2 * (b.x() - a.x())) / d;
  t.r2 = (a - Eigen::Vector2d(t.cx, t.cy)).squaredNorm();
  return true;
}

double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  return (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
}

}  // namespace

std::vector<std::array<int, 3>> delaunay(const Eigen::Matrix2Xd& points) {
  const Eigen::Index n = points.cols();
  if (n < 3) return {};
  // Work in coordinates of unit extent about the centre: the tolerances are then relative.
  const Eigen::Vector2d lo = points.rowwise().minCoeff(), hi = points.rowwise().maxCoeff();
  const Eigen::Vector2d centre = (lo + hi) / 2;
  const double extent = (hi - lo).maxCoeff();
  if (!(extent > 0) || !std::isfinite(extent)) return {};
  std::vector<Eigen::Vector2d> p(static_cast<std::size_t>(n) + 3);
  for (Eigen::Index i = 0; i < n; ++i)
    p[static_cast<std::size_t>(i)] = (points.col(i) - centre) / extent;
  // A super-triangle far around every point; its corners are n, n + 1, n + 2. Its circles
  // through two hull points bulge past the hull edge by about 1/(8·kFar) of the extent, and a
  // point closer than that to the hull would lose the sliver between: far enough that this is
  // round-off, near enough that the circle tests keep their precision (about 1e-11 of the
  // extent).
  constexpr double kFar = 1e5;
  p[static_cast<std::size_t>(n)] = {-kFar, -kFar};
  p[static_cast<std::size_t>(n) + 1] = {kFar, -kFar};
  p[static_cast<std::size_t>(n) + 2] = {0, kFar};
  const int N = static_cast<int>(n);
  std::vector<Tri> tris(1);
  tris[0].v = {N, N + 1, N + 2};
  circumcircle(p[static_cast<std::size_t>(N)], p[static_cast<std::size_t>(N) + 1],
               p[static_cast<std::size_t>(N) + 2], tris[0]);
  // Duplicates: a hash of cells of the duplicate tolerance would be faster; a map is plenty here.
  constexpr double kSame = 1e-9;
  std::map<std::pair<long long, long long>, int> seen;
  std::vector<Tri> kept;
  std::map<std::pair<int, int>, int> edges;
  for (int i = 0; i < N; ++i) {
    const Eigen::Vector2d& q = p[static_cast<std::size_t>(i)];
    const std::pair<long long, long long> key{std::llround(q.x() / kSame),
                                              std::llround(q.y() / kSame)};
    if (!seen.emplace(key, i).second) continue;
    // The triangles whose circumcircle holds q go; the hole's boundary is the edges only one of
    // them has, each joined to q.
    kept.clear();
    edges.clear();
    for (const Tri& t : tris) {
      const double d2 = (q - Eigen::Vector2d(t.cx, t.cy)).squaredNorm();
      if (d2 < t.r2 * (1 - 1e-12)) {
        for (int e = 0; e < 3; ++e) {
          const int a = t.v[static_cast<std::size_t>(e)],
                    b = t.v[static_cast<std::size_t>((e + 1) % 3)];
          ++edges[{std::min(a, b), std::max(a, b)}];
        }
      } else {
        kept.push_back(t);
      }
    }
    if (kept.size() == tris.size()) continue;  // on a circle exactly: numerically outside
    tris.swap(kept);
    for (const auto& [edge, count] : edges) {
      if (count != 1) continue;
      Tri t;
      int a = edge.first, b = edge.second;
      if (cross(p[static_cast<std::size_t>(a)], p[static_cast<std::size_t>(b)], q) < 0)
        std::swap(a, b);
      t.v = {a, b, i};
      if (circumcircle(p[static_cast<std::size_t>(a)], p[static_cast<std::size_t>(b)], q, t))
        tris.push_back(t);
    }
  }
  std::vector<std::array<int, 3>> out;
  for (const Tri& t : tris)
    if (t.v[0] < N && t.v[1] < N && t.v[2] < N) out.push_back(t.v);
  return out;
}

std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> contour_segments(
    const Eigen::Matrix2Xd& points, const Eigen::VectorXd& values,
    const std::vector<std::array<int, 3>>& triangles, double level) {
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> out;
  for (const auto& t : triangles) {
    const double v[3] = {values[t[0]], values[t[1]], values[t[2]]};
    if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) continue;
    Eigen::Vector2d ends[2];
    int found = 0;
    for (int e = 0; e < 3 && found < 2; ++e) {
      const int a = e, b = (e + 1) % 3;
      // An edge is crossed when its ends lie on either side of the level (a vertex at the level
      // counts as above, so that a crossing through it is found once).
      if ((v[a] >= level) == (v[b] >= level)) continue;
      const double s = (level - v[a]) / (v[b] - v[a]);
      ends[found++] = points.col(t[static_cast<std::size_t>(a)]) +
                      s * (points.col(t[static_cast<std::size_t>(b)]) -
                           points.col(t[static_cast<std::size_t>(a)]));
    }
    if (found == 2) out.emplace_back(ends[0], ends[1]);
  }
  return out;
}

Eigen::VectorXd interpolate_linear(const Eigen::Matrix2Xd& points, const Eigen::VectorXd& values,
                                   const std::vector<std::array<int, 3>>& triangles,
                                   const Eigen::Matrix2Xd& queries) {
  Eigen::VectorXd out =
      Eigen::VectorXd::Constant(queries.cols(), std::numeric_limits<double>::quiet_NaN());
  for (Eigen::Index k = 0; k < queries.cols(); ++k) {
    const Eigen::Vector2d q = queries.col(k);
    for (const auto& t : triangles) {
      const Eigen::Vector2d a = points.col(t[0]), b = points.col(t[1]), c = points.col(t[2]);
      const double area = cross(a, b, c);
      if (!(std::abs(area) > 0)) continue;
      const double wa = cross(q, b, c) / area, wb = cross(a, q, c) / area, wc = 1 - wa - wb;
      constexpr double kEdge = -1e-9;  // a query on an edge belongs to both triangles
      if (wa >= kEdge && wb >= kEdge && wc >= kEdge) {
        out[k] = wa * values[t[0]] + wb * values[t[1]] + wc * values[t[2]];
        break;
      }
    }
  }
  return out;
}

}  // namespace trueaxis::geometry
