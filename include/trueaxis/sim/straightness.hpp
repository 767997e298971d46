// trueaxis::sim — a seeded virtual carriage for straightness campaigns (the data of
// separation/separation.hpp).
//
// The carriage moves along x over a workpiece. Truth: workpiece profile w (sinusoids of random
// wavelength and phase plus a fine random-walk texture), guide straightness g (a bow plus
// sinusoids), pitch θ (a drift plus a sinusoid), probe zero offsets o_i and an angle-channel
// offset. Readings follow the separation's model: m_i(K) = w(x_K + s_i) + g(x_K) + s_i·θ(x_K) + o_i
// + noise. Units: mm and rad. The same options and seed give the same data on the same build.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "trueaxis/separation/separation.hpp"

namespace trueaxis::sim {

struct StraightnessOptions {
  long stations = 201;                     // number of stops
  double step = 10;                        // mm between stops
  double x0 = 0;                           // mm, first stop
  std::vector<double> offsets{0, 10, 20};  // probe offsets from probe A (mm), whole steps
  double workpiece_amplitude = 5e-3;       // mm, scale of the workpiece form error
  double guide_amplitude = 3e-3;           // mm, scale of the guide straightness error
  double pitch_amplitude = 5e-6;           // rad, scale of the pitch error (0: no pitch)
  double offset_amplitude = 20e-3;         // mm, scale of the probes' zero offsets
  double noise = 0;                        // mm, probe noise standard deviation
  bool angle = false;                      // add an angle (pitch) channel
  double angle_noise = 0;                  // rad, its noise standard deviation
  std::uint64_t seed = 1;

  void validate() const;  // throws Error
};

struct StraightnessTruth {
  // On the workpiece grid: every position a probe visits, x_q = x0 + (q + min offset/h)·h.
  Eigen::VectorXd x;                  // mm
  Eigen::VectorXd workpiece;          // mm
  Eigen::VectorXd guide;              // mm (the carriage functions evaluated at x)
  Eigen::VectorXd pitch;              // rad
  std::vector<double> probe_offsets;  // o_i, mm
  double angle_offset = 0;            // rad
  // Index of station K on this grid.
  long station_index(long K) const { return K + first_station_index; }
  long first_station_index = 0;
  double step = 0;  // mm, spacing of the grid

  // `values` (one of the truth arrays) sampled at positions `x` of this grid (mm). Throws Error if
  // a position is not on the grid.
  Eigen::VectorXd sample(const Eigen::VectorXd& x, const Eigen::VectorXd& values) const;
  // The truth on a result's grids and in its reference (separation::express_in_reference), so it
  // can be compared point by point. The parabola convention follows the result (its
  // `unobservable` list names "parabola") unless `parabola_free` says otherwise. A result in the
  // seed reference gets the LS reference.
  separation::Result like(const separation::Result& result,
                          std::optional<bool> parabola_free = std::nullopt) const;
};

struct StraightnessCampaign {
  separation::ProbeData data;
  StraightnessTruth truth;
};

StraightnessCampaign simulate_straightness(const StraightnessOptions& options);

}  // namespace trueaxis::sim
