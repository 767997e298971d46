// Compensation from a circular test: the values from the diagnosis with their sign conventions,
// the four controllers' files read back (and bad ones refused where they are wrong), and the loop
// closed on the virtual machine: the values read back from the controllers' files loaded in its
// controller, the test rerun, G down to what the model leaves.
#include "trueaxis/circular/compensation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "../test_util.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/circular/compensation.hpp"
#include "trueaxis/io/compensation/parameters.hpp"
#include "trueaxis/sim/circular.hpp"

using namespace trueaxis;

namespace {

circular::Result run_and_evaluate(const sim::Machine& m, const sim::CircularOptions& s) {
  circular::Options o;
  o.radius = s.radius;
  o.feed = s.feed;
  o.plane = s.plane;
  return circular::evaluate(sim::simulate_circular(m, s).trace, o);
}

double diagnosed(const circular::Result& r, const std::string& key) {
  for (const auto& c : r.causes)
    if (c.key == key) return c.value;
  throw Error("no cause " + key);
}

// Expects `fn` to throw an Error whose message starts with `where` and contains `what`.
template <class Fn>
void refused_at(Fn&& fn, const std::string& where, const std::string& what) {
  try {
    fn();
    ADD_FAILURE() << "not refused: " << what;
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.rfind(where, 0), 0u) << m;
    EXPECT_NE(m.find(what), std::string::npos) << m;
  }
}

}  // namespace

