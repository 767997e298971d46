// ISO 230-2 and VDI/DGQ 3441 evaluation: a small example worked by hand, simulated runs against
// their truth (backlash, temperature correction, noise within its stated spread), and what is
// still defined with one direction, one cycle or missing readings.
#include "trueaxis/positioning/positioning.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "../test_util.hpp"
#include "trueaxis/sim/machine.hpp"
#include "trueaxis/sim/positioning.hpp"

using namespace trueaxis;
using positioning::Direction;
using positioning::Reading;

namespace {

constexpr double kExact = 1e-12;  // mm: sums of a few small numbers

// Three targets, three cycles, deviations in µm (converted to mm), in a scrambled order.
std::vector<Reading> hand_example() {
  // target, direction, deviations of cycles 1..3 (µm)
  struct Row {
    double target;
    Direction d;
    double x[3];
  };
  const Row rows[] = {
      {0, Direction::Up, {1, 2, 3}},    {0, Direction::Down, {-1, 0, 1}},
      {100, Direction::Up, {4, 4, 4}},  {100, Direction::Down, {2, 3, 4}},
      {200, Direction::Up, {-2, 0, 2}}, {200, Direction::Down, {-4, -2, 0}},
  };
  std::vector<Reading> r;
  for (const auto& row : rows)
    for (int c = 0; c < 3; ++c) r.push_back({row.target, c + 1, row.d, row.x[c] * 1e-3});
  std::mt19937 rng(3);
  std::shuffle(r.begin(), r.end(), rng);  // the order of the rows must not matter
  return r;
}

}  // namespace

// Worked by hand (µm):
//   target   x̄↑  s↑  x̄↓  s↓   x̄     B    R↑  R↓  R = max(2s↑+2s↓+|B|, R↑, R↓)
//     0       2    1    0    1    1     2    4   4   max(6, 4, 4)  = 6
//   100       4    0    3    1    3.5   1    0   4   max(3, 0, 4)  = 4
//   200       0    2   -2    2   -1     2    8   8   max(10, 8, 8) = 10
// E↑ = 4 − 0 = 4; E↓ = 3 − (−2) = 5; E = 4 − (−2) = 6; M = 3.5 − (−1) = 4.5;
// A↑ = max(4, 4, 4) − min(0, 4, −4) = 8; A↓ = max(2, 5, 2) − min(−2, 1, −6) = 11;
// A = 5 − (−6) = 11; B = 2; B̄ = 5/3; R↑ = R↓ = 8; R = 10.
// VDI: U_j = 2, 1, 2; Ps_j = 6, 3, 12; P = max(1+4, 3.5+2, −1+7) − min(1−4, 3.5−2, −1−7) = 14.
TEST(Positioning, HandExampleIso230_2) {
  const auto r = positioning::evaluate(hand_example());
  ASSERT_EQ(r.targets.size(), 3u);
  EXPECT_EQ(r.cycles, 3);
  const double mean_up[] = {2, 4, 0}, s_up[] = {1, 0, 2}, mean_down[] = {0, 3, -2},
               s_down[] = {1, 1, 2}, B[] = {2, 1, 2}, R[] = {6, 4, 10};
  for (int i = 0; i < 3; ++i) {
    const auto& t = r.targets[static_cast<std::size_t>(i)];
    EXPECT_DOUBLE_EQ(t.position, 100.0 * i);
    EXPECT_EQ(t.n_up, 3);
    EXPECT_NEAR(t.mean_up, mean_up[i] * 1e-3, kExact);
    EXPECT_NEAR(t.s_up, s_up[i] * 1e-3, kExact);
    EXPECT_NEAR(t.mean_down, mean_down[i] * 1e-3, kExact);
    EXPECT_NEAR(t.s_down, s_down[i] * 1e-3, kExact);
    EXPECT_NEAR(t.B, B[i] * 1e-3, kExact);
    EXPECT_NEAR(t.R, R[i] * 1e-3, kExact);
  }
  const auto& p = r.iso;
  EXPECT_NEAR(p.E_up, 4e-3, kExact);
  EXPECT_NEAR(p.E_down, 5e-3, kExact);
  EXPECT_NEAR(p.E, 6e-3, kExact);
  EXPECT_NEAR(p.M, 4.5e-3, kExact);
  EXPECT_NEAR(p.A_up, 8e-3, kExact);
  EXPECT_NEAR(p.A_down, 11e-3, kExact);
  EXPECT_NEAR(p.A, 11e-3, kExact);
  EXPECT_NEAR(p.B, 2e-3, kExact);
  EXPECT_NEAR(p.B_mean, 5e-3 / 3, kExact);
  EXPECT_NEAR(p.R_up, 8e-3, kExact);
  EXPECT_NEAR(p.R_down, 8e-3, kExact);
  EXPECT_NEAR(p.R, 10e-3, kExact);
  const auto& v = r.vdi;
  EXPECT_NEAR(v.U, 2e-3, kExact);
  EXPECT_NEAR(v.U_mean, 5e-3 / 3, kExact);
  EXPECT_NEAR(v.Ps, 12e-3, kExact);
  EXPECT_NEAR(v.Ps_mean, 7e-3, kExact);
  EXPECT_NEAR(v.Pa, 4.5e-3, kExact);
  EXPECT_NEAR(v.P, 14e-3, kExact);
  // Three cycles and three targets over 200 mm: both departures from ISO 230-2 are named.
  ASSERT_EQ(r.warnings.size(), 2u);
  EXPECT_NE(r.warnings[0].find("3 cycles"), std::string::npos);
  EXPECT_NE(r.warnings[1].find("3 targets"), std::string::npos);
}

