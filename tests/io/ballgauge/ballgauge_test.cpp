// Ball-gauge files: round trips and located errors for bad input.
#include "trueaxis/io/ballgauge/ballgauge.hpp"

#include <gtest/gtest.h>

#include "../../test_util.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/results.hpp"
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
  EXPECT_NE(
      gmerr(R"({"placements": [{"balls": [{"index": 3, "centre": [0, 0, 0]}, {"index": 3}]}]})")
          .find("m.json:1:73: ball 3 is measured twice"),
      std::string::npos)
      << gmerr(R"({"placements": [{"balls": [{"index": 3, "centre": [0, 0, 0]}, {"index": 3}]}]})");
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

// Ball plates as their users describe them: a layout instead of 25 coordinates, the 3-2-1 frame
// balls named, and centres the CMM's software already fitted, with or without their uncertainty.
TEST(BallGaugeIo, PlatesFramesAndGivenCentres) {
  const auto plate = io::read_gauge(test::temp_file(
      "gauge.json", R"({"ball_diameter": 22, "plate": {"rows": 4, "columns": 5, "pitch": [100, 80]},
                        "frame": [0, 4, 15]})"));
  ASSERT_EQ(plate.balls.size(), 20u);
  EXPECT_EQ(plate.balls[7], Eigen::Vector3d(200, 80, 0));
  EXPECT_EQ(plate.frame_balls(), (std::array<int, 3>{0, 4, 15}));
  const std::string gp = test::temp_file("written.json", "");
  io::write_gauge(gp, plate);
  EXPECT_EQ(io::read_gauge(gp).frame, plate.frame);
  // Centres, with and without their standard uncertainty, round trip.
  ballgauge::Placement p;
  p.name = "XY";
  p.alignment = ballgauge::Alignment::ThreeTwoOne;
  for (int i = 0; i < 3; ++i) {
    ballgauge::BallPoints b;
    b.index = i;
    b.centre = Eigen::Vector3d(100.0 * i, 1, 2);
    if (i == 1) b.centre_u = Eigen::Vector3d(0.3e-3, 0.3e-3, 0.5e-3);
    p.balls.push_back(b);
  }
  // A placement probed with a stylus of its own (an upright plate from the side) says so.
  ballgauge::Placement side = p;
  side.name = "XZ";
  side.stylus_offset = Eigen::Vector3d(0, 130, -243.5);
  const std::string mp = test::temp_file("m.json", "");
  io::write_measurements(mp, {p, side});
  const auto back = io::read_measurements(mp, &plate);
  EXPECT_FALSE(back[0].stylus_offset);
  ASSERT_TRUE(back[1].stylus_offset);
  EXPECT_EQ(*back[1].stylus_offset, Eigen::Vector3d(0, 130, -243.5));
  ASSERT_EQ(back[0].balls.size(), 3u);
  EXPECT_EQ(*back[0].balls[2].centre, Eigen::Vector3d(200, 1, 2));
  EXPECT_FALSE(back[0].balls[0].centre_u.allFinite());
  EXPECT_NEAR(back[0].balls[1].centre_u.z(), 0.5e-3, 1e-15);

  auto gerr = [](const std::string& t) {
    const std::string f = test::temp_file("gauge.json", t);
    return test::error_of([&] { io::read_gauge(f); });
  };
  EXPECT_NE(gerr(R"({"ball_diameter": 22, "plate": {"rows": 1, "columns": 5, "pitch": 100}})")
                .find("gauge.json:1:41: rows must be a whole number from 2 to 100"),
            std::string::npos)
      << gerr(R"({"ball_diameter": 22, "plate": {"rows": 1, "columns": 5, "pitch": 100}})");
  EXPECT_NE(gerr(R"({"ball_diameter": 22, "plate": {"rows": 5, "columns": 5}})")
                .find("a plate needs rows, columns and pitch"),
            std::string::npos);
  EXPECT_NE(gerr(R"({"ball_diameter": 22, "balls": [[0,0,0]], "plate": {"rows": 2}})")
                .find("give the balls or a plate's layout, not both"),
            std::string::npos);
  EXPECT_NE(gerr(R"({"ball_diameter": 22, "plate": {"rows": 2, "columns": 2, "pitch": 50},
                     "frame": [0, 1, 9]})")
                .find("frame ball 9 is not a ball of the gauge (0..3)"),
            std::string::npos);
  EXPECT_NE(gerr(R"({"ball_diameter": 22, "plate": {"rows": 3, "columns": 3, "pitch": 50},
                     "frame": [0, 1, 2]})")
                .find("balls 0, 1 and 2 must span a plane"),
            std::string::npos);
  auto merr = [](const std::string& t) {
    const std::string f = test::temp_file("m.json", t);
    return test::error_of([&] { io::read_measurements(f); });
  };
  EXPECT_NE(merr(R"({"placements": [{"balls": [{"index": 0, "centre": [0, 0, 0],
                                                "points": [[1, 2, 3]]}]}]})")
                .find("give the probed points or the fitted centre, not both"),
            std::string::npos);
  EXPECT_NE(merr(R"({"placements": [{"balls": [{"index": 0, "centre": [0, 0, 0],
                                                "u_um": [0.3, 0, 0.3]}]}]})")
                .find("u_um (the centre's standard uncertainty, µm) must be > 0"),
            std::string::npos);
  EXPECT_NE(merr(R"({"placements": [{"balls": [{"index": 0, "points": [[1, 2, 3]],
                                                "u_um": [0.3, 0.3, 0.3]}]}]})")
                .find("u_um belongs to a given centre"),
            std::string::npos);
  EXPECT_NE(merr(R"({"placements": [{"stylus_offset": [0, 130],
                                      "balls": [{"index": 0, "centre": [0, 0, 0]}]}]})")
                .find("m.json:1:35: 'placements[0].stylus_offset' needs [x, y, z]"),
            std::string::npos)
      << merr(R"({"placements": [{"stylus_offset": [0, 130],
                                      "balls": [{"index": 0, "centre": [0, 0, 0]}]}]})");
  EXPECT_NE(
      merr(R"({"placements": [{"stylus_offset": [0, "a", 1], "balls": []}]})").find("m.json:1:"),
      std::string::npos);
  EXPECT_NE(merr(R"({"placements": [{"stylus": [0, 0, 1], "balls": []}]})")
                .find("unknown key 'stylus' (name, alignment, tip_radius, stylus_offset, balls)"),
            std::string::npos);
  EXPECT_NE(merr(R"({"placements": [{"balls": [{"index": 0, "centre": [0, 0]}]}]})")
                .find("'placements[0].balls[0].centre' needs [x, y, z]"),
            std::string::npos)
      << merr(R"({"placements": [{"balls": [{"index": 0, "centre": [0, 0]}]}]})");
}

