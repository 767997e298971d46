#include "trueaxis/io/surface/space.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "../../test_util.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::io {
namespace {

using test::error_of;
using test::temp_dir;
using test::temp_file;

map::ErrorMap field_map(Eigen::Index nx = 9) {
  map::ErrorMap m =
      map::sample({Eigen::VectorXd::LinSpaced(nx, 0, 400), Eigen::VectorXd::LinSpaced(4, 0, 300),
                   Eigen::VectorXd::LinSpaced(3, 0, 200)},
                  [](const Eigen::Vector3d& p) {
                    return Eigen::Vector3d(1e-2 * std::sin(p.x() / 90), 2e-3 * p.y() / 300, -3e-3);
                  });
  m.uncertainty = Eigen::Matrix3Xd::Constant(3, m.nodes(), 0.4e-3);
  return m;
}

TEST(SpaceIo, PlansAreReadInTheirUnitsAndBadOnesNameTheSpot) {
  const surface::SpacePlan p = read_plan(temp_file(
      "plan.json",
      R"({"spacing": 25, "probes": "two-point", "probe_noise_um": 0.1, "diagonals": false,)"
      "\n"
      R"( "monte_carlo": 5, "seed": 9})"));
  EXPECT_EQ(p.spacing, 25);
  EXPECT_EQ(p.probes, surface::ProbeMethod::TwoPoint);
  EXPECT_DOUBLE_EQ(p.probe_noise, 1e-4);
  EXPECT_FALSE(p.diagonals);
  EXPECT_EQ(p.monte_carlo, 5);
  EXPECT_EQ(p.seed, 9u);
  struct Case {
    std::string text, expect;
  };
  for (const Case& c : std::vector<Case>{
           {"{\"spacing\": 50,\n \"noise\": 1}", "p.json:2:11: unknown key 'noise'"},
           {"{\"probes\": \"five-point\"}", "p.json:1:12: probes must be"},
           {"{\"monte_carlo\": 1.5}", "p.json:1:17: 'monte_carlo' must be a whole number"},
           {"{\"monte_carlo\": 1}", "p.json:1:17: monte_carlo must be 0"},
           {"{\"spacing\": -5}", "p.json:1:13: spacing -5 mm: must be between 1 and 100000"},
           // Found by fuzzing: a grid of 1e-9 mm ran out of memory, 1e309 overflowed the
           // parser, 1e9 repetitions ran for ever, a subnormal spacing read as "too few stations".
           {"{\"spacing\": 1e-9}", "p.json:1:13: spacing 1e-09 mm: must be between 1 and"},
           {"{\"spacing\": 50,\n \"seed\": 1e309}",
            "p.json:2:10: the number '1e309' is out of range"},
           {"{\"monte_carlo\": 1e9}", "p.json:1:17: monte_carlo 1e+09: at most 1000"},
           {"{\"spacing\": 1e-320}", "p.json:1:13: 'spacing' = 9.99989e-321 is too small"},
           {"{\"spacing\": 1e300}", "p.json:1:13: 'spacing' = 1e+300 is out of range"},
           {"{\"probe_noise_um\": -1}", "p.json:1:20: probe_noise_um -1 µm: must be between 0"},
           {std::string(100, '[') + std::string(100, ']'), "p.json:1:65: nested more than 64"},
           {"{\"diagonals\": 1}", "p.json:1:15: 'diagonals' must be true or false"},
       }) {
    const std::string msg = error_of([&] { read_plan(temp_file("p.json", c.text)); });
    EXPECT_NE(msg.find(c.expect), std::string::npos) << "got: " << msg;
  }
}

TEST(SpaceIo, SpaceFilesRoundTripTheirGrid) {
  surface::SpaceResult s;
  s.map = field_map();
  const std::string p = temp_dir() + "/space.json";
  write_space(p, s, {});
  const map::ErrorMap r = read_error_map(p);
  for (int a = 0; a < 3; ++a) EXPECT_EQ(r.axes[a], s.map.axes[a]);
  EXPECT_LT((r.error - s.map.error).cwiseAbs().maxCoeff(), 1e-17);  // µm in the file
  EXPECT_LT((r.uncertainty - s.map.uncertainty).cwiseAbs().maxCoeff(), 1e-17);
}

TEST(SpaceIo, BadGridsNameTheSpot) {
  const std::string head = R"({"grid": {"x": [0, 1], "y": [0, 1], "z": [0, 1],)";
  struct Case {
    std::string text, expect;
  };
  for (const Case& c : std::vector<Case>{
           {head + "\n \"ex\": [1,2,3,4,5,6,7], \"ey\": [], \"ez\": []}}",
            "s.json:2:8: 'grid.ex' has 7 values for 2 x 2 x 2 = 8 grid nodes"},
           {R"({"grid": {"x": [0, 1, 1], "y": [0, 1], "z": [0, 1]}})",
            "s.json:1:23: grid x nodes must increase strictly"},
           {R"({"grid": {"x": [0], "y": [0, 1], "z": [0, 1]}})",
            "s.json:1:16: the grid needs at least two x nodes"},
           {R"({"map": {}})", "s.json:1:1: 'grid' is missing"},
           // A ball plate's plane map: a normal that is no axis, a normal axis with three
           // nodes, two band nodes with different errors.
           {head + R"( "plane": {"normal": "w"},
 "ex": [0,0,0,0,0,0,0,0], "ey": [0,0,0,0,0,0,0,0], "ez": [0,0,0,0,0,0,0,0]}})",
            "s.json:1:70: normal must be x, y or z, not 'w'"},
           {R"({"grid": {"x": [0, 1], "y": [0, 1, 2], "z": [0, 1], "plane": {"normal": "y"}}})",
            "s.json:1:29: a plane map has two y nodes (the plane's band)"},
           {head + R"( "plane": {"normal": "z"},
 "ex": [0,0,0,0,5,0,0,0], "ey": [0,0,0,0,0,0,0,0], "ez": [0,0,0,0,0,0,0,0]}})",
            "the two z nodes differ"},
           // Found by fuzzing: 5000 nodes per axis allocated 1.25e11 nodes (bad_alloc, exit 3).
           {"{\"grid\": {\"x\": [" +
                [] {
                  std::string v;
                  for (int i = 0; i < 5000; ++i) {
                    if (i) v.push_back(',');
                    v.append(std::to_string(i));
                  }
                  return v + "], \"y\": [" + v + "], \"z\": [" + v +
                         "],\n \"ex\": [1], \"ey\": [1], \"ez\": [1]}}";
                }(),
            "s.json:2:8: 'grid.ex' has 1 values for 5000 x 5000 x 5000 = 125000000000 grid nodes"},
       }) {
    const std::string msg = error_of([&] { read_error_map(temp_file("s.json", c.text)); });
    EXPECT_NE(msg.find(c.expect), std::string::npos) << "got: " << msg;
  }
  EXPECT_NE(error_of([&] { read_error_map(temp_dir() + "/none.json"); }).find("none.json"),
            std::string::npos);
}

