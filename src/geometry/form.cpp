#include <fmt/format.h>

#include <cmath>

#include "../common/figures.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/geometry/fit.hpp"

namespace trueaxis::geometry {

Form form_of(const Fit& f, double point_u) {
  if (!std::isnan(point_u) && !(point_u > 0 && std::isfinite(point_u)))
    throw Error(fmt::format(
        "the points' standard uncertainty must be a positive number of mm, not {}", point_u));
  static const char* const kNames[] = {"straightness", "flatness",     "roundness",
                                       "sphericity",   "cylindricity", "conicity"};
  Form out;
  out.name = kNames[static_cast<int>(f.element)];
  const auto n = f.residuals.size();
  if (f.zone > 0) {
    out.reference = "minimum zone";
    out.value = f.zone;
  } else {
    out.reference = fmt::format("about the least-squares {}", to_string(f.element));
    if (n == 0)
      out.value = 0;
    else if (f.element == Element::Line)  // unsigned distances: the cylinder about the line
      out.value = 2 * f.residuals.cwiseAbs().maxCoeff();
    else
      out.value = f.residuals.maxCoeff() - f.residuals.minCoeff();
  }
  if (std::isnan(point_u)) {
    out.no_uncertainty =
        "the points' own uncertainty is not stated (--point-u; point_u= in Python): their "
        "residuals mix the form with the points' noise, which nothing here separates";
    return out;
  }
  out.U = detail::peak_to_valley_U(point_u, static_cast<long>(n));
  return out;
}

std::string Form::summary() const {
  if (!U)
    return fmt::format("{} ({}): {:.4g} µm; no uncertainty: {}", name, reference, value * 1e3,
                       no_uncertainty);
  if (*resolved())
    return fmt::format("{} ({}): {} µm, U = {} µm (95 %)", name, reference,
                       detail::rounded_to(value * 1e3, *U * 1e3), detail::two_digits(*U * 1e3));
  return fmt::format(
      "{} ({}): not resolved (U = {} µm, 95 %, reaches the value): the points' noise hides the "
      "form",
      name, reference, detail::two_digits(*U * 1e3));
}

}  // namespace trueaxis::geometry
