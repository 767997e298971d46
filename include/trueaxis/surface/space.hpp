// trueaxis::surface — the error space of a 3-axis machine from a measuring campaign (error
// surfaces stacked into a space, as the sequential two-point patent's claims 2–4 do), run on the
// virtual machine of sim/machine.hpp.
//
// Grid: every axis' range divided into equal steps of at most `Plan::spacing`; stations of every
// run are grid nodes. For each error component c (ex, ey, ez) with (a, b) the other two axes:
//  1. Straightness: virtual probe runs (sensing c) along a at every (b, c) node line and along b
//     at every (a, c) node line, plus (if `diagonals`) one along the (a, b) diagonal of each
//     level; each run separated (separation/separation.hpp) and the lines of each level assembled
//     into a surface S_k(a, b) by least squares (surface::build). A surface is known only up to a
//     plane.
//  2. Stacking: virtual laser-interferometer positioning runs along c at the four corner columns
//     give each level's plane P_k relative to the first level (least squares).
//  3. Squareness: laser runs along the three face diagonals (if `diagonals`) fix the remaining
//     plane of each component up to a rigid-body motion.
//  4. Reference: the least-squares rigid-body motion of the whole field is removed. A rigid
//     translation or rotation of all positions is no error of the machine (it is the choice of
//     the machine frame; every part is aligned by probing its datums), and no instrument sees it.
// Without diagonals, the twist of every level and the three squareness errors are unobservable;
// they are fixed as "none in the least-squares sense" and named in `unobservable`.
//
// Uncertainty: the campaign is repeated with independent noise (`monte_carlo` times) and the
// standard deviation at every node is reported. Units: mm (library), µm in files.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "trueaxis/map/error_map.hpp"
#include "trueaxis/sim/machine.hpp"

namespace trueaxis::surface {

enum class ProbeMethod { TwoPoint, ThreePoint };

struct SpacePlan {
  double spacing = 50;                           // mm, largest grid step
  ProbeMethod probes = ProbeMethod::ThreePoint;  // three-point: zero difference calibrated
  double probe_noise = 0;                        // mm, displacement probes
  double laser_noise = 0;                        // mm, interferometer
  double profile_amplitude = 2e-3;               // mm, straightedges' own form error
  bool diagonals = true;                         // twist lines and squareness diagonals
  int monte_carlo = 0;                           // repetitions for the uncertainty (0: none)
  std::uint64_t seed = 1;
  void validate() const;  // throws Error
};

struct LevelSurface {
  int component = 0;       // 0, 1, 2 = ex, ey, ez
  double level = 0;        // mm, coordinate of the level along the component's axis
  double closure_rms = 0;  // mm
  double flatness_ls = 0;  // mm
};

struct SpaceResult {
  map::ErrorMap map;  // the error space (rigid-body part removed), with uncertainty if computed
  std::vector<LevelSurface> surfaces;
  long straightness_runs = 0, laser_runs = 0;
  std::vector<std::string> unobservable;
  std::string gauge;
  // The estimate against the machine's truth at the nodes, in the same reference (mm).
  double truth_rms = 0, truth_max = 0;
  std::string summary() const;
};

// The grid of the plan on the machine's ranges.
std::array<Eigen::VectorXd, 3> space_axes(const sim::Machine& machine, const SpacePlan& plan);

// The most grid nodes a campaign is run on (a 10 mm grid on a 800 x 600 x 500 mm machine has
// 252 000).
constexpr Eigen::Index kMaxGridNodes = 500000;

// Runs the campaign on the virtual machine and assembles the error space. `progress`, if given,
// is called with the fraction done (0..1] as the campaign and its repetitions advance.
SpaceResult measure_space(const sim::Machine& machine, const SpacePlan& plan,
                          const std::function<void(double)>& progress = {});

// Removes the least-squares rigid-body motion t + ω × p (over the nodes) from a map, in place.
void remove_rigid_motion(map::ErrorMap& map);

// Compensation check on the virtual machine: at `points` random commands in the grid, the
// positioning error (actual − wanted) without and with compensation by `space`, each with its
// own least-squares rigid-body motion removed (see above). mm.
struct Verification {
  long points = 0;
  double before_rms = 0, before_max = 0, after_rms = 0, after_max = 0;
  // Prediction of after_rms: the interpolation error (the truth sampled on the same grid, no
  // noise) combined with the map's interpolated uncertainty, sqrt(interp² + u²).
  // Without the map's uncertainty (no Monte Carlo) uncertainty_rms is 0 and not known:
  // predicted_rms is then only the interpolation part, a lower bound.
  double interpolation_rms = 0, uncertainty_rms = 0, predicted_rms = 0;
  bool uncertainty_known = false;
  // Per point: the wanted positions and the residual error vectors before and after (3 × points).
  Eigen::Matrix3Xd commands, before, after;
  double improvement() const { return after_rms > 0 ? before_rms / after_rms : 0; }
};
// Plain-language warnings about a measured space: the uncertainty was not computed; the grid is
// finer than the campaign supports (the map's uncertainty is more than twice the interpolation
// error, which needs the verification).
std::vector<std::string> space_warnings(const SpaceResult& space, const Verification* v);

Verification verify_compensation(const sim::Machine& machine, const map::ErrorMap& space,
                                 long points = 1000, std::uint64_t seed = 1,
                                 const map::CompensateOptions& options = {});

}  // namespace trueaxis::surface
