// What touch points tell of where the whole part stands (fit_part_move): the rigid fit handed on
// to other sections, whether the feet tell a move from a scale and see a turn, and the turn's
// uncertainty. Touched points are the feet moved by a known map, so the answers are known.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "../../src/scan/section.hpp"
#include "trueaxis/scan/controller.hpp"

namespace trueaxis {
namespace {

// Resolutions are ratios of singular values: a combination of parameters the feet do not see
// at all comes out at round-off.
constexpr double kUnseen = 1e-6;
// Noise-free touched points: the fitted turn to the fit's own convergence, and the map to
// round-off.
constexpr double kTurnDeg = 1e-6;
constexpr double kSameMap = 1e-9;  // mm

design::Section rectangle() {
  design::Section s;
  s.name = "rectangle";
  s.plane = {Eigen::Vector3d(0, 0, 10), Eigen::Vector3d::UnitZ()};
  s.polyline.resize(3, 5);
  s.polyline << 0, 80, 80, 0, 0, 0, 0, 30, 30, 0, 10, 10, 10, 10, 10;
  return s;
}

design::Section circle(double r) {
  design::Section s;
  s.name = "hole";
  s.plane = {Eigen::Vector3d(0, 0, 10), Eigen::Vector3d::UnitZ()};
  s.material = design::Side::Right;
  const int n = 361;
  s.polyline.resize(3, n);
  for (int i = 0; i < n; ++i) {
    const double t = 2 * M_PI * i / (n - 1);
    s.polyline.col(i) << r * std::cos(t), r * std::sin(t), 10;
  }
  return s;
}

// An open stretch: one 178 mm wall between two 2.8 mm legs.
design::Section u_stretch() {
  design::Section u;
  u.name = std::string("U");
  u.closed = false;
  u.plane = {Eigen::Vector3d(0, 0, 10), Eigen::Vector3d::UnitZ()};
  u.polyline.resize(3, 4);
  u.polyline << -89, -89, 89, 89, -76.7, -79.5, -79.5, -76.7, 10, 10, 10, 10;
  return u;
}

// Feet at `count` places along the sides from..to of a polyline (a side k runs from vertex k).
Eigen::Matrix3Xd feet_on(const design::Section& s, int from, int to, int per_side) {
  Eigen::Matrix3Xd f(3, (to - from) * per_side);
  for (int k = from; k < to; ++k)
    for (int j = 0; j < per_side; ++j) {
      const double u = (j + 0.5) / per_side;
      f.col((k - from) * per_side + j) =
          s.polyline.col(k) + u * (s.polyline.col(k + 1) - s.polyline.col(k));
    }
  return f;
}

// The feet moved as a part turned `deg` about `centre` and moved by `t` (in the plane).
Eigen::Matrix3Xd moved(const Eigen::Matrix3Xd& feet, double deg, const Eigen::Vector3d& centre,
                       const Eigen::Vector3d& t) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(deg * M_PI / 180, Eigen::Vector3d::UnitZ()).matrix();
  return (R * (feet.colwise() - centre)).colwise() + (centre + t);
}

// A 20 × 30 mm rectangle, two feet on each side, touched on the part moved 1.8 mm, -1.1 mm and
// turned 0.3° about its centre.
struct TurnedRectangle {
  design::Section small = [] {
    design::Section s = rectangle();
    s.polyline.row(0) *= 0.25;
    return s;
  }();
  Eigen::Vector3d t{1.8, -1.1, 0}, c{10, 15, 10};
  Eigen::Matrix3Xd feet = feet_on(small, 0, 4, 2);
  Eigen::Matrix3Xd touched = moved(feet, 0.3, c, t);
};

double turn_of(const scan::Correction& c) {
  for (const auto& [k, v] : c.parameters)
    if (k == "rotation_deg") return v;
  return NAN;
}

TEST(PartMove, ACornerOrAWallDoesNotTellAMoveFromAScaleAWholeOutlineDoes) {
  const auto rect = rectangle();
  const Eigen::Vector3d t(1.8, -1.1, 0), c(40, 15, 10);
  // One straight wall: a move along it is not seen.
  const auto wall = feet_on(rect, 0, 1, 6);
  EXPECT_LT(scan::fit_part_move(rect, wall, moved(wall, 0, c, t), 0.05).resolution, kUnseen);
  // Two walls at a corner: a scale about the corner's point is a move.
  const auto corner = feet_on(rect, 0, 2, 4);
  EXPECT_LT(scan::fit_part_move(rect, corner, moved(corner, 0, c, t), 0.05).resolution, kUnseen);
  // Three walls (an open stretch round two corners) and the whole outline tell them apart.
  const auto three = feet_on(rect, 0, 3, 3);
  EXPECT_GT(scan::fit_part_move(rect, three, moved(three, 0, c, t), 0.05).resolution, 0.1);
  const auto all = feet_on(rect, 0, 4, 2);
  EXPECT_GT(scan::fit_part_move(rect, all, moved(all, 0, c, t), 0.05).resolution, 0.1);
}

// A 20 × 30 mm rectangle's touch points fit a move within 0.1 mm when the part is also turned
// 0.3°, so a menu accepting 0.1 mm takes the move; handed on to a section 130 mm away, the turn
// left out would put it 0.68 mm off. The rigid fit has the turn, far beyond its uncertainty.
TEST(PartMove, TheRigidFitHasTheTurnAMoveLeavesOutWithItsUncertainty) {
  const TurnedRectangle r;
  const auto& [small, t, c, feet, touched] = r;
  design::Section corrected;
  const auto menu = scan::fit_corrections(small, feet, touched, 0.1, &corrected);
  ASSERT_FALSE(menu.empty());
  EXPECT_TRUE(menu.front().accepted);
  EXPECT_EQ(menu.front().type, "translation");

  const auto pm = scan::fit_part_move(small, feet, touched, 0.1);
  ASSERT_TRUE(pm.rigid.accepted);
  EXPECT_GT(pm.turn_resolution, 0.1);
  EXPECT_NEAR(turn_of(pm.rigid), 0.3, kTurnDeg);
  // Noise-free: the uncertainty is the 0.1 µm floor's, far below the turn.
  ASSERT_TRUE(std::isfinite(pm.turn_u));
  EXPECT_GT(pm.turn_u, 0);
  EXPECT_GT(std::abs(turn_of(pm.rigid)), 100 * pm.turn_u);
  // The map itself: a far point goes where the turned and moved part takes it.
  const Eigen::Vector3d far(140, 15, 10);
  const Eigen::Vector3d want = moved(far, 0.3, c, t).col(0);
  EXPECT_LT((pm.rigid.transform * far - want).norm(), kSameMap);
}

// Round a circle no turn about its centre moves a touch point: the turn is not seen, and a fit
// that would wind round the centre is reported as diverged, never handed on as a turn.
TEST(PartMove, RoundACircleNoTurnIsSeen) {
  const auto hole = circle(6);
  Eigen::Matrix3Xd feet(3, 8);
  for (int i = 0; i < 8; ++i) {
    const double a = 2 * M_PI * (i + 0.5) / 8;
    feet.col(i) << 6 * std::cos(a), 6 * std::sin(a), 10;
  }
  const auto touched = moved(feet, 0, Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 2, 0));
  const auto pm = scan::fit_part_move(hole, feet, touched, 0.05);
  EXPECT_GT(pm.resolution, 0.5);
  EXPECT_LT(pm.turn_resolution, kUnseen);
  if (pm.rigid.diverged.empty()) {
    EXPECT_LE(std::abs(turn_of(pm.rigid)), 45);
  }
}

