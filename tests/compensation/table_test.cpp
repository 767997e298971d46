// Compensation tables from positioning runs: LinuxCNC files round-trip and respect LinuxCNC's
// limits, and compensating the virtual machine with them removes what the runs measured — the
// bidirectional table the reversal too, the unidirectional one not.
#include "trueaxis/compensation/table.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "../test_util.hpp"
#include "trueaxis/io/compensation/controller.hpp"
#include "trueaxis/positioning/positioning.hpp"
#include "trueaxis/sim/machine.hpp"
#include "trueaxis/sim/positioning.hpp"

using namespace trueaxis;
using positioning::Direction;

namespace {

constexpr double kFileResolution = 0.5e-6;  // mm: LinuxCNC files carry 6 decimals

std::string comp_error(const std::string& text, int type = 1) {
  return test::error_of([&] { io::parse_linuxcnc(text, "x.comp", type); });
}

// The virtual machine's X axis with tens of µm of positioning error (far above the noise),
// measured with 17 targets, 4 µm of backlash and 0.3 µm of noise.
struct MeasuredAxis {
  sim::Machine machine;
  sim::PositioningRunOptions runs;
  positioning::Result before;

  // The axis compensated by `table`, measured again with new noise.
  positioning::Result rerun(const compensation::AxisTable& table, std::uint64_t seed) const {
    sim::PositioningRunOptions c = runs;
    c.seed = seed;
    c.compensation = [&](double p, Direction d) { return table.correction(p, d); };
    return positioning::evaluate(sim::simulate_positioning(machine, c).readings);
  }
  // The standard deviation of a mean of 5 readings after compensation: the difference of two
  // such means (the table's and the new run's).
  double sigma_mean() const { return runs.noise * std::sqrt(2.0 / 5); }
};

MeasuredAxis measured_axis(std::uint64_t machine_seed, std::uint64_t run_seed) {
  sim::MachineOptions mo;
  mo.seed = machine_seed;
  mo.positioning = 40e-6;
  MeasuredAxis a{sim::random_machine(mo), {}, {}};
  for (int i = 0; i <= 16; ++i) a.runs.targets.push_back(50.0 * i);
  a.runs.backlash = 4e-3;
  a.runs.noise = 0.3e-3;
  a.runs.seed = run_seed;
  a.before = positioning::evaluate(sim::simulate_positioning(a.machine, a.runs).readings);
  return a;
}

}  // namespace

TEST(CompensationTable, InterpolatesAndHoldsTheEnds) {
  compensation::AxisTable t{{0, 100, 300}, {1e-3, 3e-3, -1e-3}, {2e-3, 2e-3, 2e-3}};
  EXPECT_DOUBLE_EQ(t.correction(50, Direction::Up), 2e-3);
  EXPECT_DOUBLE_EQ(t.correction(200, Direction::Up), 1e-3);
  EXPECT_DOUBLE_EQ(t.correction(-10, Direction::Up), 1e-3);
  EXPECT_DOUBLE_EQ(t.correction(400, Direction::Up), -1e-3);
  EXPECT_DOUBLE_EQ(t.correction(150, Direction::Down), 2e-3);
  EXPECT_TRUE(t.bidirectional());
  t.position[2] = 100;
  EXPECT_NE(test::error_of([&] { t.validate(); }).find("must increase"), std::string::npos);
}

