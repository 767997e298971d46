// libFuzzer target: NIST .ds point sets, then every least-squares fit of what was read.
#include <cstdint>

#include "fuzz_util.hpp"
#include "trueaxis/geometry/fit.hpp"
#include "trueaxis/io/geometry/points.hpp"

using namespace trueaxis;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string p = fuzz::write_input("in.ds", data, size);
  Eigen::Matrix3Xd points;
  try {
    points = io::read_ds(p);
  } catch (const Error&) {
    return 0;
  }
  if (points.cols() > 100) return 0;  // a cone under ASan costs ~10 ms per 100 points
  for (auto e : {geometry::Element::Line, geometry::Element::Plane, geometry::Element::Circle,
                 geometry::Element::Sphere, geometry::Element::Cylinder, geometry::Element::Cone})
    fuzz::expect_only_trueaxis_errors([&] { geometry::fit(e, points); });
  for (auto e : {geometry::Element::Line, geometry::Element::Plane, geometry::Element::Circle})
    fuzz::expect_only_trueaxis_errors([&] { geometry::fit_min_zone(e, points); });
  return 0;
}