TEST(PartMove, TooFewTouchPointsForATurnSaySo) {
  const auto rect = rectangle();
  const auto feet = feet_on(rect, 0, 4, 1);
  const auto pm = scan::fit_part_move(rect, feet, feet, 0.05);
  EXPECT_FALSE(pm.rigid.accepted);
  EXPECT_FALSE(pm.rigid.diverged.empty());
  EXPECT_TRUE(std::isnan(pm.turn_u));
}

// An open stretch that is one 178 mm wall between two 2.8 mm legs (CTC 05's reachable stretch at
// z = 178.6 mm): evenly spread touch points all fall on the wall, which does not see a move
// along it. The places then go where the move, turn and scale are told apart: some on each leg,
// each 1 mm clear of the ends and of each other. A whole rectangle keeps its even places.
TEST(PartMove, TouchPointsGoWhereTheyTellTheMoveAlongAWall) {
  const design::Section u = u_stretch();
  const auto places = scan::detail::touch_places(u, 8, 0.1);
  EXPECT_LT(places.even_resolution, kUnseen);
  ASSERT_FALSE(places.even);
  EXPECT_GE(places.resolution, 0.1);
  ASSERT_EQ(places.arcs.size(), 8u);
  const double L = 2.8 + 178 + 2.8;
  int on_legs = 0;
  for (std::size_t i = 0; i < places.arcs.size(); ++i) {
    const double a = places.arcs[i];
    EXPECT_GE(a, 1 - 1e-9);
    EXPECT_LE(a, L - 1 + 1e-9);
    if (i > 0) {
      EXPECT_GE(a - places.arcs[i - 1], 1 - 1e-9);
    }
    on_legs += a < 2.8 || a > L - 2.8;
  }
  EXPECT_GE(on_legs, 2);
  // The fit on those places sees the move along the wall: a part moved 1.8 mm along it and
  // 1.1 mm across is corrected by that move.
  const auto smp = design::sample(u, 0.25);
  Eigen::Matrix3Xd feet(3, 8);
  for (int i = 0; i < 8; ++i) {
    Eigen::Index j = 0;
    (smp.arc.array() - places.arcs[static_cast<std::size_t>(i)]).abs().minCoeff(&j);
    feet.col(i) = smp.points.col(j);
  }
  const Eigen::Vector3d t(1.8, -1.1, 0);
  const auto touched = moved(feet, 0, Eigen::Vector3d::Zero(), t);
  design::Section corrected;
  const auto menu = scan::fit_corrections(u, feet, touched, 0.05, &corrected);
  ASSERT_FALSE(menu.empty());
  EXPECT_TRUE(menu.front().accepted);
  EXPECT_LT((menu.front().transform.translation() - t).norm(), kSameMap);

  const auto rect = scan::detail::touch_places(rectangle(), 8, 0.1);
  EXPECT_TRUE(rect.even);
  EXPECT_GE(rect.resolution, 0.1);
}

