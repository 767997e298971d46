#include "trueaxis/io/separation/probes.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <utility>
#include <vector>

#include "../../../src/io/fast_text.hpp"
#include "../../test_util.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/csv.hpp"

using namespace trueaxis;

namespace {

std::string read_error(const std::string& content, io::ProbeReadOptions o = {}) {
  const std::string p = test::temp_file("p.csv", content);
  try {
    io::read_probes(p, o);
  } catch (const Error& e) {
    std::string m = e.what();
    const std::string dir = test::temp_dir() + "/";
    for (auto at = m.find(dir); at != std::string::npos; at = m.find(dir)) m.erase(at, dir.size());
    return m;
  }
  return "";
}

const char* kGood = "x,a,b,c,ang\n0,1,2,3,10\n10,1,2,3,11\n20,1,2,3,12\n30,1,2,3,13\n";

}  // namespace

TEST(Probes, ReadsUnitsOffsetsAngleAndInvert) {
  io::ProbeReadOptions o;
  o.angle_column = "ang";
  o.invert = true;
  const auto d = io::read_probes(test::temp_file("g.csv", kGood), o);
  EXPECT_EQ(d.readings.cols(), 3);
  EXPECT_DOUBLE_EQ(d.readings(0, 1), -2e-3);
  EXPECT_DOUBLE_EQ(d.angle[3], 13e-6);
  EXPECT_EQ(d.offsets, (std::vector<double>{0, 10, 20}));
}

TEST(Probes, NonIncreasingX) {
  EXPECT_EQ(read_error("x,a,b\n0,1,2\n10,1,2\n10,1,2\n"),
            "p.csv:4:1: x = 10 does not increase (previous 10)");
}

TEST(Probes, UnevenSpacing) {
  EXPECT_NE(read_error("x,a,b\n0,1,2\n10,1,2\n25,1,2\n30,1,2\n").find("p.csv:4:1: uneven step"),
            std::string::npos);
}

// A dropped reading is named at the line after the gap: the step is the median spacing, not the
// mean (which the gap shifts, so every step looked uneven and the message pointed at line 3).
TEST(Probes, ADroppedStationIsNamedWhereItIs) {
  std::string text = "x,a,b\n";
  for (int k = 0; k <= 20; ++k)
    if (k != 7) text += fmt::format("{},1,2\n", 10 * k);
  EXPECT_EQ(read_error(text),
            "p.csv:9:1: x jumps from 60 to 80 mm: 1 station missing at a step of 10 mm (a dropped "
            "reading? every station is needed, in order)");
}

TEST(Probes, TooFewStations) {
  EXPECT_NE(read_error("x,a,b\n0,1,2\n10,1,2\n").find("too few stations: 2"), std::string::npos);
}

TEST(Probes, OffsetsNotWholeSteps) {
  io::ProbeReadOptions o;
  o.offsets = {0, 15};
  EXPECT_NE(read_error("x,a,b\n0,1,2\n10,1,2\n20,1,2\n", o)
                .find("not a whole multiple of the step 10 mm"),
            std::string::npos);
}

TEST(Probes, OffsetCountAndDuplicates) {
  io::ProbeReadOptions o;
  o.offsets = {0, 10, 20};
  EXPECT_NE(read_error("x,a,b\n0,1,2\n10,1,2\n20,1,2\n", o).find("2 probe columns but 3 offsets"),
            std::string::npos);
  o.offsets = {0, 10, 10};
  EXPECT_NE(read_error("x,a,b,c\n0,1,2,3\n10,1,2,3\n20,1,2,3\n", o).find("share the offset"),
            std::string::npos);
}

TEST(Probes, MissingColumnsAndBadHeader) {
  io::ProbeReadOptions o;
  o.angle_column = "level";
  EXPECT_EQ(read_error("x,a,b\n0,1,2\n10,1,2\n20,1,2\n", o),
            "p.csv:1:1: missing column 'level' (header has: x, a, b)");
  EXPECT_NE(read_error("pos,a,b\n0,1,2\n").find("p.csv:1:1: first column must be 'x'"),
            std::string::npos);
  EXPECT_NE(read_error("x,a\n0,1\n10,1\n20,1\n").find("need at least two probe columns"),
            std::string::npos);
}

TEST(Probes, NanInData) {
  EXPECT_EQ(read_error("x,a,b\n0,1,2\n10,NaN,2\n20,1,2\n"),
            "p.csv:3:4: NaN is not allowed (column 'a')");
}

