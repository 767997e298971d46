#include "trueaxis/io/sim/machine.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <random>

#include "../../test_util.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::io {
namespace {

using test::error_of;
using test::temp_dir;
using test::temp_file;

TEST(MachineIo, RoundTripKeepsEveryError) {
  sim::MachineOptions o;
  o.seed = 4;
  o.chain = "XFYZ";
  o.lead_amplitude = 0.5e-3;
  const sim::Machine m = sim::random_machine(o);
  const std::string p = temp_dir() + "/machine.json";
  write_machine(p, m);
  const sim::Machine r = read_machine(p);
  EXPECT_EQ(r.chain, "XFYZ");
  EXPECT_EQ(r.name, m.name);
  EXPECT_EQ(r.offset, m.offset);
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d c(800 * U(rng), 600 * U(rng), 500 * U(rng));
    // µm/µrad in the file: the conversion costs at most a few ulps.
    EXPECT_LT((r.error(c) - m.error(c)).norm(), 1e-14);
  }
}

TEST(MachineIo, HandWrittenMachineMeansWhatItSays) {
  const std::string p = temp_file("m.json", R"({
    "chain": "FXYZ",
    "ranges": {"x": [0, 1000], "y": [-100, 100], "z": [0, 50]},
    "offset": [0, 0, 0],
    "errors": {
      "EXX": {"polynomial": [0, 10]},
      "EYY": {"sines": [{"amplitude": 2, "period": 50}]},
      "EZZ": {"table": {"u": [0, 50], "value": [0, 4]}},
      "EC0Y": 0
    }
  })");
  const sim::Machine m = read_machine(p);
  // 10 µm/m at x = 500 mm: 5 µm; sin(2π·12.5/50) = 1: 2 µm; table midpoint: 2 µm.
  const Eigen::Vector3d e = m.error({500, 12.5, 25}) * 1e3;
  const double round_off_um = 1e-9;  // actual − nominal on ~500 mm coordinates
  EXPECT_NEAR(e.x(), 5.0, round_off_um);
  EXPECT_NEAR(e.y(), 2.0, round_off_um);
  EXPECT_NEAR(e.z(), 2.0, round_off_um);
  EXPECT_EQ(m.range[1][0], -100);
}

TEST(MachineIo, BadMachinesNameFileLineAndColumn) {
  const std::string ranges = R"("ranges": {"x": [0, 800], "y": [0, 600], "z": [0, 500]})";
  struct Case {
    std::string text, expect;
  };
  const std::vector<Case> cases = {
      {"{\"chain\": \"FYXZ\"}", "m.json:1:1: 'ranges' is missing"},
      {"{\"ranges\": {\"x\": [0, 800], \"y\": [600, 0], \"z\": [0, 500]}}",
       "m.json:1:33: 'ranges.y': min 600 must be below max 0"},
      {"{\"ranges\": {\"x\": [0, 800, 3], \"y\": [0, 600], \"z\": [0, 500]}}",
       "m.json:1:18: 'ranges.x' must be [min, max] in mm"},
      {"{\"chain\": \"FXXZ\",\n " + ranges + "}", "m.json:1:11: chain 'FXXZ' must list"},
      {"{" + ranges + ",\n \"errors\": {\"EXQ\": {}}}", "m.json:2:20: unknown error 'EXQ'"},
      {"{" + ranges + ",\n \"errors\": {\"EXX\": {\"poly\": [1]}}}",
       "m.json:2:29: unknown key 'poly'"},
      {"{" + ranges + ",\n \"errors\": {\"EXX\": {\"polynomial\": [1, \"2\"]}}}",
       "m.json:2:39: 'errors.EXX.polynomial[1]' must be a number"},
      {"{" + ranges +
           ",\n \"errors\": {\"EBY\": {\"table\": {\"u\": [0, 100], \"value\": [0, 1]}}}}",
       "m.json:2:20: EBY: table covers [0, 100] mm but the axis range is [0, 600] mm"},
      {"{" + ranges + ",\n \"errors\": {\"EXX\": {\"table\": {\"u\": [0, 800], \"value\": [0]}}}}",
       "m.json:2:55: 'errors.EXX.table.value' has 1 values for 2 positions"},
      {"{" + ranges +
           ",\n \"errors\": {\"EXX\": {\"sines\": [{\"amplitude\": 1, \"period\": 0}]}}}",
       "m.json:2:58: the period must be positive"},
      {"{" + ranges + ",\n \"offset\": [0, 0]}", "m.json:2:12: 'offset' must be [x, y, z]"},
      {"{" + ranges + ",\n \"errors\": {\"EC0Y\": NaN}}", "m.json:2:21: invalid JSON"},
  };
  for (const auto& c : cases) {
    const std::string p = temp_file("m.json", c.text);
    const std::string msg = error_of([&] { read_machine(p); });
    EXPECT_NE(msg.find(c.expect), std::string::npos) << "got: " << msg;
  }
  EXPECT_NE(error_of([&] { read_machine(temp_dir() + "/missing.json"); }).find("missing.json"),
            std::string::npos);
}

TEST(MachineIo, PointsAreReadAndCheckedAgainstTheRange) {
  sim::Machine m;
  const std::string ok = temp_file("p.csv", "x,y,z\n0,0,0\n800,600,500\n");
  const Eigen::Matrix3Xd p = read_points(ok, &m);
  ASSERT_EQ(p.cols(), 2);
  EXPECT_EQ(p(2, 1), 500);
  const std::string out = temp_file("o.csv", "x,y,z\n0,0,0\n10, 601 ,0\n");
  EXPECT_NE(error_of([&] {
              read_points(out, &m);
            }).find("o.csv:3:5: y = 601 mm is outside the machine's range [0, 600]"),
            std::string::npos);
  EXPECT_NO_THROW(read_points(out));  // no machine, no range check
  EXPECT_NE(error_of([&] { read_points(temp_file("n.csv", "x,y\n1,2\n")); }).find("'z'"),
            std::string::npos);
  EXPECT_NE(
      error_of([&] { read_points(temp_file("nan.csv", "x,y,z\n1,nan,2\n")); }).find("nan.csv:2:3"),
      std::string::npos);
  EXPECT_NE(error_of([&] { read_points(temp_file("e.csv", "x,y,z\n")); }).find("no points"),
            std::string::npos);
}

}  // namespace
}  // namespace trueaxis::io

// Found by fuzzing: "squareness errors must be finite and small" came with no location.
TEST(MachineIo, AnAbsurdSquarenessIsRefusedAtItsKey) {
  const std::string p = trueaxis::test::temp_file(
      "m.json",
      "{\"chain\": \"FYXZ\", \"ranges\": {\"x\": [0, 800], \"y\": [0, 600], \"z\": [0, "
      "500]},\n \"errors\": {\"EB0Z\": 2e5}}");
  EXPECT_EQ(trueaxis::test::error_of([&] { trueaxis::io::read_machine(p); }),
            p + ":2:21: squareness EB0Z = 200000 µrad: must be below 100000 µrad (0.1 rad)");
}