TEST(Positioning, TolerancesAndParameterNames) {
  const auto r = positioning::evaluate(hand_example());
  const auto v = positioning::check(r, {{"A", 12e-3}, {"R", 8e-3}, {"B_mean", 2e-3}, {"P", 14e-3}});
  ASSERT_EQ(v.size(), 4u);
  EXPECT_TRUE(v[0].pass);   // 11 <= 12
  EXPECT_FALSE(v[1].pass);  // 10 > 8
  EXPECT_TRUE(v[2].pass);
  EXPECT_TRUE(v[3].pass);  // 14 <= 14
  for (const auto& n : positioning::parameter_names())
    EXPECT_FALSE(std::isnan(positioning::parameter(r, n))) << n;
  EXPECT_NE(test::error_of([&] { positioning::parameter(r, "Q"); }).find("unknown parameter 'Q'"),
            std::string::npos);
  EXPECT_NE(test::error_of([&] {
              positioning::check(r, {{"A", -1}});
            }).find("positive"),
            std::string::npos);
}

TEST(Positioning, OneDirectionKeepsWhatIsDefined) {
  std::vector<Reading> up;
  for (const auto& r : hand_example())
    if (r.direction == Direction::Up) up.push_back(r);
  const auto r = positioning::evaluate(up);
  EXPECT_TRUE(r.has_up);
  EXPECT_FALSE(r.has_down);
  EXPECT_NEAR(r.iso.E_up, 4e-3, kExact);
  EXPECT_NEAR(r.iso.A_up, 8e-3, kExact);
  EXPECT_NEAR(r.iso.R_up, 8e-3, kExact);
  for (double v : {r.iso.A, r.iso.A_down, r.iso.E, r.iso.E_down, r.iso.M, r.iso.R, r.iso.R_down,
                   r.iso.B, r.iso.B_mean, r.vdi.P, r.vdi.Pa, r.vdi.Ps, r.vdi.U})
    EXPECT_TRUE(std::isnan(v));
  bool named = false;
  for (const auto& w : r.warnings)
    named = named || w.find("only '+' approaches") != std::string::npos;
  EXPECT_TRUE(named);
  // A tolerance on a parameter the runs do not define is not met.
  EXPECT_FALSE(positioning::check(r, {{"A", 1.0}})[0].pass);
}

