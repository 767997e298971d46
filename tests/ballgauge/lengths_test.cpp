// Gauge-block verification (ISO 10360-2 style): exact correction of an affine distortion, repeat
// groups, refusals, the gauge-block simulator, and Oya, Hokari and Tamura's (1988) before/after
// result on the virtual CMM.
#include "trueaxis/ballgauge/lengths.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <set>

#include "../test_util.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/sim/ballgauge.hpp"

using namespace trueaxis;
using test::error_of;
using test::temp_dir;
using test::temp_file;

namespace {

constexpr double kRoundOff = 1e-12;  // mm

// Oya, Hokari and Tamura's campaign: a 5 × 4 × 2 frame stacked in three sections, the first aligned
// by least squares; gauge blocks in the mapped box.
struct Campaign {
  sim::Machine machine;
  ballgauge::Result map;
  sim::GaugeBlockCampaign blocks;
};

Campaign campaign(double noise, std::uint64_t seed, double block_noise) {
  Campaign c;
  sim::MachineOptions mo;
  mo.seed = 5;
  c.machine = sim::random_machine(mo);
  const auto g = sim::frame_gauge();
  auto poses = sim::stacked_poses(
      g, 3, {150, 120, 60},
      Eigen::AngleAxisd(0.004, Eigen::Vector3d(0.2, -0.1, 1).normalized()).toRotationMatrix());
  poses.front().alignment = ballgauge::Alignment::LeastSquares;
  sim::BallGaugeOptions bo;
  bo.noise = noise;
  bo.seed = seed;
  const auto bg = sim::simulate_ballgauge(c.machine, g, poses, bo);
  c.map = ballgauge::calibrate(g, bg.placements);
  sim::GaugeBlockOptions go;
  for (int k = 0; k < 3; ++k) {
    go.lo[k] = c.map.grid->axes[static_cast<std::size_t>(k)].minCoeff();
    go.hi[k] = c.map.grid->axes[static_cast<std::size_t>(k)].maxCoeff();
  }
  go.noise = block_noise;
  go.seed = seed + 100;
  c.blocks = sim::simulate_gauge_blocks(c.machine, go);
  return c;
}

}  // namespace

TEST(Lengths, AnAffineDistortionIsCorrectedExactlyByTheTrilinearMap) {
  // Readings x = (I + A)·X + b: the error Δ(x) = x − X is affine in x, which trilinear
  // interpolation reproduces, so every corrected length is exact.
  Eigen::Matrix3d A;
  A << 20e-6, 5e-6, -3e-6, 4e-6, -10e-6, 8e-6, 2e-6, 6e-6, 15e-6;
  const Eigen::Vector3d b(3e-3, -2e-3, 1e-3);
  const Eigen::Matrix3d inv = (Eigen::Matrix3d::Identity() + A).inverse();
  std::array<Eigen::VectorXd, 3> axes{Eigen::VectorXd::LinSpaced(5, 0, 400),
                                      Eigen::VectorXd::LinSpaced(4, 0, 300),
                                      Eigen::VectorXd::LinSpaced(3, 0, 200)};
  const auto m = map::sample(
      axes, [&](const Eigen::Vector3d& x) -> Eigen::Vector3d { return x - inv * (x - b); });
  std::vector<ballgauge::LengthMeasurement> L;
  const Eigen::Vector3d ends[][2] = {{{10, 20, 30}, {390, 280, 190}},
                                     {{50, 150, 100}, {350, 150, 100}},
                                     {{200, 10, 5}, {200, 290, 195}}};
  for (const auto& e : ends) {
    ballgauge::LengthMeasurement l;
    l.a = (Eigen::Matrix3d::Identity() + A) * e[0] + b;
    l.b = (Eigen::Matrix3d::Identity() + A) * e[1] + b;
    l.nominal = (e[1] - e[0]).norm();
    L.push_back(l);
  }
  const auto v = ballgauge::verify_lengths(L, ballgauge::grid_correction(m));
  ASSERT_EQ(v.rows.size(), 3u);
  for (const auto& r : v.rows) {
    EXPECT_GT(std::abs(r.before), 1e-3);  // the distortion is visible
    EXPECT_LT(std::abs(r.after), kRoundOff);
  }
  EXPECT_EQ(v.positions, 3);
  EXPECT_TRUE(std::isnan(v.repeatability));  // no repeats
}

