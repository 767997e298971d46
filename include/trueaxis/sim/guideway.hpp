// trueaxis::sim — a virtual guideway carriage for guideway/guideway.hpp: one axis of the virtual
// machine (sim/machine.hpp) carrying quadrant detectors through fixed laser beams.
//
// Carriage frame (mm): z along the travel, x horizontal, y vertical, origin at the axis' reference
// point (where its error functions are defined). For the machine's X axis the carriage axes are
// (x, y, z) = machine (Y, Z, X); for Y they are (−X, Z, Y); for Z, (X, Y, Z). All three are
// right-handed, so translations and rotation vectors map by the same rotation. The truth at
// carriage position s (= the axis coordinate u) is the axis' own six errors in that frame: δx,
// δy (straightness), εx (pitch), εy (yaw), εz (roll); δz (positioning) is invisible.
//
// Readings. Small-angle (default): exactly the spec's model, dx = −(δx + εy·z − εz·y),
// dy = −(δy + εz·x − εx·z), an angle detector f·(εy, −εx). Exact: the beam (parallel to z
// through the detector's nominal x, y) meets the rotated detector plane, the spot is expressed
// in the detector's own axes, and an angle detector sees the beam direction through its lens;
// the small-angle model then errs by O(|ε|²·|p|). Noise: beam pointing jitter (per beam and
// sample, mm), spot reading noise (mm), quantisation of the readings (mm), angle-channel noise
// (rad). Optionally quadrant currents of a Gaussian spot instead of displacements.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>

#include "trueaxis/guideway/guideway.hpp"
#include "trueaxis/sim/machine.hpp"

namespace trueaxis::sim {

struct GuidewayOptions {
  int axis = 0;               // machine axis the carriage rides: 0 = X, 1 = Y, 2 = Z
  long positions = 201;       // equally spaced over the axis range
  bool exact = false;         // exact spot geometry instead of the small-angle model
  double pointing_noise = 0;  // mm, beam position jitter per beam and sample
  double noise = 0;           // mm, spot reading noise per channel
  double angle_noise = 0;     // rad, angle detectors
  double quantisation = 0;    // mm, reading resolution (0: none)
  bool currents = false;      // quadrant currents of a Gaussian spot instead of displacements
  double spot_radius = 1.0;   // mm, 1/e² radius of the Gaussian spot
  double current_noise = 0;   // relative standard deviation of each quadrant current
  std::uint64_t seed = 1;
  void validate() const;  // throws Error
};

struct GuidewayCampaign {
  Eigen::VectorXd s;         // mm
  Eigen::MatrixXd spots;     // positions × 2m, mm (dx, dy per detector), if !currents
  Eigen::MatrixXd currents;  // positions × 4m (I1..I4 per detector, sum 1), if currents
  std::array<Eigen::VectorXd, guideway::kErrors> truth;  // δx, δy (mm), εx, εy, εz (rad)
};

// The rotation whose columns are the carriage axes x, y, z in machine coordinates.
Eigen::Matrix3d carriage_axes(int axis);

GuidewayCampaign simulate_guideway(const Machine& machine, const guideway::Layout& layout,
                                   const GuidewayOptions& options);

}  // namespace trueaxis::sim