// The loop closed: a machine out of square with backlash on both axes is tested, the compensation
// written for the controllers and read back from their files, loaded in the virtual controller,
// and the test rerun. What the compensation leaves is below what the first-order model resolves.
TEST(CircularCompensation, ValuesReadBackFromTheControllersFilesCloseTheLoop) {
  constexpr double kModel = 2e-4;  // µm: the first-order model's |e|²/(2R) at these sizes
  sim::Machine m;
  m.squareness_c0y = 25e-6;
  sim::CircularOptions s;
  s.centre = Eigen::Vector3d(400, 300, 250);
  s.servo[0].backlash = 5e-3;
  s.servo[1].backlash = 6e-3;
  s.compensation.backlash[0] = 1e-3;  // X has 1 µm compensated already: 4 µm are left
  const circular::Result before = run_and_evaluate(m, s);
  const auto truth = sim::circular_truth(m, s);
  ASSERT_GT(std::max(before.ccw.G, before.cw.G), 5e-3);

  circular::CompensationOptions co;
  co.active_backlash = {1e-3, 0};  // the new value adds what is left to what is in force
  const circular::Compensation c = circular::compensation_from(before, co);
  EXPECT_TRUE(c.backlash[0].changed && c.backlash[1].changed && c.squareness.changed);
  EXPECT_NEAR(c.backlash[0].value, 1e-3 + 4e-3, kModel * 1e-3);
  EXPECT_NEAR(c.backlash[1].value, 6e-3, kModel * 1e-3);
  EXPECT_NEAR(c.squareness.value, truth.squareness, 0.01e-6);

  io::CompensationFilesOptions fo;
  fo.travel = std::array<double, 2>{0, 800};
  const std::string dir = test::temp_dir() + "/comp";
  const auto files = io::write_compensation_files(dir, c, fo);
  EXPECT_EQ(files.written.size(), 6u);      // four backlash files, two squareness tables
  EXPECT_EQ(files.not_written.size(), 2u);  // LinuxCNC and FANUC squareness, with reasons
  for (const auto& n : files.not_written) EXPECT_FALSE(n.reason.empty());

  // What each controller would load, read back from its own file.
  const io::AxisValues lcnc = io::read_linuxcnc_backlash(dir + "/linuxcnc-backlash.ini");
  const io::AxisValues sie = io::read_sinumerik_backlash(dir + "/siemens-backlash.ini");
  const io::AxisValues hei = io::read_heidenhain_backlash(dir + "/heidenhain-backlash.mp");
  const io::AxisValues fan = io::read_fanuc_backlash(dir + "/fanuc-backlash.txt");
  for (int k = 0; k < 2; ++k) {
    const auto K = static_cast<std::size_t>(k);
    ASSERT_TRUE(lcnc[K] && sie[K] && hei[K] && fan[K]);
    EXPECT_NEAR(*lcnc[K], c.backlash[K].value, 0.5e-6);
    EXPECT_NEAR(*sie[K], c.backlash[K].value, 0.5e-6);
    EXPECT_NEAR(*hei[K], c.backlash[K].value, 0.5e-4);
    EXPECT_NEAR(*fan[K], c.backlash[K].value, 0.5e-3);  // FANUC: whole detection units
  }
  EXPECT_FALSE(lcnc[2]);
  const io::CrossTable cec = io::read_sinumerik_cec(dir + "/siemens-squareness.ini");
  EXPECT_EQ(cec.input, 1);
  EXPECT_EQ(cec.output, 0);
  const double slope = (cec.at(800) - cec.at(0)) / 800;
  EXPECT_NEAR(slope, c.squareness.value, 2e-6 / 800);

  // The rerun, with the Siemens values loaded (the finest format).
  sim::CircularOptions after = s;
  after.compensation.backlash = {*sie[0], *sie[1], 0};
  after.compensation.cross_output = 0;
  after.compensation.cross_input = 1;
  after.compensation.cross_slope = slope;
  const circular::Result r = run_and_evaluate(m, after);
  EXPECT_NEAR(diagnosed(r, "backlash.X"), 0, 2e-3);  // µm: the files' 1 nm rounding, and the model
  EXPECT_NEAR(diagnosed(r, "backlash.Y"), 0, 2e-3);
  EXPECT_NEAR(diagnosed(r, "squareness"), 0, 0.02);  // µm/m
  const auto left = sim::circular_truth(m, after);
  EXPECT_NEAR(left.backlash[0], 5e-3 - *sie[0], 1e-15);
  EXPECT_NEAR(left.squareness, truth.squareness - slope, 1e-15);
  // G after: the set-up's centre offset is fitted out; what is left is round-off and the model.
  EXPECT_LT(std::max(r.ccw.G, r.cw.G), 0.01 * std::max(before.ccw.G, before.cw.G));

  // compensation.json gives the controller's values back, and applies to a test of its plane only.
  const io::AppliedCompensation applied = io::read_compensation_json(files.json_path);
  EXPECT_NEAR(applied.backlash[0], c.backlash[0].value, 1e-12);
  EXPECT_NEAR(applied.squareness, c.squareness.value, 1e-15);
  sim::CircularOptions yz;
  yz.plane = circular::Plane::parse("YZ");
  refused_at([&] { applied.apply(yz); }, files.json_path, "this test runs in YZ");
}

