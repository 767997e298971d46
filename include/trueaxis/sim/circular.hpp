// trueaxis::sim — a circular test (ISO 230-4) on the virtual machine (sim/machine.hpp) with a
// telescoping ballbar: the two axes contour a circle under their servo loops, and the ballbar
// reads the tool's distance from its centre pivot.
//
// Per axis (ServoAxis): the position loop is first order with gain K (the motor follows the
// command as x' = K·(x_cmd − x), exactly integrated between servo ticks), so it lags by
// τ = 1/K at speed; the table stops short of the motor by half the backlash each way of travel;
// at a reversal of the motor, stick-slip leaves the table behind by a spike A·exp(−Δθ/d) that
// decays over the angle d travelled after it; a ball screw's cyclic error C·sin(2π·x/P) rides
// on its position. The tool then carries the machine's 21 geometric errors at the axes' actual
// positions. The ballbar's reading is the tool's distance from the pivot (the circle's centre
// plus a set-up offset) less its calibrated length, plus its length error, a drift of its
// length over each run and reading noise.
//
// A run: the feed-in half of the overshoot arc, the data arc (sampled), the feed-out half; ccw
// first (θ increasing from 0°), then cw (θ decreasing from 360°).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>

#include "trueaxis/circular/circular.hpp"
#include "trueaxis/sim/machine.hpp"

namespace trueaxis::sim {

struct ServoAxis {
  double gain = 0;            // 1/s, position-loop gain (0: no lag)
  double backlash = 0;        // mm, lost motion at reversal (> 0: stops short)
  double spike = 0;           // mm, reversal spike (> 0: the table left behind)
  double spike_decay = 0.05;  // rad of the circle, > 0
  double cyclic = 0;          // mm, ball screw cyclic error amplitude
  double pitch = 10;          // mm, its period, > 0
};

// What the controller adds to its commands (a compensation loaded in it): per machine axis a
// backlash, half of it each way of commanded travel (so B at each reversal); and a cross-axis
// table, a linear one: `cross_slope` times the input axis' command added to the output axis'.
struct ControllerCompensation {
  std::array<double, 3> backlash{0, 0, 0};  // mm
  int cross_input = -1, cross_output = -1;  // machine axes 0..2; -1: none
  double cross_slope = 0;                   // mm/mm
};

struct CircularOptions {
  circular::Plane plane;
  // The circle's centre (commands, mm); NaN: the middle of the machine's ranges.
  Eigen::Vector3d centre = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  double radius = 100;                                     // mm
  double feed = 1000;                                      // mm/min
  double arc = 2 * 3.14159265358979323846;                 // rad of data
  double overshoot = 3.14159265358979323846;               // rad, half before the data, half after
  bool ccw = true, cw = true;                              // the directions run
  std::array<ServoAxis, 3> servo;                          // per machine axis X, Y, Z
  Eigen::Vector3d pivot_offset = Eigen::Vector3d::Zero();  // mm, the pivot from the centre
  double length_error = 0;                                 // mm, the ballbar's calibration error
  double drift = 0;                                        // mm of length change over each run
  double noise = 0;                                        // mm, reading noise (standard deviation)
  double sample_rate = 100;                                // Hz
  double servo_rate = 1000;                                // Hz
  std::uint64_t seed = 1;
  ControllerCompensation compensation;
  void validate() const;  // throws Error
};

struct CircularRun {
  circular::Trace trace;
  Eigen::VectorXd time;  // s from the start of each run
};

// Throws Error for invalid options or a circle outside the machine's ranges.
CircularRun simulate_circular(const Machine& machine, const CircularOptions& options);

// What the test of `options` on `machine` should diagnose, in circular::evaluate's conventions:
// the path's centre from the pivot (the machine's error at the centre less the pivot offset, in
// the plane), the squareness and scale
// mismatch of the plane's axes from the tool's actual positions (the angle between the actual
// +a and +b directions less 90°, a's scale error less b's, each direction the least-squares
// line of the tool as the axis moves over ±R about the centre), the lag
// mismatch 1/K_a − 1/K_b (0 where a gain is 0), and per axis the backlash and spike. With a
// compensation, the squareness and backlash are what it leaves.
struct CircularTruth {
  Eigen::Vector2d centre_offset = Eigen::Vector2d::Zero();  // mm
  double squareness = 0, scale_mismatch = 0;                // rad, relative
  double lag_mismatch = 0;                                  // s
  std::array<double, 2> backlash{}, spike{};                // mm, axes a and b
};
CircularTruth circular_truth(const Machine& machine, const CircularOptions& options);

}  // namespace trueaxis::sim