TEST(Lengths, RepeatsArePooledIntoTheRepeatability) {
  const ballgauge::Correction none{"none", [](Eigen::Ref<Eigen::Matrix3Xd>) {}, {}, {}};
  std::vector<ballgauge::LengthMeasurement> L;
  // Position 0: errors +1, −1, 0 µm; position 1: +2, 0 µm (both ends within 1 mm).
  const double e0[] = {1e-3, -1e-3, 0}, e1[] = {2e-3, 0};
  for (double e : e0) L.push_back({{0, 0, 0}, {100 + e, 0, 0}, 100});
  for (double e : e1) L.push_back({{0, 50, 0}, {0.5, 250 + e, 0}, 200});
  const auto v = ballgauge::verify_lengths(L, none);
  EXPECT_EQ(v.positions, 2);
  EXPECT_EQ(v.rows[3].position, 1);
  // Pooled: (1² + 1² + 0² + 1² + 1²) µm² over (2 + 1) degrees of freedom (position 1 is tilted
  // by 0.5 mm in x over 200 mm, which shortens its errors by a relative 3e-6).
  EXPECT_NEAR(v.repeatability, std::sqrt(4.0 / 3) * 1e-3, 1e-8);
  EXPECT_NEAR(v.before.max, std::hypot(0.5, 200 + 2e-3) - 200, kRoundOff);
  EXPECT_NEAR(v.before.min, -1e-3, kRoundOff);
  EXPECT_NEAR(v.predicted_after, v.repeatability, kRoundOff);  // no correction uncertainty
  // A different nominal is a different position, even at the same place.
  L.push_back({{0, 0, 0}, {100, 0, 0}, 100.5});
  EXPECT_EQ(ballgauge::verify_lengths(L, none).positions, 3);
}

TEST(Lengths, BadInputIsRefusedNamingTheRow) {
  const ballgauge::Correction none{"none", [](Eigen::Ref<Eigen::Matrix3Xd>) {}, {}, {}};
  EXPECT_NE(error_of([&] { ballgauge::verify_lengths({}, none); }).find("no measurements"),
            std::string::npos);
  std::vector<ballgauge::LengthMeasurement> L{{{0, 0, 0}, {100, 0, 0}, 100},
                                              {{0, 0, 0}, {100, 0, 0}, -1}};
  EXPECT_NE(error_of([&] { ballgauge::verify_lengths(L, none); }).find("length 2: the nominal"),
            std::string::npos);
  L[1] = {{5, 5, 5}, {5, 5, 5}, 10};
  EXPECT_NE(error_of([&] { ballgauge::verify_lengths(L, none); }).find("length 2: the two end"),
            std::string::npos);
  // Outside the grid: refused (or clamped when asked).
  const auto m =
      map::sample({Eigen::VectorXd::LinSpaced(2, 0, 100), Eigen::VectorXd::LinSpaced(2, 0, 100),
                   Eigen::VectorXd::LinSpaced(2, 0, 100)},
                  [](const Eigen::Vector3d&) { return Eigen::Vector3d(1e-3, 0, 0); });
  L[1] = {{0, 0, 0}, {150, 0, 0}, 150};
  EXPECT_NE(error_of([&] {
              ballgauge::verify_lengths(L, ballgauge::grid_correction(m));
            }).find("length 2: point 2 (150.000, 0.000, 0.000) mm is outside"),
            std::string::npos);
  // The caller's location comes first, for the end the correction refuses (the second here).
  ballgauge::LengthOptions located;
  located.locate = [](std::size_t index, int end) {
    return "f.csv:" + std::to_string(index + 2) + ":end" + std::to_string(end) + ": ";
  };
  EXPECT_EQ(error_of([&] {
              ballgauge::verify_lengths(L, ballgauge::grid_correction(m), located);
            }).rfind("f.csv:3:end2: grid correction: length 2: point 2 (150.000", 0),
            0u);
  map::EvalOptions clamp;
  clamp.outside = map::Outside::Clamp;
  EXPECT_LT(
      std::abs(ballgauge::verify_lengths(L, ballgauge::grid_correction(m, clamp)).rows[1].after),
      kRoundOff);  // a constant error cancels in a length
}