// Signs and what is not proposed: a value adds to the active one; a cause the data could not
// separate, or one inside its uncertainty, leaves the active value, with the reason.
TEST(CircularCompensation, ActiveValuesAddAndUnresolvedOnesAreLeft) {
  circular::Result r;
  r.plane = circular::Plane::parse("ZX");  // a = Z, b = X
  auto add = [&](std::string key, double value, std::optional<double> u, bool separated) {
    circular::Cause c;
    c.key = std::move(key);
    c.value = value;
    c.u = u;
    c.separated = separated;
    if (!separated) c.confused_with = "reversal spike of X, ccw";
    r.causes.push_back(c);
  };
  add("backlash.Z", -2.0, 0.1, true);  // µm: Z overshoots by 2 µm
  add("backlash.X", 3.0, 0.1, false);  // µm, not separated
  add("squareness", 10.0, 8.0, true);  // µm/m, inside 2u
  circular::CompensationOptions o;
  o.active_backlash = {5e-3, 1e-3};
  o.active_squareness = -4e-6;
  const auto c = circular::compensation_from(r, o);
  EXPECT_TRUE(c.backlash[0].changed);
  EXPECT_NEAR(c.backlash[0].value, 3e-3, 1e-15);  // 5 − 2 µm
  EXPECT_FALSE(c.backlash[1].changed);
  EXPECT_DOUBLE_EQ(c.backlash[1].value, 1e-3);
  EXPECT_NE(c.backlash[1].reason.find("not separated from reversal spike"), std::string::npos);
  EXPECT_FALSE(c.squareness.changed);
  EXPECT_DOUBLE_EQ(c.squareness.value, -4e-6);
  EXPECT_NE(c.squareness.reason.find("not significant"), std::string::npos);
  o.coverage = 1;  // at k = 1 the squareness is resolved
  EXPECT_NEAR(circular::compensation_from(r, o).squareness.value, 6e-6, 1e-18);
  o.coverage = -1;
  EXPECT_THROW(circular::compensation_from(r, o), Error);
  // No uncertainty (an exact fit): not proposed, and said why.
  r.causes[0].u.reset();
  EXPECT_NE(circular::compensation_from(r).backlash[0].reason.find("uncertainty"),
            std::string::npos);
}

TEST(ControllerParameters, BadFilesAreRefusedWhereTheyAreWrong) {
  const std::string p = "f";
  refused_at([&] { io::parse_linuxcnc_backlash("[JOINT_0]\nBACKLASH = x1\n", p); },
             "f:2:12:", "not a number");
  refused_at([&] { io::parse_linuxcnc_backlash("[JOINT_0]\nBACKLASH = -0.01\n", p); },
             "f:2:12:", "not negative");
  refused_at([&] { io::parse_linuxcnc_backlash("BACKLASH = 0.01\n", p); },
             "f:1:1:", "outside a [JOINT_n]");
  refused_at(
      [&] { io::parse_linuxcnc_backlash("[JOINT_1]\nBACKLASH = 0.01\nBACKLASH = 0.02\n", p); },
      "f:3:1:", "a second value for Y");
  refused_at([&] { io::parse_linuxcnc_backlash("[JOINT_5]\nBACKLASH = 0.01\n", p); },
             "f:2:1:", "not X, Y or Z");
  refused_at([&] { io::parse_linuxcnc_backlash("[EMC]\nMACHINE = m\n", p); }, "f:", "no [JOINT_n]");
  refused_at([&] { io::parse_heidenhain_backlash("MP711.0: +0.003\n", p); },
             "f:1:1:", "only MP710.x");
  refused_at([&] { io::parse_heidenhain_backlash("MP710.1: +1.5\n", p); }, "f:1:10:", "−1 … +1");
  refused_at([&] { io::parse_fanuc_backlash("%\nN1851A1P3\n", p); }, "f:", "'%' line");
  refused_at([&] { io::parse_fanuc_backlash("%\nN1852A1P3\n%\n", p); }, "f:2:2:", "only No. 1851");
  refused_at([&] { io::parse_fanuc_backlash("%\nN1851A1P3.5\n%\n", p); }, "f:2:9:", "whole number");
  refused_at([&] { io::parse_fanuc_backlash("%\n(NOT CLOSED\n%\n", p); }, "f:2:1:", "not closed");
  refused_at([&] { io::parse_sinumerik_backlash("$MA_BACKLASH[0,AX1]=0.003\n", p); },
             "f:", "does not end with M17");
  refused_at([&] { io::parse_sinumerik_backlash("$MA_BACKLASH[0,AX7]=0.003\nM17\n", p); },
             "f:1:1:", "AX1 … AX3");
  refused_at([&] { io::parse_sinumerik_backlash("$MA_BACKLASH[0,AX1]=abc\nM17\n", p); },
             "f:1:21:", "not a number");
  const std::string cec =
      "%_N_NC_CEC_INI\nCHANDATA(1)\n$AN_CEC[0,0]=0\n$AN_CEC[0,1]=0.001\n"
      "$AN_CEC_INPUT_AXIS[0]=(AX2)\n$AN_CEC_OUTPUT_AXIS[0]=(AX1)\n$AN_CEC_STEP[0]=100\n"
      "$AN_CEC_MIN[0]=0\n$AN_CEC_MAX[0]=100\nM17\n";
  const io::CrossTable t = io::parse_sinumerik_cec(cec, p);
  EXPECT_NEAR(t.at(50), 0.0005, 1e-15);
  EXPECT_NEAR(t.at(-10), 0, 1e-15);  // the end value beyond the table, as the controller holds
  auto edited = [&](const std::string& from, const std::string& to) {
    std::string s = cec;
    s.replace(s.find(from), from.size(), to);
    return s;
  };
  refused_at([&] { io::parse_sinumerik_cec(edited("MAX[0]=100", "MAX[0]=150"), p); },
             "f:", "MIN + (points − 1)·STEP");
  refused_at([&] { io::parse_sinumerik_cec(edited("$AN_CEC[0,1]", "$AN_CEC[0,2]"), p); },
             "f:", "point 1 is missing");
  refused_at([&] { io::parse_sinumerik_cec(edited("(AX2)", "(AXB)"), p); },
             "f:5:25:", "not a whole number");
  refused_at([&] { io::parse_sinumerik_cec(edited("$AN_CEC_STEP[0]=100\n", ""), p); },
             "f:", "needs $AN_CEC_INPUT_AXIS");
  refused_at(
      [&] { io::parse_sinumerik_cec(edited("$AN_CEC_MIN[0]=0", "$AN_CEC_DIRECTION[0]=1"), p); },
      "f:8:22:", "only 0 is read");
  // Writers refuse what the controller cannot take.
  const std::string dir = test::temp_dir();
  io::AxisValues neg;
  neg[0] = -0.002;
  EXPECT_THROW(io::write_linuxcnc_backlash(dir + "/l.ini", neg), Error);
  io::AxisValues big;
  big[1] = 2.0;
  EXPECT_THROW(io::write_heidenhain_backlash(dir + "/h.mp", big), Error);
  EXPECT_THROW(io::write_fanuc_backlash(dir + "/f.txt", big, 1e-4), Error);  // 20000 units
  EXPECT_THROW(io::write_sinumerik_backlash(dir + "/s.ini", io::AxisValues{}), Error);
}

