// Ball-gauge calibration (Oya, Hokari, Tamura 1988) on the virtual CMM: their 3-2-1 alignment,
// stitching through several placements, and refusals.
#include "trueaxis/ballgauge/ballgauge.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <map>

#include "../test_util.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/sim/ballgauge.hpp"

using namespace trueaxis;

namespace {

// A 5 × 4 × 2 ball frame at 80 mm pitch; balls 0, 1, 2 at (0,0,0), (80,0,0), (0,80,0).
ballgauge::Gauge frame_gauge() {
  ballgauge::Gauge g;
  g.ball_diameter = 25;
  g.balls = {{0, 0, 0}, {80, 0, 0}, {0, 80, 0}};
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 5; ++i) {
        const Eigen::Vector3d b(80.0 * i, 80.0 * j, 80.0 * k);
        if ((b - g.balls[0]).norm() > 0 && (b - g.balls[1]).norm() > 0 &&
            (b - g.balls[2]).norm() > 0)
          g.balls.push_back(b);
      }
  return g;
}

// Oya, Hokari and Tamura's layout: four z sections from three placements, each shifted up by one
// pitch.
std::vector<sim::GaugePose> poses() {
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.004, Eigen::Vector3d(0.2, -0.1, 1).normalized()).toRotationMatrix();
  std::vector<sim::GaugePose> p;
  for (int k = 0; k < 3; ++k) {
    sim::GaugePose q;
    q.name = fmt::format("z{}", k);
    q.alignment = k == 0 ? ballgauge::Alignment::ThreeTwoOne : ballgauge::Alignment::Stitch;
    q.rotation = R;
    q.translation = Eigen::Vector3d(150, 120, 60) + R * Eigen::Vector3d(0, 0, 80.0 * k);
    p.push_back(q);
  }
  return p;
}

sim::Machine cmm() {
  sim::MachineOptions o;
  o.seed = 5;
  return sim::random_machine(o);
}

}  // namespace

TEST(BallGauge, NoiseFreeStitchedMapEqualsTheTruthUpToTheAlignmentFrame) {
  const auto g = frame_gauge();
  const auto c = sim::simulate_ballgauge(cmm(), g, poses(), {});
  const auto r = ballgauge::calibrate(g, c.placements);
  ASSERT_EQ(r.points.size(), 80u);  // 5 × 4 × 4, as in Oya, Hokari and Tamura (1988)
  ASSERT_TRUE(r.grid.has_value());
  EXPECT_EQ(r.grid->size(0), 5);
  EXPECT_EQ(r.grid->size(2), 4);
  EXPECT_EQ(r.placements[1].shared, 20);
  EXPECT_LT(r.placements[2].registration_rms, 1e-12);
  // The 3-2-1 conditions hold exactly.
  EXPECT_LT(r.points[0].error.norm(), 1e-15);
  // Truth: the true centres. The map's nominal positions (x − Δ) are those centres in the frame
  // the 3-2-1 alignment chooses, so one exact rigid motion (Eigen's Umeyama, independent of the
  // library's Kabsch) must carry the truth onto them to round-off.
  std::map<std::pair<std::string, int>, Eigen::Vector3d> truth;
  for (std::size_t p = 0; p < c.placements.size(); ++p)
    for (std::size_t b = 0; b < c.placements[p].balls.size(); ++b)
      truth[{c.placements[p].name, c.placements[p].balls[b].index}] = c.true_centres[p][b];
  const auto n = static_cast<Eigen::Index>(r.points.size());
  Eigen::Matrix3Xd X(3, n), Xmap(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto& mp = r.points[static_cast<std::size_t>(i)];
    X.col(i) = truth.at({mp.placement, mp.ball});
    Xmap.col(i) = mp.nominal;
  }
  // (With dynamic sizes: GCC 12 compiling Eigen's fixed-size umeyama for AVX2 takes a 4-wide copy
  // of a 3-vector for a read past its end, -Warray-bounds.)
  const Eigen::Matrix4d T = Eigen::umeyama(Eigen::MatrixXd(X), Eigen::MatrixXd(Xmap), false);
  const Eigen::Matrix3Xd moved = (T.topLeftCorner<3, 3>() * X).colwise() + T.topRightCorner<3, 1>();
  EXPECT_LT((moved - Xmap).cwiseAbs().maxCoeff(), 1e-11);  // mm
  EXPECT_GT((X - Xmap).cwiseAbs().maxCoeff(), 1e-4);       // the frames really differ
}

