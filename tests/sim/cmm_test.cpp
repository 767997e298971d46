// The virtual scanning CMM's parts: servo limits and following error, contour distances, probe
// contact, lift-off and over-travel.
#include "trueaxis/sim/cmm.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "../test_util.hpp"

namespace trueaxis {
namespace {

constexpr double kRoundoff = 1e-9;  // mm

TEST(Servo, StepRespectsVelocityAndAccelerationLimitsAndSettles) {
  sim::ServoOptions o;
  sim::Servo s(o, Eigen::Vector3d::Zero());
  const Eigen::Vector3d target(10, -5, 2);
  Eigen::Vector3d v_prev = Eigen::Vector3d::Zero();
  double vmax = 0;
  for (int i = 0; i < 1000; ++i) {
    s.step(target, Eigen::Vector3d::Zero());
    const Eigen::Vector3d a = (s.velocity() - v_prev) / o.dt();
    EXPECT_LE(s.velocity().cwiseAbs().maxCoeff(), o.max_velocity * (1 + 1e-12));
    EXPECT_LE(a.cwiseAbs().maxCoeff(), o.max_acceleration * (1 + 1e-9));
    vmax = std::max(vmax, s.velocity().cwiseAbs().maxCoeff());
    v_prev = s.velocity();
  }
  EXPECT_GT(vmax, 0.5 * o.max_velocity);  // the limit is reached, not just respected
  EXPECT_LT((s.position() - target).norm(), 1e-6);
  EXPECT_NEAR(s.time(), 1.0, 1e-12);
  EXPECT_EQ(s.ticks(), 1000);
}

TEST(Servo, FeedForwardFollowsLinesExactlyAndCurvesClosely) {
  sim::ServoOptions o;
  const double v = 80;  // mm/s
  // A line: no error once the start transient has died.
  {
    sim::Servo s(o, Eigen::Vector3d::Zero());
    const Eigen::Vector3d dir = Eigen::Vector3d(1, 2, 0).normalized();
    double worst_late = 0;
    for (int i = 0; i < 1000; ++i) {
      s.step(dir * v * s.time(), dir * v);  // the path's position now, and its velocity
      if (i > 300) worst_late = std::max(worst_late, (s.position() - dir * v * s.time()).norm());
    }
    EXPECT_LT(worst_late, 1e-6);
  }
  // A circle of radius R: the following error stays of the order of lag²·v²/R.
  {
    const double R = 25;
    sim::Servo s(o, Eigen::Vector3d(R, 0, 0));
    double worst = 0;
    const double w = v / R;
    auto at = [&](double t) {
      return Eigen::Vector3d(R * std::cos(w * t), R * std::sin(w * t), 0);
    };
    for (int i = 0; i < 3000; ++i) {
      const double t = s.time();
      s.step(at(t), Eigen::Vector3d(-v * std::sin(w * t), v * std::cos(w * t), 0));
      if (i > 300) worst = std::max(worst, (s.position() - at(s.time())).norm());
    }
    const double scale = o.lag * o.lag * v * v / R;
    EXPECT_GT(worst, 0.01 * scale);  // the lag is really there
    EXPECT_LT(worst, 10 * scale);
  }
}

TEST(Servo, RefusesAnUnstableLoop) {
  sim::ServoOptions o;
  o.position_gain = 1000;
  EXPECT_NE(test::error_of([&] { o.validate(); }).find("stable"), std::string::npos);
  o = {};
  o.lag = 0.0005;
  EXPECT_NE(test::error_of([&] { o.validate(); }).find("two ticks"), std::string::npos);
}

// A 100 × 100 square, material inside (counter-clockwise, material on the left).
sim::Contour square() {
  Eigen::Matrix3Xd p(3, 4);
  p << 0, 100, 100, 0, 0, 0, 100, 100, 0, 0, 0, 0;
  return sim::Contour(p, Eigen::Vector3d::UnitZ(), true, true);
}

TEST(Contour, SignedDistancesNormalsAndArcAroundASquare) {
  const auto c = square();
  EXPECT_NEAR(c.length(), 400, kRoundoff);
  auto n = c.nearest(Eigen::Vector3d(50, -3, 7));  // below the bottom side, off the plane
  EXPECT_NEAR(n.distance, 3, kRoundoff);
  EXPECT_NEAR(n.arc, 50, kRoundoff);
  EXPECT_NEAR(n.normal.dot(Eigen::Vector3d(0, -1, 0)), 1, kRoundoff);
  n = c.nearest(Eigen::Vector3d(50, 4, 0));  // inside the material
  EXPECT_NEAR(n.distance, -4, kRoundoff);
  n = c.nearest(Eigen::Vector3d(103, 104, 0));  // beyond a convex corner
  EXPECT_NEAR(n.distance, 5, kRoundoff);
  EXPECT_NEAR(n.arc, 200, kRoundoff);
  EXPECT_NEAR((n.normal - Eigen::Vector3d(0.6, 0.8, 0)).norm(), 0, kRoundoff);
  n = c.nearest(Eigen::Vector3d(99, 98, 0));  // inside, near the corner
  EXPECT_NEAR(n.distance, -1, kRoundoff);
}

TEST(Contour, HintedSearchFindsTheSameAsAFullSearch) {
  // A finely divided circle, queried along a path and then with jumps.
  const int n = 2000;
  Eigen::Matrix3Xd p(3, n);
  for (int i = 0; i < n; ++i)
    p.col(i) << 25 * std::cos(2 * M_PI * i / n), 25 * std::sin(2 * M_PI * i / n), 0;
  const sim::Contour hinted(p, Eigen::Vector3d::UnitZ(), true, false);  // a hole
  for (int k = 0; k < 500; ++k) {
    const double a = (k < 400 ? 0.01 * k : 2.7 * k), r = 24 + 0.5 * std::sin(k);
    const Eigen::Vector3d q(r * std::cos(a), r * std::sin(a), 0);
    const sim::Contour fresh(p, Eigen::Vector3d::UnitZ(), true, false);
    const auto h = hinted.nearest(q), f = fresh.nearest(q);
    EXPECT_NEAR(h.distance, f.distance, kRoundoff) << k;
    EXPECT_NEAR(h.distance, 25 * std::cos(M_PI / n) - r, 25 * (1 - std::cos(M_PI / n)) + 1e-9);
    EXPECT_GT(h.distance, 0);  // in the hole: the free side
  }
}

TEST(Probe, ContactLiftOffAndOvertravel) {
  const auto c = square();
  sim::ProbeOptions o;
  o.tip_radius = 1.5;
  o.range = 0.8;
  sim::Probe probe(o);
  // Free: the ball centre 2 mm from the side.
  auto r = probe.read(Eigen::Vector3d(50, -2, 0), c);
  EXPECT_FALSE(r.contact);
  EXPECT_EQ(r.deflection.norm(), 0);
  // Pushed 0.3 mm: deflection along the outward normal, ball centre on the offset surface.
  r = probe.read(Eigen::Vector3d(50, -1.2, 0), c);
  EXPECT_TRUE(r.contact);
  EXPECT_FALSE(r.overtravel);
  EXPECT_NEAR((r.deflection - Eigen::Vector3d(0, -0.3, 0)).norm(), 0, kRoundoff);
  const Eigen::Vector3d centre = Eigen::Vector3d(50, -1.2, 0) + r.deflection;
  EXPECT_NEAR((centre - o.tip_radius * r.surface.normal - Eigen::Vector3d(50, 0, 0)).norm(), 0,
              kRoundoff);
  // Beyond the range.
  r = probe.read(Eigen::Vector3d(50, -0.5, 0), c);
  EXPECT_TRUE(r.overtravel);
  // Noise: the reading scatters with the stated standard deviation.
  o.noise = 0.002;
  sim::Probe noisy(o);
  double s2 = 0;
  const int m = 4000;
  for (int i = 0; i < m; ++i) {
    const auto q = noisy.read(Eigen::Vector3d(50, -1.2, 0), c);
    s2 += (q.deflection - q.true_deflection).squaredNorm();
  }
  const double sigma = std::sqrt(s2 / (3.0 * m));
  EXPECT_NEAR(sigma, o.noise, 4 * o.noise / std::sqrt(2.0 * 3 * m));  // ±4 standard errors
  o.range = 0;
  EXPECT_NE(test::error_of([&] { o.validate(); }).find("range"), std::string::npos);
}

}  // namespace
}  // namespace trueaxis

