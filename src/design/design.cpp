// Design data: checks, lengths and samples of section curves (NURBS curves are evaluated by Open
// CASCADE Technology, in libtrueaxis_occt.so, loaded on first use: occt_api.hpp).
#include "trueaxis/design/design.hpp"

#include <fmt/format.h>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <utility>
#include <vector>

#include "../common/eigen_instances.hpp"
#include "occt_api.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::design {
namespace {

constexpr double kMaxCoordinate = 1e6;  // mm: beyond any machine
constexpr int kMaxDegree = 25;          // OCCT's limit

std::optional<Problem> check_points(const Eigen::Matrix3Xd& pts, const Plane& plane,
                                    const std::string& field) {
  for (Eigen::Index i = 0; i < pts.cols(); ++i) {
    if (!pts.col(i).allFinite() || pts.col(i).cwiseAbs().maxCoeff() > kMaxCoordinate)
      return Problem{field, i,
                     fmt::format("a coordinate is not a number within ±{:g} mm", kMaxCoordinate)};
    const double off = (pts.col(i) - plane.origin).dot(plane.normal);
    if (std::abs(off) > kPlanarTolerance)
      return Problem{field, i,
                     fmt::format("the point is {:.4g} mm off the section plane (allowed {:g} mm): "
                                 "a section curve must lie in its plane",
                                 off, kPlanarTolerance)};
  }
  return std::nullopt;
}

}  // namespace

const char* to_string(Side s) {
  return s == Side::Left ? "left" : "right";
}

namespace {
std::optional<Problem> check_space_curve(const Section& s) {
  if (s.nurbs) return Problem{"curve/nurbs", -1, "a space curve (with normals) is a polyline"};
  const Eigen::Matrix3Xd& p = s.polyline;
  if (p.cols() < 2)
    return Problem{"curve/polyline", -1,
                   fmt::format("{} point(s): a polyline needs at least 2", p.cols())};
  if (s.normals.cols() != p.cols())
    return Problem{"normals", -1,
                   fmt::format("{} normals for {} points: a space curve needs one surface "
                               "normal per point",
                               s.normals.cols(), p.cols())};
  for (Eigen::Index i = 0; i < p.cols(); ++i) {
    if (!p.col(i).allFinite() || p.col(i).cwiseAbs().maxCoeff() > kMaxCoordinate)
      return Problem{"curve/polyline", i,
                     fmt::format("a coordinate is not a number within ±{:g} mm", kMaxCoordinate)};
    if (i > 0 && (p.col(i) - p.col(i - 1)).norm() < 1e-9)
      return Problem{"curve/polyline", i, "the point repeats the one before it"};
    if (!s.normals.col(i).allFinite() || !(s.normals.col(i).norm() > 1e-9))
      return Problem{"normals", i, "the surface normal has no direction (zero length)"};
  }
  if (s.closed && (p.col(p.cols() - 1) - p.col(0)).norm() > kClosureTolerance)
    return Problem{"closed", -1,
                   fmt::format("the curve is marked closed but ends {:.4g} mm from its start "
                               "(allowed {:g} mm): repeat the first point at the end, or set "
                               "\"closed\": false",
                               (p.col(p.cols() - 1) - p.col(0)).norm(), kClosureTolerance)};
  return std::nullopt;
}
}  // namespace

