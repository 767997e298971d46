// The search of the reversal spikes' decay and each axis' reversal delay: the values at which
// the diagnosis' least squares fit best. Internal to src/circular.
#pragma once

#include <array>
#include <functional>
#include <string>

#include "model.hpp"

namespace trueaxis::circular::detail {

struct Searched {
  double decay = 0;               // rad
  std::array<double, 2> delay{};  // rad, per axis a, b
  // Why the decay has no uncertainty (empty when it has one): given, or found at an end of the
  // range searched.
  std::string decay_note;
  // When the decay was found: the standard uncertainty of ln(decay) as found, given the
  // residuals' standard deviation (mm); infinite when the decay changes nothing.
  std::function<double(double sigma)> u_log_decay;
};

// `x`: every sample of `t` (Samples::of over all); `ccw`, `cw`: the directions run. The decay
// (when o.spike_decay is 0) on a log scale over 0.5° … 30°, and the delays (when
// o.reversal_delay < 0) over 0 … 5°.
Searched search(const Trace& t, const Samples& x, const Options& o, bool ccw, bool cw);

}  // namespace trueaxis::circular::detail
