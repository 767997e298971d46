// trueaxis::report — the section for positioning accuracy by ISO 230-2 / VDI 3441.
#pragma once

#include <string>
#include <vector>

#include "trueaxis/positioning/positioning.hpp"
#include "trueaxis/report/html.hpp"

namespace trueaxis::report {

// The standard's plot (mean deviations per direction with ±2s bands and the bidirectional mean;
// for VDI 3441 the mean position with its ±(U + Ps)/2 band), every reading per direction, the
// parameter table with the tolerances and their verdicts, and the per-target table. Parameters
// the runs do not define read "not defined".
Section positioning_section(const std::string& title, const positioning::Result& result,
                            positioning::Standard standard,
                            const std::vector<positioning::Verdict>& verdicts = {});

}  // namespace trueaxis::report
