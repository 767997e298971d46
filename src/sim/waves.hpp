// Private: seeded sums of sinusoids, the smooth random shapes of the simulators.
#pragma once

#include <cmath>
#include <random>
#include <vector>

namespace trueaxis::sim::detail {

struct Wave {
  double amplitude, k, phase;  // a·sin(k·u + phase)
};

// `count` waves of total amplitude about `amplitude` and wavelengths uniform in
// [lmin, lmax]·length, with random phases.
inline std::vector<Wave> random_waves(std::mt19937_64& rng, int count, double amplitude,
                                      double length, double lmin, double lmax) {
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::vector<Wave> w;
  for (int i = 0; i < count; ++i) {
    const double lambda = length * (lmin + (lmax - lmin) * U(rng));
    w.push_back({amplitude * (0.3 + 0.7 * U(rng)) / std::sqrt(static_cast<double>(count)),
                 2 * M_PI / lambda, 2 * M_PI * U(rng)});
  }
  return w;
}

inline double eval_waves(const std::vector<Wave>& ws, double u) {
  double s = 0;
  for (const auto& w : ws) s += w.amplitude * std::sin(w.k * u + w.phase);
  return s;
}

}  // namespace trueaxis::sim::detail
