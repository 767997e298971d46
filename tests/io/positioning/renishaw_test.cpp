// Renishaw .rtl files: what is read (sections, wrapped target lists, run directions from the
// order the laser took the targets), the round trip through the writer, and every refusal with
// file:line:col.
#include "trueaxis/io/positioning/renishaw.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>

#include "../../test_util.hpp"
#include "trueaxis/positioning/positioning.hpp"
#include "trueaxis/sim/machine.hpp"
#include "trueaxis/sim/positioning.hpp"

using namespace trueaxis;
using positioning::Direction;

namespace {

constexpr double kFileResolution = 0.5e-7;  // mm: deviations carry 4 decimals of a µm

// A file as Renishaw's software lays it out: CR LF, keys with and without spaces around ':',
// targets wrapped five to a line, a second run that goes down, sections this reader does not
// interpret.
const std::string kRtl =
    "HEADER::\r\n"
    "File type : RTL\r\n"
    "Owner : Renishaw\r\n"
    "Version no : 3\r\n"
    "TARGET DATA::\r\n"
    "Filetype : Linear\r\n"
    "Target-count:6\r\n"
    "Targets :\r\n"
    "   0.0000  100.0000  200.0000  300.0000  400.0000\r\n"
    " 500.0000\r\n"
    "Flags : 0\r\n"
    "USER-TEXT::\r\n"
    "Machine: VMC 850\r\n"
    "Serial No: 1234\r\n"
    "Date: 24/11/2026 10:15\r\n"
    "Axis: X\r\n"
    "RUNS::\r\n"
    "Run-count : 4\r\n"
    "DEVIATIONS::\r\n"
    "Run Target Data:\r\n"
    "1  1  0.0000\r\n"
    "1  2  1.2000\r\n"
    "1  3  2.1000\r\n"
    "1  4  2.9000\r\n"
    "1  5  3.2000\r\n"
    "1  6  4.0000\r\n"
    "2  6  1.0000\r\n"
    "2  5  0.4000\r\n"
    "2  4  -0.1000\r\n"
    "2  3  -0.8000\r\n"
    "2  2  -1.9000\r\n"
    "2  1  -3.0000\r\n"
    "3  1  0.2000\r\n"
    "3  2  1.4000\r\n"
    "3  3  2.3000\r\n"
    "3  4  3.1000\r\n"
    "3  5  3.0000\r\n"
    "3  6  4.2000\r\n"
    "4  6  1.2000\r\n"
    "4  5  0.6000\r\n"
    "4  4  0.1000\r\n"
    "4  3  -0.6000\r\n"
    "4  2  -1.7000\r\n"
    "4  1  -2.8000\r\n"
    "EQUIPMENT::\r\n"
    "Laser : XL-80 123456\r\n"
    "Material temp 1 : 20.31\r\n";

std::string rtl_error(const std::string& text, const io::RtlOptions& o = {}) {
  return test::error_of([&] { io::parse_rtl(text, "x.rtl", o); });
}

// kRtl with `from` replaced by `to` (the first occurrence).
std::string edited(const std::string& from, const std::string& to) {
  std::string s = kRtl;
  const auto at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return s.replace(at, from.size(), to);
}

}  // namespace

TEST(RenishawRtl, ReadsTargetsRunsAndTheirDirections) {
  EXPECT_TRUE(io::looks_like_rtl("\r\n" + kRtl));
  EXPECT_FALSE(io::looks_like_rtl("target_mm,cycle,direction,deviation_um\n"));
  const io::RtlFile f = io::parse_rtl(kRtl, "x.rtl");
  ASSERT_EQ(f.targets.size(), 6u);
  EXPECT_DOUBLE_EQ(f.targets[5], 500);
  EXPECT_EQ(f.run_count, 4);
  EXPECT_TRUE(f.warnings.empty());
  ASSERT_EQ(f.runs.readings.size(), 24u);
  // Run 2 lists 500 mm first: a '-' run, cycle 1 of that direction; run 3 is '+' cycle 2.
  const auto& r2 = f.runs.readings[6];
  EXPECT_EQ(r2.direction, Direction::Down);
  EXPECT_EQ(r2.cycle, 1);
  EXPECT_DOUBLE_EQ(r2.target, 500);
  EXPECT_DOUBLE_EQ(r2.deviation, 1e-3);
  EXPECT_EQ(f.runs.lines[6], 27u);
  EXPECT_EQ(f.runs.readings[12].direction, Direction::Up);
  EXPECT_EQ(f.runs.readings[12].cycle, 2);
  EXPECT_EQ(f.runs.readings[23].cycle, 2);
  bool machine = false;
  for (const auto& [k, v] : f.fields) machine |= k == "Machine" && v == "VMC 850";
  EXPECT_TRUE(machine);
  // The evaluation of the file, worked by hand at 300 mm: up 2.9 and 3.1 um, down -0.1 and
  // 0.1 um, so the reversal there is 3.0 um.
  const auto r = positioning::evaluate(f.runs.readings);
  EXPECT_NEAR(r.targets[3].mean_up, 3.0e-3, 1e-12);
  EXPECT_NEAR(r.targets[3].mean_down, 0.0, 1e-12);
  EXPECT_NEAR(r.targets[3].B, 3.0e-3, 1e-12);
}

