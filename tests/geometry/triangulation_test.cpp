// The plane triangulation behind a surface's contour map: Delaunay's empty-circle property, the
// hull covered, a plane reproduced exactly by the linear surface, contours where it crosses.
#include "trueaxis/geometry/triangulation.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

using namespace trueaxis;

namespace {

double area(const Eigen::Matrix2Xd& p, const std::array<int, 3>& t) {
  const Eigen::Vector2d a = p.col(t[0]), b = p.col(t[1]), c = p.col(t[2]);
  return 0.5 * ((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
}

// A Union Jack's stations on a 1200 × 900 plate: the perimeter, the two diagonals and the two
// centre lines, 9 stations each; the corners and the centre lie on several lines.
Eigen::Matrix2Xd union_jack() {
  const double L = 1200, W = 900;
  const Eigen::Vector2d corners[4] = {{0, 0}, {L, 0}, {L, W}, {0, W}};
  std::vector<Eigen::Vector2d> pts;
  auto line = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    for (int k = 0; k <= 8; ++k) pts.push_back(a + (b - a) * k / 8.0);
  };
  for (int i = 0; i < 4; ++i) line(corners[i], corners[(i + 1) % 4]);
  line(corners[0], corners[2]);
  line(corners[1], corners[3]);
  line({0, W / 2}, {L, W / 2});
  line({L / 2, 0}, {L / 2, W});
  Eigen::Matrix2Xd m(2, static_cast<Eigen::Index>(pts.size()));
  for (std::size_t i = 0; i < pts.size(); ++i) m.col(static_cast<Eigen::Index>(i)) = pts[i];
  return m;
}

}  // namespace

TEST(Triangulation, DelaunayCoversTheHullWithEmptyCircles) {
  constexpr double kArea = 1e-6;  // mm², round-off of the summed areas
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> U(0, 1);
  Eigen::Matrix2Xd p(2, 300);
  for (Eigen::Index i = 0; i < p.cols(); ++i) p.col(i) << 500 * U(rng), 300 * U(rng);
  p.col(0) << 0, 0;  // corners, so that the hull is the rectangle
  p.col(1) << 500, 0;
  p.col(2) << 500, 300;
  p.col(3) << 0, 300;
  const auto t = geometry::delaunay(p);
  std::vector<int> used(300, 0);
  for (const auto& tri : t)
    for (int v : tri) used[static_cast<std::size_t>(v)] = 1;
  EXPECT_EQ(std::count(used.begin(), used.end(), 1), 300);  // every point a vertex
  double total = 0;
  for (const auto& tri : t) {
    EXPECT_GT(area(p, tri), 0);  // counter-clockwise
    total += area(p, tri);
    // No point inside any triangle's circumcircle.
    const Eigen::Vector2d a = p.col(tri[0]), b = p.col(tri[1]), c = p.col(tri[2]);
    const double d =
        2 * (a.x() * (b.y() - c.y()) + b.x() * (c.y() - a.y()) + c.x() * (a.y() - b.y()));
    const Eigen::Vector2d o((a.squaredNorm() * (b.y() - c.y()) + b.squaredNorm() * (c.y() - a.y()) +
                             c.squaredNorm() * (a.y() - b.y())) /
                                d,
                            (a.squaredNorm() * (c.x() - b.x()) + b.squaredNorm() * (a.x() - c.x()) +
                             c.squaredNorm() * (b.x() - a.x())) /
                                d);
    const double r = (a - o).norm();
    for (Eigen::Index i = 0; i < p.cols(); ++i) EXPECT_GE((p.col(i) - o).norm(), r * (1 - 1e-9));
  }
  EXPECT_NEAR(total, 500.0 * 300.0, kArea);
}

TEST(Triangulation, AUnionJacksStationsAreTriangulatedAndAPlaneIsReproduced) {
  constexpr double kValue = 1e-9;  // µm: a plane is linear, so exact to round-off
  const Eigen::Matrix2Xd p = union_jack();
  const auto t = geometry::delaunay(p);  // duplicates (corners, centre, crossings) used once
  double total = 0;
  for (const auto& tri : t) total += area(p, tri);
  EXPECT_NEAR(total, 1200.0 * 900.0, 1e-6);
  Eigen::VectorXd h(p.cols());
  for (Eigen::Index i = 0; i < p.cols(); ++i) h[i] = 0.002 * p(0, i) - 0.001 * p(1, i) + 3;
  Eigen::Matrix2Xd q(2, 4);
  q << 10, 600, 1190, 1300, 890, 450, 5, 100;
  const Eigen::VectorXd v = geometry::interpolate_linear(p, h, t, q);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(v[k], 0.002 * q(0, k) - 0.001 * q(1, k) + 3, kValue);
  EXPECT_TRUE(std::isnan(v[3]));  // outside the plate
  // The plane's contour at 3 µm is the line 2x = y, from (0, 0) to (450, 900).
  const auto seg = geometry::contour_segments(p, h, t, 3);
  ASSERT_FALSE(seg.empty());
  double length = 0;
  for (const auto& [a, b] : seg) {
    EXPECT_NEAR(2 * a.x() - a.y(), 0, 1e-9);
    EXPECT_NEAR(2 * b.x() - b.y(), 0, 1e-9);
    length += (b - a).norm();
  }
  EXPECT_NEAR(length, std::hypot(450.0, 900.0), 1e-6);
  // Too few points, or all on one line: no triangle.
  EXPECT_TRUE(geometry::delaunay(Eigen::Matrix2Xd(2, 2)).empty());
  Eigen::Matrix2Xd line(2, 5);
  line << 0, 1, 2, 3, 4, 0, 1, 2, 3, 4;
  EXPECT_TRUE(geometry::delaunay(line).empty());
}