std::optional<Problem> check(const Section& s) {
  if (s.space_curve()) return check_space_curve(s);
  if (!s.plane.origin.allFinite() || s.plane.origin.cwiseAbs().maxCoeff() > kMaxCoordinate)
    return Problem{"plane/origin", -1, "the plane origin is not a point within ±1e6 mm"};
  if (!s.plane.normal.allFinite() || !(s.plane.normal.norm() > 1e-9))
    return Problem{"plane/normal", -1, "the plane normal has no direction (zero length)"};
  if (std::string why = head_refusal(s.probe); !why.empty())
    return Problem{"probe", -1, "the probe head cannot take " + why};
  Plane plane = s.plane;
  plane.normal.normalize();
  if (s.nurbs && s.polyline.cols())
    return Problem{"curve", -1, "a section has one curve: either 'nurbs' or 'polyline'"};
  Eigen::Vector3d first, last;
  if (s.nurbs) {
    const Nurbs& n = *s.nurbs;
    const long np = static_cast<long>(n.control_points.cols());
    if (n.degree < 1 || n.degree > kMaxDegree)
      return Problem{"curve/nurbs/degree", -1,
                     fmt::format("degree {} is outside 1..{}", n.degree, kMaxDegree)};
    if (np < n.degree + 1)
      return Problem{"curve/nurbs/control_points", -1,
                     fmt::format("{} control points are too few for degree {} (at least {})", np,
                                 n.degree, n.degree + 1)};
    if (n.weights.size() != np)
      return Problem{"curve/nurbs/weights", -1,
                     fmt::format("{} weights for {} control points", n.weights.size(), np)};
    for (Eigen::Index i = 0; i < n.weights.size(); ++i)
      if (!std::isfinite(n.weights[i]) || !(n.weights[i] > 0) || n.weights[i] > 1e6)
        return Problem{"curve/nurbs/weights", i, "weights must be positive (and at most 1e6)"};
    if (n.knots.size() != np + n.degree + 1)
      return Problem{"curve/nurbs/knots", -1,
                     fmt::format("{} knots; a degree-{} curve with {} control points needs {} "
                                 "(control points + degree + 1)",
                                 n.knots.size(), n.degree, np, np + n.degree + 1)};
    for (Eigen::Index i = 0; i < n.knots.size(); ++i) {
      if (!std::isfinite(n.knots[i]) || std::abs(n.knots[i]) > 1e9)
        return Problem{"curve/nurbs/knots", i, "a knot is not a finite number"};
      if (i > 0 && n.knots[i] < n.knots[i - 1])
        return Problem{
            "curve/nurbs/knots", i,
            fmt::format("knots must not decrease ({:g} after {:g})", n.knots[i], n.knots[i - 1])};
    }
    // Multiplicities: at most the degree inside the curve (else it falls apart there), at most
    // degree + 1 at the ends (a clamped curve).
    for (Eigen::Index i = 0, j; i < n.knots.size(); i = j) {
      for (j = i; j < n.knots.size() && n.knots[j] == n.knots[i];) ++j;
      const bool end = i == 0 || j == n.knots.size();
      const long limit = end ? n.degree + 1 : n.degree;
      if (j - i > limit)
        return Problem{
            "curve/nurbs/knots", j - 1,
            fmt::format("knot {:g} is repeated {} times; at most {} {}", n.knots[i], j - i, limit,
                        end ? "at an end (degree + 1)" : "inside the curve (the degree)")};
    }
    if (!(n.knots[n.knots.size() - 1] > n.knots[0]))
      return Problem{"curve/nurbs/knots", -1, "all knots are equal: the curve has no extent"};
    if (auto p = check_points(n.control_points, plane, "curve/nurbs/control_points")) return p;
    if (std::string why = detail::occt_api().nurbs_ends(s, first, last); !why.empty())
      return Problem{"curve/nurbs", -1, std::move(why)};
  } else {
    const Eigen::Matrix3Xd& p = s.polyline;
    if (p.cols() < 2)
      return Problem{"curve/polyline", -1,
                     fmt::format("{} point(s): a polyline needs at least 2", p.cols())};
    if (auto pr = check_points(p, plane, "curve/polyline")) return pr;
    for (Eigen::Index i = 1; i < p.cols(); ++i)
      if ((p.col(i) - p.col(i - 1)).norm() < 1e-9)
        return Problem{"curve/polyline", i, "the point repeats the one before it"};
    first = p.col(0);
    last = p.col(p.cols() - 1);
  }
  if (s.closed && (last - first).norm() > kClosureTolerance)
    return Problem{"closed", -1,
                   fmt::format("the curve is marked closed but ends {:.4g} mm from its start "
                               "(allowed {:g} mm): repeat the first point at the end, or set "
                               "\"closed\": false",
                               (last - first).norm(), kClosureTolerance)};
  return std::nullopt;
}

std::optional<Section> as_plane_section(const Section& s, std::string* why) {
  if (!s.space_curve()) return s;
  const Eigen::Matrix3Xd& p = s.polyline;
  const Eigen::Vector3d c = p.rowwise().mean();
  const Eigen::Matrix3Xd q = p.colwise() - c;
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(q, Eigen::ComputeFullU);
  const Eigen::Vector3d n = svd.matrixU().col(2);  // the direction of least spread
  const double off = (n.transpose() * q).cwiseAbs().maxCoeff();
  double tilt = 0;
  for (Eigen::Index i = 0; i < p.cols(); ++i)
    tilt = std::max(
        tilt, std::abs(std::asin(std::clamp(s.normals.col(i).normalized().dot(n), -1.0, 1.0))));
  if (off > kPlanarTolerance || tilt > 1e-3) {
    if (why)
      *why = fmt::format(
          "the path is three-dimensional: its points leave their best-fit plane by up to "
          "{:.3f} mm and its surface normals tilt out of it by up to {:.1f}°",
          off, tilt * 180 / M_PI);
    return std::nullopt;
  }
  Section out = s;
  out.normals.resize(3, 0);
  out.plane = {c, n};
  // Material on the left (seen from n, along the curve) when the surface normals point to the
  // right of the direction of travel: t × n.
  double vote = 0;
  for (Eigen::Index i = 0; i + 1 < p.cols(); ++i)
    vote += (p.col(i + 1) - p.col(i)).cross(n).dot(s.normals.col(i));
  out.material = vote >= 0 ? Side::Left : Side::Right;
  // Exactly in the plane.
  for (Eigen::Index i = 0; i < p.cols(); ++i)
    out.polyline.col(i) -= (out.polyline.col(i) - c).dot(n) * n;
  return out;
}

