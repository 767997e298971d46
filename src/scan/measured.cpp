// Measured points as design data: a whole contour overwritten, or a local deviation spliced in.
#include <algorithm>
#include <cmath>

#include "section.hpp"
#include "trueaxis/sim/cmm.hpp"

namespace trueaxis::scan::detail {
namespace {

// The points thinned to the vertices that keep every one of them within kThinning of the
// polyline (Douglas & Peucker 1973). A convex corner, where the ball rolls about the edge and
// the points stand still, keeps its vertex: a polyline of evenly spaced points would cut it, and
// the next part's path would then run into the corner.
constexpr double kThinning = 0.002;  // mm: four times a good probe's 0.5 µm noise
std::vector<Eigen::Vector3d> thinned(const std::vector<Eigen::Vector3d>& pts) {
  std::vector<char> keep(pts.size(), 0);
  if (!pts.empty()) keep.front() = keep.back() = 1;
  std::vector<std::pair<std::size_t, std::size_t>> todo;
  if (pts.size() > 2) todo.emplace_back(0, pts.size() - 1);
  while (!todo.empty()) {
    const auto [a, b] = todo.back();
    todo.pop_back();
    const Eigen::Vector3d d = pts[b] - pts[a];
    const double len2 = d.squaredNorm();
    double worst = -1;
    std::size_t at = a;
    for (std::size_t i = a + 1; i < b; ++i) {
      const Eigen::Vector3d v = pts[i] - pts[a];
      const double t = len2 > 0 ? std::clamp(v.dot(d) / len2, 0.0, 1.0) : 0.0;
      const double e = (v - t * d).norm();
      if (e > worst) worst = e, at = i;
    }
    if (worst > kThinning) {
      keep[at] = 1;
      if (at - a > 1) todo.emplace_back(a, at);
      if (b - at > 1) todo.emplace_back(at, b);
    }
  }
  std::vector<Eigen::Vector3d> kept;
  for (std::size_t i = 0; i < pts.size(); ++i)
    if (keep[i]) kept.push_back(pts[i]);
  return kept;
}

// The samples' surface points in the section's plane, repeats (within 0.1 µm) left out.
std::vector<Eigen::Vector3d> in_plane(const design::Section& s, const std::vector<Sample>& samples,
                                      std::size_t from, std::size_t to) {
  const Eigen::Vector3d n = s.plane.normal.normalized();
  std::vector<Eigen::Vector3d> pts;
  for (std::size_t i = from; i < to; ++i) {
    const Eigen::Vector3d& x = samples[i].surface;
    const Eigen::Vector3d p = x - (x - s.plane.origin).dot(n) * n;
    if (pts.empty() || (p - pts.back()).norm() >= 1e-4) pts.push_back(p);
  }
  return pts;
}

design::Section with_polyline(const design::Section& s, const std::vector<Eigen::Vector3d>& pts) {
  design::Section out = s;
  out.nurbs.reset();
  out.polyline.resize(3, static_cast<Eigen::Index>(pts.size()));
  for (std::size_t i = 0; i < pts.size(); ++i)
    out.polyline.col(static_cast<Eigen::Index>(i)) = pts[i];
  return out;
}

}  // namespace

design::Section overwrite(const design::Section& s, const std::vector<Sample>& samples) {
  auto pts = in_plane(s, samples, 0, samples.size());
  if (s.closed) {
    while (pts.size() > 2 && (pts.back() - pts.front()).norm() < 0.25) pts.pop_back();
    pts.push_back(pts.front());
  }
  return with_polyline(s, thinned(pts));
}

std::optional<Splice> splice(const design::Section& s, const std::vector<Sample>& samples,
                             double at, double rejoin) {
  if (!s.closed || s.space_curve() || samples.size() < 10) return std::nullopt;
  // The design as a polyline within 10 nm of it, every corner a vertex.
  const design::Samples d = design::sample(s, 1.0, 1e-5);
  const double L = design::length(s);
  const Eigen::Vector3d n = s.plane.normal.normalized();
  const sim::Contour contour(d.points, n, true, s.material == design::Side::Left);
  std::vector<double> dev(samples.size()), arc(samples.size());
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const auto q = contour.nearest(samples[i].surface);
    dev[i] = q.distance;
    arc[i] = q.arc;
  }
  auto ahead = [&](double from, double to) {  // arc from `from` forward to `to`, round the start
    double a = to - from;
    while (a < 0) a += L;
    while (a >= L) a -= L;
    return a;
  };
  // The sample nearest the stop, then the last one before it on the design, and the first after
  // it that stays on the design for kSettled mm.
  constexpr double kSettled = 2.0;  // mm
  std::size_t k = 0;
  for (std::size_t i = 1; i < samples.size(); ++i)
    if (std::min(ahead(arc[i], at), ahead(at, arc[i])) <
        std::min(ahead(arc[k], at), ahead(at, arc[k])))
      k = i;
  std::optional<std::size_t> first, last;
  for (std::size_t i = k + 1; i-- > 0;)
    if (std::abs(dev[i]) < rejoin) {
      first = i;
      break;
    }
  for (std::size_t i = k; i < samples.size() && !last; ++i) {
    if (std::abs(dev[i]) >= rejoin) continue;
    std::size_t j = i;
    while (j + 1 < samples.size() && std::abs(dev[j + 1]) < rejoin &&
           samples[j].arc - samples[i].arc < kSettled)
      ++j;
    if (samples[j].arc - samples[i].arc >= kSettled) last = i;
  }
  // Not back on the design within the scan (or never off it before the stop): nothing to splice.
  if (!first || !last || *last <= *first + 1 || *first == k) return std::nullopt;
  Splice out;
  out.from = arc[*first];
  out.to = arc[*last];
  const double span = ahead(out.from, out.to);
  if (!(span > 0) || span > 0.5 * L) return std::nullopt;
  // The measured stretch, then the design from where the part rejoins it round to where it left.
  auto pts = thinned(in_plane(s, samples, *first, *last + 1));
  const Eigen::Index m = d.points.cols();
  std::vector<std::pair<double, Eigen::Index>> rest;
  for (Eigen::Index i = 0; i < m; ++i) {
    const double a = ahead(out.to, d.arc[i]);
    if (a > 1e-6 && a < L - span - 1e-6) rest.emplace_back(a, i);
  }
  std::sort(rest.begin(), rest.end());
  for (const auto& [a, i] : rest) pts.push_back(d.points.col(i));
  pts.push_back(pts.front());
  out.section = with_polyline(s, pts);
  out.largest = 0;
  for (std::size_t i = *first; i <= *last; ++i)
    out.largest = std::max(out.largest, std::abs(dev[i]));
  return out;
}

}  // namespace trueaxis::scan::detail
