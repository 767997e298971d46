// Ball-gauge files: round trips and located errors for bad input.
#include "trueaxis/io/ballgauge/ballgauge.hpp"

#include <gtest/gtest.h>

#include "../../test_util.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/sim/ballgauge.hpp"

using namespace trueaxis;

TEST(BallGaugeIo, RoundTripsGaugeAndMeasurements) {
  const auto g = sim::frame_gauge(3, 2, 2, 80, 20);
  const std::string gp = test::temp_file("gauge.json", "");
  io::write_gauge(gp, g);
  const auto back = io::read_gauge(gp);
  ASSERT_EQ(back.balls.size(), g.balls.size());
  EXPECT_EQ(back.balls[5], g.balls[5]);
  EXPECT_EQ(back.ball_diameter, 20);
  sim::MachineOptions mo;
  const auto c = sim::simulate_ballgauge(sim::random_machine(mo), g,
                                         sim::stacked_poses(g, 2, {200, 150, 60}), {});
  const std::string mp = test::temp_file("m.json", "");
  io::write_measurements(mp, c.placements);
  const auto p = io::read_measurements(mp);
  ASSERT_EQ(p.size(), 2u);
  EXPECT_EQ(p[1].alignment, ballgauge::Alignment::Stitch);
  EXPECT_EQ(p[0].balls[3].points, c.placements[0].balls[3].points);  // shortest round trip
}

TEST(BallGaugeIo, BadFilesNameFileLineAndColumn) {
  auto gerr = [](const std::string& t) {
    const std::string p = test::temp_file("gauge.json", t);
    return test::error_of([&] { io::read_gauge(p); });
  };
  auto merr = [](const std::string& t) {
    const std::string p = test::temp_file("m.json", t);
    return test::error_of([&] { io::read_measurements(p); });
  };
  EXPECT_NE(gerr(R"({"ball_diameter": 25, "balls": [[0,0,0],[80,0],[0,80,0]]})")
                .find("gauge.json:1:41: 'balls[1]' needs [x, y, z]"),
            std::string::npos)
      << gerr(R"({"ball_diameter": 25, "balls": [[0,0,0],[80,0],[0,80,0]]})");
  EXPECT_NE(gerr(R"({"ball_diameter": 25, "balls": [[0,0,0],[80,0,0],[160,0,0]]})")
                .find("must span a plane"),
            std::string::npos);
  EXPECT_NE(gerr(R"({"balls": []})").find("'ball_diameter' is missing"), std::string::npos);
  EXPECT_NE(merr(R"({"placements": [{"alignment": "3-2-1", "balls": []}]})")
                .find("m.json:1:31: alignment must be \"321\", \"ls\" or \"stitch\""),
            std::string::npos)
      << merr(R"({"placements": [{"alignment": "3-2-1", "balls": []}]})");
  EXPECT_NE(merr(R"({"placements": [{"balls": [{"points": [[1,2,3]]}]}]})")
                .find("ball without an 'index'"),
            std::string::npos);
  EXPECT_NE(
      merr(R"({"placements": [{"balls": [{"index": 1.5, "points": []}]}]})").find("whole number"),
      std::string::npos);
  EXPECT_NE(merr(R"({"placements": [{"probe": 1}]})").find("unknown key 'probe'"),
            std::string::npos);
  // Against the gauge: an index it does not have, a ball measured twice.
  const auto g = sim::frame_gauge(3, 2, 2, 80, 20);  // 12 balls
  auto gmerr = [&](const std::string& t) {
    const std::string p = test::temp_file("m.json", t);
    return test::error_of([&] { io::read_measurements(p, &g); });
  };
  EXPECT_NE(gmerr(R"({"placements": [{"balls": [{"index": 12, "points": []}]}]})")
                .find("m.json:1:38: ball index 12 is not in the gauge (0..11)"),
            std::string::npos)
      << gmerr(R"({"placements": [{"balls": [{"index": 12, "points": []}]}]})");
  EXPECT_NE(gmerr(R"({"placements": [{"balls": [{"index": 3}, {"index": 3}]}]})")
                .find("m.json:1:52: ball 3 is measured twice"),
            std::string::npos)
      << gmerr(R"({"placements": [{"balls": [{"index": 3}, {"index": 3}]}]})");
  // Found by fuzzing: 1e10 was converted first and reported as "ball index -2147483648".
  EXPECT_NE(gmerr(R"({"placements": [{"balls": [{"index": 1e10, "points": []}]}]})")
                .find("m.json:1:38: ball index 1e+10 is not in the gauge (0..11)"),
            std::string::npos)
      << gmerr(R"({"placements": [{"balls": [{"index": 1e10, "points": []}]}]})");
  EXPECT_NE(merr(R"({"placements": [{"balls": [{"index": 1e10, "points": []}]}]})")
                .find("ball index 1e+10 is out of range"),
            std::string::npos);
}

TEST(BallGaugeIo, BallsRoundTripAndBadFilesAreLocated) {
  const std::vector<sim::Ball> balls{{{150, 120, 60}, 12.5}, {{230.25, 120, 60}, 12.5}};
  const std::string p = test::temp_file("balls.csv", "");
  io::write_balls(p, balls);
  const auto back = io::read_balls(p);
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[1].centre, balls[1].centre);
  EXPECT_EQ(back[1].radius, 12.5);
  auto err = [](const std::string& t) {
    const std::string p = test::temp_file("balls.csv", t);
    return test::error_of([&] { io::read_balls(p); });
  };
  EXPECT_NE(err("x,y,z,diameter\n1,2,3,25\n4,5,6,0\n").find("balls.csv:3:7: ball diameter 0 mm"),
            std::string::npos)
      << err("x,y,z,diameter\n1,2,3,25\n4,5,6,0\n");
  EXPECT_NE(err("x,y,z\n1,2,3\n").find("balls.csv:1:"), std::string::npos);
  EXPECT_NE(err("x,y,z\n1,2,3\n").find("diameter"), std::string::npos);
  EXPECT_NE(err("x,y,z,diameter\n").find("no balls"), std::string::npos);
  EXPECT_NE(err("x,y,z,diameter\n1,2,abc,25\n").find("balls.csv:2:5:"), std::string::npos)
      << err("x,y,z,diameter\n1,2,abc,25\n");
}