// The menu gives the same part move as fit_part_move, without fitting again: with a move as its
// choice (the turn fitted on top), and with a turn as its choice (that turn itself).
TEST(PartMove, TheMenuGivesThePartMoveItsTouchPointsTell) {
  const TurnedRectangle r;
  const auto& [small, t, c, feet, touched] = r;
  for (const double accept : {0.1, 0.01}) {
    scan::PartMove from_menu;
    design::Section corrected;
    const auto menu = scan::fit_corrections(small, feet, touched, accept, &corrected, &from_menu);
    ASSERT_TRUE(menu.back().accepted);
    EXPECT_EQ(menu.back().type, accept == 0.1 ? "translation" : "rotation");
    const auto alone = scan::fit_part_move(small, feet, touched, accept);
    ASSERT_TRUE(from_menu.rigid.accepted) << accept;
    EXPECT_NEAR(turn_of(from_menu.rigid), turn_of(alone.rigid), kTurnDeg);
    EXPECT_NEAR(from_menu.turn_u, alone.turn_u, 1e-3 * alone.turn_u);
    EXPECT_EQ(from_menu.resolution, alone.resolution);
    EXPECT_EQ(from_menu.turn_resolution, alone.turn_resolution);
    const Eigen::Vector3d far(140, 15, 10);
    EXPECT_LT((from_menu.rigid.transform * far - moved(far, 0.3, c, t).col(0)).norm(), kSameMap);
  }
}

