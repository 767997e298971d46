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

// Gauge-block verification as in Oya et al. 1988, figure 10: length errors against the nominal
// length before and after each correction (scatter), and a table of range, mean and RMS with the
// level the repeatability and the correction's uncertainty predict. With `mpe`: the E0 check of
// every set (before and after each correction) with its verdict, and the ±MPE envelope in the
// figure.
Section lengths_section(const std::string& title,
                        const std::vector<ballgauge::LengthVerification>& results,
                        const ballgauge::Mpe* mpe = nullptr);

}  // namespace trueaxis::report
