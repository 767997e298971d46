// Private: the "grid" object shared by space.json and the ball-gauge map.json (read back by
// io::read_error_map): axes x, y, z (mm), the node layout, ex/ey/ez and ux/uy/uz (µm).
#pragma once

#include <nlohmann/json.hpp>

#include "trueaxis/map/error_map.hpp"

namespace trueaxis::io::detail {

nlohmann::ordered_json grid_json(const map::ErrorMap& m);

}  // namespace trueaxis::io::detail
