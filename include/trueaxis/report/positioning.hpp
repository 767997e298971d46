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

// ISO 230-2's plot of an axis before and after its compensation, on one pair of axes: each run's
// mean deviation per direction (before dashed, after solid) with its ±2s band, and the range
// its A spans. The runs need not share targets (a compensated axis is often measured at other
// positions). Appended to `section` with a sentence on what the compensation removed.
void add_before_after(Section& section, const positioning::Result& before,
                      const positioning::Result& after);

}  // namespace trueaxis::report
