// Private: what the simulators share: seeded sums of sinusoids (their smooth random shapes) and
// the probe grid and sensor offsets of a displacement-probe campaign.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "trueaxis/sim/straightness.hpp"

namespace trueaxis::sim::detail {

// The exact rotation whose rotation vector is v (axis v/|v|, angle |v|; rad). No small-angle
// linearisation.
inline Eigen::Matrix3d rotation(const Eigen::Vector3d& v) {
  const double a = v.norm();
  if (a == 0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(a, v / a).toRotationMatrix();
}

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

// Probe offsets in whole steps and the grid of positions the probes visit: station K is grid
// point K − pmin; probe i at station K reads grid point K − pmin + steps[i].
struct ProbeGrid {
  std::vector<long> steps;
  long pmin = 0, pmax = 0;  // min(0, steps), max(0, steps)
  long points = 0;          // stations + pmax − pmin
  double length = 0;        // mm, (points − 1)·step

  ProbeGrid(const std::vector<double>& offsets, double step, long stations) {
    for (double s : offsets) steps.push_back(std::lround(s / step));
    pmin = std::min(0L, *std::min_element(steps.begin(), steps.end()));
    pmax = std::max(0L, *std::max_element(steps.begin(), steps.end()));
    points = stations + (pmax - pmin);
    length = static_cast<double>(points - 1) * step;
  }
};

// Draws the probes' zero offsets (uniform in ±amplitude) and, with an angle channel, its offset
// (uniform in ±20 µrad) into `truth`, and sizes `data` for `stations` stops.
inline void start_probe_data(std::mt19937_64& rng, const std::vector<double>& offsets,
                             long stations, double amplitude, bool angle, StraightnessTruth& truth,
                             separation::ProbeData& data) {
  std::uniform_real_distribution<double> U(0.0, 1.0);
  for (std::size_t i = 0; i < offsets.size(); ++i)
    truth.probe_offsets.push_back(amplitude * (2 * U(rng) - 1));
  truth.angle_offset = angle ? 20e-6 * (2 * U(rng) - 1) : 0.0;
  data.offsets = offsets;
  data.x.resize(stations);
  data.readings.resize(stations, static_cast<Eigen::Index>(offsets.size()));
  if (angle) data.angle.resize(stations);
}

}  // namespace trueaxis::sim::detail