// Two stretches of one outline cut apart by what the stylus cannot reach, each of two walls at
// a corner: neither tells a move from a scale, together they do. Pooled, their touch points give
// the part's turn and move; on a part scaled instead, no rigid move fits them, and nothing is
// told; rounds in planes that are not parallel are not pooled.
TEST(PartMove, StretchesThatCannotTellAMoveAloneTellItTogether) {
  const auto rect = rectangle();
  auto stretch = [&](int from, int to, const std::string& name) {
    design::Section s = rect;
    s.name = name;
    s.closed = false;
    s.polyline = rect.polyline.middleCols(from, to - from + 1);
    return s;
  };
  const design::Section a = stretch(0, 2, "a"), b = stretch(2, 4, "b");
  const Eigen::Vector3d t(1.8, -1.1, 0), c(40, 15, 10);
  const Eigen::Matrix3Xd fa = feet_on(rect, 0, 2, 4), fb = feet_on(rect, 2, 4, 4);
  EXPECT_LT(scan::fit_part_move(a, fa, moved(fa, 0.3, c, t), 0.05).resolution, kUnseen);
  EXPECT_LT(scan::fit_part_move(b, fb, moved(fb, 0.3, c, t), 0.05).resolution, kUnseen);
  const std::vector<scan::detail::TouchRound> rounds{{a, fa, moved(fa, 0.3, c, t)},
                                                     {b, fb, moved(fb, 0.3, c, t)}};
  const auto both = scan::detail::pooled_part_move(rounds, 0.05, "a, b");
  ASSERT_TRUE(both);
  EXPECT_TRUE(both->accepted);
  EXPECT_EQ(both->found_on, "a, b");
  EXPECT_NEAR(turn_of(*both), 0.3, kTurnDeg);
  for (const Eigen::Vector3d& far : {Eigen::Vector3d(140, 15, 10), Eigen::Vector3d(-60, 90, 10)})
    EXPECT_LT((both->transform * far - moved(far, 0.3, c, t).col(0)).norm(), kSameMap);
  EXPECT_LT(both->residual_after, kSameMap);

  // Scaled 1 % about the outline's centre: each stretch alone fits a move; together, no rigid
  // move leaves the touch points within 0.05 mm.
  auto scaled = [&](const Eigen::Matrix3Xd& f) {
    return Eigen::Matrix3Xd((1.01 * (f.colwise() - c)).colwise() + c);
  };
  EXPECT_FALSE(
      scan::detail::pooled_part_move({{a, fa, scaled(fa)}, {b, fb, scaled(fb)}}, 0.05, "a, b"));
  // A stretch in a plane at right angles is not pooled with one in the outline's plane.
  design::Section side = b;
  side.plane.normal = Eigen::Vector3d::UnitX();
  EXPECT_FALSE(scan::detail::pooled_part_move(
      {{a, fa, moved(fa, 0.3, c, t)}, {side, fb, moved(fb, 0.3, c, t)}}, 0.05, "a, side"));
  // One round alone is what part_move_of judges; too few points for a turn and a move, nothing.
  EXPECT_FALSE(scan::detail::pooled_part_move({}, 0.05, ""));
  EXPECT_FALSE(scan::detail::pooled_part_move(
      {{a, fa.leftCols(2), moved(fa.leftCols(2), 0.3, c, t)}}, 0.05, "a"));
}

// Touch places the ball cannot get to are taken to the nearest it can, never exchanged for,
// and the set still tells the move along a wall where it can.
TEST(PartMove, TouchPointsGoOnlyWhereTheBallGetsTo) {
  const design::Section u = u_stretch();
  // Nothing from x = -20 to 20 on the wall (a post over it, say).
  const auto usable = [](const Eigen::Vector3d& foot, const Eigen::Vector3d&) {
    return std::abs(foot.x()) > 20;
  };
  const auto places = scan::detail::touch_places(u, 8, 0.1, usable);
  ASSERT_EQ(places.arcs.size(), 8u);
  EXPECT_GE(places.unreachable, 1);
  EXPECT_FALSE(places.even);
  EXPECT_GE(places.resolution, 0.1);
  const auto smp = design::sample(u, 0.5);
  for (const double a : places.arcs) {
    Eigen::Index j = 0;
    (smp.arc.array() - a).abs().minCoeff(&j);
    EXPECT_GT(std::abs(smp.points(0, j)), 20 - 1e-9) << a;
  }
  // A rectangle's even places, where all are usable, stay even; where one is not, it moves.
  EXPECT_TRUE(scan::detail::touch_places(rectangle(), 8, 0.1, [](const auto&, const auto&) {
                return true;
              }).even);
  const auto moved_one = scan::detail::touch_places(
      rectangle(), 8, 0.1, [](const Eigen::Vector3d& f, const auto&) { return f.x() > 12; });
  EXPECT_FALSE(moved_one.even);
  EXPECT_GE(moved_one.unreachable, 1);
  EXPECT_EQ(moved_one.arcs.size(), 8u);
  const auto rs = design::sample(rectangle(), 0.5);
  for (const double a : moved_one.arcs) {
    Eigen::Index j = 0;
    (rs.arc.array() - a).abs().minCoeff(&j);
    EXPECT_GT(rs.points(0, j), 12 - 1e-9) << a;
  }
}

}  // namespace
}  // namespace trueaxis