TEST(CompensationTable, LinuxCncRoundTripsAndRefusesWhatLinuxCncWouldNotRead) {
  const compensation::AxisTable t{{0, 50, 100.5}, {1.25e-3, -2e-3, 0}, {3.5e-3, 0.1e-3, -4e-3}};
  const std::string dir = test::temp_dir();
  for (int type : {0, 1}) {
    const std::string p = dir + "/x" + std::to_string(type) + ".comp";
    EXPECT_EQ(io::write_linuxcnc(p, t, type), 3);
    const auto back = io::read_linuxcnc(p, type);
    ASSERT_EQ(back.position.size(), 3u);
    for (std::size_t i = 0; i < 3; ++i) {
      EXPECT_NEAR(back.position[i], t.position[i], kFileResolution);
      EXPECT_NEAR(back.forward[i], t.forward[i], kFileResolution);
      EXPECT_NEAR(back.reverse[i], t.reverse[i], kFileResolution);
    }
  }
  // Type 0 holds actual positions: nominal − trim.
  EXPECT_EQ(comp_error("0 -0.001 0.002\n10 9.999 10.003\n", 0), "(no error)");
  const auto a = io::parse_linuxcnc("0 -0.001 0.002\n10 9.999 10.003\n", "x.comp", 0);
  EXPECT_NEAR(a.forward[0], 1e-3, 1e-15);
  EXPECT_NEAR(a.reverse[1], -3e-3, 1e-12);
  EXPECT_EQ(comp_error("0 0 0\n10 0\n"),
            "x.comp:2:5: expected three numbers 'nominal forward reverse' (LinuxCNC stops reading "
            "at such a line), found 2");
  EXPECT_EQ(comp_error("0 0 0\n10 0 x1\n"), "x.comp:2:6: 'x1' is not a number");
  EXPECT_EQ(comp_error("0 0 0\n10 0 0 0\n"), "x.comp:2:8: more than three numbers on a line");
  EXPECT_EQ(comp_error("0 0 0\n0 0 0\n"),
            "x.comp:2:1: nominal 0 does not increase (LinuxCNC needs ascending nominals)");
  EXPECT_EQ(comp_error("0 0 0\n\n10 0 0\n"),
            "x.comp:2:1: blank line: LinuxCNC stops reading here and would ignore the lines after "
            "it");
  EXPECT_EQ(comp_error("0 0 0\n10 0 0\n\n\n"), "(no error)");
  EXPECT_EQ(comp_error("0 0 0\n"), "x.comp: a compensation table needs at least two lines");
  EXPECT_EQ(comp_error("0 0 0\n1 0 0\n", 2), "the LinuxCNC compensation type must be 0 or 1");
  std::string many;
  for (int i = 0; i <= io::kLinuxCncMaxPoints; ++i) many += std::to_string(i) + " 0 0\n";
  EXPECT_EQ(comp_error(many),
            "x.comp:257:1: more than 256 lines: LinuxCNC takes at most 256 per joint");
  compensation::AxisTable big;
  for (int i = 0; i <= io::kLinuxCncMaxPoints; ++i) {
    big.position.push_back(i);
    big.forward.push_back(0);
    big.reverse.push_back(0);
  }
  EXPECT_NE(test::error_of([&] {
              io::write_linuxcnc(dir + "/big.comp", big, 1);
            }).find("at most 256 compensation points"),
            std::string::npos);
}

// The virtual machine's X axis with 4 µm of backlash, measured, compensated through a LinuxCNC
// file and measured again.
TEST(CompensationTable, CompensatingTheVirtualMachineRemovesWhatWasMeasured) {
  const MeasuredAxis ax = measured_axis(12, 3);
  const auto& before = ax.before;
  const auto& o = ax.runs;
  const auto& m = ax.machine;
  ASSERT_GT(before.iso.E, 10e-3);
  const std::string dir = test::temp_dir();
  auto rerun = [&](bool bidirectional) {
    io::write_linuxcnc(dir + "/x.comp", compensation::from_positioning(before, bidirectional), 1);
    return ax.rerun(io::read_linuxcnc(dir + "/x.comp", 1), 4);
  };
  const auto bi = rerun(true);
  const auto uni = rerun(false);
  // After the bidirectional table, each mean deviation is the difference of two means of 5
  // noisy readings (σ·√(2/5)) plus the machine's change between nodes 50 mm apart, which the
  // linear interpolation does not see at the nodes themselves: E is at the noise level.
  const double sigma_mean = ax.sigma_mean();
  EXPECT_LT(bi.iso.E, 2 * 4.5 * sigma_mean);
  EXPECT_NEAR(bi.iso.B_mean, 0, 4.5 * sigma_mean / std::sqrt(17.0));
  // The unidirectional table leaves the reversal: B̄ stays at −backlash, and E holds it.
  EXPECT_NEAR(uni.iso.B_mean, -o.backlash, 4.5 * sigma_mean / std::sqrt(17.0));
  EXPECT_GT(uni.iso.E, o.backlash - 2 * 4.5 * sigma_mean);
  EXPECT_LT(uni.iso.M, 2 * 4.5 * sigma_mean);  // the mean bidirectional deviation is removed
  // Accuracy before and after.
  EXPECT_LT(bi.iso.A, before.iso.A / 3);
  // One direction only: a bidirectional table is refused, a unidirectional one made.
  std::vector<positioning::Reading> up;
  for (const auto& r : sim::simulate_positioning(m, o).readings)
    if (r.direction == Direction::Up) up.push_back(r);
  const auto one = positioning::evaluate(up);
  EXPECT_NE(test::error_of([&] {
              compensation::from_positioning(one, true);
            }).find("has no mean deviation for '-' approaches"),
            std::string::npos);
  EXPECT_NO_THROW(compensation::from_positioning(one, false));
}