namespace trueaxis {
namespace {

// Queries that walk inside the material past a convex corner: the nearest point jumps to the
// other side of the corner, far along the contour from the last one found. (A search around the
// last segment alone stayed on the first side.)
TEST(Contour, NearestIsExactWhenTheNearestSideSwitches) {
  Eigen::Matrix3Xd p(3, 8000);
  for (int i = 0; i < 8000; ++i) {
    const double a = 0.05 * i;  // arc along the square's sides
    const int side = static_cast<int>(a / 100);
    const double u = a - 100 * side;
    const double xy[4][2] = {{u, 0}, {100, u}, {100 - u, 100}, {0, 100 - u}};
    p.col(i) << xy[side][0], xy[side][1], 0;
  }
  const sim::Contour walked(p, Eigen::Vector3d::UnitZ(), true, true);
  for (int k = 0; k <= 300; ++k) {
    const Eigen::Vector3d q(99.9 - 0.01 * k, 98.9, 0);  // from near x = 100 to near y = 100
    const sim::Contour fresh(p, Eigen::Vector3d::UnitZ(), true, true);
    const auto a = walked.nearest(q), b = fresh.nearest(q);
    EXPECT_NEAR(a.distance, b.distance, kRoundoff) << k;
    EXPECT_NEAR(a.distance, -std::min(100 - q.x(), 100 - q.y()), kRoundoff) << k;
  }
  EXPECT_FALSE(walked.nearest_within(Eigen::Vector3d(50, 50, 0), 10));  // the centre: 50 away
  EXPECT_TRUE(walked.nearest_within(Eigen::Vector3d(50, 5, 0), 10));
}

}  // namespace
}  // namespace trueaxis
