// Simulated parts: the true contour under translation, rotation, scale, bumps and form noise, and
// part.json with its refusals.
#include "trueaxis/sim/part.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "../test_parts.hpp"
#include "../test_util.hpp"
#include "trueaxis/io/design/design.hpp"

namespace trueaxis {
namespace {

constexpr double kTol = 1e-9;  // mm

// The square of NIST's I++ test part at z = 25 (material inside), alone.
design::Design ipp_like() {
  auto d = test::square_and_hole();
  d.sections.resize(1);
  return d;
}

TEST(Part, TranslationRotationAndScaleMoveTheContour) {
  sim::Part p{ipp_like(), {}};
  const Eigen::Vector3d c = sim::centroid(p.design);
  EXPECT_NEAR((c - Eigen::Vector3d(50, 50, 25)).norm(), 0, 1e-6);
  p.deviation.translation = Eigen::Vector3d(2, -1, 5);  // z: along the walls, not seen
  auto tc = sim::true_contour(p, p.design.sections[0], 1);
  auto n = tc.nearest(Eigen::Vector3d(50, -3, 25));
  EXPECT_NEAR(n.distance, 2, kTol);  // the bottom side moved to y = −1
  n = tc.nearest(Eigen::Vector3d(105, 50, 25));
  EXPECT_NEAR(n.distance, 3, kTol);  // the right side to x = 102
  // Rotation about z at the centroid: a corner swings out by the right amount.
  p.deviation = {};
  p.deviation.rotation_deg = Eigen::Vector3d(0, 0, 1);
  tc = sim::true_contour(p, p.design.sections[0], 1);
  const double a = M_PI / 180;
  const Eigen::Vector3d corner(50 + 50 * std::cos(a) - 50 * std::sin(a),
                               50 + 50 * std::sin(a) + 50 * std::cos(a), 25);
  EXPECT_NEAR(tc.nearest(corner).distance, 0, kTol);
  // Uniform scale about the centroid: the side at x = 100 moves to 50 + 50·s.
  p.deviation = {};
  p.deviation.scale = 1.01;
  tc = sim::true_contour(p, p.design.sections[0], 1);
  EXPECT_NEAR(tc.nearest(Eigen::Vector3d(110, 50, 25)).distance, 110 - 50.5 - 50, kTol);
  // Scale along y only, about a given point (the origin).
  p.deviation = {};
  p.deviation.scale_direction = Eigen::Vector3d::UnitY();
  p.deviation.directional_scale = 1.02;
  p.deviation.scale_about = Eigen::Vector3d::Zero();
  p.deviation.scale_about_given = true;
  tc = sim::true_contour(p, p.design.sections[0], 1);
  EXPECT_NEAR(tc.nearest(Eigen::Vector3d(50, 110, 25)).distance, 110 - 102, kTol);
  EXPECT_NEAR(tc.nearest(Eigen::Vector3d(110, 50, 25)).distance, 10, kTol);
}

TEST(Part, BumpsAndFormNoise) {
  sim::Part p{ipp_like(), {}};
  p.deviation.bumps = {{"outer", 50, 0.4, 10}, {"outer", 398, -0.2, 8}};  // the second wraps
  const auto tc = sim::true_contour(p, p.design.sections[0], 0.05);
  EXPECT_NEAR(tc.nearest(Eigen::Vector3d(50, -5, 25)).distance, 5 - 0.4, 1e-6);  // the crest
  EXPECT_NEAR(tc.nearest(Eigen::Vector3d(44, -5, 25)).distance, 5, 1e-6);        // beyond it
  // Samples every 0.05 mm of arc from (0, 0) along the bottom side: the point at arc 47.5 mm
  // is half way down the bump's flank (a raised cosine of width 10), pushed out by 0.2 mm.
  EXPECT_NEAR((tc.points().col(950) - Eigen::Vector3d(47.5, -0.2, 25)).norm(), 0, kTol);
  // The dent centred 2 mm before the end (arc 398: on the left side at y = 2) reaches 0.2 mm
  // into the material; 3 mm away from its centre, past the start, it is 0.2·(1 + cos 3π/4)/2.
  EXPECT_NEAR((tc.points().col(7960) - Eigen::Vector3d(0.2, 2, 25)).norm(), 0, kTol);
  EXPECT_NEAR(
      (tc.points().col(20) - Eigen::Vector3d(1, 0.2 * 0.5 * (1 + std::cos(2 * M_PI * 3 / 8)), 25))
          .norm(),
      0, kTol);
  // Form noise: its standard deviation along the normal, over the whole contour.
  sim::Part q{ipp_like(), {}};
  q.deviation.noise = 0.005;
  q.deviation.seed = 11;
  const auto nc = sim::true_contour(q, q.design.sections[0], 2);  // at the knots
  double s2 = 0;
  int m = 0;
  for (Eigen::Index i = 0; i < nc.points().cols(); ++i) {
    const Eigen::Vector3d x = nc.points().col(i);
    const double off =
        std::min({std::abs(x.x()), std::abs(x.x() - 100), std::abs(x.y()), std::abs(x.y() - 100)});
    s2 += off * off;
    ++m;
  }
  EXPECT_NEAR(std::sqrt(s2 / m), q.deviation.noise, 0.3 * q.deviation.noise);  // 200 samples
  const auto again = sim::true_contour(q, q.design.sections[0], 2);
  EXPECT_EQ((again.points() - nc.points()).norm(), 0);  // seeded: reproducible
}

TEST(Part, PartJsonRoundTripAndRefusals) {
  sim::Part p{ipp_like(), {}};
  p.deviation.scale = 1.001;
  p.deviation.rotation_deg = Eigen::Vector3d(0, 0, 0.5);
  p.deviation.translation = Eigen::Vector3d(0.5, 0, 0);
  p.deviation.bumps = {{"outer", 120, 0.3, 12}};
  p.deviation.noise = 0.001;
  p.deviation.seed = 5;
  const std::string path = test::temp_dir() + "/part.json";
  io::write_part(path, p);
  const auto back = io::read_part(path);
  EXPECT_EQ(back.design.sections.size(), 1u);
  EXPECT_DOUBLE_EQ(back.deviation.scale, 1.001);
  EXPECT_EQ(back.deviation.bumps.size(), 1u);
  EXPECT_EQ(back.deviation.seed, 5u);
  const auto a = sim::true_contour(p, p.design.sections[0], 1);
  const auto b = sim::true_contour(back, back.design.sections[0], 1);
  EXPECT_LT((a.points() - b.points()).norm(), 1e-9);

  const std::string design =
      R"({"sections": [{"name": "s", "plane": {"origin": [0, 0, 0], "normal": [0, 0, 1]}, "closed": false, "curve": {"polyline": [[0, 0, 0], [10, 0, 0]]}, "material": "left"}]})";
  auto err = [&](const std::string& dev) {
    return test::error_of([&] {
      io::parse_part("{\"design\": " + design + ",\n\"deviation\": " + dev + "}", "p.json");
    });
  };
  EXPECT_EQ(err("{}"), "(no error)");
  EXPECT_NE(err(R"({"bumps": [{"section": "t", "arc_mm": 1, "height_mm": 0.1, "width_mm": 2}]})")
                .find("p.json:2:25: bump on section 't': the design has no such section"),
            std::string::npos)
      << err(R"({"bumps": [{"section": "t", "arc_mm": 1, "height_mm": 0.1, "width_mm": 2}]})");
  EXPECT_NE(err(R"({"bumps": [{"section": "s", "arc_mm": 1, "height_mm": 0.1, "width_mm": 0}]})")
                .find("width 0 mm must be in (0, 10000]"),
            std::string::npos);
  EXPECT_NE(err(R"({"scale": 0})").find("p.json:2:14: part scale 0: must be in [0.5, 2]"),
            std::string::npos)
      << err(R"({"scale": 0})");
  EXPECT_NE(err(R"({"rotation_deg": [0, 0, 90]})").find("within ±45°"), std::string::npos);
  EXPECT_NE(err(R"({"translation": [0, 0]})").find("needs [dx, dy, dz (mm)]"), std::string::npos);
  EXPECT_NE(err(R"({"twist": 1})").find("unknown key 'twist'"), std::string::npos);
  EXPECT_NE(err(R"({"seed": -1})").find("whole number"), std::string::npos);
  EXPECT_NE(test::error_of([] {
              io::parse_part(R"({"deviation": {}})", "p.json");
            }).find("'design' is missing"),
            std::string::npos);
}

}  // namespace
}  // namespace trueaxis
