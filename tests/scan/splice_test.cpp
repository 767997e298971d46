// A local deviation measured and spliced into the design data (src/scan/measured.cpp): a raised
// cosine bump 2 mm high and 30 mm wide laid by hand on a square's outline, across the point the
// contour starts at, sampled as an autonomous scan records it.
#include <gtest/gtest.h>

#include <cmath>

#include "../../src/scan/section.hpp"
#include "trueaxis/sim/cmm.hpp"

namespace trueaxis {
namespace {

constexpr double kHeight = 2, kWidth = 30, kRejoin = 0.045;  // mm
constexpr double kSpacing = 0.2;                             // mm between samples

// The 100 mm square (material inside, counter-clockwise) starting mid-way along its bottom edge,
// so that arc 0 is on a straight edge.
design::Section square() {
  design::Section s;
  s.plane = {Eigen::Vector3d(0, 0, 25), Eigen::Vector3d::UnitZ()};
  s.polyline.resize(3, 6);
  s.polyline << 50, 100, 100, 0, 0, 50, 0, 0, 100, 100, 0, 0, 25, 25, 25, 25, 25, 25;
  return s;
}

// The bump's height u mm along the edge from its middle (x = 50 + u on the bottom edge).
double bump(double u) {
  return std::abs(u) < kWidth / 2 ? kHeight * 0.5 * (1 + std::cos(2 * M_PI * u / kWidth)) : 0;
}

// Samples along the bottom edge from x = 50 + from to x = 50 + to, pushed out (−y) by the bump.
std::vector<scan::Sample> along(double from, double to) {
  std::vector<scan::Sample> out;
  for (double u = from; u <= to + 1e-9; u += kSpacing) {
    scan::Sample s;
    s.arc = u - from;
    s.surface = Eigen::Vector3d(50 + u, -bump(u), 25);
    s.normal = -Eigen::Vector3d::UnitY();
    s.contact = true;
    out.push_back(s);
  }
  return out;
}

TEST(Splice, ABumpAcrossTheContoursStartIsSplicedWhereThePartLeavesAndRejoinsIt) {
  const auto s = square();
  // The scan from 25 mm before the middle to 35 mm after it; the stop at 5 mm before it.
  const auto sp = scan::detail::splice(s, along(-25, 35), 400 - 5, kRejoin);
  ASSERT_TRUE(sp.has_value());
  // Where the bump is kRejoin high: 15 − 30·acos(1 − 2·0.045/2)/2π from the middle.
  const double edge = kWidth / 2 - kWidth * std::acos(1 - 2 * kRejoin / kHeight) / (2 * M_PI);
  EXPECT_NEAR(sp->from, 400 - edge, kSpacing);
  EXPECT_NEAR(sp->to, edge, kSpacing);
  EXPECT_NEAR(sp->largest, kHeight, 1e-9);
  // The new design follows the bump and keeps the rest of the square.
  const auto& p = sp->section.polyline;
  ASSERT_GE(p.cols(), 6);
  EXPECT_LT((p.col(0) - p.col(p.cols() - 1)).norm(), 1e-12);  // closed
  const sim::Contour c(p, Eigen::Vector3d::UnitZ(), true, true);
  for (double u : {-10.0, -3.0, 0.0, 4.0, 11.0})
    EXPECT_LT(std::abs(c.nearest(Eigen::Vector3d(50 + u, -bump(u), 25)).distance), 0.002) << u;
  for (const Eigen::Vector3d& q : {Eigen::Vector3d(100, 0, 25), Eigen::Vector3d(100, 100, 25),
                                   Eigen::Vector3d(0, 50, 25), Eigen::Vector3d(20, 0, 25)})
    EXPECT_LT(std::abs(c.nearest(q).distance), 1e-9) << q.transpose();
}

TEST(Splice, NothingWhenTheScanDoesNotShowThePartComingBack) {
  const auto s = square();
  // Ends on the bump's far flank: the part has not rejoined its design.
  EXPECT_FALSE(scan::detail::splice(s, along(-25, 10), 400 - 5, kRejoin).has_value());
  // Starts on the bump: where the part left its design is not seen.
  EXPECT_FALSE(scan::detail::splice(s, along(-5, 35), 400 - 3, kRejoin).has_value());
  // An open section is not spliced.
  auto open = s;
  open.closed = false;
  EXPECT_FALSE(scan::detail::splice(open, along(-25, 35), 400 - 5, kRejoin).has_value());
}

}  // namespace
}  // namespace trueaxis