TEST(BallGauge, ProbingNoisePropagatesToTheStatedUncertainty) {
  // The map from noisy probing against the noise-free map of the same placements: the deviation
  // of every component, over all points and several seeds, against its stated uncertainty. The
  // uncertainty must grow with the stitches.
  const auto g = frame_gauge();
  const auto m = cmm();
  const auto exact = ballgauge::calibrate(g, sim::simulate_ballgauge(m, g, poses(), {}).placements);
  std::vector<double> z;
  double u_first = 0, u_last = 0;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    sim::BallGaugeOptions o;
    o.noise = 0.5e-3;
    o.seed = seed;
    const auto r = ballgauge::calibrate(g, sim::simulate_ballgauge(m, g, poses(), o).placements);
    ASSERT_EQ(r.points.size(), exact.points.size());
    for (std::size_t i = 0; i < r.points.size(); ++i)
      for (int k = 0; k < 3; ++k)
        if (r.points[i].uncertainty[k] > 0)
          z.push_back((r.points[i].error[k] - exact.points[i].error[k]) /
                      r.points[i].uncertainty[k]);
    u_first += r.points[5].uncertainty.norm();
    u_last += r.points.back().uncertainty.norm();
  }
  double ss = 0, inside = 0;
  for (double v : z) {
    ss += v * v;
    inside += std::abs(v) <= 2;
  }
  const double rms = std::sqrt(ss / static_cast<double>(z.size()));
  EXPECT_GT(rms, 0.6);
  EXPECT_LT(rms, 1.4);
  EXPECT_GT(inside / static_cast<double>(z.size()), 0.85);
  EXPECT_GT(u_last, u_first);  // two stitches away from the 3-2-1 placement
  std::printf("ball gauge noise: RMS z %.2f, within 2u %.3f, u first %.3f µm, last %.3f µm\n", rms,
              inside / static_cast<double>(z.size()), u_first / 6 * 1e3, u_last / 6 * 1e3);
}

TEST(BallGauge, LeastSquaresAlignmentHasNoRigidErrorAndSmallerUncertainty) {
  const auto g = frame_gauge();
  const auto m = cmm();
  auto ps = poses();
  ps[0].alignment = ballgauge::Alignment::LeastSquares;
  sim::BallGaugeOptions o;
  o.noise = 0.5e-3;
  const auto ls = ballgauge::calibrate(g, sim::simulate_ballgauge(m, g, ps, o).placements);
  const auto t321 = ballgauge::calibrate(g, sim::simulate_ballgauge(m, g, poses(), o).placements);
  // The first placement's errors have no translation left (their mean is zero) ...
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int i = 0; i < 40; ++i) mean += ls.points[static_cast<std::size_t>(i)].error;
  EXPECT_LT((mean / 40).norm(), 1e-12);
  // ... and the uncertainty of the whole map is far smaller than with three balls' lever arms.
  double u_ls = 0, u_321 = 0;
  for (std::size_t i = 0; i < ls.points.size(); ++i) {
    u_ls = std::max(u_ls, ls.points[i].uncertainty.maxCoeff());
    u_321 = std::max(u_321, t321.points[i].uncertainty.maxCoeff());
  }
  EXPECT_LT(u_ls, 0.5 * u_321);
  std::printf("largest uncertainty: LS alignment %.3f µm, 3-2-1 %.3f µm\n", u_ls * 1e3,
              u_321 * 1e3);
  // Noise-free, the LS-aligned map is the truth up to one rigid motion, as for 3-2-1.
  o.noise = 0;
  const auto exact = ballgauge::calibrate(g, sim::simulate_ballgauge(m, g, ps, o).placements);
  const auto c = sim::simulate_ballgauge(m, g, ps, o);
  Eigen::Matrix3Xd X(3, 80), Xmap(3, 80);
  for (int i = 0; i < 80; ++i) {
    const auto& mp = exact.points[static_cast<std::size_t>(i)];
    const std::size_t pl = static_cast<std::size_t>(mp.placement.back() - '0');
    for (std::size_t b = 0; b < c.placements[pl].balls.size(); ++b)
      if (c.placements[pl].balls[b].index == mp.ball) X.col(i) = c.true_centres[pl][b];
    Xmap.col(i) = mp.nominal;
  }
  // (With dynamic sizes: GCC 12 compiling Eigen's fixed-size umeyama for AVX2 takes a 4-wide copy
  // of a 3-vector for a read past its end, -Warray-bounds.)
  const Eigen::Matrix4d T = Eigen::umeyama(Eigen::MatrixXd(X), Eigen::MatrixXd(Xmap), false);
  const Eigen::Matrix3Xd moved = (T.topLeftCorner<3, 3>() * X).colwise() + T.topRightCorner<3, 1>();
  EXPECT_LT((moved - Xmap).cwiseAbs().maxCoeff(), 1e-11);
}