TEST(RenishawRtl, RoundTripsSimulatedRunsThroughTheWriter) {
  sim::MachineOptions mo;
  mo.seed = 5;
  const sim::Machine m = sim::random_machine(mo);
  sim::PositioningRunOptions o;
  for (int i = 0; i <= 12; ++i) o.targets.push_back(50.0 * i);
  o.backlash = 3e-3;
  o.noise = 0.4e-3;
  const auto run = sim::simulate_positioning(m, o);
  const std::string path = test::temp_dir() + "/runs.rtl";
  io::write_rtl(path, run.readings, {{"Axis", "X"}});
  const io::RtlFile f = io::read_rtl(path);
  EXPECT_TRUE(f.warnings.empty());
  EXPECT_EQ(f.run_count, 2 * o.cycles);
  ASSERT_EQ(f.runs.readings.size(), run.readings.size());
  const auto a = positioning::evaluate(run.readings);
  const auto b = positioning::evaluate(f.runs.readings);
  EXPECT_NEAR(a.iso.A, b.iso.A, 2 * kFileResolution);
  EXPECT_NEAR(a.iso.E, b.iso.E, 2 * kFileResolution);
  EXPECT_NEAR(a.iso.B_mean, b.iso.B_mean, 2 * kFileResolution);
  EXPECT_NEAR(a.iso.R, b.iso.R, 8 * kFileResolution);
  for (std::size_t i = 0; i < a.targets.size(); ++i) {
    EXPECT_DOUBLE_EQ(a.targets[i].position, b.targets[i].position);
    EXPECT_NEAR(a.targets[i].mean_down, b.targets[i].mean_down, kFileResolution);
  }
}

TEST(RenishawRtl, SortedRunsAreNamedAndTheirDirectionsCanBeGiven) {
  // Every run listed in target order: read as one direction, with a warning.
  std::string sorted = kRtl;
  for (int run : {2, 4}) {
    std::string block, rev;
    for (int t = 6; t >= 1; --t) {
      const std::string key = fmt::format("{}  {}  ", run, t);
      const auto at = sorted.find(key);
      const auto end = sorted.find("\r\n", at) + 2;
      rev = sorted.substr(at, end - at) + rev;
      sorted.erase(at, end - at);
      if (t == 1) sorted.insert(at, rev);
    }
  }
  const auto one_way = io::parse_rtl(sorted, "x.rtl");
  ASSERT_EQ(one_way.warnings.size(), 1u);
  EXPECT_NE(one_way.warnings[0].find("every run lists its targets in increasing order"),
            std::string::npos);
  EXPECT_EQ(one_way.runs.readings[6].direction, Direction::Up);
  EXPECT_EQ(one_way.runs.readings[6].cycle, 2);
  io::RtlOptions o;
  o.directions = io::RunDirections::UpDown;
  const auto both = io::parse_rtl(sorted, "x.rtl", o);
  EXPECT_TRUE(both.warnings.empty());
  const auto a = positioning::evaluate(both.runs.readings);
  const auto b = positioning::evaluate(io::parse_rtl(kRtl, "x.rtl").runs.readings);
  EXPECT_DOUBLE_EQ(a.iso.A, b.iso.A);
  EXPECT_DOUBLE_EQ(a.iso.B_mean, b.iso.B_mean);
  o.directions = io::RunDirections::AllDown;
  EXPECT_EQ(io::parse_rtl(kRtl, "x.rtl", o).runs.readings[0].direction, Direction::Down);
}

