// trueaxis::report — the section for a circular test (ISO 230-4).
#pragma once

#include <string>

#include "trueaxis/circular/circular.hpp"
#include "trueaxis/report/html.hpp"

namespace trueaxis::report {

// The polar plot ISO 230-4 draws (both directions' paths, the deviation magnified about the
// nominal circle, rings at a round deviation), the figures per direction (G, F, H), the
// diagnosis (each cause's value, u and share, or what it is not separated from), and per
// direction the trace unwrapped against the angle with the fitted model, and the residual.
// `trace` is the trace `result` was evaluated from (same samples).
Section circular_section(const std::string& title, const circular::Result& result,
                         const circular::Trace& trace);

}  // namespace trueaxis::report
