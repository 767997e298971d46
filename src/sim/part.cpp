// A manufactured part that differs from its design.
#include "trueaxis/sim/part.hpp"

#include <fmt/format.h>

#include <cmath>
#include <random>

#include "trueaxis/error.hpp"

namespace trueaxis::sim {
namespace {
// The true contour's chords stay this close to the part's curve (mm): at corners the polyline
// has the corner itself, so a ball is never told a corner is cut.
constexpr double kChordTolerance = 1e-5;
}  // namespace

void Part::validate() const {
  const PartDeviation& v = deviation;
  auto bad = [](const std::string& what) { throw Error(what); };
  if (design.sections.empty()) bad("part: the design has no sections");
  if (!(v.scale >= 0.5 && v.scale <= 2))
    bad(fmt::format("part scale {:g}: must be in [0.5, 2]", v.scale));
  if (!(v.directional_scale >= 0.5 && v.directional_scale <= 2))
    bad(fmt::format("part directional scale {:g}: must be in [0.5, 2]", v.directional_scale));
  if (!v.scale_direction.allFinite() || !(v.scale_direction.norm() > 0))
    bad("part scale direction: needs a non-zero direction");
  if (!v.scale_about.allFinite() || v.scale_about.cwiseAbs().maxCoeff() > 1e6)
    bad("part scale centre: not a point within ±1e6 mm");
  if (!v.rotation_deg.allFinite() || v.rotation_deg.cwiseAbs().maxCoeff() > 45)
    bad("part rotation: each angle must be within ±45°");
  if (!v.translation.allFinite() || v.translation.cwiseAbs().maxCoeff() > 1000)
    bad("part translation: each component must be within ±1000 mm");
  if (!(v.noise >= 0 && v.noise <= 1))
    bad(fmt::format("part form noise {:g} mm: must be in [0, 1] mm", v.noise));
  for (const Bump& b : v.bumps) sim::validate(b, design);
}

void validate(const Bump& b, const design::Design& design) {
  bool found = false;
  for (const auto& s : design.sections) found = found || s.name == b.section;
  if (!found)
    throw Error(fmt::format("bump on section '{}': the design has no such section", b.section));
  if (!(std::abs(b.height) <= 10))
    throw Error(fmt::format("bump on '{}': height {:g} mm is beyond ±10 mm", b.section, b.height));
  if (!(b.width > 0 && b.width <= 1e4))
    throw Error(
        fmt::format("bump on '{}': width {:g} mm must be in (0, 10000]", b.section, b.width));
  if (!std::isfinite(b.arc))
    throw Error(fmt::format("bump on '{}': the arc position is not a number", b.section));
}

Eigen::Vector3d centroid(const design::Design& d) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double w = 0;
  for (const auto& s : d.sections) {
    const auto smp = design::sample(s, 0.5);
    sum += smp.points.rowwise().sum();
    w += static_cast<double>(smp.points.cols());
  }
  return w > 0 ? Eigen::Vector3d(sum / w) : sum;
}