TEST(Positioning, OneCycleHasNoSpread) {
  std::vector<Reading> one;
  for (const auto& r : hand_example())
    if (r.cycle == 1) one.push_back(r);
  const auto r = positioning::evaluate(one);
  EXPECT_NEAR(r.iso.E, 4e-3 - (-4e-3), kExact);  // cycle 1: ↑ 1, 4, −2; ↓ −1, 2, −4
  EXPECT_NEAR(r.iso.B, 2e-3, kExact);
  EXPECT_TRUE(std::isnan(r.iso.R));
  EXPECT_TRUE(std::isnan(r.iso.A));
  EXPECT_TRUE(std::isnan(r.vdi.P));
}

TEST(Positioning, MissingAndDuplicateReadings) {
  auto r = hand_example();
  const auto gone = std::find_if(r.begin(), r.end(), [](const Reading& x) {
    return x.target == 100 && x.cycle == 2 && x.direction == Direction::Down;
  });
  r.erase(gone);
  EXPECT_EQ(test::error_of([&] { positioning::evaluate(r); }).substr(0, 44),
            "no '-' reading at target 100 mm in cycle 2 (");
  positioning::Options o;
  o.allow_incomplete = true;
  const auto res = positioning::evaluate(r, o);
  EXPECT_EQ(res.targets[1].n_down, 2);
  EXPECT_NEAR(res.targets[1].mean_down, 3e-3, kExact);  // (2 + 4) / 2
  EXPECT_NE(res.warnings[0].find("incomplete cycles"), std::string::npos);

  auto d = hand_example();
  d.push_back(d[4]);
  EXPECT_NE(test::error_of([&] { positioning::evaluate(d); }).find("readings 5 and 19 are both"),
            std::string::npos);
  auto t = hand_example();
  t[0].material_temperature = 21;
  EXPECT_NE(test::error_of([&] {
              positioning::evaluate(t);
            }).find("material temperature is given for 1 of 18 readings"),
            std::string::npos);
  EXPECT_NE(test::error_of([] { positioning::evaluate({}); }).find("no readings"),
            std::string::npos);
  auto c = hand_example();
  c[2].cycle = 0;
  EXPECT_NE(test::error_of([&] { positioning::evaluate(c); }).find("cycles count from 1"),
            std::string::npos);
}

// Simulated runs against their truth: the per-target means lie within their stated spread of
// the noise-free means; B̄ recovers the backlash; s recovers the noise.
TEST(Positioning, SimulatedRunsAgainstTruth) {
  sim::MachineOptions mo;
  mo.seed = 5;
  const sim::Machine m = sim::random_machine(mo);
  sim::PositioningRunOptions o;
  for (int i = 0; i <= 20; ++i) o.targets.push_back(40.0 * i);
  o.cycles = 10;
  o.backlash = 4e-3;
  o.noise = 0.5e-3;
  o.seed = 11;
  const auto run = sim::simulate_positioning(m, o);
  const auto r = positioning::evaluate(run.readings);
  ASSERT_EQ(r.targets.size(), 21u);
  // Each mean has standard deviation σ/√n; allow 4.5 of them (a false alarm over 42 means has a
  // probability below 3e-4).
  const double tol_mean = 4.5 * o.noise / std::sqrt(10.0);
  double s_sum = 0;
  for (std::size_t i = 0; i < 21; ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    EXPECT_NEAR(r.targets[i].mean_up, run.up[ii], tol_mean);
    EXPECT_NEAR(r.targets[i].mean_down, run.down[ii], tol_mean);
    s_sum += r.targets[i].s_up + r.targets[i].s_down;
  }
  // B̄ averages 42 means: spread σ·√(2/n)/√21.
  EXPECT_NEAR(r.iso.B_mean, -o.backlash, 4.5 * o.noise * std::sqrt(2.0 / 10) / std::sqrt(21.0));
  // The mean of 42 sample standard deviations (9 degrees of freedom each) is within 10 % of σ.
  EXPECT_NEAR(s_sum / 42, o.noise, 0.1 * o.noise);
  // E from the truth's means, within the means' spread.
  double hi = -1, lo = 1;
  for (Eigen::Index i = 0; i < 21; ++i) {
    hi = std::max({hi, run.up[i], run.down[i]});
    lo = std::min({lo, run.up[i], run.down[i]});
  }
  EXPECT_NEAR(r.iso.E, hi - lo, 2 * tol_mean);
  EXPECT_GT(r.iso.E, 5 * tol_mean);  // the machine's error is far above the noise
}