TEST(CompensationTable, SinumerikLecRoundTripsResamplesAndRefuses) {
  const std::string dir = test::temp_dir();
  // Equidistant targets: the values come back as written (6 decimals).
  const compensation::AxisTable t{
      {-200, -100, 0, 100}, {3e-3, -1e-3, 0, 2.5e-3}, {3e-3, -1e-3, 0, 2.5e-3}};
  io::SinumerikOptions o;
  o.axis = "X1";
  EXPECT_EQ(io::write_sinumerik(dir + "/x.mpf", t, o), 4);
  std::string axis;
  const auto back = io::read_sinumerik(dir + "/x.mpf", &axis);
  EXPECT_EQ(axis, "X1");
  ASSERT_EQ(back.position.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_NEAR(back.position[i], t.position[i], 1e-9);
    EXPECT_NEAR(back.forward[i], t.forward[i], kFileResolution);
  }
  // Non-uniform targets are interpolated linearly onto the step.
  const compensation::AxisTable u{{0, 30, 100}, {0, 3e-3, -4e-3}, {0, 3e-3, -4e-3}};
  o.step = 10;
  EXPECT_EQ(io::write_sinumerik(dir + "/u.mpf", u, o), 11);
  const auto ub = io::read_sinumerik(dir + "/u.mpf");
  EXPECT_NEAR(ub.forward[2], 2e-3, kFileResolution);  // 20 mm: 2/3 of the way to 3 µm
  EXPECT_NEAR(ub.forward[10], -4e-3, kFileResolution);
  EXPECT_NEAR(ub.forward[5], 3e-3 - 7e-3 * 20 / 70, kFileResolution);
  // What the controller would refuse or what the table cannot hold.
  const compensation::AxisTable bi{{0, 10}, {1e-3, 1e-3}, {2e-3, 2e-3}};
  EXPECT_NE(test::error_of([&] {
              io::write_sinumerik(dir + "/b.mpf", bi);
            }).find("one curve for both directions"),
            std::string::npos);
  o.step = 0.01;
  o.max_points = 200;
  EXPECT_NE(test::error_of([&] {
              io::write_sinumerik(dir + "/m.mpf", u, o);
            }).find("exceed MD38000 $MA_MM_ENC_COMP_MAX_POINTS = 200"),
            std::string::npos);
  auto err = [](const std::string& text) {
    return test::error_of([&] { io::parse_sinumerik(text, "x.mpf"); });
  };
  const std::string tail =
      "$AA_ENC_COMP_STEP[0,X1]=1.0\n$AA_ENC_COMP_MIN[0,X1]=0\n$AA_ENC_COMP_MAX[0,X1]=1.0\nM17\n";
  EXPECT_EQ(err("%_N_AX_EEC_INI\nCHANDATA(1)\n$AA_ENC_COMP[0,0,X1]=0.003 ; +3 um\n"
                "$AA_ENC_COMP[0,1,X1]=-0.001\n" +
                tail),
            "(no error)");
  EXPECT_EQ(err("$AA_ENC_COMP[0,0,X1]=0.003\n$AA_ENC_COMP[0,2,X1]=0\n" + tail),
            "x.mpf: interpolation point 1 is missing");
  EXPECT_EQ(err("$AA_ENC_COMP[0,0,X1]=0.003\n$AA_ENC_COMP[0,1,X1]=abc\n" + tail),
            "x.mpf:2:22: 'abc' is not a number");
  EXPECT_EQ(err("$AA_ENC_COMP[0,0,X1]=0.003\n$AA_ENC_COMP[0,1,Y1]=0\n" + tail),
            "x.mpf:2:14: this file is for measuring system 0 of axis X1");
  EXPECT_EQ(err("$AA_ENC_COMP[0,0,X1]=0.003\n$AA_ENC_COMP[0,0,X1]=0\n" + tail),
            "x.mpf:2:1: interpolation point 0 is given twice");
  EXPECT_EQ(err("$AA_ENC_COMP[0,0,X1]=0\n$AA_ENC_COMP[0,1,X1]=0\nG01 X10\n" + tail),
            "x.mpf:3:1: 'G01 X10': expected $AA_ENC_COMP... = value");
  EXPECT_EQ(err("$AA_ENC_COMP[0,0,X1]=0\n$AA_ENC_COMP[0,1,X1]=0\n" + tail + "X1=0\n"),
            "x.mpf:7:1: text after M17 (the end of the program)");
  EXPECT_EQ(err("$AA_ENC_COMP[0,0,X1]=0\n$AA_ENC_COMP[0,1,X1]=0\n$AA_ENC_COMP_STEP[0,X1]=2.0\n"
                "$AA_ENC_COMP_MIN[0,X1]=0\n$AA_ENC_COMP_MAX[0,X1]=1.0\n"),
            "x.mpf: 2 points of 2 mm from 0 mm end at 2 mm, not at $AA_ENC_COMP_MAX = 1 mm");
  EXPECT_EQ(err("$AA_ENC_COMP[0,0,X1]=0\n$AA_ENC_COMP[0,1,X1]=0\n$AA_ENC_COMP_IS_MODULO[0,X1]=1\n"),
            "x.mpf:3:30: modulo tables (rotary axes) are not read");
  EXPECT_EQ(err("$AA_ENC_COMP[0,0,X1]=0\n"),
            "x.mpf: a compensation table needs at least two points");
}