TEST(Lengths, GaugeBlocksOnAPerfectMachineMeasureTheirNominalLengths) {
  sim::Machine perfect;  // no errors
  sim::GaugeBlockOptions o;
  o.lo = {100, 100, 100};
  o.hi = {500, 400, 300};
  const auto c = sim::simulate_gauge_blocks(perfect, o);
  ASSERT_EQ(c.lengths.size(), 7u * 5u * 3u);  // ISO 10360-2: 7 positions, 5 lengths, 3 repeats
  for (std::size_t i = 0; i < c.lengths.size(); ++i) {
    const auto& l = c.lengths[i];
    EXPECT_NEAR((l.b - l.a).norm(), l.nominal, kRoundOff);
    EXPECT_LT((l.a - c.true_a[i]).norm(), kRoundOff);
    for (int k = 0; k < 3; ++k) {  // inside the box with its margin
      EXPECT_GE(std::min(l.a[k], l.b[k]), o.lo[k] + o.margin - kRoundOff);
      EXPECT_LE(std::max(l.a[k], l.b[k]), o.hi[k] - o.margin + kRoundOff);
    }
  }
  // The z position's longest block is 90 % of the 190 mm room.
  EXPECT_EQ(c.position[3 * 5 * 2], "z");
  EXPECT_DOUBLE_EQ(c.lengths[3 * 5 * 2 + 12].nominal, std::floor(0.9 * 190));
  // Given lengths that do not fit a position are left out there.
  o.lengths = {150, 350};
  const auto d = sim::simulate_gauge_blocks(perfect, o);
  int z = 0;
  for (const auto& p : d.position) z += p == "z";
  EXPECT_EQ(z, 3);  // only 150 mm fits the 190 mm of z
  o.lengths = {1000};
  EXPECT_NE(error_of([&] { sim::simulate_gauge_blocks(perfect, o); }).find("no length fits"),
            std::string::npos);
}

TEST(Lengths, OyaHokariTamuraResultAtHalfAMicrometreOfProbingNoise) {
  // Before and after correction. Noise like Oya, Hokari and Tamura's (0.5 µm per coordinate) on the
  // balls and on the blocks.
  const Campaign noisy = campaign(0.5e-3, 11, 0.5e-3);
  const auto v =
      ballgauge::verify_lengths(noisy.blocks.lengths, ballgauge::grid_correction(*noisy.map.grid));
  ASSERT_EQ(v.rows.size(), 105u);
  EXPECT_EQ(v.positions, 35);
  // Before: errors of several µm spread like their −2 … +6 µm; after: within about ±2 µm.
  EXPECT_GT(v.before.range(), 8e-3);
  EXPECT_LT(v.after.range(), 0.5 * v.before.range());
  EXPECT_LT(std::max(-v.after.min, v.after.max), 2.5e-3);
  EXPECT_GT(v.before.rms / v.after.rms, 3.0);
  // The expected level: the repeatability, the map's uncertainty and (known here only from the
  // simulation) the interpolation error of the grid: the same map and blocks without noise.
  const Campaign clean = campaign(0, 11, 0);
  const auto v0 =
      ballgauge::verify_lengths(clean.blocks.lengths, ballgauge::grid_correction(*clean.map.grid));
  const double expected = std::hypot(v.predicted_after, v0.after.rms);
  EXPECT_GT(v.after.rms, 0.5 * expected);
  EXPECT_LT(v.after.rms, 1.5 * expected);
  // The repeatability estimates the block noise: two ends, 0.5 µm along the block each.
  EXPECT_NEAR(v.repeatability, std::sqrt(2.0) * 0.5e-3, 0.25 * std::sqrt(2.0) * 0.5e-3);
}

