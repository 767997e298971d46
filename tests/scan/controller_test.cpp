// The error-tolerant scanning controller on the virtual CMM: every branch of the flow, checked
// against the simulated part's truth.
#include "trueaxis/scan/controller.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "../test_util.hpp"

namespace trueaxis {
namespace {

constexpr double kServoTol = 2e-3;  // mm: noise-free points on the true surface
constexpr double kParamTol = 5e-3;  // mm: a fitted translation against the truth

design::Design square_and_hole() {
  design::Design d;
  design::Section sq;
  sq.name = "outer";
  sq.plane = {Eigen::Vector3d(0, 0, 25), Eigen::Vector3d::UnitZ()};
  sq.polyline.resize(3, 5);
  sq.polyline << 0, 100, 100, 0, 0, 0, 0, 100, 100, 0, 25, 25, 25, 25, 25;
  d.sections.push_back(sq);
  design::Section hole;
  hole.name = "hole";
  hole.plane = sq.plane;
  hole.material = design::Side::Right;
  const int n = 73;
  hole.polyline.resize(3, n);
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * (i % (n - 1)) / (n - 1);
    hole.polyline.col(i) << 50 + 25 * std::cos(a), 50 + 25 * std::sin(a), 25;
  }
  d.sections.push_back(hole);
  return d;
}

double worst_distance(const scan::VirtualCmm& cmm, const design::Section& s,
                      const std::vector<scan::Sample>& pts) {
  double w = 0;
  for (const auto& p : pts) w = std::max(w, std::abs(cmm.distance(s.plane, p.surface)));
  return w;
}

int count(const scan::Result& r, const std::string& ev) {
  int n = 0;
  for (const auto& e : r.events) n += e.event == ev;
  return n;
}

double param(const scan::Correction& c, const std::string& name) {
  for (const auto& [k, v] : c.parameters)
    if (k == name) return v;
  return NAN;
}

TEST(Controller, PerfectPartScansAlongTheDesignOnly) {
  const auto d = square_and_hole();
  scan::VirtualCmm cmm(sim::Part{d, {}}, {}, Eigen::Vector3d(50, -20, 40));
  const auto r = scan::scan(cmm, d, {});
  ASSERT_TRUE(r.ok()) << r.summary();
  EXPECT_EQ(count(r, "trajectory_error"), 0);
  EXPECT_EQ(count(r, "section_done"), 2);
  EXPECT_EQ(r.events.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_LT(worst_distance(cmm, d.sections[i], r.sections[i].points), kServoTol);
    EXPECT_EQ(r.sections[i].time.touch, 0);
    EXPECT_EQ(r.sections[i].time.autonomous, 0);
  }
}

TEST(Controller, TranslatedPartIsCorrectedByATranslation) {
  const auto d = square_and_hole();
  sim::Part part{d, {}};
  part.deviation.translation = Eigen::Vector3d(1.8, -1.1, 0);  // |t| = 2.1 mm > 1.5
  scan::VirtualCmm cmm(part, {}, Eigen::Vector3d(50, -20, 40));
  const auto r = scan::scan(cmm, d, {});
  ASSERT_TRUE(r.ok()) << r.summary();
  for (std::size_t i = 0; i < 2; ++i) {
    const auto& s = r.sections[i];
    EXPECT_EQ(s.trajectory_errors, 1) << s.name;
    EXPECT_EQ(s.autonomous_count, 0) << s.name;
    ASSERT_FALSE(s.corrections.empty());
    const auto& c = s.corrections.back();
    ASSERT_TRUE(c.accepted);
    EXPECT_EQ(c.type, "translation");
    EXPECT_NEAR(param(c, "dx_mm"), 1.8, kParamTol) << s.name;
    EXPECT_NEAR(param(c, "dy_mm"), -1.1, kParamTol) << s.name;
    EXPECT_LT(worst_distance(cmm, d.sections[i], s.points), kServoTol);
    EXPECT_GT(s.time.touch, 0);
  }
  EXPECT_EQ(count(r, "correction_applied"), 2);
  EXPECT_EQ(count(r, "rescan"), 2);
}

TEST(Controller, RotatedAndScaledPartsGetTheirCorrections) {
  const auto d = square_and_hole();
  {
    sim::Part part{d, {}};
    part.deviation.rotation_deg = Eigen::Vector3d(0, 0, 2);  // corners move 2.5 mm
    scan::VirtualCmm cmm(part, {}, Eigen::Vector3d(50, -20, 40));
    auto design = d;
    design.sections.resize(1);
    const auto r = scan::scan(cmm, design, {});
    ASSERT_TRUE(r.ok()) << r.summary();
    const auto& c = r.sections[0].corrections.back();
    EXPECT_EQ(c.type, "rotation");
    EXPECT_NEAR(param(c, "rotation_deg"), 2, 1e-3);
    EXPECT_NEAR(param(c, "dx_mm"), 0, kParamTol);
    EXPECT_LT(worst_distance(cmm, d.sections[0], r.sections[0].points), kServoTol);
  }
  {
    sim::Part part{d, {}};
    part.deviation.scale = 1.04;  // the square's sides move 2 mm
    scan::VirtualCmm cmm(part, {}, Eigen::Vector3d(50, -20, 40));
    auto design = d;
    design.sections.resize(1);
    const auto r = scan::scan(cmm, design, {});
    ASSERT_TRUE(r.ok()) << r.summary();
    const auto& c = r.sections[0].corrections.back();
    EXPECT_EQ(c.type, "scale");
    EXPECT_NEAR(param(c, "scale"), 1.04, 1e-5);
  }
}

TEST(Controller, LocalBumpFallsBackToAutonomousAndTheNextPartScansClean) {
  const auto d = square_and_hole();
  sim::Part part{d, {}};
  part.deviation.bumps = {{"outer", 150, 2.0, 30}};  // 2 mm high on the right side
  scan::VirtualCmm cmm(part, {}, Eigen::Vector3d(50, -20, 40));
  const auto r = scan::scan(cmm, d, {});
  ASSERT_TRUE(r.ok()) << r.summary();
  const auto& outer = r.sections[0];
  EXPECT_EQ(outer.autonomous_count, 1);
  EXPECT_EQ(count(r, "design_overwritten"), 1);
  EXPECT_EQ(count(r, "correction_applied"), 0);
  EXPECT_GE(count(r, "correction_rejected"), 1);
  EXPECT_LT(worst_distance(cmm, d.sections[0], outer.points), kServoTol);
  // The hole has no bump: design-value scanning only.
  EXPECT_EQ(r.sections[1].trajectory_errors, 0);
  // The second part of the batch, with the corrected design data: no trajectory error.
  part.deviation.seed = 2;
  scan::VirtualCmm cmm2(part, {}, Eigen::Vector3d(50, -20, 40));
  const auto r2 = scan::scan(cmm2, r.design, {});
  ASSERT_TRUE(r2.ok()) << r2.summary();
  EXPECT_EQ(count(r2, "trajectory_error"), 0);
  EXPECT_LT(worst_distance(cmm2, d.sections[0], r2.sections[0].points), kServoTol);
  EXPECT_LT(r2.time.total, r.time.total / 3);
}

TEST(Controller, LoopLimitAndPlainDesignStrategyStop) {
  const auto d = square_and_hole();
  sim::Part part{d, {}};
  part.deviation.bumps = {{"outer", 150, 2.0, 30}};
  scan::ControllerOptions o;
  o.max_autonomous = 0;
  {
    scan::VirtualCmm cmm(part, {}, Eigen::Vector3d(50, -20, 40));
    const auto r = scan::scan(cmm, d, o);
    EXPECT_FALSE(r.ok());
    EXPECT_EQ(count(r, "loop_limit"), 1);
    EXPECT_NE(r.sections[0].reason.find("loop limit"), std::string::npos);
  }
  o = {};
  o.strategy = scan::Strategy::Design;
  {
    scan::VirtualCmm cmm(part, {}, Eigen::Vector3d(50, -20, 40));
    const auto r = scan::scan(cmm, d, o);
    EXPECT_FALSE(r.sections[0].ok);
    EXPECT_NE(r.sections[0].reason.find("trajectory error"), std::string::npos);
    EXPECT_EQ(count(r, "error_exit"), 1);
  }
}

}  // namespace
}  // namespace trueaxis