TEST(CompensationTable, HeidenhainComTableRoundTripsBothDirectionsAndRefuses) {
  const std::string dir = test::temp_dir();
  // Forward and reverse differ: the BACKLASH column carries forward − reverse.
  const compensation::AxisTable t{
      {-90, -40, 10, 60}, {3e-3, -1.5e-3, 0, 2.5e-3}, {1e-3, -3.5e-3, -2e-3, 0.5e-3}};
  io::HeidenhainOptions o;
  o.axis = "y";
  EXPECT_EQ(io::write_heidenhain(dir + "/y.com", t, o), 4);
  const std::string text = test::read_file(dir + "/y.com");
  EXPECT_EQ(text.substr(0, text.find('\n')), "BEGIN Y.COM MM");
  EXPECT_NE(text.find("\n1     -40.0000        -0.0015         +0.0020\n"), std::string::npos)
      << text;
  std::string axis;
  const auto back = io::read_heidenhain(dir + "/y.com", &axis);
  EXPECT_EQ(axis, "Y");
  ASSERT_EQ(back.position.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_NEAR(back.position[i], t.position[i], 1e-12);
    EXPECT_NEAR(back.forward[i], t.forward[i], 0.5e-7);
    EXPECT_NEAR(back.reverse[i], t.reverse[i], 1e-7);
  }
  // The controller's limit: 256 points per table.
  compensation::AxisTable big;
  for (int i = 0; i < 257; ++i) {
    big.position.push_back(i);
    big.forward.push_back(0);
    big.reverse.push_back(0);
  }
  EXPECT_NE(test::error_of([&] {
              io::write_heidenhain(dir + "/big.com", big);
            }).find("at most 256 points; the table has 257"),
            std::string::npos);
  o.axis = "AXISPOS";
  EXPECT_NE(test::error_of([&] { io::write_heidenhain(dir + "/b.com", t, o); }).find("not an axis"),
            std::string::npos);
  auto err = [](const std::string& s, std::string axis = "") {
    return test::error_of([&] { io::parse_heidenhain(s, "x.com", &axis); });
  };
  const std::string head = "BEGIN X.COM MM\nNR    AXISPOS   X        BACKLASH\n";
  EXPECT_EQ(err(head + "0 0 +0.001 0\n1 50 -0.002 +0.001\n[END]\n"), "(no error)");
  // Two axis columns (sag of Z and pitch of Y over the same positions): say which one.
  const std::string two = "BEGIN YZ.COM MM\nNR AXISPOS Y Z\n0 0 0 0\n1 50 0.001 0.002\n[END]\n";
  EXPECT_EQ(err(two), "x.com:2:14: the table compensates several axes (Y, Z): say which to read");
  std::string z = "Z";
  EXPECT_NEAR(io::parse_heidenhain(two, "x.com", &z).forward[1], 0.002, 1e-15);
  EXPECT_NEAR(
      io::parse_heidenhain("BEGIN X.COM INCH\nNR AXISPOS X\n0 0 0\n1 2 0.0001\n[END]\n", "x.com")
          .forward[1],
      0.00254, 1e-15);
  EXPECT_EQ(err("NR AXISPOS X\n"),
            "x.com:1:1: 'NR AXISPOS X': expected 'BEGIN NAME.COM MM' (a HEIDENHAIN table)");
  EXPECT_EQ(err("BEGIN X.COM MM\nNR X\n"),
            "x.com:2:1: the column names need NR and AXISPOS (a compensation value table)");
  EXPECT_EQ(err(head + "0 0 +0.001 0\n2 50 -0.002 0\n[END]\n"),
            "x.com:4:1: NR 2: the points are numbered 0, 1, 2, ... (expected 1)");
  EXPECT_EQ(err(head + "0 0 +0.001 0\n1 0 -0.002 0\n[END]\n"),
            "x.com:4:3: AXISPOS 0 does not increase");
  EXPECT_EQ(err(head + "0 0 +0.001\n"), "x.com:3:11: 3 fields, the table has 4 columns");
  EXPECT_EQ(err(head + "0 0 +0.00l 0\n"), "x.com:3:5: '+0.00l' is not a number");
  EXPECT_EQ(err(head + "0 0 +0.001 0\n1 50 -0.002 0\n"),
            "x.com: no [END] line (the table is cut short)");
  EXPECT_EQ(err(head + "0 0 +0.001 0\n1 50 -0.002 0\n[END]\nNR\n"), "x.com:6:1: text after [END]");
  EXPECT_EQ(err("BEGIN X.COM FEET\n"), "x.com:1:13: unit 'FEET': MM or INCH");
  EXPECT_EQ(err(head + "0 0 +0.001 0\n[END]\n"),
            "x.com: a compensation table needs at least two points");
  std::string text257 = head;
  for (int i = 0; i < 257; ++i) text257 += fmt::format("{} {} 0 0\n", i, i);
  EXPECT_EQ(err(text257 + "[END]\n"),
            "x.com:259:1: more than 256 points: the control takes at most 256");
}