// The E0 check against a user's MPE (ISO 10360-2 simple acceptance): the envelope A + L/K,
// capped at B, and the verdict from the largest |E| / MPE(L).
TEST(Lengths, E0AgainstAnMpe) {
  const auto m = ballgauge::Mpe::parse("1.5 + L/300");
  EXPECT_DOUBLE_EQ(m.at(300), 2.5);
  EXPECT_DOUBLE_EQ(ballgauge::Mpe::parse("2").at(1000), 2);
  EXPECT_DOUBLE_EQ(ballgauge::Mpe::parse("1.5+L/300,2").at(600), 2);
  for (const char* bad : {"", "x", "1.5+L/0", "1.5+L/-3", "-1", "1.5+L/300,", "1.5*L"})
    EXPECT_NE(error_of([&] { ballgauge::Mpe::parse(bad); }).find("MPE"), std::string::npos) << bad;
  std::vector<ballgauge::LengthRow> rows(3);
  rows[0].nominal = 300;
  rows[0].before = 2.4e-3;  // 96 % of 2.5 µm
  rows[1].nominal = 0.001;
  rows[1].before = -1.4e-3;
  rows[2].nominal = 600;
  rows[2].before = 3.6e-3;  // 3.5 µm allowed: beyond
  auto c = ballgauge::check_mpe(rows, m, false);
  EXPECT_FALSE(c.pass());
  EXPECT_EQ(c.failed, 1);
  EXPECT_NEAR(c.worst_ratio, 3.6 / 3.5, 1e-12);
  rows[2].before = -3.4e-3;
  c = ballgauge::check_mpe(rows, m, false);
  EXPECT_TRUE(c.pass());
  EXPECT_NEAR(c.worst_ratio, 3.4 / 3.5, 1e-12);
}

// ISO 10360-2's positions are the lines the set-ups lie along: the simulated test's seven (X, Y,
// Z and the box's four space diagonals) are found from the measured end points alone, every
// length of a position on one line, each line named by its direction.
TEST(Lengths, SetUpsAreGroupedIntoTheLinesOfIso10360Positions) {
  const Campaign noisy = campaign(0.5e-3, 11, 0.5e-3);
  const ballgauge::Correction none{"none", [](Eigen::Ref<Eigen::Matrix3Xd>) {}, {}, {}};
  const auto v = ballgauge::verify_lengths(noisy.blocks.lengths, none);
  ASSERT_EQ(v.line_directions.size(), 7u);
  std::map<std::string, int> line_of;
  for (std::size_t i = 0; i < v.rows.size(); ++i) {
    const auto it = line_of.emplace(noisy.blocks.position[i], v.rows[i].line).first;
    EXPECT_EQ(it->second, v.rows[i].line) << noisy.blocks.position[i];
  }
  ASSERT_EQ(line_of.size(), 7u);
  std::set<int> distinct;
  for (const auto& [name, line] : line_of) distinct.insert(line);
  EXPECT_EQ(distinct.size(), 7u);
  const auto name = [&](const char* pos) {
    return ballgauge::direction_name(v.line_directions[static_cast<std::size_t>(line_of.at(pos))]);
  };
  EXPECT_EQ(name("x"), "along X");
  EXPECT_EQ(name("z"), "along Z");
  EXPECT_EQ(name("+x+y+z"), "space diagonal (+X+Y+Z)");
  EXPECT_EQ(name("-x+y+z").rfind("space diagonal (", 0), 0u);
  EXPECT_EQ(ballgauge::direction_name(Eigen::Vector3d(0.8, -0.6, 0.01)),
            "XY plane diagonal (+X−Y)");
  // Two set-ups along X, 100 mm apart, are two positions; within the tolerance, one.
  std::vector<ballgauge::LengthMeasurement> L{{{0, 0, 0}, {100, 0, 0}, 100},
                                              {{0, 100, 0}, {100, 100, 0}, 100},
                                              {{10, 5, 0}, {210, 5, 0}, 200}};
  const auto w = ballgauge::verify_lengths(L, none);
  EXPECT_EQ(w.line_directions.size(), 2u);
  EXPECT_EQ(w.rows[0].line, 0);
  EXPECT_EQ(w.rows[1].line, 1);
  EXPECT_EQ(w.rows[2].line, 0);
}