Eigen::Affine3d transform(const Part& part) {
  const PartDeviation& v = part.deviation;
  const Eigen::Vector3d c = centroid(part.design);
  const Eigen::Vector3d about = v.scale_about_given ? v.scale_about : c;
  const Eigen::Vector3d u = v.scale_direction.normalized();
  const Eigen::Matrix3d S =
      v.scale * (Eigen::Matrix3d::Identity() + (v.directional_scale - 1) * u * u.transpose());
  const Eigen::Vector3d a = v.rotation_deg * (M_PI / 180);
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(a.z(), Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(a.y(), Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(a.x(), Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  // x -> R (S (x − about) + about − c) + c + t
  Eigen::Affine3d T = Eigen::Affine3d::Identity();
  T.linear() = R * S;
  T.translation() = R * (about - S * about - c) + c + v.translation;
  return T;
}

namespace {
// The local form deviation along the outward normal at each sample (mm): bumps and form noise.
Eigen::VectorXd form_deviation(const Part& part, const design::Section& s,
                               const design::Samples& smp) {
  const PartDeviation& v = part.deviation;
  const Eigen::Index n = smp.points.cols();
  const double total = design::length(s);
  Eigen::VectorXd dev = Eigen::VectorXd::Zero(n);
  for (const Bump& b : v.bumps) {
    if (b.section != s.name) continue;
    for (Eigen::Index i = 0; i < n; ++i) {
      double d = smp.arc[i] - b.arc;
      if (s.closed) d -= total * std::round(d / total);  // around the start of a closed curve
      if (std::abs(d) < b.width / 2)
        dev[i] += b.height * 0.5 * (1 + std::cos(2 * M_PI * d / b.width));
    }
  }
  if (v.noise > 0) {
    // Gaussian values every 2 mm of arc, joined by a smooth (cosine) blend: form noise with the
    // stated standard deviation at the knots, seeded per section.
    std::seed_seq seq{static_cast<std::uint64_t>(v.seed),
                      static_cast<std::uint64_t>(std::hash<std::string>{}(s.name))};
    std::mt19937_64 rng(seq);
    std::normal_distribution<double> g(0, v.noise);
    // Knots about 2 mm apart; on a closed curve they divide it evenly and wrap around.
    const int m = s.closed ? std::max(1, static_cast<int>(std::round(total / 2)))
                           : static_cast<int>(std::ceil(total / 2)) + 1;
    const double step = s.closed ? total / m : 2.0;
    std::vector<double> k(static_cast<std::size_t>(m));
    for (double& x : k) x = g(rng);
    for (Eigen::Index i = 0; i < n; ++i) {
      const double x = smp.arc[i] / step;
      const int j = std::min(static_cast<int>(std::floor(x)), s.closed ? m - 1 : m - 2);
      const double f = 0.5 * (1 - std::cos(M_PI * std::clamp(x - j, 0.0, 1.0)));
      const int j1 = s.closed ? (j + 1) % m : std::min(j + 1, m - 1);
      dev[i] += (1 - f) * k[static_cast<std::size_t>(j)] + f * k[static_cast<std::size_t>(j1)];
    }
  }
  return dev;
}
}  // namespace

namespace {

// The contour of the moved solid that stands for design section `s`: of the contours the moved
// part has in the section's plane, the one nearest to the moved design curve.
design::Section moved_contour(const Part& part, const design::Section& s,
                              const Eigen::Affine3d& T) {
  design::Plane plane = s.plane;
  plane.normal.normalize();
  const design::Design cut = design::moved_sections(part.design.solid, T, plane);
  const auto probe = design::sample(s, 2.0);
  Eigen::Matrix3Xd moved(3, probe.points.cols());
  for (Eigen::Index i = 0; i < probe.points.cols(); ++i) {
    const Eigen::Vector3d x = T * probe.points.col(i);
    moved.col(i) = x - (x - plane.origin).dot(plane.normal) * plane.normal;
  }
  double best = INFINITY;
  const design::Section* chosen = nullptr;
  for (const auto& c : cut.sections) {
    const auto smp = design::sample(c, 0.5);
    const Contour cc(smp.points, plane.normal, c.closed, c.material == design::Side::Left);
    double sum = 0;
    for (Eigen::Index i = 0; i < moved.cols(); ++i)
      sum += std::abs(cc.nearest(moved.col(i)).distance);
    if (sum < best) {
      best = sum;
      chosen = &c;
    }
  }
  if (!chosen)
    throw Error(
        fmt::format("section '{}': the simulated part has no contour in its plane", s.name));
  return *chosen;
}

}  // namespace

Contour true_contour(const Part& part, const design::Section& s, double spacing) {
  if (s.space_curve())
    throw Error("section '" + s.name + "' is a space curve, not a contour in a plane");
  const Eigen::Affine3d T = transform(part);
  const Eigen::Vector3d normal = s.plane.normal.normalized();
  if (!part.design.solid.empty()) {
    // The exact section of the moved solid, then the local form deviations along its normals,
    // placed by the design arc each point comes from.
    const design::Section real = moved_contour(part, s, T);
    design::Samples smp = design::sample(real, spacing, kChordTolerance);
    // The design curve as a polyline within the chord tolerance: its nearest points give the
    // design arcs as exactly as the contour is built.
    const auto fine = design::sample(s, 1.0, kChordTolerance);
    const Contour design_curve(fine.points, normal, s.closed, s.material == design::Side::Left);
    const Eigen::Affine3d back = T.inverse();
    design::Samples at_design = smp;
    for (Eigen::Index i = 0; i < smp.points.cols(); ++i)
      at_design.arc[i] = design_curve.nearest(back * smp.points.col(i)).arc;
    const Eigen::VectorXd dev = form_deviation(part, s, at_design);
    Eigen::Matrix3Xd p(3, smp.points.cols());
    for (Eigen::Index i = 0; i < smp.points.cols(); ++i)
      p.col(i) = smp.points.col(i) + dev[i] * smp.normals.col(i);
    return Contour(std::move(p), normal, real.closed, real.material == design::Side::Left);
  }
  const auto smp = design::sample(s, spacing, kChordTolerance);
  const Eigen::Index n = smp.points.cols();
  const Eigen::VectorXd dev = form_deviation(part, s, smp);
  Eigen::Matrix3Xd p(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d x = T * (smp.points.col(i) + dev[i] * smp.normals.col(i));
    p.col(i) = x - (x - s.plane.origin).dot(normal) * normal;
  }
  return Contour(std::move(p), normal, s.closed, s.material == design::Side::Left);
}

SpaceCurve true_space_curve(const Part& part, const design::Section& s, double spacing) {
  const auto smp = design::sample(s, spacing);
  const Eigen::Index n = smp.points.cols();
  const Eigen::VectorXd dev = form_deviation(part, s, smp);
  const Eigen::Affine3d T = transform(part);
  // Normals transform with the inverse transpose (a scale along one direction tilts them).
  const Eigen::Matrix3d N = T.linear().inverse().transpose();
  const Eigen::Index m = s.closed ? n + 1 : n;  // a closed curve's samples do not repeat the start
  Eigen::Matrix3Xd p(3, m), nn(3, m);
  for (Eigen::Index i = 0; i < m; ++i) {
    const Eigen::Index k = i % n;
    p.col(i) = T * (smp.points.col(k) + dev[k] * smp.normals.col(k));
    nn.col(i) = (N * smp.normals.col(k)).normalized();
  }
  return SpaceCurve(std::move(p), std::move(nn));
}

}  // namespace trueaxis::sim