TEST(CompensationTable, FanucPitchErrorDataReproducesTheManualsExample) {
  // FANUC's parameter manual (pitch error compensation, example 1): stroke -400 .. +800 mm,
  // interval 50 mm, reference position at 0 with point number 40: the farthest points are 33
  // (40 - 400/50 + 1) and 56 (40 + 800/50).
  const std::string dir = test::temp_dir();
  compensation::AxisTable stroke{{-400, 800}, {0, 0}, {0, 0}};
  io::FanucOptions o;
  o.reference = 0;
  o.interval = 50;
  o.first_number = 33;
  io::FanucTable ft = io::write_fanuc(dir + "/s.txt", stroke, o);
  EXPECT_EQ(ft.reference_number, 40);
  EXPECT_EQ(ft.negative_number, 33);
  EXPECT_EQ(ft.positive_number, 56);
  // Its compensation values at points 33 .. 48 over -400 .. +400 mm: the absolute compensation
  // they add up to, written as a table, gives them back exactly.
  const std::vector<int> manual = {2, 1, 1, -2, 0, -1, 0, -1, 2, 1, 0, -1, -1, -2, 0, 1};
  compensation::AxisTable t;
  for (int n = 32; n <= 48; ++n) {
    int a = 0;  // detection units (um), zero at point 40
    for (int k = 41; k <= n; ++k) a += manual[static_cast<std::size_t>(k - 33)];
    for (int k = n + 1; k <= 40; ++k) a -= manual[static_cast<std::size_t>(k - 33)];
    t.position.push_back((n - 40) * 50.0);
    t.forward.push_back(a * 1e-3);
  }
  t.reverse = t.forward;
  ft = io::write_fanuc(dir + "/x.txt", t, o);
  EXPECT_EQ(ft.magnification, 1);
  EXPECT_EQ(ft.values, manual);
  const std::string text = test::read_file(dir + "/x.txt");
  EXPECT_NE(text.find("\nN3620A1P40\nN3621A1P33\nN3622A1P48\nN3623A1P1\nN3624A1P50.0\nN10033P2\n"),
            std::string::npos)
      << text;
  io::FanucTable raw;
  const auto back = io::read_fanuc(dir + "/x.txt", o, &raw);
  EXPECT_EQ(raw.values, manual);
  ASSERT_EQ(back.position.size(), t.position.size());
  for (std::size_t i = 0; i < t.position.size(); ++i) {
    EXPECT_DOUBLE_EQ(back.position[i], t.position[i]);
    EXPECT_NEAR(back.forward[i], t.forward[i], 1e-12);
  }
}

