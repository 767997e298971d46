// trueaxis::sim — virtual laser-interferometer positioning runs (ISO 230-2 test cycle) on one
// axis of the virtual machine.
//
// The laser beam runs along the axis through the tool point; the retroreflector rides on the
// tool and the interferometer is zeroed at the first target P₁ (the datum). Each cycle approaches
// the targets P₁ < … < P_m in the positive direction (↑) and then P_m … P₁ in the negative one
// (↓), the standard test cycle of ISO 230-2:2014 (figure 1). With reading k of K taken at the
// normalised time τ_k = k / (K − 1), the deviation at target P approached in direction d is
//
//     x = e(P + c) − e(P₁) + c ∓ b/2 + drift·τ + growth·τ·(P − P₁)/1000 mm
//         + α·(T(τ) − 20 °C)·(P − P₁) + noise,
//
// with e the machine's error along the axis at the tool point (all 21 errors, with their Abbe
// offsets), c the compensation added to the command, b the backlash (lost motion: an approach
// in + stops short by b/2, one in − overshoots by b/2), a linear zero drift, an unrecorded
// thermal growth of the scale that reaches `growth` mm per metre at the end, and, when a material
// temperature ramp T(τ) from `temperature_start` to `temperature_end` is given, the expansion of
// the axis that the readings' temperatures let an evaluation correct. Units: mm, °C, 1/K.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <vector>

#include "trueaxis/positioning/positioning.hpp"
#include "trueaxis/sim/machine.hpp"

namespace trueaxis::sim {

struct PositioningRunOptions {
  int axis = 0;                 // 0, 1, 2 = X, Y, Z
  std::vector<double> targets;  // mm, strictly increasing, within the axis range
  Eigen::Vector3d at = Eigen::Vector3d::Constant(positioning::kNaN);  // other axes (mm); NaN:
                                                                      // middle of their range
  int cycles = 5;
  double backlash = 0;  // mm, >= 0
  double noise = 0;     // mm, standard deviation of each reading
  double drift = 0;     // mm over the whole test
  double growth = 0;    // mm per metre reached at the end of the test
  double temperature_start = positioning::kNaN, temperature_end = positioning::kNaN;  // °C
  double expansion_coefficient = 11.5e-6;                                             // 1/K
  // Added to each command (mm): a compensation table's correction at target P, direction d.
  std::function<double(double, positioning::Direction)> compensation;
  std::uint64_t seed = 1;
  void validate(const Machine& machine) const;  // throws Error
};

struct PositioningRun {
  std::vector<positioning::Reading> readings;  // in the order they were taken
  // Truth per target (mm): the machine's error relative to the datum, e(P) − e(P₁), and the
  // noise-free mean deviation of each direction over the cycles at 20 °C (what an evaluation with
  // the temperature correction should find, up to noise).
  Eigen::VectorXd targets, geometric, up, down;
};

PositioningRun simulate_positioning(const Machine& machine, const PositioningRunOptions& options);

// The same runs as an interferometer log: the laser's reading sampled at `rate` while the axis
// moves at `feed` between stops of `dwell` seconds at the targets, overrunning by `overrun` mm
// beyond the end targets before each reversal (no stop there), the log starting at rest at the
// lower overrun point. The reading at a stop is target + the run's deviation, plus sample noise.
struct LogSimOptions {
  double rate = 10;         // samples per second
  double feed = 1000;       // mm/min
  double dwell = 3;         // s
  double overrun = 5;       // mm
  double sample_noise = 0;  // mm, on every sample
};
struct PositioningLog {
  positioning::Log log;
  PositioningRun run;  // the readings the stops hold, in time order, and the truth
};
PositioningLog simulate_positioning_log(const Machine& machine,
                                        const PositioningRunOptions& options,
                                        const LogSimOptions& log_options = {});

}  // namespace trueaxis::sim
