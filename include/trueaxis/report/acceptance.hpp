// trueaxis::report — the sections of a CMM acceptance test (ISO 10360-2 E0/R0, ISO 10360-5).
#pragma once

#include <string>

#include "trueaxis/acceptance/acceptance.hpp"
#include "trueaxis/report/html.hpp"

namespace trueaxis::report {

// E0: the verdict with its decision rule; every length error against its nominal length, one
// colour per position, each repetition a marker, between the ±MPE envelope (dashed) and the
// zone MPE − U where conformance is proven (dotted); R0 per length; the positions.
Section e0_section(const std::string& title, const acceptance::E0Result& result);

// Probing: PForm and PSize with their MPEs and verdicts; the 25 radial deviations drawn over
// the sphere seen from above its pole (the pattern's rings joined, each point at its magnified
// deviation), and a table of the points.
Section probing_section(const std::string& title, const acceptance::ProbingResult& result,
                        const Eigen::Vector3d& pole = Eigen::Vector3d::UnitZ());

}  // namespace trueaxis::report
