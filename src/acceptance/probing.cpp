// ISO 10360-5's probing errors PForm and PSize on a reference sphere (acceptance.hpp).
#include <fmt/format.h>

#include <cmath>

#include "trueaxis/acceptance/acceptance.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/geometry/fit.hpp"

namespace trueaxis::acceptance {

std::vector<Eigen::Vector3d> probing_pattern(const Eigen::Vector3d& pole) {
  constexpr double kDeg = 3.14159265358979323846 / 180;
  // A frame about the pole: u, v across it.
  const Eigen::Vector3d n = pole.normalized();
  const Eigen::Vector3d helper =
      std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d u = (helper - helper.dot(n) * n).normalized(), v = n.cross(u);
  std::vector<Eigen::Vector3d> out{n};
  // Rings at 22.5°, 45°, 67.5° and 90° from the pole with 4, 8, 4 and 8 points, each ring's
  // first point turned 22.5° from the one before's.
  const int count[4] = {4, 8, 4, 8};
  for (int ring = 0; ring < 4; ++ring) {
    const double polar = 22.5 * (ring + 1) * kDeg;
    for (int k = 0; k < count[ring]; ++k) {
      const double az = (22.5 * ring + 360.0 * k / count[ring]) * kDeg;
      out.push_back(std::cos(polar) * n + std::sin(polar) * (std::cos(az) * u + std::sin(az) * v));
    }
  }
  return out;
}

ProbingResult run_probing(const Setup& setup, const Touch& touch, const ProbingOptions& options) {
  setup.validate();
  if (!setup.sphere)
    throw Error(
        "the set-up has no reference sphere (\"sphere\": centre, diameter_mm, u_um, "
        "form_um)");
  const auto& s = *setup.sphere;
  const auto dirs = probing_pattern(s.pole);
  ProbingResult r;
  r.points.resize(3, static_cast<Eigen::Index>(dirs.size()));
  for (std::size_t i = 0; i < dirs.size(); ++i)
    r.points.col(static_cast<Eigen::Index>(i)) =
        touch(s.centre + s.diameter / 2 * dirs[i], -dirs[i]);
  const auto fit = geometry::fit(geometry::Element::Sphere, r.points);
  r.centre = fit.point;
  r.diameter = fit.diameter;
  r.radial = fit.residuals;
  r.form = r.radial.maxCoeff() - r.radial.minCoeff();
  r.size = r.diameter - s.diameter;
  r.U_form = s.form;
  r.U_size = 2 * s.u_diameter;
  r.mpe_form = options.mpe_form;
  r.mpe_size = options.mpe_size;
  auto judge = [](double value, double mpe, double U) {
    return value > mpe + U    ? Verdict::DoesNotConform
           : value <= mpe - U ? Verdict::Conforms
                              : Verdict::NotProven;
  };
  if (r.mpe_form) r.form_verdict = judge(r.form, *r.mpe_form, r.U_form);
  if (r.mpe_size) r.size_verdict = judge(std::abs(r.size), *r.mpe_size, r.U_size);
  r.rule =
      "ISO 14253-1: conformance is proven when the error ≤ MPE − U, non-conformance when it is "
      "> MPE + U; U(PForm) = the sphere's certified form, U(PSize) = 2·u(D) of its certificate";
  return r;
}

std::string ProbingResult::summary() const {
  std::string s =
      fmt::format("PForm {:.2f} µm, PSize {:+.2f} µm (LS diameter {:.4f} mm, 25 points)",
                  form * 1e3, size * 1e3, diameter);
  if (form_verdict)
    s += fmt::format("; PForm {} (MPE {:g} µm)", to_string(*form_verdict), *mpe_form * 1e3);
  if (size_verdict)
    s += fmt::format("; PSize {} (MPE {:g} µm)", to_string(*size_verdict), *mpe_size * 1e3);
  return s;
}

}  // namespace trueaxis::acceptance
