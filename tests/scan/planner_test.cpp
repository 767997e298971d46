// Motion planning against a solid whose clearances are known by hand: a 100 × 100 × 50 mm block
// on the table and a slab overhanging its front face higher up.
#include "trueaxis/scan/planner.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "trueaxis/design/design.hpp"

namespace trueaxis {
namespace {

constexpr double kTip = 1, kMargin = 2.5, kReach = 0.1;  // mm (kReach: the planner's own)
constexpr double kEdge = 0.02;  // mm: the blocked arcs' ends are found to a hundredth of the step

// Boxes as one mesh, each face (two triangles) its own face id.
std::shared_ptr<const solid::Mesh> boxes(const std::vector<Eigen::AlignedBox3d>& list) {
  Eigen::Matrix3Xd v(3, 8 * static_cast<Eigen::Index>(list.size()));
  Eigen::Matrix3Xi t(3, 12 * static_cast<Eigen::Index>(list.size()));
  std::vector<int> faces;
  // Corner k has x from bit 0, y from bit 1, z from bit 2; each face as two triangles.
  static const int quads[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1},
                                  {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
  for (std::size_t b = 0; b < list.size(); ++b) {
    const Eigen::Index v0 = 8 * static_cast<Eigen::Index>(b),
                       t0 = 12 * static_cast<Eigen::Index>(b);
    for (int k = 0; k < 8; ++k)
      v.col(v0 + k) << (k & 1 ? list[b].max() : list[b].min()).x(),
          (k & 2 ? list[b].max() : list[b].min()).y(), (k & 4 ? list[b].max() : list[b].min()).z();
    for (int f = 0; f < 6; ++f) {
      const int* q = quads[f];
      t.col(t0 + 2 * f) << v0 + q[0], v0 + q[1], v0 + q[2];
      t.col(t0 + 2 * f + 1) << v0 + q[0], v0 + q[2], v0 + q[3];
      faces.push_back(static_cast<int>(6 * b) + f);
      faces.push_back(static_cast<int>(6 * b) + f);
    }
  }
  return std::make_shared<const solid::Mesh>(std::move(v), std::move(t), std::move(faces));
}

const Eigen::AlignedBox3d kBlock(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(100, 100, 50));
// Over the front face (y = 0) from x = 40 to 60, reaching 10 mm out, 70 to 80 mm high.
const Eigen::AlignedBox3d kSlab(Eigen::Vector3d(40, -10, 70), Eigen::Vector3d(60, 5, 80));

scan::Planner planner(const std::vector<Eigen::AlignedBox3d>& list) {
  return scan::Planner(boxes(list), kTip, scan::Stylus{}, kMargin, 20, 0);
}

// The scanning path of a closed polyline section (corners 3 × n, the first repeated at the end,
// material on the left) with the ball of kTip.
design::ScanPath path_round(const design::Plane& plane, const Eigen::Matrix3Xd& corners) {
  design::Section s;
  s.plane = plane;
  s.polyline = corners;
  design::PathOptions po;
  po.tip_radius = kTip;
  return design::make_path(s, po);
}

// A retract up along the stylus beside the wall it scanned, the ball 0.2 mm off it (the stem, Ø1
// on a Ø2 ball, 0.7 mm) all the way up: the whole move is judged at once, by its least
// clearance.
TEST(Planner, ARetractAlongTheStylusIsJudgedByItsLeastClearance) {
  const auto p = planner({kBlock});
  const Eigen::Vector3d u = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d a(50, -1.2, 25), top(50, -1.2, 120);
  EXPECT_NEAR(p.clearance(a, u), 0.2, 1e-9);
  EXPECT_TRUE(p.clear(a, top, u, 0.15));
  EXPECT_FALSE(p.clear(a, top, u, 0.25));
  EXPECT_TRUE(p.clear(top, a, u, 0.15));  // coming down the same way

  // A slab above, at 150 to 160 mm: going up, the probe body's round top (96.5 mm above the
  // ball: the stylus is 50 mm to the body's nose, the body 40 mm from there and Ø13) meets its
  // underside when the ball is at 150 − 96.5 = 53.5 mm.
  const auto over = planner(
      {kBlock, Eigen::AlignedBox3d(Eigen::Vector3d(40, -10, 150), Eigen::Vector3d(60, 5, 160))});
  EXPECT_FALSE(over.clear(a, top, u, 0.1));
  EXPECT_TRUE(over.clear(a, Eigen::Vector3d(50, -1.2, 53.5 - 0.1 - 0.05), u, 0.1));
  EXPECT_FALSE(over.clear(a, Eigen::Vector3d(50, -1.2, 53.5 - 0.1 + 0.05), u, 0.1));
  // A ball whose whole way is inside the part is not clear.
  EXPECT_FALSE(p.clear(Eigen::Vector3d(50, 50, 10), Eigen::Vector3d(50, 50, 40), u, 0.1));
  // Nor one that ends on the table.
  EXPECT_FALSE(p.clear(Eigen::Vector3d(-20, -20, 30), Eigen::Vector3d(-20, -20, 0.5), u, 0.1));
}

// Scanning round the block at z = 25 with the stylus vertical: the slab over the front face
// blocks the probe body (Ø13, from 56.5 to 90 mm above the ball on its axis, so its lower end is
// 1.5 mm above the slab's top) wherever it comes within the reach of the slab, and, for a part
// that may stand the margin off its design, that much further on either side. Everything else is
// reachable.
TEST(Planner, AnOverhangBlocksTheStretchUnderItAndTheMarginBesideIt) {
  Eigen::Matrix3Xd corners(3, 5);
  corners << 0, 100, 100, 0, 0, 0, 0, 100, 100, 0, 25, 25, 25, 25, 25;
  const auto path = path_round({Eigen::Vector3d(0, 0, 25), Eigen::Vector3d::UnitZ()}, corners);
  const Eigen::Vector3d u = Eigen::Vector3d::UnitZ();

  EXPECT_TRUE(planner({kBlock}).unreachable(path, u).empty());

  const auto blocked = planner({kBlock, kSlab}).unreachable(path, u);
  ASSERT_EQ(blocked.size(), 1u);
  const auto from = path.at(blocked[0].from).p, to = path.at(blocked[0].to).p;
  // Across the slab's x-edges: the body's end at 25 + 56.5 = 81.5 mm, 1.5 mm above the slab.
  const double body = 6.5 + kReach, above = 25 + 56.5 - 80;
  const double beside = std::sqrt(body * body - above * above);
  EXPECT_NEAR(std::min(from.x(), to.x()), 40 - beside - kMargin, kEdge) << blocked[0].why;
  EXPECT_NEAR(std::max(from.x(), to.x()), 60 + beside + kMargin, kEdge) << blocked[0].why;
  EXPECT_NEAR(from.y(), -(kTip - design::PathOptions{}.pushing), 1e-6);
  EXPECT_NEAR(to.y(), -(kTip - design::PathOptions{}.pushing), 1e-6);
  // The first place met is blocked only for a part off its design.
  EXPECT_NE(blocked[0].why.find("probe body would run into the part if the part stood off"),
            std::string::npos)
      << blocked[0].why;
}

// Scanning the block in the vertical plane y = 0 with the stylus vertical, over its top: a post
// stands on the top at x = 48 to 52, off the plane by `gap`. A part that is off its design across
// the plane (up to the margin, as a move on the table takes it) brings the post onto the ball
// and stylus unless it stands farther off than the margin and the ball's radius (and the reach);
// the plane does not cross the post, so the ball may not touch it. In a horizontal plane the
// part rests on the table: nothing is looked for across it.
TEST(Planner, APostBesideAVerticalPlaneBlocksThePathForAPartOffAcrossThePlane) {
  // Counter-clockwise seen from +y (material on the left): in the plane's (x, -z) frame.
  Eigen::Matrix3Xd corners(3, 5);
  corners << 0, 0, 100, 100, 0, 0, 0, 0, 0, 0, 0, 50, 50, 0, 0;
  const auto path = path_round({Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitY()}, corners);
  const Eigen::Vector3d u = Eigen::Vector3d::UnitZ();
  // The path over the top is above it (its normal away from the material).
  ASSERT_GT(path.at(path.length() * 0.375).normal.z(), 0.99);
  const Eigen::AlignedBox3d block(Eigen::Vector3d(0, -50, 0), Eigen::Vector3d(100, 50, 50));
  auto post = [](double gap) {
    return Eigen::AlignedBox3d(Eigen::Vector3d(48, gap, 50), Eigen::Vector3d(52, gap + 4, 80));
  };
  // Whether the path over the post's x is blocked, and why.
  auto over_post = [&](const std::vector<scan::Planner::Blocked>& blocked) -> std::string {
    for (const auto& b : blocked)
      for (double a = b.from; a <= b.to; a += 0.25) {
        const Eigen::Vector3d p = path.at(a).p;
        if (p.z() > 50 && std::abs(p.x() - 50) < 1) return b.why;
      }
    return "";
  };
  EXPECT_EQ(over_post(planner({block}).unreachable(path, u)), "");
  const double beyond = kMargin + kTip + kReach;  // the post no placement brings to the ball
  EXPECT_EQ(over_post(planner({block, post(beyond + 0.1)}).unreachable(path, u)), "");
  const std::string why = over_post(planner({block, post(beyond - 0.1)}).unreachable(path, u));
  EXPECT_NE(why.find("if the part stood off its design"), std::string::npos) << why;

  // A horizontal plane 1 mm under the block's top: a part that stood higher would be cut above
  // its top (no wall, the ball pushed on over the top face), but the part rests on the table.
  corners << 0, 100, 100, 0, 0, -50, -50, 50, 50, -50, 49, 49, 49, 49, 49;
  EXPECT_TRUE(
      planner({block}).unreachable(path_round({Eigen::Vector3d(0, 0, 49), u}, corners), u).empty());
}

// A free move past a tall post (20 × 20 mm, 200 mm high), from one side of it to the other at
// 25 mm: over the top, the stylus would rise 196 mm and come down as far. A CMM program goes
// round beside the post at the move's own level instead, each leg keeping the margin (the probe
// body, Ø13, as well as the ball). The caller's cost chooses among the ways; the first move of a
// run, which does not trust where the machine stands, still rises first.
TEST(Planner, AMovePastATallPostGoesRoundItAtItsLevelWhereThatCostsLess) {
  const auto p =
      planner({Eigen::AlignedBox3d(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(20, 20, 200))});
  const Eigen::Vector3d u = Eigen::Vector3d::UnitZ(), a(-10, 10, 25), b(30, 10, 25);
  ASSERT_FALSE(p.clear(a, b, u, kMargin));
  auto length = [&](const std::vector<Eigen::Vector3d>& way) {
    return scan::Planner::length(a, way);
  };
  const auto round = p.route(a, b, u);
  ASSERT_FALSE(round.empty());
  EXPECT_LT((round.back() - b).norm(), 1e-12);
  Eigen::Vector3d at = a;
  for (const Eigen::Vector3d& q : round) {
    EXPECT_NEAR(q.z(), 25, 1e-9);
    EXPECT_TRUE(p.clear(at, q, u, kMargin)) << q.transpose();
    at = q;
  }
  // Over the top: up to the post's top, the ball's radius and the 20 mm clearance, and down.
  const double top = 200 + kTip + 20;
  const double over = 2 * (top - 25) + (b - a).norm();
  EXPECT_LT(length(round), over);

  const auto first = p.route(a, b, u, true);
  ASSERT_EQ(first.size(), 3u);
  EXPECT_NEAR(first[0].z(), top, 1e-9);
  EXPECT_NEAR(length(first), over, 1e-9);

  // A cost that counts only the time spent below 100 mm (say, where something else stands).
  const auto high = p.route(a, b, u, false, [&](const std::vector<Eigen::Vector3d>& way) {
    double low = 0;
    Eigen::Vector3d from = a;
    for (const Eigen::Vector3d& q : way) {
      if (std::max(from.z(), q.z()) < 100) low += (q - from).norm();
      from = q;
    }
    return low;
  });
  ASSERT_EQ(high.size(), 3u);
  EXPECT_NEAR(high[0].z(), top, 1e-9);
}

}  // namespace
}  // namespace trueaxis