TEST(CompensationTable, FanucChoosesTheMagnificationAndRefusesWhatTheControlWould) {
  const std::string dir = test::temp_dir();
  // 0.3 mm between points 10 mm apart: 300 detection units, more than 127: magnification 3.
  const compensation::AxisTable steep{{0, 10, 20, 30}, {0, 0.3, 0.1, 0.2}, {0, 0.3, 0.1, 0.2}};
  io::FanucOptions o;
  io::FanucTable ft = io::write_fanuc(dir + "/f.txt", steep, o);
  EXPECT_EQ(ft.magnification, 3);
  const auto back = io::read_fanuc(dir + "/f.txt", o);
  for (std::size_t i = 1; i < back.position.size(); ++i)
    EXPECT_NEAR(back.forward[i], steep.forward[i - 1], 1.5e-3 + 1e-12);  // half of 3 units
  const compensation::AxisTable bi{{0, 10}, {1e-3, 1e-3}, {2e-3, 2e-3}};
  EXPECT_NE(test::error_of([&] { io::write_fanuc(dir + "/b.txt", bi); }).find("parameter 1851"),
            std::string::npos);
  o.max_feedrate = 30000;  // mm/min: the interval must be at least 4 mm
  o.interval = 2;
  EXPECT_NE(test::error_of([&] {
              io::write_fanuc(dir + "/b.txt", steep, o);
            }).find("below the control's minimum, the maximum feedrate / 7500 = 4 mm"),
            std::string::npos);
  o = {};
  o.interval = 0.01;
  EXPECT_NE(test::error_of([&] {
              io::write_fanuc(dir + "/b.txt", steep, o);
            }).find("beyond the control's highest point number 1023"),
            std::string::npos);
  o = {};
  const compensation::AxisTable cliff{{0, 10}, {0, 20}, {0, 20}};  // 20 mm over 10 mm
  EXPECT_NE(test::error_of([&] {
              io::write_fanuc(dir + "/b.txt", cliff, o);
            }).find("even at magnification 100"),
            std::string::npos);
  o.magnification = 2;
  EXPECT_NE(test::error_of([&] {
              io::write_fanuc(dir + "/b.txt", steep, o);
            }).find("at magnification 2 a point's value leaves -128..127"),
            std::string::npos);
  auto err = [](const std::string& s) {
    return test::error_of([&] { io::parse_fanuc(s, "f.txt"); });
  };
  const std::string p = "%\nN3620A1P1\nN3621A1P0\nN3622A1P2\nN3623A1P1\nN3624A1P10.0\n";
  EXPECT_EQ(err(p + "N10000P1\nN10001P-2\nN10002P3\n%\n"), "(no error)");
  EXPECT_EQ(err(p + "N10000P1\nN10002P3\n%\n"), "f.txt: point 1 (N10001) has no value");
  EXPECT_EQ(err(p + "N10000P1\nN10001P200\nN10002P3\n%\n"),
            "f.txt:8:8: point value 200: a whole number from -128 to 127");
  EXPECT_EQ(err(p + "N10000P1\nN10000P2\n%\n"), "f.txt:8:1: point 0 is given twice");
  EXPECT_EQ(err(p + "N10000P1 (FIRST\n"), "f.txt:7:10: a comment '(' is not closed on its line");
  EXPECT_EQ(err(p + "X10\n"), "f.txt:7:1: expected 'N'");
  EXPECT_EQ(err(p + "N3625P10\n"), "f.txt:7:1: parameter 3625 needs an axis address (A1, A2, ...)");
  EXPECT_EQ(err(p + "N10000P1\nN10001P1\nN10002P1\n%\nN1P1\n"),
            "f.txt:11:1: text after the closing '%'");
  EXPECT_EQ(err("%\nN3620A1P1\nN10000P1\n%\n"), "f.txt: parameter 3621 for axis 1 is missing");
  EXPECT_EQ(err("%\nN3620A1P1\nN3621A1P2\nN3622A1P3\nN3624A1P10.0\n%\n"),
            "f.txt: the points must satisfy 3621 <= 3620 <= 3622 with 3621 < 3622 (got 2, 1, 3)");
  EXPECT_EQ(err("%\nN3620A1P1.5\n"), "f.txt:2:9: parameter 3620: a whole number from 0");
}

