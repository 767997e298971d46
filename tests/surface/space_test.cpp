#include "trueaxis/surface/space.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "trueaxis/error.hpp"

namespace trueaxis::surface {
namespace {

constexpr double kRoundOff = 1e-10;  // mm: hundreds of separations, surfaces and solves chained

sim::Machine small_machine(std::uint64_t seed = 3) {
  sim::MachineOptions o;
  o.range = {{{0, 400}, {0, 300}, {0, 200}}};
  o.seed = seed;
  return sim::random_machine(o);
}

bool names(const SpaceResult& r, const std::string& what) {
  return std::any_of(r.unobservable.begin(), r.unobservable.end(),
                     [&](const std::string& s) { return s.find(what) != std::string::npos; });
}

TEST(Space, NoiseFreeCampaignRecoversTheMachineUpToItsRigidBodyMotion) {
  for (std::uint64_t seed : {3, 4}) {
    const sim::Machine m = small_machine(seed);
    SpacePlan p;
    p.spacing = 50;
    const SpaceResult r = measure_space(m, p);
    EXPECT_EQ(r.map.size(0), 9);
    EXPECT_EQ(r.map.size(2), 5);
    EXPECT_LT(r.truth_max, kRoundOff) << r.summary();
    EXPECT_GT(r.map.error.colwise().norm().maxCoeff(), 2e-3);  // the machine has µm errors
    EXPECT_FALSE(names(r, "twist"));
    EXPECT_FALSE(names(r, "squareness"));
    EXPECT_TRUE(names(r, "rigid-body"));
  }
}

// A run reports its progress: increasing fractions that end at 1, over every repetition.
TEST(Space, ProgressAdvancesToTheEnd) {
  const sim::Machine m = small_machine();
  SpacePlan p;
  p.spacing = 100;
  p.probe_noise = 0.05e-3;
  p.monte_carlo = 3;
  std::vector<double> seen;
  measure_space(m, p, [&](double f) { seen.push_back(f); });
  ASSERT_GT(seen.size(), 10u);
  EXPECT_TRUE(std::is_sorted(seen.begin(), seen.end()));
  EXPECT_GT(seen.front(), 0);
  EXPECT_DOUBLE_EQ(seen.back(), 1.0);
}

// No figure that was not computed, and a word when the grid is finer than the noise allows: a
// 20 mm grid came out worse than a 50 mm one, with no word.
TEST(Space, WarningsSayWhatTheDataCannotSupport) {
  const sim::Machine m = small_machine();
  SpacePlan p;
  p.spacing = 100;
  p.probe_noise = 0.05e-3;
  SpaceResult r = measure_space(m, p);
  Verification v = verify_compensation(m, r.map, 200);
  EXPECT_FALSE(v.uncertainty_known);
  auto w = space_warnings(r, &v);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("uncertainty was not computed"), std::string::npos);
  EXPECT_NE(r.summary().find("not computed"), std::string::npos);

  p.monte_carlo = 4;
  r = measure_space(m, p);
  v = verify_compensation(m, r.map, 200);
  EXPECT_TRUE(v.uncertainty_known);
  EXPECT_TRUE(space_warnings(r, &v).empty()) << space_warnings(r, &v)[0];

