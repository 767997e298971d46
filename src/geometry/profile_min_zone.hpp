// Private to the library: the minimum zone of a profile whose stations the caller has already
// checked to be strictly increasing (the separation's grids). Units as the data's (mm).
#pragma once

#include <Eigen/Core>

#include "trueaxis/geometry/straightness.hpp"

namespace trueaxis::geometry::detail {

// min_zone(x, y) without its check of x's order, whose pass over x it saves (then only y is
// read in full). Precondition: x strictly increasing and finite, n >= 2 (not checked: a wrong x
// gives a wrong zone).
MinZone min_zone_of_increasing(const Eigen::VectorXd& x, const Eigen::VectorXd& y);

}  // namespace trueaxis::geometry::detail