// compensation.json read back: what is not one is refused where it is wrong.
TEST(CircularCompensation, BadCompensationFilesAreRefusedWhereTheyAreWrong) {
  auto file = [&](const std::string& name, const std::string& text) {
    return test::temp_file(name, text);
  };
  const std::string kind =
      file("kind.json", "{\n \"kind\": \"circular\",\n \"plane\": \"XY\"\n}\n");
  refused_at([&] { io::read_compensation_json(kind); },
             kind + ":2:10:", "not a circular test's compensation");
  const std::string plane =
      file("plane.json", "{\"kind\": \"circular compensation\", \"plane\": \"XZ\"}\n");
  refused_at([&] { io::read_compensation_json(plane); }, plane + ":1:44:", "XY, YZ or ZX");
  const std::string value = file(
      "value.json",
      "{\"kind\": \"circular compensation\", \"plane\": \"XY\",\n \"backlash_um\": {\"X\": "
      "{\"value\": \"3\"}, \"Y\": {\"value\": 5}}, \"squareness_um_per_m\": {\"value\": 1}}\n");
  refused_at([&] { io::read_compensation_json(value); }, value + ":2:33:", "backlash_um.X.value");
  const std::string missing =
      file("missing.json",
           "{\"kind\": \"circular compensation\", \"plane\": \"XY\",\n \"backlash_um\": {\"X\": "
           "{\"value\": 3}, \"Y\": {\"value\": 5}}}\n");
  refused_at([&] { io::read_compensation_json(missing); }, missing + ":", "squareness_um_per_m");
}
