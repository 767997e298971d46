// Guideway files and the QPD conversion: located errors for every bad input, and the
// calibration table against the linear gain for a Gaussian spot.
#include "trueaxis/io/guideway/guideway.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "../../test_util.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/results.hpp"

using namespace trueaxis;

namespace {

const char* kLayout = R"({"detectors": [
  {"name": "a", "kind": "position", "position": [-60, 0, 0]},
  {"name": "b", "kind": "position", "position": [60, 0, 150]},
  {"name": "c", "kind": "position", "position": [0, 80, 300]}],
 "qpd": {"gain_um": 500, "min_sum": 0.1}}
)";

std::string layout_error(const std::string& text) {
  const std::string p = test::temp_file("layout.json", text);
  return test::error_of([&] { io::read_layout(p); });
}

}  // namespace

TEST(GuidewayIo, ReadsLayoutAndSpots) {
  const auto g = io::read_layout(test::temp_file("layout.json", kLayout));
  ASSERT_EQ(g.layout.detectors.size(), 3u);
  EXPECT_EQ(g.layout.detectors[2].position, Eigen::Vector3d(0, 80, 300));
  ASSERT_TRUE(g.qpd.has_value());
  EXPECT_DOUBLE_EQ(g.qpd->gain, 0.5);
  // Detector a by currents (signal sx = 0.2, sy = -0.1 → 100, -50 µm), b and c by displacement.
  const auto sp = io::read_spots(test::temp_file("spots.csv",
                                                 "s,a_i1,a_i2,a_i3,a_i4,b_dx,b_dy,c_dx,c_dy\n"
                                                 "0,0.25,0.2,0.25,0.3,1,2,3,4\n"
                                                 "10,0.25,0.25,0.25,0.25,5,6,7,8\n"),
                                 g);
  ASSERT_EQ(sp.spots.rows(), 2);
  EXPECT_NEAR(sp.spots(0, 0), 0.5 * ((0.25 + 0.3) - (0.2 + 0.25)), 1e-15);
  EXPECT_NEAR(sp.spots(0, 1), 0.5 * ((0.25 + 0.2) - (0.25 + 0.3)), 1e-15);
  EXPECT_DOUBLE_EQ(sp.spots(1, 5), 8e-3);
  EXPECT_DOUBLE_EQ(sp.s[1], 10);
}

// Spot columns that carry their unit read as the plain file.
TEST(GuidewayIo, SpotsWithUnitsInTheHeaderReadAsThePlainFile) {
  const auto g = io::read_layout(test::temp_file("layout.json", kLayout));
  const auto plain = io::read_spots(test::temp_file("spots.csv",
                                                    "s,a_dx,a_dy,b_dx,b_dy,c_dx,c_dy\n"
                                                    "0,1,2,3,4,5,6\n10,7,8,9,10,11,12\n"),
                                    g);
  const auto units = io::read_spots(
      test::temp_file("spots_units.csv",
                      "s [m],a_dx [\xC2\xB5m],a_dy (um),b_dx / nm,b_dy,c_dx [mm],c_dy\n"
                      "0,1,2,3000,4,0.005,6\n0.01,7,8,9000,10,0.011,12\n"),
      g);
  EXPECT_LT((units.spots - plain.spots).cwiseAbs().maxCoeff(), 1e-18);
  EXPECT_EQ(units.s, plain.s);
  const std::string e = test::error_of([&] {
    io::read_spots(test::temp_file("spots_bad.csv",
                                   "s,a_dx [s],a_dy,b_dx,b_dy,c_dx,c_dy\n"
                                   "0,1,2,3,4,5,6\n"),
                   g);
  });
  EXPECT_NE(e.find("spots_bad.csv:1:3: column 'a_dx [s]' is in s, a time"), std::string::npos) << e;
}

TEST(GuidewayIo, BadLayoutsNameFileLineAndColumn) {
  std::string t = kLayout;
  t.replace(t.find("\"b\""), 3, "\"a\"");
  EXPECT_NE(layout_error(t).find("layout.json:3:12: detector name 'a' is used twice"),
            std::string::npos)
      << layout_error(t);
  t = kLayout;
  // a, b and c on the z axis: no triangle.
  t.replace(t.find("[0, 80, 300]"), 12, "[0, 0, 300]");
  t.replace(t.find("[60, 0, 150]"), 12, "[0, 0, 150]");
  t.replace(t.find("[-60, 0, 0]"), 11, "[0, 0, 0]");
  EXPECT_NE(layout_error(t).find("lie on one line"), std::string::npos) << layout_error(t);
  EXPECT_NE(layout_error(t).find("layout.json:1:15:"), std::string::npos) << layout_error(t);
  t = kLayout;
  t.replace(t.find("\"position\", \"position\": [-60, 0, 0]"), 10, "\"mirror\"");
  EXPECT_NE(layout_error(t).find("kind must be \"position\" or \"angle\""), std::string::npos);
  EXPECT_NE(layout_error(R"({"detectors": [{"name": "f", "kind": "angle"}]})")
                .find("needs a positive 'focal_length'"),
            std::string::npos);
  EXPECT_NE(layout_error(R"({"detectors": [{"name": "a", "kind": "position"}]})")
                .find("needs a 'position'"),
            std::string::npos);
  EXPECT_NE(layout_error(R"({"detectors": [], "lens": 3})").find("unknown key 'lens'"),
            std::string::npos);
  t = kLayout;
  t.replace(t.find("\"gain_um\": 500"), 14, "\"gain_um\": -1");
  EXPECT_NE(layout_error(t).find("positive gain"), std::string::npos) << layout_error(t);
}

