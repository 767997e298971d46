#include <fmt/format.h>

#include <cmath>

#include "trueaxis/report/fit.hpp"

namespace trueaxis::report {

Section fit_section(const std::string& title, const geometry::Fit& f) {
  using geometry::Element;
  Section s;
  s.title = title;
  s.references = {refs::kIso10360_6, refs::kShakarji, refs::kGum};
  s.warnings = f.warnings;
  const bool zone = f.zone > 0;
  s.intro_html = fmt::format(
      "<p>{} fit of a {}{}. Residuals are orthogonal distances to the element (ISO 10360-6). "
      "{}</p>",
      zone ? "Minimum-zone (Chebyshev)" : "Least-squares (Gaussian)",
      escape(geometry::to_string(f.element)),
      f.dof > 0 ? fmt::format(", {} degrees of freedom", f.dof) : "",
      f.has_uncertainty
          ? "Uncertainties come from the Jacobian at the solution scaled by the residual "
            "variance (independent point errors of equal variance); U = 2u (k = 2, about 95 %)."
          : "No uncertainty is stated for this fit.");
  s.table.push_back({"quantity", "value", "standard uncertainty u", "expanded U (k = 2)"});
  auto row = [&](const std::string& name, double v, double u, const char* unit, int digits) {
    const std::string val = fmt::format("{:.{}f} {}", v, digits, unit);
    if (!f.has_uncertainty) return s.table.push_back({name, val, "-", "-"});
    s.table.push_back(
        {name, val, fmt::format("{:.2g} {}", u, unit), fmt::format("{:.2g} {}", 2 * u, unit)});
  };
  const bool centre = f.element == Element::Circle || f.element == Element::Sphere;
  const bool normal = f.element == Element::Plane || f.element == Element::Circle;
  const char* axes = "xyz";
  for (int k = 0; k < 3; ++k)
    row(fmt::format("{} {}", centre ? "centre" : "point", axes[k]), f.point[k], f.u_point[k], "mm",
        6);
  if (f.element != Element::Sphere)
    for (int k = 0; k < 3; ++k)
      row(fmt::format("{} {}", normal ? "normal" : "direction", axes[k]), f.direction[k],
          f.u_direction[k], "", 9);
  if (f.diameter > 0) row("diameter", f.diameter, f.u_diameter, "mm", 6);
  if (f.element == Element::Cone) {
    row("distance (axis point to surface)", f.distance, f.u_distance, "mm", 6);
    row("apex angle", f.apex_angle * 180 / M_PI, f.u_apex_angle * 180 / M_PI, "deg", 6);
  }
  if (zone) s.table.push_back({"zone width", fmt::format("{:.4f} µm", f.zone * 1e3), "", ""});
  s.table.push_back(
      {"residual RMS / max", fmt::format("{:.4f} / {:.4f} µm", f.rms * 1e3, f.max * 1e3), "", ""});
  // The residuals in the order of the points: a pattern (a lobe, a step, a drift) shows what
  // the element does not describe; random scatter is what a good fit leaves.
  if (f.residuals.size() > 0) {
    const auto n = f.residuals.size();
    Plot p;
    p.title = fmt::format("residuals: orthogonal distance of each point to the fitted {}",
                          geometry::to_string(f.element));
    p.x_label = "point (in the order of the input)";
    p.whole_x = true;
    p.y_label = "residual (µm)";
    p.x = Eigen::VectorXd::LinSpaced(n, 1, static_cast<double>(n));
    p.series.push_back({"residual", f.residuals * 1e3, {}, "#1f77b4", false, true});
    s.plots.push_back(std::move(p));
  }
  return s;
}

}  // namespace trueaxis::report