// The 3-2-1 alignment belongs to the gauge, not to the machine's axes: ball 0 fixed, ball 1 free
// only along 0→1, ball 2 only in the plane of balls 0, 1, 2. With ball 0→1 along machine y the
// machine-component form of the conditions reported 1.83 mm errors for balls whose true errors are
// a few µm, with exit 0; vertical placements were refused. Every placement below, flat, on its
// side, upright or oblique, must give the machine's errors up to the alignment's rigid motion.
TEST(BallGauge, ThreeTwoOneHoldsInEveryOrientationOfTheGauge) {
  constexpr double kRoundOff = 1e-10;  // mm: noise-free, exact rotations
  const auto g = frame_gauge();
  const auto machine = cmm();
  const Eigen::Vector3d X = Eigen::Vector3d::UnitX(), Y = Eigen::Vector3d::UnitY(),
                        Z = Eigen::Vector3d::UnitZ();
  auto frame = [](const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
    Eigen::Matrix3d R;  // gauge U, V, W → machine
    R << u, v, u.cross(v);
    return R;
  };
  const std::vector<std::pair<std::string, Eigen::Matrix3d>> orientations = {
      {"U along x, V along y (as in Oya, Hokari and Tamura)", frame(X, Y)},
      {"U along y, V along -x", frame(Y, -X)},
      {"U along -x, V along -y", frame(-X, -Y)},
      {"XZ plate: U along x, V along z", frame(X, Z)},
      {"YZ plate: U along y, V along z", frame(Y, Z)},
      {"ZY plate: U along z, V along y", frame(Z, Y)},
      {"oblique", Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix()},
  };
  for (const auto& [what, R] : orientations) {
    SCOPED_TRACE(what);
    // Placed inside the machine's volume: the rotated gauge's lowest corner at (100, 100, 60).
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9);
    for (const auto& b : g.balls) lo = lo.cwiseMin(R * b);
    sim::GaugePose pose;
    pose.name = "p";
    pose.alignment = ballgauge::Alignment::ThreeTwoOne;
    pose.rotation = R;
    pose.translation = Eigen::Vector3d(100, 100, 60) - lo;
    const auto c = sim::simulate_ballgauge(machine, g, {pose}, {});
    const auto r = ballgauge::calibrate(g, c.placements);
    ASSERT_EQ(r.points.size(), g.balls.size());
    // The machine's own errors at the balls, and the map's.
    double true_max = 0, map_max = 0;
    const auto n = static_cast<Eigen::Index>(r.points.size());
    Eigen::MatrixXd truth(3, n), nominal(3, n);
    for (Eigen::Index i = 0; i < n; ++i) {
      const auto& mp = r.points[static_cast<std::size_t>(i)];
      const auto b = static_cast<std::size_t>(i);
      ASSERT_EQ(c.placements[0].balls[b].index, mp.ball);
      truth.col(i) = c.true_centres[0][b];
      nominal.col(i) = mp.nominal;
      true_max = std::max(true_max, (mp.measured - c.true_centres[0][b]).norm());
      map_max = std::max(map_max, mp.error.norm());
    }
    // The nominal positions are the true centres moved rigidly (the frame the alignment picks).
    const Eigen::Matrix4d T = Eigen::umeyama(truth, nominal, false);
    const Eigen::MatrixXd moved =
        (T.topLeftCorner<3, 3>() * truth).colwise() + Eigen::Vector3d(T.topRightCorner<3, 1>());
    EXPECT_LT((moved - nominal).cwiseAbs().maxCoeff(), kRoundOff);
    // That motion is of the size of the machine's errors over the gauge, not millimetres: the
    // map's errors stay within a few times the true ones (µm here).
    EXPECT_GT(true_max, 1e-3);
    EXPECT_LT(map_max, 10 * true_max) << "map " << map_max * 1e3 << " µm, true " << true_max * 1e3;
    // The 3-2-1 conditions in the gauge's frame.
    auto at = [&](int ball) {
      for (const auto& mp : r.points)
        if (mp.ball == ball) return mp;
      ADD_FAILURE() << "ball " << ball << " not mapped";
      return ballgauge::MapPoint{};
    };
    const auto b0 = at(0), b1 = at(1), b2 = at(2);
    EXPECT_LT(b0.error.norm(), kRoundOff);
    const Eigen::Vector3d u = (b1.measured - b0.measured).normalized();
    EXPECT_LT(b1.error.cross(u).norm(), kRoundOff);  // along 0→1 only
    const Eigen::Vector3d w = u.cross(b2.measured - b0.measured).normalized();
    EXPECT_LT(std::abs(b2.error.dot(w)), kRoundOff);  // in the plane of balls 0, 1, 2
  }
}