TEST(ResultJson, RoundTripAndBadInput) {
  separation::Result r;
  r.method = separation::Method::ThreePoint;
  r.workpiece = {Eigen::VectorXd::LinSpaced(3, 0, 2), Eigen::VectorXd{{1e-3, -2e-3, 0.5e-3}},
                 Eigen::VectorXd{{1e-4, 1e-4, 2e-4}}};
  r.guide = {Eigen::VectorXd::LinSpaced(3, 0, 2), Eigen::VectorXd{{0, 1e-3, 0}}, {}};
  r.pitch =
      separation::Profile{Eigen::VectorXd::LinSpaced(2, 0, 1), Eigen::VectorXd{{1e-6, -1e-6}}, {}};
  r.unobservable = {"line", "parabola"};
  r.workpiece_straightness.ls = 3e-3;
  r.workpiece_straightness.min_zone = 2.5e-3;
  r.workpiece_straightness.U = 0.4e-3;
  r.no_uncertainty = "the guide's: none";
  const std::string p = test::temp_file("r.json", "");
  io::write_result(p, r);
  const auto back = io::read_result(p);
  ASSERT_TRUE(back.workpiece_straightness.U.has_value());
  EXPECT_DOUBLE_EQ(*back.workpiece_straightness.U, 0.4e-3);
  EXPECT_EQ(back.workpiece_straightness.resolved(), true);
  EXPECT_FALSE(back.guide_straightness.U.has_value());  // written as null
  EXPECT_FALSE(back.sigma.has_value());                 // written as null
  EXPECT_EQ(back.no_uncertainty, r.no_uncertainty);
  const std::string text = test::read_file(p);
  EXPECT_NE(text.find("\"U_um\": null, \"resolved\": null"), std::string::npos) << text;
  EXPECT_NE(text.find("\"resolved\": true"), std::string::npos) << text;
  EXPECT_EQ(back.method, separation::Method::ThreePoint);
  EXPECT_TRUE(back.workpiece.value.isApprox(r.workpiece.value, 1e-15));
  EXPECT_TRUE(back.workpiece.uncertainty.isApprox(r.workpiece.uncertainty, 1e-15));
  ASSERT_TRUE(back.pitch);
  EXPECT_TRUE(back.pitch->value.isApprox(r.pitch->value, 1e-15));
  EXPECT_EQ(back.unobservable, r.unobservable);

  auto err = [](const std::string& text) {
    try {
      io::read_result(test::temp_file("bad.json", text));
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(err("{\"workpiece\": {\"x\": [0, 1], \n\"value\": [1, }").find("bad.json:2:"),
            std::string::npos);
  const std::string bad = test::temp_file("bad.json", "");
  EXPECT_EQ(err("{\"workpiece\": {\"x\": [0, 1], \"value\": [1]},\n \"guide\": {\"x\": [0, 1], "
                "\"value\": [1, 2]}}"),
            bad + ":1:38: 'workpiece': x has 2 values but value has 1");
  EXPECT_EQ(err("{\"guide\": {}}"), bad + ":1:1: 'workpiece' is missing");
  EXPECT_EQ(err("{\"workpiece\": {\n  \"x\": [0, \"a\"], \"value\": [1, 2]}}"),
            bad + ":2:12: 'workpiece.x[1]' must be a number");
  EXPECT_EQ(err("{\"method\": \"five-point\", \"workpiece\": {}}").rfind(bad + ":1:12: ", 0), 0u);
  // A figure's uncertainty that is neither a number nor null is named where it stands.
  const std::string two = "{\"x\": [0, 1], \"value\": [1, 2]}";
  const std::string with_u = "{\"workpiece\": " + two + ", \"guide\": " + two +
                             ",\n \"straightness\": {\"workpiece\": {\"ls\": 1, \"min_zone\": 1, "
                             "\"U_um\": \"big\"}, \"guide\": {\"ls\": 1, \"min_zone\": 1}}}";
  EXPECT_EQ(err(with_u).rfind(bad + ":2:", 0), 0u) << err(with_u);
  EXPECT_NE(err(with_u).find("U_um"), std::string::npos) << err(with_u);
}

// x arrays that repeat the previous one or its start reuse its text: the file must read back
// exactly, whether the text was cut inside one formatting piece or at a piece's edge.
TEST(ResultJson, SharedGridsReadBackExactly) {
  const Eigen::Index n = 150000;  // several formatting pieces
  separation::Result r;
  const Eigen::VectorXd xw = Eigen::VectorXd::LinSpaced(n + 2, -0.02, 0.01 * (n - 1)) * 1.0000001;
  r.workpiece = {xw, Eigen::VectorXd::Constant(n + 2, 1e-3), {}};
  r.guide = {xw.head(n), Eigen::VectorXd::Constant(n, 2e-3), {}};  // the start of the last
  r.pitch = separation::Profile{xw.head(2), Eigen::VectorXd::Constant(2, 1e-6), {}};
  const std::string p = test::temp_file("grids.json", "");
  io::write_result(p, r);
  auto back = io::read_result(p);
  EXPECT_EQ(back.workpiece.x, r.workpiece.x);
  EXPECT_EQ(back.guide.x, r.guide.x);
  ASSERT_TRUE(back.pitch);
  EXPECT_EQ(back.pitch->x, r.pitch->x);
  // A grid that is not the start of the last one is written in full.
  r.guide.x = xw.tail(n);
  r.pitch = separation::Profile{xw.tail(n), Eigen::VectorXd::Constant(n, 1e-6), {}};
  io::write_result(p, r);
  back = io::read_result(p);
  EXPECT_EQ(back.guide.x, r.guide.x);
  ASSERT_TRUE(back.pitch);
  EXPECT_EQ(back.pitch->x, r.pitch->x);
}

// An angle column (µrad) read as a fourth probe (µm) turned a 2.6 µm straightness into 237 µm:
// columns are taken as probes only when that is unambiguous.
TEST(Probes, AngleColumnIsNeverASilentProbe) {
  const char* with_angle = "x,a,b,c,angle\n0,1,2,3,10\n10,1,2,3,11\n20,1,2,3,12\n30,1,2,3,13\n";
  EXPECT_EQ(read_error(with_angle),
            "p.csv:1:9: column 'angle' looks like an angle channel, not a probe: give --angle "
            "angle to use it (µrad), or --probes to list the probe columns");
  io::ProbeReadOptions o;
  o.offsets = {0, 10, 20};
  EXPECT_EQ(read_error(std::string(kGood), o),
            "p.csv:1:9: unexpected column 'ang': 3 offsets were given for 4 data columns; name "
            "the probe columns with --probes, or an angle channel with --angle");
  // Named probes: exactly those, in that order; other columns are left alone.
  io::ProbeReadOptions named;
  named.probe_columns = {"c", "a"};
  const auto d = io::read_probes(test::temp_file("n.csv", with_angle), named);
  ASSERT_EQ(d.readings.cols(), 2);
  EXPECT_DOUBLE_EQ(d.readings(0, 0), 3e-3);
  EXPECT_DOUBLE_EQ(d.readings(0, 1), 1e-3);
  EXPECT_EQ(d.angle.size(), 0);
  named.probe_columns = {"a", "x"};
  EXPECT_EQ(read_error(with_angle, named),
            "p.csv:1:1: column 'x' cannot be a probe (it is the station position)");
  named.probe_columns = {"a", "zz"};
  EXPECT_NE(read_error(with_angle, named).find("zz"), std::string::npos);
}

// Units written in the names read to the same data as the plain file; an angle channel is known
// by its unit as well as by its name.
TEST(Probes, UnitsInTheHeaderReadAsThePlainFile) {
  constexpr double kRoundOff = 1e-15;  // mm: a nm → µm → mm conversion of a few µm
  io::ProbeReadOptions o;
  o.angle_column = "pitch";
  const auto plain = io::read_probes(
      test::temp_file("u0.csv", "x,a,b,c,pitch\n0,1,2,3,10\n10,1.5,2,3,11\n20,1,2.5,3,12\n"), o);
  const auto units = io::read_probes(
      test::temp_file("u1.csv",
                      "x [m],a (\xC2\xB5m),b / nm,c_um,pitch [mrad]\n0,1,2000,3,0.010\n"
                      "0.01,1.5,2000,3,0.011\n0.02,1,2500,3,0.012\n"),
      o);
  ASSERT_EQ(units.readings.cols(), plain.readings.cols());
  EXPECT_TRUE(units.x.isApprox(plain.x, kRoundOff));
  EXPECT_LT((units.readings - plain.readings).cwiseAbs().maxCoeff(), kRoundOff);
  EXPECT_LT((units.angle - plain.angle).cwiseAbs().maxCoeff(), 1e-18);
  EXPECT_EQ(read_error("x,a,b,c,tilt [arcsec]\n0,1,2,3,1\n10,1,2,3,1\n20,1,2,3,1\n"),
            "p.csv:1:9: column 'tilt [arcsec]' looks like an angle channel, not a probe: give "
            "--angle tilt to use it (µrad), or --probes to list the probe columns");
  // x written in metres against offsets in mm: named, with the unit it looks like.
  io::ProbeReadOptions mm;
  mm.offsets = {0, 10, 20};
  std::string metres = "x,a,b,c\n";
  for (int k = 0; k < 50; ++k) metres += fmt::format("{},1,2,3\n", 0.01 * k);
  EXPECT_EQ(read_error(metres, mm),
            "p.csv:1:1: x spans only 0.49 mm but the probes are 20 mm apart: no point of the "
            "workpiece is read by two probes. Is x in metres? Name the column 'x [m]' (or write "
            "millimetres)");
  EXPECT_EQ(read_error(metres.replace(0, 1, "x [m]"), mm), "");  // said so: read as 0 .. 490 mm
  EXPECT_EQ(read_error("x [s],a,b\n0,1,2\n10,1,2\n20,1,2\n"),
            "p.csv:1:1: column 'x [s]' is in s, a time; x holds a length (for example in mm)");
  EXPECT_EQ(read_error("x,a,b [\xC2\xB0"
                       "C]\n0,1,2\n10,1,2\n20,1,2\n"),
            "p.csv:1:5: column 'b [\xC2\xB0"
            "C]' is in \xC2\xB0"
            "C, a temperature; b holds a "
            "length (for example in \xC2\xB5m)");
}

// A large file's arrays are asked for in transparent huge pages before they are written (a page
// fault per 4 KB of new memory was a third of a 10⁶-station run): the parsed columns, the probe
// data, and the text pieces numbers are formatted into.
TEST(Probes, LargeArraysAskForHugePages) {
  constexpr int kRows = 400000;  // 3.2 MB per column
  std::string text = "x,a,b\n";
  for (int i = 0; i < kRows; ++i) text += fmt::format("{},{},{}\n", i, i % 7, i % 11);
  const std::string path = trueaxis::test::temp_file("big.csv", text);
  const auto table = trueaxis::io::CsvTable::read(path);
  const auto d = trueaxis::io::read_probes(path);
  std::vector<std::string> pieces;
  const Eigen::VectorXd v = Eigen::VectorXd::LinSpaced(kRows, 0, 1);
  trueaxis::io::detail::format_numbers(v.data(), kRows, 1.0, ',', pieces);
  ASSERT_EQ(table.rows(), static_cast<std::size_t>(kRows));
  ASSERT_EQ(d.readings.rows(), kRows);
  EXPECT_EQ(table.column(2)[kRows - 1], (kRows - 1) % 11);
  EXPECT_EQ(d.readings(kRows - 1, 0), 1e-3 * ((kRows - 1) % 7));
  const std::vector<std::pair<const char*, const void*>> arrays{
      {"column", table.column(1).data() + kRows / 2},
      {"station positions", d.x.data() + kRows / 2},
      {"readings", d.readings.data() + kRows},
      {"formatted text", pieces.front().data() + pieces.front().size() / 2}};
  for (const auto& [what, p] : arrays) {
    const std::string flags = trueaxis::test::vm_flags_of_mapping(p);
    ASSERT_NE(flags, "") << what << ": no mapping holds it";
    EXPECT_NE(flags.find(" hg"), std::string::npos) << what << ": " << flags;
  }
}

// A file that states where its probes stood: "name@mm" in the probe columns' names. The offsets
// come from the names (the same result as --offsets), --probes finds a column by its stem, a
// unit written before '@' is converted, and a file that states nothing is marked as assumed.
TEST(Probes, OffsetsWrittenInTheColumnNames) {
  const std::string named =
      test::temp_file("named.csv",
                      "x,a@0,b [nm]@10,c @ 30 mm\n0,1,2000,3\n10,1,2000,3\n20,1,2000,3\n30,1,2000,"
                      "3\n40,1,2000,3\n");
  const auto d = io::read_probes(named);
  EXPECT_EQ(d.offsets, (std::vector<double>{0, 10, 30}));
  EXPECT_FALSE(d.offsets_assumed);
  EXPECT_NEAR(d.readings(0, 1), 2e-3, 1e-15);  // 2000 nm = 2 µm = 0.002 mm
  io::ProbeReadOptions o;
  o.probe_columns = {"a", "c"};
  const auto picked = io::read_probes(named, o);
  EXPECT_EQ(picked.offsets, (std::vector<double>{0, 30}));
  // Round trip: write_probes names the columns with their offsets.
  separation::ProbeData w = d;
  const std::string back = test::temp_file("back.csv", "");
  io::write_probes(back, w);
  EXPECT_EQ(io::read_probes(back).offsets, d.offsets);
  const auto plain = io::read_probes(test::temp_file("plain.csv", kGood));
  EXPECT_TRUE(plain.offsets_assumed);
  EXPECT_NE(read_error("x,a@0,b@0.5.1\n0,1,2\n10,1,2\n20,1,2\n")
                .find("column 'b@0.5.1': the probe offset after '@' must be a number of mm"),
            std::string::npos);
  const char* angle_named = "x,a@0,b [urad]@10\n0,1,2\n10,1,2\n20,1,2\n";
  EXPECT_NE(read_error(angle_named).find("p.csv:1:7: column 'b [urad]@10' looks like an angle"),
            std::string::npos)
      << read_error(angle_named);
  io::ProbeReadOptions both;
  both.probe_columns = {"a", "b [urad]"};
  EXPECT_NE(read_error(angle_named, both).find("a probe reads a length, not µrad"),
            std::string::npos)
      << read_error(angle_named, both);
}
