// Private: JSON pieces shared by the writers. The "grid" object of space.json and the ball-gauge
// map.json (read back by io::read_error_map): axes x, y, z (mm), the node layout, ex/ey/ez and
// ux/uy/uz (µm). A 3-vector as [x, y, z].
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "trueaxis/map/error_map.hpp"

namespace trueaxis::io::detail {

nlohmann::ordered_json grid_json(const map::ErrorMap& m);

// [x, y, z] · scale (e.g. 1e3 for mm → µm).
inline nlohmann::ordered_json xyz(const Eigen::Vector3d& v, double scale = 1.0) {
  return {v.x() * scale, v.y() * scale, v.z() * scale};
}

}  // namespace trueaxis::io::detail