TEST(GuidewayIo, BadSpotsNameFileLineAndColumn) {
  const auto g = io::read_layout(test::temp_file("layout.json", kLayout));
  auto err = [&](const std::string& text, bool skip = false) {
    const std::string p = test::temp_file("spots.csv", text);
    return test::error_of([&] { io::read_spots(p, g, skip); });
  };
  const std::string good = "a_dx,a_dy,b_dx,b_dy,c_dx,c_dy\n";
  EXPECT_NE(err("x," + good + "0,1,2,3,4,5,6\n").find("first column must be 's'"),
            std::string::npos);
  EXPECT_NE(err("s," + good.substr(0, good.size() - 1) + ",q_dx\n0,1,2,3,4,5,6,7\n")
                .find("spots.csv:1:33: column 'q_dx' names no detector"),
            std::string::npos)
      << err("s," + good.substr(0, good.size() - 1) + ",q_dx\n0,1,2,3,4,5,6,7\n");
  EXPECT_NE(err("s,a_dx,b_dx,b_dy,c_dx,c_dy\n0,1,2,3,4,5\n").find("needs both a_dx and a_dy"),
            std::string::npos);
  EXPECT_NE(err("s,b_dx,b_dy,c_dx,c_dy\n0,1,2,3,4\n").find("detector 'a' has no columns"),
            std::string::npos);
  EXPECT_NE(err("s,a_dz,b_dx,b_dy,c_dx,c_dy\n0,1,2,3,4,5\n").find("expected <name>_dx"),
            std::string::npos);
  // A lost spot (sum 0.04 < min_sum 0.1) on line 3.
  const std::string cur =
      "s,a_i1,a_i2,a_i3,a_i4,b_dx,b_dy,c_dx,c_dy\n0,1,1,1,1,0,0,0,0\n10,0.01,0.01,0.01,0.01,0,0,0,"
      "0\n20,1,1,1,1,0,0,0,0\n";
  EXPECT_NE(err(cur).find("spots.csv:3:4: detector 'a' at s = 10 mm: spot lost"), std::string::npos)
      << err(cur);
  const auto sp = io::read_spots(test::temp_file("spots.csv", cur), g, true);
  EXPECT_EQ(sp.s.size(), 2);
  ASSERT_EQ(sp.skipped.size(), 1u);
  EXPECT_DOUBLE_EQ(sp.s[1], 20);
  // Out of the linear range: sx = 0.96 > 0.9.
  EXPECT_NE(err("s,a_i1,a_i2,a_i3,a_i4,b_dx,b_dy,c_dx,c_dy\n0,0.49,0.01,0.01,0.49,0,0,0,0\n")
                .find("outside the linear range"),
            std::string::npos);
}

TEST(Qpd, CalibrationTableBeatsTheLinearGainFarFromCentre) {
  // A Gaussian spot of 1/e² radius w: the signal is erf(√2 x / w). The linear gain is the
  // centre slope's inverse; the table samples the response at 41 points over ±0.8 w.
  const double w = 1.0;
  guideway::Qpd lin;
  lin.gain = w * std::sqrt(M_PI) / (2 * std::sqrt(2.0));
  lin.max_signal = 0.99;
  guideway::Qpd tab;
  tab.table_signal.resize(41);
  tab.table_displacement.resize(41);
  for (int i = 0; i < 41; ++i) {
    const double x = -0.8 * w + 1.6 * w * i / 40;
    tab.table_displacement[i] = x;
    tab.table_signal[i] = guideway::gaussian_signal(x, w);
  }
  tab.validate();
  lin.validate();
  double worst_lin = 0, worst_tab = 0;
  for (double x = 0.05; x <= 0.6 + 1e-12; x += 0.05) {
    const double s = guideway::gaussian_signal(x, w);
    worst_lin = std::max(worst_lin, std::abs(lin.displacement(s) - x));
    worst_tab = std::max(worst_tab, std::abs(tab.displacement(s) - x));
  }
  // Near the centre both agree; at 0.6 w the linear gain is off by tens of percent.
  EXPECT_LT(std::abs(lin.displacement(guideway::gaussian_signal(0.01, w)) - 0.01), 1e-5);
  EXPECT_GT(worst_lin, 0.1 * 0.6);
  EXPECT_LT(worst_tab, 2e-3 * w);
  std::printf("Gaussian spot, |x| <= 0.6 w: linear gain error %.4f w, table error %.5f w\n",
              worst_lin, worst_tab);
  EXPECT_NE(test::error_of([&] { tab.displacement(0.99); }).find("outside the calibration table"),
            std::string::npos);
}

// A result on a machine axis reads back with its ISO 230-1 names; an axis that is not one is
// refused where it stands.
TEST(GuidewayResultFile, MachineAxisReadsBackAndABadOneIsRefused) {
  guideway::Result r;
  r.s = Eigen::VectorXd::LinSpaced(3, 0, 100);
  r.value[0] = Eigen::VectorXd::Zero(3);
  r.axis = 1;
  const std::string path = test::temp_dir() + "/g.json";
  io::write_guideway_result(path, r);
  EXPECT_EQ(io::read_guideway_result(path).axis, 1);
  EXPECT_EQ(io::read_guideway_result(path).name(0), "EXY (horizontal)");
  const std::string bad = test::temp_file(
      "bad-axis.json",
      "{\"kind\": \"guideway\", \"s\": [0, 1], \"observable\": {},\n \"axis\": \"W\"}");
  EXPECT_EQ(test::error_of([&] {
              io::read_guideway_result(bad);
            }).rfind(bad + ":2:10: the machine axis the carriage rides: X, Y or Z", 0),
            0u)
      << test::error_of([&] { io::read_guideway_result(bad); });
}
