// The virtual CMM on a part equal to its design and on a moved one: design-value scanning,
// touches and autonomous scanning measure the true surface.
#include <gtest/gtest.h>

#include <cmath>

#include "../test_parts.hpp"
#include "../test_util.hpp"
#include "trueaxis/scan/machine.hpp"

namespace trueaxis {
namespace {

// Noise-free: each point is the ball centre (carriage position + deflection) less the tip radius
// along the deflection, which lands on the true surface whatever the servo's following error;
// only round-off is left.
constexpr double kSurfaceRoundoff = 1e-9;  // mm

using test::square_and_hole;

// A free move through waypoints does not stop at each: over the part and round it in ten legs
// it ends where the last one is, sooner than ten moves that each stop (1.37 s against 2.0 s:
// its 23° turns are taken at 73 mm/s, where the servo's lag keeps it within 0.2 mm), and the turns
// at 90° cost more than those at 10°.
TEST(VirtualCmm, FreeMoveThroughWaypointsTurnsWithoutStopping) {
  sim::Part part{square_and_hole(), {}};
  std::vector<Eigen::Vector3d> way{{50, -20, 60}};
  for (int k = 1; k <= 8; ++k) way.emplace_back(50 + 10 * k, -20 - (k % 2) * 2.0, 60);
  way.emplace_back(140, 50, 60);
  const Eigen::Vector3d home(50, -20, 40);
  scan::VirtualCmm through(part, {}, home), stops(part, {}, home);
  through.move_through(way, 200);
  for (const auto& p : way) stops.move(p, 200);
  EXPECT_LT((through.position() - way.back()).norm(), 1e-4);
  EXPECT_LT((stops.position() - way.back()).norm(), 1e-4);
  EXPECT_LT(through.time(), 0.8 * stops.time()) << through.time() << " s against " << stops.time();
  // A right angle is turned slower than a 10° bend of the same legs.
  auto time_through = [&](double turn_deg) {
    scan::VirtualCmm m(part, {}, Eigen::Vector3d(0, -50, 60));
    const double t = turn_deg * M_PI / 180;
    m.move_through({{50, -50, 60}, {50 + 50 * std::cos(t), -50 + 50 * std::sin(t), 60}}, 200);
    return m.time();
  };
  EXPECT_GT(time_through(90), time_through(10));
  EXPECT_THROW(through.move_through({}, 200), Error);
  EXPECT_THROW(through.move_through({Eigen::Vector3d(NAN, 0, 0)}, 200), Error);
  // A speed per leg: the same way with one leg slowed to the guarded speed takes longer, and
  // no slower leg than the speed it is given.
  scan::VirtualCmm slowed(part, {}, home);
  std::vector<double> speeds(way.size(), 200);
  speeds[3] = *slowed.guarded_speed();
  slowed.move_legs(way, speeds);
  EXPECT_LT((slowed.position() - way.back()).norm(), 1e-4);
  EXPECT_GT(slowed.time(), through.time());
  EXPECT_THROW(slowed.move_legs(way, {200}), Error);
  speeds[3] = 0;
  EXPECT_THROW(slowed.move_legs(way, speeds), Error);
  // The guarded speed stops the machine within half the probe's overtravel: braking at the
  // path's acceleration after the servo's lag (2000 mm/s², 7 ms, 2 mm: 50.8 mm/s).
  constexpr double kSpeedTol = 0.1;  // mm/s
  EXPECT_NEAR(*slowed.guarded_speed(), 50.8, kSpeedTol);
  scan::VirtualCmmOptions bad;
  bad.overtravel = 0;
  EXPECT_NE(test::error_of([&] { scan::VirtualCmm(part, bad, home); }).find("overtravel"),
            std::string::npos);
}

TEST(VirtualCmm, DesignValueScanOfAPerfectPartFollowsItsSurface) {
  sim::Part part{square_and_hole(), {}};
  scan::VirtualCmm cmm(part, {}, Eigen::Vector3d(50, -20, 40));
  design::PathOptions po;
  po.tip_radius = 1;
  po.pushing = 0.3;
  for (const auto& s : part.design.sections) {
    const auto path = design::make_path(s, po);
    // Over the part to the next section's start: the machine checks free moves for collisions.
    const Eigen::Vector3d start =
        path.at(0).p + scan::ScanSettings{}.approach_clearance * path.at(0).normal;
    cmm.move(Eigen::Vector3d(cmm.position().x(), cmm.position().y(), 60), 100);
    cmm.move(Eigen::Vector3d(start.x(), start.y(), 60), 100);
    cmm.move(start, 100);
    double worst_dl = 0;
    const auto out = cmm.scan_path(path, {}, [&](const scan::Sample& x) {
      worst_dl = std::max(worst_dl, std::abs(x.delta_l));
      return true;
    });
    ASSERT_TRUE(out.completed) << s.name << ": " << out.fault;
    EXPECT_GT(out.samples.size(), path.length() / 0.2 * 0.9);
    double worst = 0;
    for (const auto& x : out.samples)
      worst = std::max(worst, std::abs(cmm.distance(s.plane, x.surface)));
    EXPECT_LT(worst, kSurfaceRoundoff) << s.name;
    EXPECT_LT(worst_dl, 0.05) << s.name;  // the servo lags on the corner arcs, a little
  }
  EXPECT_GT(cmm.time(), 5);  // 550 mm at ≤ 100 mm/s, and the approaches
}

TEST(VirtualCmm, TouchAndAutonomousScanFindAMovedPart) {
  sim::Part part{square_and_hole(), {}};
  part.deviation.translation = Eigen::Vector3d(2, -1, 0);
  scan::VirtualCmm cmm(part, {}, Eigen::Vector3d(50, -20, 40));
  const auto& plane = part.design.sections[0].plane;
  const auto t =
      cmm.touch(plane, Eigen::Vector3d(50, -10, 25), Eigen::Vector3d(0, 1, 0), 20, 5, 0.3);
  ASSERT_TRUE(t);
  EXPECT_NEAR(t->surface.y(), -1, 1e-6);
  EXPECT_NEAR(t->normal.dot(Eigen::Vector3d(0, -1, 0)), 1, 1e-9);
  EXPECT_FALSE(
      cmm.touch(plane, Eigen::Vector3d(50, -30, 25), Eigen::Vector3d(0, 1, 0), 10, 5, 0.3));

  const double t0 = cmm.time();
  scan::ScanSettings st;
  const auto out = cmm.scan_unknown(plane, Eigen::Vector3d(50, -10, 25), Eigen::Vector3d(0, 1, 0),
                                    design::Side::Left, true, 400, 12, st);
  ASSERT_TRUE(out.completed) << out.fault;
  double worst = 0;
  for (const auto& x : out.samples)
    worst = std::max(worst, std::abs(cmm.distance(plane, x.surface)));
  EXPECT_LT(worst, kSurfaceRoundoff);
  EXPECT_NEAR(out.samples.back().arc, 400, 2);
  EXPECT_GT(cmm.time() - t0, 400 / 12.0);  // slow: about 10× the design-value time
}

// A CMM with geometric errors measures the part with its errors in the points: each reported
// point plus the machine's error at the scale position it was read at lies on the true surface.
TEST(VirtualCmm, GeometricErrorsOfTheMachineAreInTheMeasuredPoints) {
  sim::Part part{square_and_hole(), {}};
  sim::Machine m;
  m.name = "skewed";
  m.offset = Eigen::Vector3d(0, 0, -100);
  m.errors[0][0].polynomial = {0, 0.2};      // EXX: 200 µm/m scale error of X
  m.errors[1][2].polynomial = {0, 0, 0.05};  // EZY: a 50 µm/m² bow
  m.errors[2][3].polynomial = {0, 50e-6};    // EAZ: roll of the ram, 50 µrad/m
  m.squareness_c0y = 30e-6;                  // Y leans 30 µrad towards X
  scan::VirtualCmmOptions vo;
  vo.geometry = m;
  scan::VirtualCmm cmm(part, vo, Eigen::Vector3d(50, -20, 40));
  // Centred in the default 800 × 600 × 500 travel.
  EXPECT_NEAR(cmm.part_origin().x(), 400 - 50, 1e-9);
  EXPECT_NEAR(cmm.part_origin().z(), 250 - 25 - 100, 1e-9);
  design::PathOptions po;
  const auto& s = part.design.sections[0];
  const auto out = cmm.scan_path(design::make_path(s, po), {}, [](const auto&) { return true; });
  ASSERT_TRUE(out.completed) << out.fault;
  // The scale position is the reported point + (r − pushing) along the normal to within the
  // deflection's noise-free difference; the error's slope (≈ 2·10⁻⁴) makes that ≪ 0.1 µm.
  constexpr double kModel = 1e-4;  // mm
  double raw = 0, corrected = 0;
  for (const auto& x : out.samples) {
    raw = std::max(raw, std::abs(cmm.distance(s.plane, x.surface)));
    const Eigen::Vector3d scale = x.surface + (po.tip_radius - po.pushing) * x.normal;
    corrected =
        std::max(corrected, std::abs(cmm.distance(s.plane, x.surface + cmm.machine_error(scale))));
  }
  EXPECT_GT(raw, 0.02);  // 200 µm/m at 300–400 mm from the scale's zero
  EXPECT_LT(corrected, kModel);

  // A part that does not fit in the travel is refused in words.
  vo.geometry->range[0] = {0, 100};
  EXPECT_THROW(
      {
        try {
          scan::VirtualCmm small(part, vo);
        } catch (const Error& e) {
          EXPECT_NE(std::string(e.what()).find("does not fit on machine 'skewed'"),
                    std::string::npos);
          throw;
        }
      },
      Error);
}

}  // namespace
}  // namespace trueaxis
