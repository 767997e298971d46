// Numbers printed to the resolution their uncertainty supports (JCGM 100:2008, GUM, clause 7.2.6:
// an uncertainty is stated with at most two significant digits, and the value rounded to match).
#pragma once

#include <string>

namespace trueaxis::detail {

// Decimal places that show `u` with two significant digits (none for u ≥ 10; 0 for u = 0 or not
// finite).
int decimals_for(double u);
// `u` with two significant digits, in fixed notation ("0.21", "1.2", "35", "111").
std::string two_digits(double u);
// `value` rounded to the decimal places of two_digits(u).
std::string rounded_to(double value, double u);

}  // namespace trueaxis::detail
