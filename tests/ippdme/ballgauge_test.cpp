// A ball-gauge campaign measured through the I++ DME server with PtMeas gives the same error map
// as the campaign simulated in process: the calibration loop closed over the real protocol.
#include "trueaxis/ippdme/ballgauge.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "../test_util.hpp"
#include "serving.hpp"
#include "trueaxis/ballgauge/ballgauge.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis {
namespace {

using namespace ippdme;
using test::Running;

constexpr double kTipRadius = 1.5;  // mm, the server's probe and the campaign's
// Without probe noise the two campaigns read the same distorted spheres: the server's probe
// meets them a little aside of the nominal point (by the machine's error, some µm, which moves a
// reading along the sphere, not off it) and reads at 0.2 mm of deflection (the axes' errors
// 0.2 mm further on), both of second order; the protocol rounds the point to 0.01 µm and the
// normal to 1e-5 (15 nm at the tip radius), and the map's centres come from 10 such points.
constexpr double kSameExactMap = 0.05e-3;  // mm
constexpr double kNoise = 0.5e-3;          // probe noise (mm) of the noisy campaigns
constexpr double kWithinUncertainty = 5;   // stated standard uncertainties of the difference

sim::Machine machine() {
  sim::MachineOptions o;
  o.seed = 5;
  return sim::random_machine(o);
}

struct Campaign {
  ballgauge::Gauge gauge = sim::frame_gauge(3, 3, 2, 80, 25);
  std::vector<sim::GaugePose> poses;
  sim::BallGaugeOptions options;
  Campaign() {
    const Eigen::Matrix3d R =
        Eigen::AngleAxisd(0.004, Eigen::Vector3d(0.2, -0.1, 1).normalized()).toRotationMatrix();
    poses = sim::stacked_poses(gauge, 2, {150, 120, 60}, R);
    options.tip_radius = kTipRadius;
  }
};

ServerOptions serving(const Campaign& c, double noise) {
  ServerOptions o = test::quick();
  o.engine.cmm.geometry = machine();
  const auto& g = *o.engine.cmm.geometry;
  o.engine.cmm.home = Eigen::Vector3d(g.range[0][0], g.range[1][1], g.range[2][1]) + g.offset;
  o.engine.cmm.probe.tip_radius = kTipRadius;
  o.engine.cmm.probe.noise = noise;
  o.engine.cmm.probe.seed = 3;
  o.engine.balls = sim::gauge_balls(c.gauge, c.poses);
  return o;
}

// The campaign measured through a server (PtMeas), and how many commands it took.
ballgauge::Result through_server(const Campaign& c, double noise, long* commands = nullptr) {
  Running server(serving(c, noise));
  RemoteCmmOptions ro;
  ro.client = server.client();
  ro.tip_radius = 0;  // the server's
  RemoteCmm cmm(ro);
  const double r = cmm.tip_radius();
  EXPECT_EQ(r, kTipRadius);
  EXPECT_EQ(cmm.tool_radius(), kTipRadius);
  const auto campaign = sim::measure_ballgauge(c.gauge, c.poses, c.options,
                                               ball_probe(cmm, sim::gauge_balls(c.gauge, c.poses)));
  if (commands) *commands = cmm.commands();
  return ballgauge::calibrate(c.gauge, campaign.placements);
}

// The largest difference of the two maps' error vectors (mm), and the largest in units of their
// combined stated uncertainty.
struct Difference {
  double worst = 0, worst_z = 0;
};
Difference compare(const ballgauge::Result& a, const ballgauge::Result& b) {
  Difference d;
  EXPECT_EQ(a.points.size(), b.points.size());
  for (std::size_t i = 0; i < std::min(a.points.size(), b.points.size()); ++i) {
    const auto &p = a.points[i], &q = b.points[i];
    EXPECT_EQ(p.placement, q.placement);
    EXPECT_EQ(p.ball, q.ball);
    for (int k = 0; k < 3; ++k) {
      const double diff = std::abs(p.error[k] - q.error[k]);
      d.worst = std::max(d.worst, diff);
      const double u = std::hypot(p.uncertainty[k], q.uncertainty[k]);
      if (u > 0) d.worst_z = std::max(d.worst_z, diff / u);
    }
  }
  return d;
}

}  // namespace