// The lines of ISO 10360-2's positions read back with the lengths; a direction that is not a
// unit vector, or a line number no line has, is refused where it stands.
TEST(LengthVerificationFile, PositionLinesReadBackAndBadOnesAreRefused) {
  const ballgauge::Correction none{"none", [](Eigen::Ref<Eigen::Matrix3Xd>) {}, {}, {}};
  const std::vector<ballgauge::LengthMeasurement> L{{{0, 0, 0}, {100, 0, 0}, 100},
                                                    {{0, 0, 0}, {0, 0, 150}, 150}};
  const std::string path = test::temp_dir() + "/v.json";
  io::write_length_verification(path, {ballgauge::verify_lengths(L, none)});
  const auto back = io::read_length_verification(path);
  ASSERT_EQ(back.front().line_directions.size(), 2u);
  EXPECT_EQ(back.front().rows[1].line, 1);
  const std::string head =
      "{\"results\": [{\"correction\": \"none\", \"positions\": 1, \"before\": {\"min\": 0, "
      "\"max\": 0, \"mean\": 0, \"rms\": 0}, \"after\": {\"min\": 0, \"max\": 0, \"mean\": 0, "
      "\"rms\": 0}, \"repeatability\": null, \"correction_uncertainty_rms\": 0, "
      "\"expected_after_rms\": null,\n";
  const std::string row =
      "\"lengths\": [{\"nominal\": 100, \"position\": 0, \"before\": 0, \"after\": 0, "
      "\"uncertainty\": 0, \"line\": ";
  const std::string not_unit =
      test::temp_file("not-unit.json", head + "\"lines\": [[1, 1, 0]],\n" + row + "0}]}]}");
  EXPECT_NE(test::error_of([&] {
              io::read_length_verification(not_unit);
            }).find("not-unit.json:2:11: a line's direction must be a unit vector"),
            std::string::npos)
      << test::error_of([&] { io::read_length_verification(not_unit); });
  const std::string no_line =
      test::temp_file("no-line.json", head + "\"lines\": [[1, 0, 0]],\n" + row + "3}]}]}");
  EXPECT_NE(test::error_of([&] { io::read_length_verification(no_line); }).find("no-line.json:3:"),
            std::string::npos)
      << test::error_of([&] { io::read_length_verification(no_line); });
}