double length(const Section& s) {
  if (!s.nurbs) {
    double l = 0;
    for (Eigen::Index i = 1; i < s.polyline.cols(); ++i)
      l += (s.polyline.col(i) - s.polyline.col(i - 1)).norm();
    return l;
  }
  double l = 0;
  if (const std::string why = detail::occt_api().nurbs_length(s, l); !why.empty()) throw Error(why);
  return l;
}

namespace {
// A polyline sampled directly (exact, and far faster than integrating its B-spline form): each
// segment divided evenly at no more than `spacing`, so that every vertex is a sample.
Samples sample_polyline(const Section& s, double spacing) {
  const Eigen::Matrix3Xd& p = s.polyline;
  const Eigen::Index m = p.cols();
  std::vector<int> pieces(static_cast<std::size_t>(m - 1));
  int count = 1;
  for (Eigen::Index i = 0; i + 1 < m; ++i) {
    const double len = (p.col(i + 1) - p.col(i)).norm();
    pieces[static_cast<std::size_t>(i)] =
        std::max(1, static_cast<int>(std::ceil(len / spacing - 1e-9)));
    count += pieces[static_cast<std::size_t>(i)];
  }
  if (s.closed) --count;  // the end repeats the start
  Samples out;
  out.points.resize(3, count);
  out.normals.resize(3, count);
  out.arc.resize(count);
  const Eigen::Vector3d pn = s.plane.normal.normalized();
  const bool space = s.space_curve();
  int k = 0;
  double arc = 0;
  for (Eigen::Index i = 0; i + 1 < m && k < count; ++i) {
    const Eigen::Vector3d d = p.col(i + 1) - p.col(i);
    const double len = d.norm();
    const Eigen::Vector3d left = pn.cross(d / len);
    const Eigen::Vector3d normal = s.material == Side::Left ? Eigen::Vector3d(-left) : left;
    const int n = pieces[static_cast<std::size_t>(i)];
    for (int j = 0; j < n && k < count; ++j, ++k) {
      const double f = static_cast<double>(j) / n;
      out.points.col(k) = p.col(i) + d * f;
      out.normals.col(k) = space ? Eigen::Vector3d(((1 - f) * s.normals.col(i).normalized() +
                                                    f * s.normals.col(i + 1).normalized())
                                                       .normalized())
                                 : normal;
      out.arc[k] = arc + len * j / n;
    }
    arc += len;
  }
  if (k < count) {  // an open polyline: its last point
    const Eigen::Vector3d d = p.col(m - 1) - p.col(m - 2);
    const Eigen::Vector3d left = pn.cross(d.normalized());
    out.points.col(k) = p.col(m - 1);
    out.normals.col(k) = space ? Eigen::Vector3d(s.normals.col(m - 1).normalized())
                               : Eigen::Vector3d(s.material == Side::Left ? -left : left);
    out.arc[k] = arc;
  }
  return out;
}
}  // namespace

Samples sample(const Section& s, double spacing) {
  if (!(spacing > 0)) throw Error("the sample spacing must be positive (mm)");
  if (!s.nurbs) return sample_polyline(s, spacing);
  Samples out;
  if (const std::string why = detail::occt_api().nurbs_sample(s, spacing, out); !why.empty())
    throw Error(why);
  return out;
}

Eigen::Vector3d stylus_axis(const ProbeOrientation& o) {
  const double a = o.a_deg * M_PI / 180, b = o.b_deg * M_PI / 180;
  // The stylus points from the head to the ball along (sin A sin B, −sin A cos B, −cos A).
  return Eigen::Vector3d(-std::sin(a) * std::sin(b), std::sin(a) * std::cos(b), std::cos(a));
}

std::string head_refusal(const ProbeOrientation& o) {
  auto on_step = [](double v) {
    return std::abs(v / kHeadStep - std::round(v / kHeadStep)) < 1e-9;
  };
  if (!std::isfinite(o.a_deg) || o.a_deg < 0 || o.a_deg > kHeadMaxA)
    return fmt::format("A = {:g}°: the head tilts the stylus from 0° (straight down) to {:g}°",
                       o.a_deg, kHeadMaxA);
  if (!std::isfinite(o.b_deg) || std::abs(o.b_deg) > 180)
    return fmt::format("B = {:g}°: the head turns from −180° to 180°", o.b_deg);
  if (!on_step(o.a_deg) || !on_step(o.b_deg))
    return fmt::format("A = {:g}°, B = {:g}°: the head indexes in steps of {:g}°", o.a_deg, o.b_deg,
                       kHeadStep);
  return {};
}

