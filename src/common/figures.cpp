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
  std::string s = fmt::format("{:.{}f}", value, decimals_for(u));
  // A value that rounds to zero is "0.00", not "-0.00".
  if (s[0] == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

double peak_to_valley_U(double u_max, long n) {
  // z with P(|N(0,1)| > z) = 0.05/n: bisection on erfc(z/√2), monotone on [0, 40].
  const double tail = 0.05 / static_cast<double>(std::max(n, 1L));
  double lo = 0, hi = 40;
  for (int i = 0; i < 200 && hi - lo > 1e-12; ++i) {
    const double z = 0.5 * (lo + hi);
    (std::erfc(z / std::sqrt(2.0)) > tail ? lo : hi) = z;
  }
  return 2 * 0.5 * (lo + hi) * u_max;
}

bool is_round_off(double noise, double readings_size) {
  return !(noise > 1e-9 * readings_size);
}

std::string noise_free_reason(std::string_view instrument) {
  return fmt::format(
      "noise-free input: the redundant readings agree to round-off, so there is no noise to "
      "estimate an uncertainty from (give --sigma for {} noise)",
      instrument);
}

}  // namespace trueaxis::detail
