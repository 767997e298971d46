// trueaxis::report — the section for an error-tolerant scanning run: per section its status,
// machine time by activity, corrections and autonomous scans; the trajectory error ΔL along
// every design-value scan with the tolerance; the measured contour coloured by its deviation
// from the design; and the log of decisions.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "trueaxis/design/design.hpp"
#include "trueaxis/report/html.hpp"
#include "trueaxis/scan/controller.hpp"

namespace trueaxis::report {

inline constexpr const char* kErrorTolerantScanning =
    "Mitutoyo Corporation, method for controlling a shape measuring apparatus (error-tolerant "
    "design-value scanning with geometric correction and autonomous fallback), Japanese patent "
    "JP 6484108 B2.";

// `design`: the design data the run started from (deviations are drawn against it).
// `tolerance`: the ΔL tolerance of the run (mm). `truth_um`: per section, each measured point's
// distance from the simulated part (µm), or empty. `true_part`: per section, points of the
// simulated part's true contour (3 × n, mm), or empty. A plane view per section draws the
// design, the corrected design, the measured points and the true part, their deviations from
// the design magnified.
Section scan_section(const std::string& title, const scan::Result& result,
                     const design::Design& design, double tolerance,
                     const std::vector<Eigen::VectorXd>& truth_um = {},
                     const std::vector<Eigen::Matrix3Xd>& true_part = {});

}  // namespace trueaxis::report