Section piece(const Section& s, double from, double to, const std::string& name) {
  if (s.space_curve()) throw Error("section '" + s.name + "': a space curve has no pieces");
  const double total = length(s);
  if (!(from >= 0 && from < to && to <= (s.closed ? from + total : total) + 1e-9))
    throw Error(fmt::format("section '{}': no stretch from {:g} to {:g} mm of its {:g} mm", s.name,
                            from, to, total));
  Section out;
  if (s.nurbs) {
    if (const std::string why = detail::occt_api().nurbs_piece(s, from, to, out); !why.empty())
      throw Error(fmt::format("section '{}': {}", s.name, why));
  } else {
    // Walk the polyline (wrapping a closed one) and keep what lies between the two arcs.
    const Eigen::Matrix3Xd& p = s.polyline;
    std::vector<Eigen::Vector3d> kept;
    double arc = 0;
    const int laps = s.closed ? 2 : 1;
    for (int lap = 0; lap < laps; ++lap)
      for (Eigen::Index i = 0; i + 1 < p.cols(); ++i) {
        const Eigen::Vector3d a = p.col(i), b = p.col(i + 1);
        const double len = (b - a).norm(), a0 = arc, a1 = arc + len;
        arc = a1;
        if (a1 < from || a0 > to || len <= 0) continue;
        const Eigen::Vector3d q0 = a + (b - a) * std::clamp((from - a0) / len, 0.0, 1.0);
        const Eigen::Vector3d q1 = a + (b - a) * std::clamp((to - a0) / len, 0.0, 1.0);
        if (kept.empty() || (kept.back() - q0).norm() > 1e-9) kept.push_back(q0);
        if ((kept.back() - q1).norm() > 1e-9) kept.push_back(q1);
      }
    out = s;
    out.polyline.resize(3, static_cast<Eigen::Index>(kept.size()));
    for (std::size_t i = 0; i < kept.size(); ++i)
      out.polyline.col(static_cast<Eigen::Index>(i)) = kept[i];
  }
  out.name = name;
  out.closed = false;
  return out;
}

void StepCutOptions::validate() const {
  if (!(min_join >= 1e-7 && min_join <= max_join && max_join <= 1))
    throw Error(fmt::format("join tolerances {:g} to {:g} mm: need 1e-7 ≤ least ≤ largest ≤ 1 mm",
                            min_join, max_join));
}

StepCut cut_step(const std::string& path, const std::vector<StepSectionRequest>& planes,
                 const StepCutOptions& options) {
  options.validate();
  StepCut out;
  if (const std::string why = detail::occt_api().cut_step(path, planes, options, out); !why.empty())
    throw Error(why);
  out.design.solid = std::filesystem::absolute(path).lexically_normal().string();
  return out;
}

Samples sample(const Section& s, double spacing, double chord_tolerance) {
  if (!(spacing > 0) || !(chord_tolerance > 0))
    throw Error("the sample spacing and chord tolerance must be positive (mm)");
  if (!s.nurbs) return sample_polyline(s, spacing);  // its vertices are points: chords exact
  Samples out;
  if (const std::string why =
          detail::occt_api().nurbs_sample_fine(s, spacing, chord_tolerance, out);
      !why.empty())
    throw Error(why);
  return out;
}

Design moved_sections(const std::string& step, const Eigen::Affine3d& t, const Plane& plane) {
  double map[12];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) map[4 * r + c] = t.matrix()(r, c);
  Design out;
  if (const std::string why = detail::occt_api().moved_sections(step, map, plane, out);
      !why.empty())
    throw Error(fmt::format("{}: the part moved as simulated: {}", step, why));
  return out;
}

void assign_probes(Design& design, const std::map<std::string, ProbeOrientation>& by_plane) {
  for (auto& s : design.sections) {
    auto it = by_plane.find(s.name);
    if (const auto dot = s.name.rfind('.'); it == by_plane.end() && dot != std::string::npos)
      it = by_plane.find(s.name.substr(0, dot));
    if (it != by_plane.end()) s.probe = it->second;
  }
}

Design from_step(const std::string& path, const std::vector<StepSectionRequest>& planes) {
  StepCut cut = cut_step(path, planes);
  if (!cut.failures.empty())
    throw Error(fmt::format("{}: section '{}': {}", path, cut.failures.front().name,
                            cut.failures.front().reason));
  return std::move(cut.design);
}

}  // namespace trueaxis::design
