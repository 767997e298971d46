#include "figures.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace trueaxis::detail {

int decimals_for(double u) {
  if (!std::isfinite(u) || u == 0) return 0;
  // Two significant digits of u: the second one's decimal place, computed from u as it prints
  // (0.0996 prints as 0.10, one decimal place fewer than its exponent says).
  int d = 1 - static_cast<int>(std::floor(std::log10(std::abs(u))));
  if (d > 0 && std::abs(u) * std::pow(10.0, d) >= 99.5) --d;
  return std::clamp(d, 0, 15);
}

std::string two_digits(double u) {
  return fmt::format("{:.{}f}", u, decimals_for(u));
}

std::string rounded_to(double value, double u) {
  return fmt::format("{:.{}f}", value, decimals_for(u));
}

}  // namespace trueaxis::detail