// A warming axis: readings carry the material temperature; corrected to 20 °C the evaluation
// finds the truth, uncorrected it finds the expansion too.
// A unit mix-up passes every structural check: the magnitudes give it away, and no tolerance is
// judged PASS on such data.
TEST(Positioning, AUnitMixUpIsNamedAndNoToleranceIsJudged) {
  sim::MachineOptions mo;
  mo.seed = 5;
  const sim::Machine m = sim::random_machine(mo);
  sim::PositioningRunOptions o;
  for (int i = 0; i <= 16; ++i) o.targets.push_back(50.0 * i);
  o.backlash = 3e-3;
  o.noise = 0.5e-3;
  const auto run = sim::simulate_positioning(m, o);
  const std::vector<std::pair<std::string, double>> tol{{"A", 25e-3}};
  const auto good = positioning::evaluate(run.readings);
  EXPECT_TRUE(good.implausible.empty()) << good.implausible;
  EXPECT_TRUE(positioning::check(good, tol)[0].pass);
  // Deviations written in mm into the µm column: read 1000 times too small.
  std::vector<Reading> mm = run.readings;
  for (Reading& r : mm) r.deviation *= 1e-3;
  const auto small = positioning::evaluate(mm);
  EXPECT_NE(small.implausible.find("look like millimetres in a micrometre column"),
            std::string::npos)
      << small.implausible;
  EXPECT_EQ(small.warnings.front(), small.implausible);
  const auto v = positioning::check(small, tol);
  EXPECT_FALSE(v[0].pass);  // A of a few nm would "pass" 25 um
  EXPECT_EQ(v[0].not_judged, small.implausible);
  // Targets in metres: 0 .. 0.8 "mm" of travel.
  std::vector<Reading> metres = run.readings;
  for (Reading& r : metres) r.target *= 1e-3;
  positioning::Options eo;
  eo.target_tolerance = 1e-7;
  const auto tiny = positioning::evaluate(metres, eo);
  EXPECT_NE(tiny.implausible.find("the targets span only 0.8 mm"), std::string::npos)
      << tiny.implausible;
  EXPECT_NE(tiny.implausible.find("'target [m]'"), std::string::npos);
  EXPECT_FALSE(positioning::check(tiny, tol)[0].pass);
}

TEST(Positioning, TemperatureCorrectionRemovesTheExpansion) {
  sim::MachineOptions mo;
  mo.seed = 8;
  const sim::Machine m = sim::random_machine(mo);
  sim::PositioningRunOptions o;
  for (int i = 0; i <= 16; ++i) o.targets.push_back(50.0 * i);
  o.temperature_start = 22;
  o.temperature_end = 23.5;
  o.expansion_coefficient = 11.5e-6;
  const auto run = sim::simulate_positioning(m, o);  // no noise: exact up to round-off
  const auto r = positioning::evaluate(run.readings);
  ASSERT_TRUE(r.temperature_corrected);
  EXPECT_NEAR(r.material_min, 22, 1e-12);
  EXPECT_NEAR(r.material_max, 23.5, 1e-12);
  for (std::size_t i = 0; i < r.targets.size(); ++i) {
    EXPECT_NEAR(r.targets[i].mean_up, run.up[static_cast<Eigen::Index>(i)], 1e-12);
    EXPECT_NEAR(r.targets[i].mean_down, run.down[static_cast<Eigen::Index>(i)], 1e-12);
  }
  // The largest correction is at 800 mm where the last cycle's '-' pass starts: reading 153 of
  // 0..169, at 22 + 1.5·153/169 °C.
  EXPECT_NEAR(r.max_correction, 11.5e-6 * (2 + 1.5 * 153 / 169) * 800, 1e-12);
  positioning::Options raw;
  raw.correct_temperature = false;
  const auto u = positioning::evaluate(run.readings, raw);
  EXPECT_GT(u.iso.E, r.iso.E + 15e-3);
  // The warming of 1.5 K during the test is named.
  bool named = false;
  for (const auto& w : r.warnings)
    named = named || w.find("changed by 1.50 K") != std::string::npos;
  EXPECT_TRUE(named);
}