TEST(CompensationTable, HeidenhainAndFanucTablesCompensateTheVirtualMachine) {
  const MeasuredAxis ax = measured_axis(21, 7);
  const auto& before = ax.before;
  ASSERT_GT(before.iso.E, 10e-3);
  const std::string dir = test::temp_dir();
  auto rerun = [&](const compensation::AxisTable& table) { return ax.rerun(table, 8); };
  const double sigma_mean = ax.sigma_mean();
  // HEIDENHAIN: both directions in one table (the BACKLASH column): the reversal goes too.
  io::write_heidenhain(dir + "/x.com", compensation::from_positioning(before, true));
  const auto heidenhain = rerun(io::read_heidenhain(dir + "/x.com"));
  EXPECT_LT(heidenhain.iso.E, 2 * 4.5 * sigma_mean);
  EXPECT_NEAR(heidenhain.iso.B_mean, 0, 4.5 * sigma_mean / std::sqrt(17.0));
  // FANUC: one curve, whole micrometres, zero at the reference position (the first target):
  // the mean bidirectional deviation goes, the reversal stays for parameter 1851.
  io::FanucOptions fo;
  io::write_fanuc(dir + "/x.txt", compensation::from_positioning(before, false), fo);
  fo.reference = 0;
  const auto fanuc = rerun(io::read_fanuc(dir + "/x.txt", fo));
  const double rounding = 0.5e-3;  // mm: half a detection unit on each side of a difference
  EXPECT_LT(fanuc.iso.M, 2 * 4.5 * sigma_mean + 2 * rounding);
  EXPECT_NEAR(fanuc.iso.B_mean, -ax.runs.backlash, 4.5 * sigma_mean / std::sqrt(17.0));
  EXPECT_LT(fanuc.iso.A, before.iso.A / 2);
}
