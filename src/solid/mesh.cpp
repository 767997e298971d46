// A part's boundary as a triangle mesh with a bounding-volume hierarchy: clearance of points and
// segments. The closest-point routines are those of C. Ericson, "Real-Time Collision Detection"
// (2005): point–triangle §5.1.5, segment–segment §5.1.9; a segment crossing a triangle is found
// by the Möller–Trumbore test (T. Möller, B. Trumbore, "Fast, minimum storage ray/triangle
// intersection", 1997).
#include "trueaxis/solid/mesh.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <limits>
#include <map>
#include <mutex>
#include <numeric>

#include "../design/occt_api.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/geometry/distance.hpp"

namespace trueaxis::solid {
namespace {

using V = Eigen::Vector3d;

// Closest point of triangle abc to p.
V closest_on_triangle(const V& p, const V& a, const V& b, const V& c) {
  const V ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const V bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + (d1 / (d1 - d3)) * ab;
  const V cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + (d2 / (d2 - d6)) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  const double denom = 1 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

// Does segment p–q cross triangle abc?
bool crosses(const V& p, const V& q, const V& a, const V& b, const V& c) {
  const V d = q - p, e1 = b - a, e2 = c - a;
  const V h = d.cross(e2);
  const double det = e1.dot(h);
  if (std::abs(det) < 1e-300) return false;
  const double inv = 1 / det;
  const V s = p - a;
  const double u = inv * s.dot(h);
  if (u < 0 || u > 1) return false;
  const V qv = s.cross(e1);
  const double v = inv * d.dot(qv);
  if (v < 0 || u + v > 1) return false;
  const double t = inv * e2.dot(qv);
  return t >= 0 && t <= 1;
}

double segment_triangle2(const V& p, const V& q, const V& a, const V& b, const V& c) {
  if (crosses(p, q, a, b, c)) return 0;
  double best = (closest_on_triangle(p, a, b, c) - p).squaredNorm();
  best = std::min(best, (closest_on_triangle(q, a, b, c) - q).squaredNorm());
  best = std::min(best, geometry::segment_distance2(p, q, a, b));
  best = std::min(best, geometry::segment_distance2(p, q, b, c));
  best = std::min(best, geometry::segment_distance2(p, q, c, a));
  return best;
}

double box_point2(const Eigen::AlignedBox3d& box, const V& p) {
  return box.squaredExteriorDistance(p);
}

// The squared gap between two boxes (0 where they overlap).
double box_gap2(const Eigen::AlignedBox3d& x, const Eigen::AlignedBox3d& y) {
  double bound = 0;
  for (int k = 0; k < 3; ++k) {
    const double gap = std::max({0.0, x.min()[k] - y.max()[k], y.min()[k] - x.max()[k]});
    bound += gap * gap;
  }
  return bound;
}

// A lower bound of the squared distance from the segment to the box: the larger of the box's
// distance to the segment's own box and that of a sphere round the box to the segment.
double box_segment2(const Eigen::AlignedBox3d& box, const V& a, const V& b) {
  const double bound = box_gap2(box, Eigen::AlignedBox3d(a.cwiseMin(b), a.cwiseMax(b)));
  const V c = box.center();
  const double radius = 0.5 * box.diagonal().norm();
  const V d = b - a;
  const double t = d.squaredNorm() > 0 ? std::clamp((c - a).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0;
  const double dist = std::max(0.0, (a + t * d - c).norm() - radius);
  return std::max(bound, dist * dist);
}

}  // namespace

Mesh::Mesh(Eigen::Matrix3Xd vertices, Eigen::Matrix3Xi triangles, std::vector<int> faces)
    : v_(std::move(vertices)), tri_(std::move(triangles)), face_(std::move(faces)) {
  if (!v_.allFinite()) throw Error("solid mesh: a vertex is not a finite point");
  if (tri_.size() > 0 && (tri_.minCoeff() < 0 || tri_.maxCoeff() >= v_.cols()))
    throw Error(
        fmt::format("solid mesh: a triangle refers to a vertex beyond the {} given", v_.cols()));
  if (face_.empty()) {
    face_.resize(static_cast<std::size_t>(tri_.cols()));
    std::iota(face_.begin(), face_.end(), 0);
  }
  if (face_.size() != static_cast<std::size_t>(tri_.cols()))
    throw Error("solid mesh: one face id per triangle is needed");
  if (!face_.empty() && *std::min_element(face_.begin(), face_.end()) < 0)
    throw Error("solid mesh: face ids must not be negative");
  build();
}

void Mesh::build() {
  box_.setEmpty();
  for (Eigen::Index i = 0; i < v_.cols(); ++i) box_.extend(v_.col(i));
  const int nf = face_.empty() ? 0 : *std::max_element(face_.begin(), face_.end()) + 1;
  face_box_.assign(static_cast<std::size_t>(nf), Eigen::AlignedBox3d());
  for (auto& b : face_box_) b.setEmpty();
  for (Eigen::Index t = 0; t < tri_.cols(); ++t)
    for (int k = 0; k < 3; ++k) face_box_[face_[t]].extend(v_.col(tri_(k, t)));
  nodes_.clear();
  order_.resize(static_cast<std::size_t>(tri_.cols()));
  std::iota(order_.begin(), order_.end(), 0);
  if (tri_.cols() > 0) {
    nodes_.reserve(2 * order_.size());
    build(0, static_cast<int>(order_.size()));
  }
}

int Mesh::build(int first, int count) {
  const int id = static_cast<int>(nodes_.size());
  nodes_.push_back({});
  Eigen::AlignedBox3d box, centres;
  box.setEmpty();
  centres.setEmpty();
  for (int i = first; i < first + count; ++i) {
    const int t = order_[i];
    V c = V::Zero();
    for (int k = 0; k < 3; ++k) {
      box.extend(v_.col(tri_(k, t)));
      c += v_.col(tri_(k, t));
    }
    centres.extend(c / 3);
  }
  nodes_[id].box = box;
  if (count <= 4) {
    nodes_[id].first = first;
    nodes_[id].count = count;
    return id;
  }
  int axis = 0;
  centres.diagonal().maxCoeff(&axis);
  const int half = count / 2;
  auto centre = [&](int t) {
    return v_(axis, tri_(0, t)) + v_(axis, tri_(1, t)) + v_(axis, tri_(2, t));
  };
  std::nth_element(order_.begin() + first, order_.begin() + first + half,
                   order_.begin() + first + count,
                   [&](int a, int b) { return centre(a) < centre(b); });
  const int left = build(first, half);
  const int right = build(first + half, count - half);
  nodes_[id].left = left;
  nodes_[id].right = right;
  return id;
}

Mesh Mesh::transformed(const Eigen::Affine3d& t) const {
  Eigen::Matrix3Xd v = (t.linear() * v_).colwise() + t.translation();
  return Mesh(std::move(v), tri_, face_);
}

bool Mesh::inside(const V& p) const {
  // Parity of the crossings of a ray from p (Jordan's theorem for a closed surface), in a
  // direction no CAD part is likely to have edges or faces along; a ray through an edge or a
  // vertex is cast again in another.
  static const V dirs[3] = {V(0.5772, 0.5781, 0.5768).normalized(),
                            V(-0.3117, 0.8263, 0.4691).normalized(),
                            V(0.7219, -0.2894, 0.6286).normalized()};
  if (nodes_.empty() || !box_.contains(p)) return false;
  for (const V& d : dirs) {
    const V inv = d.cwiseInverse();
    int crossings = 0;
    bool grazed = false;
    int stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0 && !grazed) {
      const Node& n = nodes_[stack[--top]];
      // Slab test of the ray against the node's box.
      const V t0 = (n.box.min() - p).cwiseProduct(inv), t1 = (n.box.max() - p).cwiseProduct(inv);
      const double enter = t0.cwiseMin(t1).maxCoeff(), leave = t0.cwiseMax(t1).minCoeff();
      if (leave < std::max(enter, 0.0)) continue;
      if (n.left >= 0) {
        if (top + 2 > 128) throw Error("solid mesh: the hierarchy is too deep");
        stack[top++] = n.left;
        stack[top++] = n.right;
        continue;
      }
      for (int i = n.first; i < n.first + n.count; ++i) {
        const int t = order_[i];
        // Möller & Trumbore (1997), with the barycentric coordinates kept off the edges.
        const V a = v_.col(tri_(0, t)), e1 = v_.col(tri_(1, t)) - a, e2 = v_.col(tri_(2, t)) - a;
        const V q = d.cross(e2);
        const double det = e1.dot(q);
        if (std::abs(det) < 1e-14 * e1.norm() * e2.norm()) continue;  // parallel to the ray
        const V s = p - a;
        const double u = s.dot(q) / det;
        const V r = s.cross(e1);
        const double v = d.dot(r) / det, w = e2.dot(r) / det;
        constexpr double kEdge = 1e-9;
        if (u < -kEdge || v < -kEdge || u + v > 1 + kEdge || w < 0) continue;
        if (u < kEdge || v < kEdge || u + v > 1 - kEdge) {
          grazed = true;
          break;
        }
        ++crossings;
      }
    }
    if (!grazed) return crossings % 2 == 1;
  }
  return false;
}

bool scans_on(const Mesh& mesh, const Eigen::Vector3d& c, const std::vector<char>& skip,
              const Eigen::Vector3d& plane_normal) {
  constexpr double h = 1e-4;  // mm: central differences of the distance
  Eigen::Vector3d g;
  for (int i = 0; i < 3; ++i) {
    Eigen::Vector3d e = Eigen::Vector3d::Zero();
    e[i] = h;
    g[i] = (mesh.distance(c + e, INFINITY, skip) - mesh.distance(c - e, INFINITY, skip)) / (2 * h);
  }
  if (!(g.norm() > 0.5)) return false;  // a ridge or a corner: no one normal
  return std::abs(g.normalized().dot(plane_normal)) < 0.5;
}

std::vector<char> Mesh::faces_crossing(const V& origin, const V& normal) const {
  std::vector<char> out(face_box_.size(), 0);
  const V n = normal.normalized();
  for (std::size_t f = 0; f < face_box_.size(); ++f) {
    double lo = INFINITY, hi = -INFINITY;
    for (int k = 0; k < 8; ++k) {
      const double h =
          (face_box_[f].corner(static_cast<Eigen::AlignedBox3d::CornerType>(k)) - origin).dot(n);
      lo = std::min(lo, h);
      hi = std::max(hi, h);
    }
    out[f] = lo <= 1e-6 && hi >= -1e-6;
  }
  return out;
}

// Best-first descent of the hierarchy for the least squared distance from something (a point,
// a segment) to the faces not skipped: box_d2(box) bounds it from below for a node, tri_d2(t,
// best2) is it for triangle t, or anything not below best2 when the triangle cannot be nearer.
// `limit` when nothing is nearer.
template <class BoxD2, class TriD2>
double Mesh::nearest(double limit, const std::vector<char>& skip, BoxD2 box_d2,
                     TriD2 tri_d2) const {
  if (nodes_.empty()) return limit;
  double best2 = limit * limit;
  int stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[stack[--top]];
    if (box_d2(n.box) >= best2) continue;
    if (n.left < 0) {
      for (int i = n.first; i < n.first + n.count; ++i) {
        const int t = order_[i];
        if (!skip.empty() && skip[face_[t]]) continue;
        best2 = std::min(best2, tri_d2(t, best2));
      }
      continue;
    }
    // The nearer child last, so that it is searched first.
    const double dl = box_d2(nodes_[n.left].box), dr = box_d2(nodes_[n.right].box);
    if (top + 2 > 128) throw Error("solid mesh: the hierarchy is too deep");
    if (dl < dr) {
      stack[top++] = n.right;
      stack[top++] = n.left;
    } else {
      stack[top++] = n.left;
      stack[top++] = n.right;
    }
  }
  return std::min(limit, std::sqrt(best2));
}

double Mesh::distance(const V& p, double limit, const std::vector<char>& skip) const {
  return nearest(
      limit, skip, [&](const Eigen::AlignedBox3d& box) { return box_point2(box, p); },
      [&](int t, double) {
        return (closest_on_triangle(p, v_.col(tri_(0, t)), v_.col(tri_(1, t)), v_.col(tri_(2, t))) -
                p)
            .squaredNorm();
      });
}

double Mesh::distance(const V& a, const V& b, double limit, const std::vector<char>& skip) const {
  // A triangle is tested in full only if its own box is nearer than the best so far (the gap
  // between the boxes bounds the distance from below).
  const Eigen::AlignedBox3d sb(a.cwiseMin(b), a.cwiseMax(b));
  auto triangle = [&](int t, double best2) {
    const V &p = v_.col(tri_(0, t)), &q = v_.col(tri_(1, t)), &r = v_.col(tri_(2, t));
    const Eigen::AlignedBox3d tb(p.cwiseMin(q).cwiseMin(r), p.cwiseMax(q).cwiseMax(r));
    if (box_gap2(tb, sb) >= best2) return best2;
    return segment_triangle2(a, b, p, q, r);
  };
  // A segment along a coordinate axis (a stylus standing vertical) is its own box: the gap
  // between the boxes is its exact distance from a node's box.
  if (((a - b).array() != 0).count() <= 1)
    return nearest(
        limit, skip, [&](const Eigen::AlignedBox3d& box) { return box_gap2(box, sb); }, triangle);
  return nearest(
      limit, skip, [&](const Eigen::AlignedBox3d& box) { return box_segment2(box, a, b); },
      triangle);
}

double Mesh::highest(const V& up) const {
  return v_.cols() ? (up.transpose() * v_).maxCoeff() : -INFINITY;
}

double Mesh::highest_near(const V& up, const V& a, const V& b, double radius) const {
  // Everything projected along `up` onto the plane through the origin normal to it; a triangle
  // counts, with its highest vertex, when its shadow comes within `radius` of the segment's.
  auto flat = [&](const V& p) { return V(p - p.dot(up) * up); };
  const V fa = flat(a), fb = flat(b);
  const double r2 = radius * radius;
  double best = -INFINITY;
  for (Eigen::Index t = 0; t < tri_.cols(); ++t) {
    const V p0 = v_.col(tri_(0, t)), p1 = v_.col(tri_(1, t)), p2 = v_.col(tri_(2, t));
    const double h = std::max({p0.dot(up), p1.dot(up), p2.dot(up)});
    if (h <= best) continue;
    const V f0 = flat(p0), f1 = flat(p1), f2 = flat(p2);
    // A wall seen from above is a line: its edges decide. Otherwise the full test.
    double d2 = std::min({geometry::segment_distance2(fa, fb, f0, f1),
                          geometry::segment_distance2(fa, fb, f1, f2),
                          geometry::segment_distance2(fa, fb, f2, f0)});
    if (d2 > r2 && (f1 - f0).cross(f2 - f0).norm() > 1e-12)
      d2 = std::min({d2, (closest_on_triangle(fa, f0, f1, f2) - fa).squaredNorm(),
                     (closest_on_triangle(fb, f0, f1, f2) - fb).squaredNorm()});
    if (d2 <= r2) best = h;
  }
  return best;
}

std::shared_ptr<const Mesh> load_step(const std::string& path, double deflection) {
  if (!(deflection >= 1e-4 && deflection <= 1))
    throw Error(fmt::format("solid mesh deflection {:g} mm: must be 1e-4 to 1 mm", deflection));
  static std::mutex mutex;
  static std::map<std::pair<std::string, double>, std::shared_ptr<const Mesh>> cache;
  std::lock_guard<std::mutex> lock(mutex);
  auto& slot = cache[{path, deflection}];
  if (slot) return slot;
  design::detail::MeshData data;
  if (const std::string why = design::detail::occt_api().step_mesh(path, deflection, data);
      !why.empty())
    throw Error(why);
  slot = std::make_shared<const Mesh>(std::move(data.vertices), std::move(data.triangles),
                                      std::move(data.faces));
  return slot;
}

}  // namespace trueaxis::solid
