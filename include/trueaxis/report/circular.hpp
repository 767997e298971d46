// trueaxis::report — the section for a circular test (ISO 230-4).
#pragma once

#include <string>

#include "trueaxis/circular/circular.hpp"
#include "trueaxis/circular/compensation.hpp"
#include "trueaxis/report/html.hpp"

namespace trueaxis::report {

// The polar plot ISO 230-4 draws (both directions' paths, the deviation magnified about the
// nominal circle, rings at a round deviation), the figures per direction (G, F, H), the
// diagnosis (each cause's value, u and share, or what it is not separated from), and per
// direction the trace unwrapped against the angle with the fitted model, and the residual.
// `trace` is the trace `result` was evaluated from (same samples).
// With `before` (a test of the same plane and radius before a compensation, and its trace), its
// paths are drawn on the same polar plot, dashed, on the same scale, and its figures beside the
// new ones.
struct CircularBefore {
  const circular::Result* result = nullptr;
  const circular::Trace* trace = nullptr;
};
Section circular_section(const std::string& title, const circular::Result& result,
                         const circular::Trace& trace, const CircularBefore& before = {});

// A table of the compensation derived from the test: each value to enter, what was active, what
// the test found with its uncertainty, or why it is left as it is; and the files written (file,
// controller, what) with what could not be written and why.
void add_compensation(Section& section, const circular::Compensation& compensation,
                      const std::vector<std::vector<std::string>>& files);

}  // namespace trueaxis::report
