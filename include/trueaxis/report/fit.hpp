// trueaxis::report — the section for a least-squares (or minimum-zone) fit of a geometric
// element: its parameters with standard and expanded (k = 2) uncertainties, residuals, warnings.
#pragma once

#include <string>

#include "trueaxis/geometry/fit.hpp"
#include "trueaxis/report/html.hpp"

namespace trueaxis::report {

Section fit_section(const std::string& title, const geometry::Fit& fit);

}  // namespace trueaxis::report