TEST(RenishawRtl, BadFilesNameFileLineAndColumn) {
  EXPECT_EQ(rtl_error("target_mm,cycle\n"),
            "x.rtl:1:1: 'target_mm,cycle': expected a section line such as 'HEADER::' (is this "
            "a Renishaw .rtl file?)");
  EXPECT_EQ(rtl_error(""),
            "x.rtl: no 'Target-count' in TARGET DATA:: (is this a Renishaw .rtl "
            "file?)");
  EXPECT_EQ(rtl_error(edited("Target-count:6", "Target-count:7")),
            "x.rtl:8:1: Target-count is 7 (line 7) but the Targets list has 6");
  EXPECT_EQ(rtl_error(edited("Target-count:6", "Target-count:six")),
            "x.rtl:7:14: Target-count 'six' is not a whole number from 1 to 100000");
  EXPECT_EQ(rtl_error(edited("  300.0000", "  3OO.0000")),
            "x.rtl:9:32: '3OO.0000' is not a number");
  EXPECT_EQ(rtl_error(edited("  300.0000", "  200.0000")),
            "x.rtl:9:1: target 4 (200 mm) is listed twice (also target 3)");
  EXPECT_EQ(rtl_error(edited("Filetype : Linear", "Filetype : Angular")),
            "x.rtl:6:12: Filetype 'Angular': only linear positioning tests are read");
  EXPECT_EQ(rtl_error(edited("Run-count : 4", "Run-count : 3")),
            "x.rtl:39:1: run '4' is not a whole number from 1 to 3 (the file's run-count)");
  EXPECT_EQ(rtl_error(edited("1  6  4.0000", "1  7  4.0000")),
            "x.rtl:26:4: target '7' is not a whole number from 1 to 6 (the file's "
            "target-count)");
  EXPECT_EQ(rtl_error(edited("1  6  4.0000", "1  6  4.0000  1")),
            "x.rtl:26:15: expected 'run target deviation' (3 numbers), found 4");
  EXPECT_EQ(rtl_error(edited("1  6  4.0000", "1  6  four")), "x.rtl:26:7: 'four' is not a number");
  EXPECT_EQ(rtl_error(edited("1  6  4.0000", "1  5  4.0000")),
            "x.rtl:26:1: run 1 has a second reading at target 5");
  EXPECT_EQ(rtl_error(edited("1  6  4.0000", "1  1e9  4")),
            "x.rtl:26:4: target '1e+09' is not a whole number from 1 to 6 (the file's "
            "target-count)");
  // A run that goes up and comes back: its direction is not in its order.
  EXPECT_EQ(rtl_error(edited("1  5  3.2000\r\n1  6  4.0000", "1  6  4.0000\r\n1  5  3.2000")),
            "x.rtl:26:1: run 1 goes up to 500 mm and then back to 400 mm: its direction "
            "cannot be read from the order of its targets; give the runs' directions");
  EXPECT_EQ(rtl_error(edited("Run Target Data:\r\n", "")),
            "x.rtl:20:1: '1  1  0.0000': expected 'Run Target Data:' and lines 'run target "
            "deviation'");
  EXPECT_EQ(rtl_error(edited("Run Target Data:", "Run Target Data: 1")),
            "x.rtl:20:18: the readings start on the next line");
  // Sections in another order: the readings' numbers are checked against the counts that come
  // after them.
  std::string runs_last = kRtl;
  const std::string runs = "RUNS::\r\nRun-count : 4\r\n";
  runs_last.erase(runs_last.find(runs), runs.size());
  EXPECT_EQ(rtl_error(runs_last + "RUNS::\r\nRun-count : 4\r\n"), "(no error)");
  EXPECT_EQ(rtl_error(runs_last + "RUNS::\r\nRun-count : 3\r\n"),
            "x.rtl:37:1: run 4 is beyond the file's Run-count 3");
  EXPECT_EQ(rtl_error(edited("   0.0000  100", "   0.0000 @100")),
            "x.rtl:9:11: '@100.0000' is not a number");
}