TEST(BallGaugeOverIpp, ExactCampaignGivesTheInProcessMap) {
  const Campaign c;
  long commands = 0;
  const auto there = through_server(c, 0, &commands);
  const auto here = ballgauge::calibrate(
      c.gauge, sim::simulate_ballgauge(machine(), c.gauge, c.poses, c.options).placements);
  ASSERT_EQ(there.points.size(), 27u);  // 3 × 3 × 3 balls: two placements sharing a layer
  ASSERT_TRUE(there.grid.has_value());
  const auto d = compare(here, there);
  EXPECT_LT(d.worst, kSameExactMap);
  // The machine's errors are really in the map (tens of µm), and the probed points lie on the
  // same spheres as in process (the balls as the machine's errors distort them: some 0.5 µm).
  double largest = 0;
  for (const auto& p : there.points) largest = std::max(largest, p.error.norm());
  EXPECT_GT(largest, 50 * kSameExactMap);
  ASSERT_EQ(here.placements.size(), there.placements.size());
  for (std::size_t i = 0; i < here.placements.size(); ++i)
    EXPECT_NEAR(there.placements[i].diameter_error_max, here.placements[i].diameter_error_max,
                kSameExactMap)
        << there.placements[i].name;
  // Each of the 360 probings is a PtMeas and a GoTo back out, plus the moves round the balls.
  EXPECT_GT(commands, 2 * 360);
  std::printf("ball gauge over I++ DME: map differs by %.4f µm at most; %ld commands\n",
              d.worst * 1e3, commands);
}

TEST(BallGaugeOverIpp, NoisyCampaignAgreesWithinTheStatedUncertainty) {
  Campaign c;
  c.options.noise = kNoise;
  const auto there = through_server(c, kNoise);
  const auto here = ballgauge::calibrate(
      c.gauge, sim::simulate_ballgauge(machine(), c.gauge, c.poses, c.options).placements);
  const auto d = compare(here, there);
  EXPECT_LT(d.worst_z, kWithinUncertainty);
  EXPECT_GT(d.worst, 0);  // different noise on the two sides
  std::printf("noisy ball gauge over I++ DME: worst difference %.3f µm, %.2f u\n", d.worst * 1e3,
              d.worst_z);
}

TEST(BallGaugeOverIpp, AGaugeNotWhereItsPoseSaysIsNamed) {
  // The server's gauge stands 10 mm off the pose the campaign assumes: the first probing finds
  // no surface within its search, and the error names the ball.
  Campaign c;
  auto o = serving(c, 0);
  for (auto& b : o.engine.balls) b.centre.x() += 10;
  Running server(o);
  RemoteCmmOptions ro;
  ro.client = server.client();
  ro.tip_radius = kTipRadius;
  RemoteCmm cmm(ro);
  const auto err = test::error_of([&] {
    sim::measure_ballgauge(c.gauge, c.poses, c.options,
                           ball_probe(cmm, sim::gauge_balls(c.gauge, c.poses)));
  });
  EXPECT_NE(err.find("placement 1 ball 0: no surface within 3 mm"), std::string::npos) << err;
}

TEST(BallGaugeOverIpp, BadProbingOptionsAreRefused) {
  BallProbingOptions o;
  o.clearance = 0;
  EXPECT_NE(test::error_of([&] { o.validate(); }).find("clearance"), std::string::npos);
  o = {};
  o.search = -1;
  EXPECT_NE(test::error_of([&] { o.validate(); }).find("search"), std::string::npos);
  o = {};
  o.move_speed = 0;
  EXPECT_NE(test::error_of([&] { o.validate(); }).find("speeds"), std::string::npos);
}

}  // namespace trueaxis
