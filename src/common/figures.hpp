// Numbers printed to the resolution their uncertainty supports (JCGM 100:2008, GUM, clause 7.2.6:
// an uncertainty is stated with at most two significant digits, and the value rounded to match).
#pragma once

#include <string>
#include <string_view>

namespace trueaxis::detail {

// Decimal places that show `u` with two significant digits (none for u ≥ 10; 0 for u = 0 or not
// finite).
int decimals_for(double u);
// `u` with two significant digits, in fixed notation ("0.21", "1.2", "35", "111").
std::string two_digits(double u);
// `value` rounded to the decimal places of two_digits(u).
std::string rounded_to(double value, double u);

// Expanded uncertainty (95 % coverage) of a peak-to-valley figure (straightness, flatness, PV)
// read off n points whose largest standard uncertainty is `u_max`. The figure's error is at most
// max eᵢ − min eᵢ ≤ 2·max|eᵢ|, and every |eᵢ| ≤ z·uᵢ at once with probability ≥ 95 % when
// z = Φ⁻¹(1 − 0.025/n) (Bonferroni's inequality: it holds however the points are correlated).
// So U = 2·z·u_max: 2·3.9·u for 500 points. The largest value of n independent noisy points
// grows with n, which a plain 2u ignores.
double peak_to_valley_U(double u_max, long n);

// Whether a noise level estimated from residuals is round-off rather than noise: below 1e-9 of
// the readings' largest size, readings that agree so well come from a simulation or a copy.
bool is_round_off(double noise, double readings_size);
// Why no uncertainty is stated for such readings; `instrument` names whose noise --sigma gives
// ("the probes'").
std::string noise_free_reason(std::string_view instrument);

}  // namespace trueaxis::detail
