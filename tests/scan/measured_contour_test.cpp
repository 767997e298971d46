// What the error-tolerant flow does with an autonomous scan's contour that no scanning path can
// follow: it is the section's measurement, the design data stay, and the run goes on.
#include <gtest/gtest.h>

#include <algorithm>

#include "../test_parts.hpp"
#include "trueaxis/scan/controller.hpp"

namespace trueaxis {
namespace {

int count(const scan::Result& r, const std::string& ev) {
  return static_cast<int>(std::count_if(r.events.begin(), r.events.end(),
                                        [&](const auto& e) { return e.event == ev; }));
}

// A CMM whose autonomous scans of the hole report it shrunk to a 0.4 mm circle about its
// centre: a measured contour no scanning path can follow (the tip does not fit in it).
class ShrinkingHoleCmm : public scan::Machine {
 public:
  explicit ShrinkingHoleCmm(scan::VirtualCmm& cmm) : cmm_(cmm) {}
  void orient(const Eigen::Vector3d& axis) override {
    Machine::orient(axis);
    cmm_.orient(axis);
  }
  double time() const override { return cmm_.time(); }
  std::optional<double> probe_range() const override { return cmm_.probe_range(); }
  Eigen::Vector3d position() const override { return cmm_.position(); }
  void move(const Eigen::Vector3d& to, double speed) override { cmm_.move(to, speed); }
  void move_through(const std::vector<Eigen::Vector3d>& way, double speed) override {
    cmm_.move_through(way, speed);
  }
  std::optional<scan::Touch> touch(const design::Plane& plane, const Eigen::Vector3d& start,
                                   const Eigen::Vector3d& direction, double distance, double speed,
                                   double trigger) override {
    return cmm_.touch(plane, start, direction, distance, speed, trigger);
  }
  scan::ScanOutcome scan_path(const design::ScanPath& path, const scan::ScanSettings& settings,
                              const scan::Monitor& monitor) override {
    return cmm_.scan_path(path, settings, monitor);
  }
  scan::ScanOutcome scan_unknown(const design::Plane& plane, const Eigen::Vector3d& start,
                                 const Eigen::Vector3d& approach, design::Side material,
                                 bool closed, double length, double speed,
                                 const scan::ScanSettings& settings) override {
    auto out = cmm_.scan_unknown(plane, start, approach, material, closed, length, speed, settings);
    if (material == design::Side::Right)  // the hole
      for (auto& p : out.samples) {
        const Eigen::Vector3d c(50, 50, p.surface.z());
        p.surface = c + 0.4 * (p.surface - c).normalized();
      }
    return out;
  }

 private:
  scan::VirtualCmm& cmm_;
};

// An autonomous scan whose contour no path can follow (a notch of the real part narrower than
// the tip) is the section's measurement: the run goes on, and the design data are not replaced
// by it (the next part would find no path either). It once stopped the whole run.
TEST(Controller, AMeasuredContourNoPathFollowsIsTheMeasurementAndTheRunGoesOn) {
  const auto d = test::square_and_hole();
  sim::Part part{d, {}};
  part.deviation.bumps = {{"hole", 40, 2.0, 20}};  // the design scan of the hole stops there
  scan::VirtualCmm cmm(part, {}, Eigen::Vector3d(50, -20, 40));
  ShrinkingHoleCmm shrinking(cmm);
  const auto r = scan::scan(shrinking, d, {});
  EXPECT_TRUE(r.stopped.empty()) << r.stopped;
  ASSERT_EQ(r.sections.size(), 2u);
  EXPECT_TRUE(r.ok()) << r.summary();
  const auto hole = std::find_if(r.sections.begin(), r.sections.end(),
                                 [](const scan::SectionResult& x) { return x.name == "hole"; });
  ASSERT_NE(hole, r.sections.end());
  EXPECT_GE(hole->autonomous_count, 1);
  EXPECT_FALSE(hole->points.empty());
  bool said = false;
  for (const auto& e : r.events)
    said = said || (e.section == "hole" && e.event == "section_done" &&
                    e.decision.find("not kept as the design data") != std::string::npos);
  EXPECT_TRUE(said);
  EXPECT_EQ(count(r, "design_overwritten"), 0);
  // The hole's design data for the next part are the design's.
  for (const auto& s : r.design.sections)
    if (s.name == "hole") {
      EXPECT_TRUE(s.polyline.isApprox(d.sections[1].polyline, 1e-15));
    }
}

}  // namespace
}  // namespace trueaxis
