// trueaxis::report — sections for the ball-gauge map and the length verification (Oya, Hokari,
// Tamura 1988; ISO 10360-2).
#pragma once

#include <string>
#include <vector>

#include "trueaxis/ballgauge/ballgauge.hpp"
#include "trueaxis/ballgauge/lengths.hpp"
#include "trueaxis/ballgauge/parametric.hpp"
#include "trueaxis/report/html.hpp"

namespace trueaxis::report {

// The map: its placements (table) and the error-vector field as one distorted XY grid per z
// level, all at one magnification (in-plane errors move the nodes, ez is the colour). With a
// parametric model, its fit statistics are tabulated too.
Section ballgauge_section(const std::string& title, const ballgauge::Result& result,
                          const ballgauge::ParametricResult* parametric = nullptr);

// The identified model's errors against a known machine's (a simulation's truth, or a
// reference calibration), two plots per axis over the identified span, identified solid and
// known dashed, one colour per component (component_colour). First the error of the stylus tip
// as the axis moves with the others mid-span, per component: what ball-gauge data see, less what
// they never fix (its value mid-span, which moves with the placements' poses, and across the
// axis its slope, which is squareness and a rotation of the whole map). Then the axis' rotation
// errors, each less its value mid-span; a rotation the data do not see, or, for the axis that
// carries a single stylus, cannot tell from that axis' straightness (both move the tip alike), is
// drawn for the known machine only and named. A table gives the largest difference of each
// beside the known one's span, and the squareness errors as ISO 230-1 defines them. Returns the
// largest differences as drawn.
struct FunctionDifferences {
  double translation = 0;  // mm, over the nine translation functions
  double rotation = 0;     // rad, over the nine rotation functions
  double squareness = 0;   // rad
};
FunctionDifferences add_error_functions(Section& section, const ballgauge::ParametricResult& model,
                                        const sim::Machine& known,
                                        const std::string& known_name = "true");

// Gauge-block verification as in Oya et al. 1988, figure 10: length errors against the nominal
// length before and after each correction (scatter), and a table of range, mean and RMS with the
// level the repeatability and the correction's uncertainty predict. With `mpe`: the E0 check of
// every set (before and after each correction) with its verdict, and the ±MPE envelope in the
// figure.
Section lengths_section(const std::string& title,
                        const std::vector<ballgauge::LengthVerification>& results,
                        const ballgauge::Mpe* mpe = nullptr);

}  // namespace trueaxis::report
