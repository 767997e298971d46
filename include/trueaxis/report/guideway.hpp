// trueaxis::report — the section for the five guideway errors (ISO 230-1 names).
#pragma once

#include <array>
#include <string>

#include "trueaxis/guideway/guideway.hpp"
#include "trueaxis/report/html.hpp"

namespace trueaxis::report {

// A table (observable, PV, RMS, uncertainty per error; condition number; what the layout cannot
// see) and five plots, one per error against s, with ±2u bands. If `truth` is given (δx, δy in
// mm, angles in rad, same positions), it is overlaid dashed and the largest recovery error is
// tabulated.
Section guideway_section(const std::string& title, const guideway::Result& result,
                         const std::array<Eigen::VectorXd, guideway::kErrors>* truth = nullptr);

}  // namespace trueaxis::report