// LinuxCNC's rules for a COMP_FILE, checked independently of the writer: every line three
// numbers, nominals strictly increasing, at most 256 lines.
std::vector<std::array<double, 3>> parse_linuxcnc(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::vector<std::array<double, 3>> rows;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::array<double, 3> r{};
    std::string extra;
    EXPECT_TRUE(static_cast<bool>(ls >> r[0] >> r[1] >> r[2])) << "not three numbers: " << line;
    EXPECT_FALSE(static_cast<bool>(ls >> extra)) << "more than three fields: " << line;
    if (!rows.empty()) {
      EXPECT_GT(r[0], rows.back()[0]) << "nominals must increase";
    }
    rows.push_back(r);
  }
  EXPECT_LE(rows.size(), 256u);
  return rows;
}

TEST(SpaceIo, LinuxCncFilesFollowItsRules) {
  const map::ErrorMap m = field_map();
  const map::Interpolator f(m);
  const Eigen::Vector3d at(0, 150, 100);
  for (int axis = 0; axis < 3; ++axis)
    for (int type : {0, 1}) {
      const std::string p = temp_dir() + fmt::format("/{}{}.comp", axis, type);
      const int n = write_linuxcnc(p, m, axis, at, type);
      const auto rows = parse_linuxcnc(p);
      ASSERT_EQ(static_cast<int>(rows.size()), n);
      ASSERT_EQ(n, m.size(axis));
      for (const auto& r : rows) {
        Eigen::Vector3d q = at;
        q[axis] = r[0];
        const double e = f(q)[axis];
        const double expected = type == 0 ? r[0] + e : -e;
        EXPECT_NEAR(r[1], expected, 0.6e-6);  // six decimals in the file
        EXPECT_EQ(r[1], r[2]);                // no reversal error in the map
      }
    }
  EXPECT_NE(error_of([&] {
              write_linuxcnc(temp_dir() + "/big.comp", field_map(300), 0, at, 1);
            }).find("at most 256"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              write_linuxcnc(temp_dir() + "/out.comp", m, 0, {0, 999, 100}, 1);
            }).find("outside the map's grid"),
            std::string::npos);
  EXPECT_THROW(write_linuxcnc(temp_dir() + "/t.comp", m, 0, at, 2), Error);
}

TEST(SpaceIo, CsvTableHasEveryNode) {
  const map::ErrorMap m = field_map();
  const std::string p = temp_dir() + "/t.csv";
  write_map_csv(p, m);
  std::ifstream in(p);
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header, "x,y,z,ex_um,ey_um,ez_um,ux_um,uy_um,uz_um");
  long rows = 0;
  for (std::string l; std::getline(in, l);) ++rows;
  EXPECT_EQ(rows, m.nodes());
}

}  // namespace
}  // namespace trueaxis::io
