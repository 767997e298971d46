#include "trueaxis/sim/straightness.hpp"

#include <gtest/gtest.h>

#include "trueaxis/error.hpp"

using namespace trueaxis;

TEST(SimStraightness, ReproducibleAndFollowsTheModel) {
  sim::StraightnessOptions o;
  o.stations = 50;
  o.offsets = {0, 10, 30};
  o.angle = true;
  const auto a = sim::simulate_straightness(o);
  const auto b = sim::simulate_straightness(o);
  EXPECT_EQ(a.data.readings, b.data.readings);
  o.seed = 2;
  EXPECT_NE(sim::simulate_straightness(o).data.readings, a.data.readings);
  const auto& T = a.truth;
  for (long K = 0; K < o.stations; ++K) {
    const long q = T.station_index(K);
    EXPECT_DOUBLE_EQ(T.x[q], a.data.x[K]);
    for (int i = 0; i < 3; ++i) {
      const double s = o.offsets[static_cast<std::size_t>(i)];
      const double m = T.workpiece[q + std::lround(s / o.step)] + T.guide[q] + s * T.pitch[q] +
                       T.probe_offsets[static_cast<std::size_t>(i)];
      EXPECT_NEAR(a.data.readings(K, i), m, 1e-18);
    }
    EXPECT_NEAR(a.data.angle[K], T.pitch[q] + T.angle_offset, 1e-20);
  }
}

TEST(SimStraightness, RejectsBadOptions) {
  sim::StraightnessOptions o;
  o.offsets = {0, 15};
  EXPECT_THROW(sim::simulate_straightness(o), Error);
  o.offsets = {0, 10};
  o.stations = 2;
  EXPECT_THROW(sim::simulate_straightness(o), Error);
  o.stations = 10;
  o.noise = -1;
  EXPECT_THROW(sim::simulate_straightness(o), Error);
}