TEST(Positioning, SimulatorRefusesBadOptions) {
  const sim::Machine m = sim::random_machine({});
  sim::PositioningRunOptions o;
  o.targets = {0, 100, 900};  // x runs 0..800
  EXPECT_NE(test::error_of([&] { sim::simulate_positioning(m, o); }).find("outside"),
            std::string::npos);
  o.targets = {0, 100, 50};
  EXPECT_NE(test::error_of([&] { sim::simulate_positioning(m, o); }).find("increasing"),
            std::string::npos);
  o.targets = {0, 100};
  o.temperature_start = 21;
  EXPECT_NE(test::error_of([&] { sim::simulate_positioning(m, o); }).find("both"),
            std::string::npos);
}

// An interferometer log of the standard test cycle (overrun before each reversal, no stop
// there): the stops at the targets give back the run's readings — target, cycle, direction and
// deviation — and the stop at rest before the first approach is named and not used.
TEST(Positioning, TargetsFoundByDwellInALog) {
  sim::MachineOptions mo;
  mo.seed = 6;
  const sim::Machine m = sim::random_machine(mo);
  sim::PositioningRunOptions o;
  o.targets = {0, 55, 103, 160, 240, 300};  // uneven spacing, as ISO 230-2 recommends
  o.cycles = 3;
  o.backlash = 2e-3;
  o.noise = 0.4e-3;
  const auto sl = sim::simulate_positioning_log(m, o);
  const auto found = positioning::readings_from_log(sl.log, o.targets);
  EXPECT_EQ(found.stops, 37);
  ASSERT_EQ(found.ignored.size(), 1u);
  EXPECT_NE(found.ignored[0].find("no target within 0.5 mm"), std::string::npos);
  ASSERT_EQ(found.readings.size(), sl.run.readings.size());
  for (std::size_t k = 0; k < found.readings.size(); ++k) {
    const auto &a = found.readings[k], &b = sl.run.readings[k];
    EXPECT_EQ(a.target, b.target);
    EXPECT_EQ(a.cycle, b.cycle);
    EXPECT_EQ(a.direction, b.direction);
    EXPECT_NEAR(a.deviation, b.deviation, 1e-12);
  }
  // Sample noise of 0.2 µm on a 10 Hz log: each stop's value averages 16 samples.
  sim::LogSimOptions lo;
  lo.sample_noise = 0.2e-3;
  const auto noisy = sim::simulate_positioning_log(m, o, lo);
  const auto fn = positioning::readings_from_log(noisy.log, o.targets);
  ASSERT_EQ(fn.readings.size(), noisy.run.readings.size());
  for (std::size_t k = 0; k < fn.readings.size(); ++k)
    EXPECT_NEAR(fn.readings[k].deviation, noisy.run.readings[k].deviation, 4.5 * 0.2e-3 / 4);
  // Malformed logs and targets.
  positioning::Log bad = sl.log;
  bad.time[5] = bad.time[4];
  EXPECT_NE(test::error_of([&] {
              positioning::readings_from_log(bad, o.targets);
            }).find("log sample 6: time"),
            std::string::npos);
  EXPECT_NE(test::error_of([&] {
              positioning::readings_from_log(sl.log, {0, 55, 55});
            }).find("strictly increasing"),
            std::string::npos);
  positioning::LogOptions lopt;
  lopt.dwell_time = 0;
  EXPECT_NE(test::error_of([&] {
              positioning::readings_from_log(sl.log, o.targets, lopt);
            }).find("dwell time must be positive"),
            std::string::npos);
  // Stops longer than the log's dwells are not stops: nothing is found.
  lopt.dwell_time = 10;
  EXPECT_EQ(positioning::readings_from_log(sl.log, o.targets, lopt).stops, 0);
}