TEST(BallGauge, BadPlacementsAreRefusedWithTheReason) {
  const auto g = frame_gauge();
  auto c = sim::simulate_ballgauge(cmm(), g, poses(), {});
  auto err = [&](const std::vector<ballgauge::Placement>& p) {
    return test::error_of([&] { ballgauge::calibrate(g, p); });
  };
  auto p = c.placements;
  p[1].balls[3].index = 99;
  EXPECT_NE(err(p).find("z1: ball index 99 is not in the gauge"), std::string::npos) << err(p);
  p = c.placements;
  p[0].balls[4].points.conservativeResize(3, 3);
  EXPECT_NE(err(p).find("z0: ball 4 has 3 probed points; at least 5"), std::string::npos);
  p = c.placements;
  p[0].alignment = ballgauge::Alignment::Stitch;
  EXPECT_NE(err(p).find("first placement must define the frame"), std::string::npos);
  p = c.placements;
  std::swap(p[1], p[2]);  // z2 does not overlap z0
  EXPECT_NE(err(p).find("z2: 0 of its balls lie within 1 mm of points mapped in its frame"),
            std::string::npos)
      << err(p);
  // An aligned placement after the first starts a frame of its own, and the stitch after it
  // joins that frame only.
  p = c.placements;
  p[1].alignment = ballgauge::Alignment::LeastSquares;
  {
    const auto r = ballgauge::calibrate(g, p);
    EXPECT_EQ(r.frames, 2);
    EXPECT_EQ(r.points.back().frame, 1);
    EXPECT_FALSE(r.grid);
  }
  // z0 aligned, z2 aligned anew, then z0 again stitched: it overlaps the first frame only.
  p = {c.placements[0], c.placements[2], c.placements[0]};
  p[1].alignment = ballgauge::Alignment::LeastSquares;
  p[2].alignment = ballgauge::Alignment::Stitch;
  EXPECT_NE(err(p).find("z0: 0 of its balls lie within 1 mm of points mapped in its frame"),
            std::string::npos)
      << err(p);
  // A stitch probed with another stylus than its frame's sees other errors (the angular errors
  // move each tip by its own arm): refused. The same stylus stated on both is accepted.
  p = c.placements;
  p[0].stylus_offset = Eigen::Vector3d(0, 0, -100);
  p[1].stylus_offset = Eigen::Vector3d(0, 120, 0);
  EXPECT_NE(err(p).find("z1: probed with the stylus offset (0, 120, 0) mm, but its frame (z0) with "
                        "(0, 0, -100) mm"),
            std::string::npos)
      << err(p);
  p[1].stylus_offset = p[0].stylus_offset;
  EXPECT_EQ(ballgauge::calibrate(g, p).frames, 1);
  p = c.placements;
  p[0].balls.erase(p[0].balls.begin() + 1);  // ball 1 missing from the 3-2-1 placement
  EXPECT_NE(err(p).find("needs the gauge's frame balls 0, 1 and 2 measured"), std::string::npos);
  p = c.placements;
  p[2].balls.push_back(p[2].balls[0]);
  EXPECT_NE(err(p).find("is measured twice"), std::string::npos);
  p = c.placements;
  std::swap(p[0].balls[1].index, p[0].balls[3].index);  // numbered unlike the gauge file
  EXPECT_NE(err(p).find("3-2-1 alignment: balls 0 and 1 are measured"), std::string::npos)
      << err(p);
  EXPECT_NE(err(p).find("are the balls numbered as in the gauge file?"), std::string::npos);
  ballgauge::Gauge bad = g;
  bad.balls[2] = {160, 0, 0};  // where another ball of the frame is
  EXPECT_NE(test::error_of([&] { bad.validate(); }).find("balls 2 and "), std::string::npos);
  EXPECT_NE(test::error_of([&] { bad.validate(); }).find("are at the same place"),
            std::string::npos);
}