  p.spacing = 20;
  p.probe_noise = 0.3e-3;
  r = measure_space(m, p);
  v = verify_compensation(m, r.map, 200);
  w = space_warnings(r, &v);
  ASSERT_FALSE(w.empty());
  EXPECT_NE(w.back().find("finer than this campaign supports"), std::string::npos) << w.back();
  // The spacing it suggests is measurably better: the same campaign on that grid compensates the
  // machine to a smaller RMS, as the warning predicts.
  const auto at = w.back().find("(about ");
  ASSERT_NE(at, std::string::npos) << w.back();
  const double suggested = std::stod(w.back().substr(at + 7));
  EXPECT_GT(suggested, 20);
  p.spacing = suggested;
  const SpaceResult r2 = measure_space(m, p);
  const Verification v2 = verify_compensation(m, r2.map, 200);
  EXPECT_LT(v2.after_rms, v.after_rms) << suggested << " mm";
  EXPECT_LT(v2.predicted_rms, v.predicted_rms);
}

TEST(Space, AGridTooFineToMeasureIsRefusedBeforeAnyWork) {
  const sim::Machine m = small_machine();
  SpacePlan p;
  p.spacing = 1;  // 401 x 301 x 201 nodes
  const std::string msg = [&] {
    try {
      space_axes(m, p);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  }();
  EXPECT_NE(msg.find("spacing 1 mm gives a 401 x 301 x 201 grid (24260901 nodes)"),
            std::string::npos)
      << msg;
  p.spacing = 1e-300;
  EXPECT_THROW(space_axes(m, p), Error);
}

TEST(Space, WithoutDiagonalsTwistAndSquarenessAreUnobservableAndSaidSo) {
  const sim::Machine m = small_machine();
  SpacePlan p;
  p.diagonals = false;
  const SpaceResult r = measure_space(m, p);
  EXPECT_TRUE(names(r, "twist of every level"));
  EXPECT_TRUE(names(r, "squareness"));
  // The machine's squareness (~20 µrad over 300 mm) is missing from the map: µm, not round-off.
  EXPECT_GT(r.truth_max, 1e-3);
}

TEST(Space, TwoPointProbesCarryThePitchIntoTheMap) {
  // The two-point patent's method assumes no pitch; ~10 µrad pitch integrates to µm along a line.
  const sim::Machine m = small_machine();
  SpacePlan p;
  p.probes = ProbeMethod::TwoPoint;
  const SpaceResult r = measure_space(m, p);
  EXPECT_GT(r.truth_rms, 0.1e-3);
}

TEST(Space, NoisyMapAgreesWithItsUncertaintyAndCompensationReachesThePredictedLevel) {
  const sim::Machine m = small_machine();
  SpacePlan p;
  p.probe_noise = 0.05e-3;
  p.laser_noise = 0.05e-3;
  p.monte_carlo = 20;
  p.seed = 7;
  const SpaceResult r = measure_space(m, p);
  ASSERT_EQ(r.map.uncertainty.cols(), r.map.nodes());
  // The estimate against the truth in units of the stated uncertainty.
  map::ErrorMap truth =
      map::sample(r.map.axes, [&](const Eigen::Vector3d& q) { return m.error(q); });
  remove_rigid_motion(truth);
  const Eigen::ArrayXXd z =
      (r.map.error - truth.error).array() / r.map.uncertainty.array().max(1e-12);
  const double within2 = (z.abs() <= 2).cast<double>().mean();
  const double z_rms = std::sqrt(z.square().mean());
  EXPECT_GT(within2, 0.80);
  EXPECT_GT(z_rms, 0.5);  // 20 repetitions: the uncertainty itself is known to about ±16 %,
  EXPECT_LT(z_rms, 1.6);  // and the nodes of one campaign are strongly correlated

  const Verification v = verify_compensation(m, r.map, 1000, 11);
  EXPECT_GT(v.before_rms, 2e-3);
  EXPECT_GT(v.improvement(), 5.0);
  EXPECT_GT(v.after_rms, 0.5 * v.predicted_rms);
  EXPECT_LT(v.after_rms, 1.5 * v.predicted_rms);
  EXPECT_GT(v.uncertainty_rms, 0);
  EXPECT_GT(v.interpolation_rms, 0);
}

TEST(Space, RemovingTheRigidMotionLeavesTheRestAlone) {
  const sim::Machine m = small_machine();
  map::ErrorMap a =
      map::sample({Eigen::VectorXd::LinSpaced(5, 0, 400), Eigen::VectorXd::LinSpaced(4, 0, 300),
                   Eigen::VectorXd::LinSpaced(3, 0, 200)},
                  [&](const Eigen::Vector3d& q) { return m.error(q); });
  map::ErrorMap b = a;
  const Eigen::Vector3d t(3e-3, -2e-3, 1e-3), w(20e-6, -10e-6, 30e-6);
  for (Eigen::Index i = 0; i < b.nodes(); ++i) b.error.col(i) += t + w.cross(b.node(i));
  remove_rigid_motion(a);
  remove_rigid_motion(b);
  EXPECT_LT((a.error - b.error).cwiseAbs().maxCoeff(), 1e-15);
  remove_rigid_motion(a);  // idempotent
  EXPECT_LT((a.error - b.error).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(Space, PlansAreValidated) {
  const sim::Machine m = small_machine();
  SpacePlan p;
  p.spacing = 0;
  EXPECT_THROW(measure_space(m, p), Error);
  p = {};
  p.monte_carlo = 1;
  EXPECT_THROW(measure_space(m, p), Error);
  p = {};
  p.probe_noise = -1;
  EXPECT_THROW(measure_space(m, p), Error);
  EXPECT_THROW(verify_compensation(m, measure_space(m, {}).map, 3), Error);
}

}  // namespace
}  // namespace trueaxis::surface
