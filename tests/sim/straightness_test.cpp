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

TEST(SimStraightness, SampleAndLikeFollowTheGrid) {
  sim::StraightnessOptions o;
  o.stations = 20;
  const auto c = sim::simulate_straightness(o);
  const auto& T = c.truth;
  Eigen::VectorXd at(2);
  at << T.x[3], T.x[7];
  const Eigen::VectorXd v = T.sample(at, T.guide);
  EXPECT_EQ(v[0], T.guide[3]);
  EXPECT_EQ(v[1], T.guide[7]);
  at[1] = T.x[7] + 0.5 * o.step;  // between grid points
  EXPECT_THROW(T.sample(at, T.guide), Error);
  at[1] = T.x[T.x.size() - 1] + o.step;  // beyond the grid
  EXPECT_THROW(T.sample(at, T.guide), Error);

  // like(): the truth on a result's grids, in its reference (guide residual from its LS line).
  separation::Result r;
  r.workpiece = {T.x.head(10), Eigen::VectorXd::Zero(10), {}};
  r.guide = {T.x.head(10), Eigen::VectorXd::Zero(10), {}};
  const auto t = T.like(r);
  const Eigen::VectorXd g = T.guide.head(10);
  const Eigen::VectorXd xc = T.x.head(10).array() - T.x.head(10).mean();
  const double slope = xc.dot(g) / xc.squaredNorm();
  const Eigen::VectorXd expect = g.array() - g.mean() - slope * xc.array();
  EXPECT_LT((t.guide.value - expect).cwiseAbs().maxCoeff(), 1e-17);
}