// Found by fuzzing: one wrong touch (a probed point 11 m off) gave a map with 11 m errors and
// only a warning. It is now refused, naming the point, or left out on request with the map as
// good as without it.
TEST(BallGauge, AWrongTouchIsRefusedOrLeftOutByName) {
  const auto g = sim::frame_gauge();
  sim::BallGaugeOptions so;
  so.noise = 0.5e-3;
  const auto c = sim::simulate_ballgauge(cmm(), g, poses(), so);
  const auto clean = ballgauge::calibrate(g, c.placements);
  auto bad = c.placements;
  bad[1].balls[7].points(0, 3) += 11000;  // one point 11 m off
  const std::string m = test::error_of([&] { ballgauge::calibrate(g, bad); });
  EXPECT_EQ(m.find(fmt::format("{}: ball {}: point 4 is 1.098e+04 mm off the sphere through the "
                               "other 9 points",
                               bad[1].name, bad[1].balls[7].index)),
            0u)
      << m;
  EXPECT_NE(m.find("--drop-outliers"), std::string::npos);
  ballgauge::Options o;
  o.drop_outliers = true;
  const auto r = ballgauge::calibrate(g, bad, o);
  ASSERT_EQ(r.placements[1].dropped.size(), 1u);
  EXPECT_NE(r.summary().find("point 4 is"), std::string::npos);
  double worst = 0;
  for (std::size_t i = 0; i < r.points.size(); ++i)
    worst = std::max(worst, (r.points[i].error - clean.points[i].error).norm());
  EXPECT_LT(worst, 3 * 0.5e-3);  // one point fewer on one ball: a probing-noise-sized change
  // Ordinary scatter is no wrong touch: the clean data pass the default tolerance untouched.
  for (const auto& p : clean.placements) EXPECT_TRUE(p.dropped.empty());
}
