// trueaxis::compensation — one axis' compensation table, as numerically controlled machines take
// it: at nominal (commanded) positions of the axis, the correction the controller adds to the
// command, one value for motion in the positive direction (forward) and one for motion in the
// negative direction (reverse). Between nodes the controller interpolates linearly.
//
// From a positioning evaluation (ISO 230-2 runs) the corrections are the negated mean
// deviations: forward = −x̄↑, reverse = −x̄↓, so that the reversal value B is compensated too; a
// unidirectional table uses −x̄ = −(x̄↑ + x̄↓)/2 in both directions and leaves the reversal. From
// an error map the correction is the negated error along the axis (no reversal: forward ==
// reverse). Units: mm.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "trueaxis/map/error_map.hpp"
#include "trueaxis/positioning/positioning.hpp"

namespace trueaxis::compensation {

struct AxisTable {
  std::vector<double> position;  // mm, strictly increasing, at least two
  std::vector<double> forward;   // mm, added to the command when moving in +
  std::vector<double> reverse;   // mm, added to the command when moving in −

  // Throws Error: fewer than two nodes, sizes that differ, non-finite values, positions not
  // strictly increasing.
  void validate() const;
  bool bidirectional() const { return forward != reverse; }
  // The correction at `p` for motion in direction `d`: linear between nodes, the end value
  // beyond them (as LinuxCNC holds it).
  double correction(double p, positioning::Direction d) const;
};

// Throws Error if a target lacks the mean it needs (a direction not measured: then only a
// unidirectional table of the measured direction can be made, which `bidirectional` = false
// gives).
AxisTable from_positioning(const positioning::Result& result, bool bidirectional = true);

// The corrections along the grid line of `map` through `at` (mm; its own coordinate along
// `axis` is ignored), at the map's nodes along `axis` (0, 1, 2).
AxisTable from_map(const map::ErrorMap& map, int axis, const Eigen::Vector3d& at);

// The centre of the map's grid (mm): the default `at` of a table, the line through the middle.
Eigen::Vector3d grid_centre(const map::ErrorMap& map);

}  // namespace trueaxis::compensation
