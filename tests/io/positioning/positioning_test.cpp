// runs.csv: what is read, what is refused (file:line:col), and the result JSON's keys.
#include "trueaxis/io/positioning/positioning.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "../../test_util.hpp"
#include "trueaxis/positioning/positioning.hpp"

using namespace trueaxis;

namespace {

std::string runs_error(const std::string& text) {
  return test::error_of([&] { io::parse_runs(text, "runs.csv"); });
}

}  // namespace

TEST(PositioningIo, ReadsRunsInAnyColumnOrder) {
  const auto r = io::parse_runs(
      "# laser run, X axis\r\n"
      "Cycle, direction, target_mm, deviation_um, material_temp_c, air_temp_c\r\n"
      "1, +, 0, 0.5, 20.5, 20.1\r\n"
      "\r\n"
      "1, down, 50, -1.25, 20.6, 20.2\r\n",
      "runs.csv");
  ASSERT_EQ(r.readings.size(), 2u);
  EXPECT_TRUE(r.has_material);
  EXPECT_TRUE(r.has_air);
  EXPECT_EQ(r.lines[1], 5u);
  EXPECT_EQ(r.readings[0].direction, positioning::Direction::Up);
  EXPECT_EQ(r.readings[1].direction, positioning::Direction::Down);
  EXPECT_DOUBLE_EQ(r.readings[1].target, 50);
  EXPECT_DOUBLE_EQ(r.readings[1].deviation, -1.25e-3);
  EXPECT_DOUBLE_EQ(r.readings[1].material_temperature, 20.6);
  EXPECT_DOUBLE_EQ(r.readings[0].air_temperature, 20.1);
}

// A laser's runs saved from a German Excel: "sep=;", semicolons, decimal commas, quotes, CRLF.
TEST(PositioningIo, RunsFromASpreadsheetReadAsThePlainFile) {
  const auto plain = io::parse_runs(
      "target_mm,cycle,direction,deviation_um,material_temp_c\n"
      "0,1,+,0.5,20.5\n50.5,1,+,-1.25,20.6\n50.5,1,-,2,20.6\n",
      "runs.csv");
  for (const char* text : {
           "sep=;\r\ntarget_mm;cycle;direction;deviation_um;material_temp_c\r\n"
           "0;1;+;0,5;20,5\r\n50,5;1;+;-1,25;20,6\r\n50,5;1;-;2;20,6\r\n",
           "\"target_mm\",\"cycle\",\"direction\",\"deviation_um\",\"material_temp_c\"\n"
           "0,1,\"+\",\"0,5\",\"20,5\"\n\"50,5\",1,\"+\",\"-1,25\",\"20,6\"\n"
           "\"50,5\",1,\"-\",2,\"20,6\"\n",
       }) {
    SCOPED_TRACE(text);
    const auto r = io::parse_runs(text, "runs.csv");
    ASSERT_EQ(r.readings.size(), plain.readings.size());
    for (std::size_t i = 0; i < r.readings.size(); ++i) {
      EXPECT_EQ(r.readings[i].target, plain.readings[i].target);
      EXPECT_EQ(r.readings[i].deviation, plain.readings[i].deviation);
      EXPECT_EQ(r.readings[i].direction, plain.readings[i].direction);
      EXPECT_EQ(r.readings[i].material_temperature, plain.readings[i].material_temperature);
    }
  }
  EXPECT_EQ(runs_error("target_mm;cycle;direction;deviation_um\n0;1;+;0,5\n50;1;+;x\n"),
            "runs.csv:3:8: 'x' is not a number (column 'deviation_um')");
}

// Units written in the header, as instruments and spreadsheets write them, read to the same
// readings as the plain file; a unit of the wrong kind, or none a table can hold, is refused.
TEST(PositioningIo, UnitsInTheHeaderConvertOrAreRefused) {
  constexpr double kRoundOff = 1e-12;  // mm: a unit conversion's rounding on 0.05 .. 500 mm
  const auto plain = io::parse_runs(
      "target_mm,cycle,direction,deviation_um,air_temp_c\n"
      "0,1,+,0.5,20.5\n250,1,+,-1.25,20.6\n250,1,-,2,20.6\n",
      "runs.csv");
  for (const char* text : {
           "target [mm],cycle,direction,deviation [\xC2\xB5m],air_temp [\xC2\xB0"
           "C]\n"
           "0,1,+,0.5,20.5\n250,1,+,-1.25,20.6\n250,1,-,2,20.6\n",
           "Target (m),Cycle,Direction,Deviation / nm,Air_Temp (C)\n"
           "0,1,+,500,20.5\n0.25,1,+,-1250,20.6\n0.25,1,-,2000,20.6\n",
           "target_mm,cycle,direction,deviation (\xCE\xBCm),air_temp_degC\n"  // Greek mu
           "0,1,+,0.5,20.5\n250,1,+,-1.25,20.6\n250,1,-,2,20.6\n",
           "sep=;\ntarget [mm];cycle;direction;deviation [\xB5m];air_temp [\xB0"
           "C]\n"  // Latin-1
           "0;1;+;0,5;20,5\n250;1;+;-1,25;20,6\n250;1;-;2;20,6\n",
           "target [in],cycle,direction,deviation [mm],air_temp_c\n"
           "0,1,+,0.0005,20.5\n9.842519685039370,1,+,-0.00125,20.6\n"
           "9.842519685039370,1,-,0.002,20.6\n",
       }) {
    SCOPED_TRACE(text);
    const auto r = io::parse_runs(text, "runs.csv");
    ASSERT_EQ(r.readings.size(), plain.readings.size());
    for (std::size_t i = 0; i < r.readings.size(); ++i) {
      EXPECT_NEAR(r.readings[i].target, plain.readings[i].target, kRoundOff);
      EXPECT_NEAR(r.readings[i].deviation, plain.readings[i].deviation, kRoundOff);
      EXPECT_EQ(r.readings[i].air_temperature, plain.readings[i].air_temperature);
    }
  }
  EXPECT_EQ(runs_error("target_mm,cycle,direction,deviation [s]\n0,1,+,1\n"),
            "runs.csv:1:27: column 'deviation [s]' is in s, a time; deviation holds a length "
            "(for example in \xC2\xB5m)");
  EXPECT_EQ(runs_error("target_mm,cycle [mm],direction,deviation_um\n0,1,+,1\n"),
            "runs.csv:1:11: column 'cycle [mm]' is in mm, a length; cycle holds a plain number "
            "and takes no unit");
  EXPECT_EQ(runs_error("target [furlong],cycle,direction,deviation_um\n0,1,+,1\n"),
            "runs.csv:1:1: column 'target [furlong]': 'furlong' is not a unit this table can "
            "hold (lengths mm, \xC2\xB5m, nm, m, in; angles rad, mrad, \xC2\xB5rad, deg, arcsec; "
            "times s, ms, min; temperatures \xC2\xB0"
            "C)");
  EXPECT_EQ(runs_error("target_mm,target [m],cycle,direction,deviation_um\n"),
            "runs.csv:1:11: column 'target [m]' holds the target again (column 'target_mm' "
            "before it)");
  // The range check is on the converted value: 2 km of axis is refused in mm.
  EXPECT_EQ(runs_error("target [m],cycle,direction,deviation_um\n2000,1,+,1\n"),
            "runs.csv:2:1: 2e+06 mm is out of range in column 'target [m]' (its size must be at "
            "most 1e+06 mm)");
}

// A dropped reading is named at the line where the run skips the target, not by its count.
TEST(PositioningIo, AMissingReadingIsNamedWhereTheRunSkipsIt) {
  const std::string text =
      "target_mm,cycle,direction,deviation_um\n"
      "0,1,+,1\n100,1,+,2\n200,1,+,3\n"   // lines 2-4
      "200,1,-,3\n100,1,-,2\n0,1,-,1\n"   // lines 5-7
      "0,2,+,1\n200,2,+,3\n"              // lines 8-9: 100 mm dropped before line 9
      "200,2,-,3\n100,2,-,2\n0,2,-,1\n";  // lines 10-12
  const auto runs = io::parse_runs(text, "runs.csv");
  positioning::Options o;
  o.locate = [&](std::size_t k) { return fmt::format("runs.csv:{}:1: ", runs.lines[k]); };
  EXPECT_EQ(test::error_of([&] { positioning::evaluate(runs.readings, o); }),
            "runs.csv:9:1: no '+' reading at target 100 mm in cycle 2 (every target needs one "
            "reading per cycle and direction; allow incomplete cycles to evaluate each target "
            "with the readings it has)");
  // The last target of a '-' run dropped: named at the run's last reading.
  std::string full = text;
  full.insert(full.find("200,2,+,3"), "100,2,+,2\n");
  const auto tail = io::parse_runs(full.substr(0, full.rfind("0,2,-,1\n")), "runs.csv");
  o.locate = [&](std::size_t k) { return fmt::format("runs.csv:{}:1: ", tail.lines[k]); };
  const std::string e = test::error_of([&] { positioning::evaluate(tail.readings, o); });
  EXPECT_EQ(e.substr(0, e.find(" (")), "runs.csv:12:1: no '-' reading at target 0 mm in cycle 2");
  // A reading given twice (as a Renishaw file can list it) is named at both places.
  std::vector<positioning::Reading> twice = runs.readings;
  std::vector<std::size_t> lines = runs.lines;
  twice.push_back(runs.readings[0]);
  lines.push_back(13);
  o.locate = [&](std::size_t k) { return fmt::format("runs.csv:{}:1: ", lines[k]); };
  EXPECT_EQ(test::error_of([&] { positioning::evaluate(twice, o); }),
            "runs.csv:13:1: cycle 1 '+' at target 0 mm again (first at runs.csv:2:1)");
  // Without a place, as from Python with readings made in memory, the message stands alone.
  o.locate = nullptr;
  const std::string bare = test::error_of([&] { positioning::evaluate(runs.readings, o); });
  EXPECT_EQ(bare.substr(0, bare.find(" (")), "no '+' reading at target 100 mm in cycle 2");
}

TEST(PositioningIo, BadRunsNameFileLineAndColumn) {
  const std::string h = "target_mm,cycle,direction,deviation_um\n";
  EXPECT_EQ(runs_error(""),
            "runs.csv: no header (expected target_mm,cycle,direction,deviation_um)");
  EXPECT_EQ(runs_error(h), "runs.csv:1:1: no readings after the header");
  EXPECT_EQ(runs_error("target_mm,cycle,dir,deviation_um\n"),
            "runs.csv:1:17: unknown column 'dir' (target_mm, cycle, direction, deviation_um, "
            "material_temp_c, air_temp_c; a unit may be written in the name, as in 'target [m]' "
            "or 'deviation (nm)')");
  EXPECT_EQ(runs_error("target_mm,cycle,direction\n0,1,+\n"),
            "runs.csv:1:1: the header has no 'deviation' column (target_mm, cycle, direction "
            "and deviation_um are needed; a unit may be written in the name)");
  EXPECT_EQ(runs_error("target_mm,cycle,cycle,deviation_um\n"),
            "runs.csv:1:17: column 'cycle' appears twice");
  EXPECT_EQ(runs_error(h + "0,1,+\n"), "runs.csv:2:6: 3 fields, the header has 4 columns");
  EXPECT_EQ(runs_error(h + "0,1,+,1,2\n"), "runs.csv:2:8: 5 fields, the header has 4 columns");
  EXPECT_EQ(runs_error(h + "0,1,x,1\n"),
            "runs.csv:2:5: direction 'x': use '+' (approach moving in +) or '-'");
  EXPECT_EQ(runs_error(h + "0,1.5,+,1\n"),
            "runs.csv:2:3: cycle '1.5' is not a whole number from 1");
  EXPECT_EQ(runs_error(h + "0,0,+,1\n"), "runs.csv:2:3: cycle '0' is not a whole number from 1");
  EXPECT_EQ(runs_error(h + "0,1,+,abc\n"),
            "runs.csv:2:7: 'abc' is not a number (column 'deviation_um')");
  EXPECT_EQ(runs_error(h + "0,1,+,nan\n"),
            "runs.csv:2:7: 'nan' is not a number (column 'deviation_um')");
  EXPECT_EQ(runs_error(h + "0,1,+,\n"), "runs.csv:2:7: empty field in column 'deviation_um'");
  EXPECT_EQ(runs_error(h + "2e6,1,+,1\n"),
            "runs.csv:2:1: 2e+06 mm is out of range in column 'target_mm' (its size must be at "
            "most 1e+06 mm)");
  EXPECT_EQ(runs_error(h + "0,1,+,1\n\n10,1,+,1\n0,1,+,2\n"),
            "runs.csv:5:1: cycle 1 '+' at target 0 mm was already read on line 2");
  EXPECT_EQ(runs_error("target_mm,cycle,direction,deviation_um,material_temp_c\n0,1,+,1,200\n"),
            "runs.csv:2:9: 200 is not a plausible temperature in degrees Celsius (column "
            "'material_temp_c')");
}

TEST(PositioningIo, RoundTripAndResultKeys) {
  std::vector<positioning::Reading> rs;
  for (int c = 1; c <= 2; ++c)
    for (double p : {0.0, 100.0, 200.0}) {
      rs.push_back({p, c, positioning::Direction::Up, 1e-3 * (p / 100 + c), 20.25});
      rs.push_back({p, c, positioning::Direction::Down, -1e-3 * (p / 100 + c), 20.5});
    }
  const std::string dir = test::temp_dir();
  io::write_runs(dir + "/runs.csv", rs);
  const auto back = io::read_runs(dir + "/runs.csv");
  ASSERT_EQ(back.readings.size(), rs.size());
  for (std::size_t k = 0; k < rs.size(); ++k) {
    EXPECT_EQ(back.readings[k].target, rs[k].target);
    EXPECT_EQ(back.readings[k].deviation, rs[k].deviation);  // shortest exact form
    EXPECT_EQ(back.readings[k].cycle, rs[k].cycle);
    EXPECT_EQ(back.readings[k].direction, rs[k].direction);
    EXPECT_EQ(back.readings[k].material_temperature, rs[k].material_temperature);
  }
  const auto r = positioning::evaluate(back.readings);
  const auto v = positioning::check(r, {{"A", 1.0}});
  io::write_positioning_result(dir + "/p.json", r, positioning::Standard::Iso230_2, v);
  std::ifstream f(dir + "/p.json");
  const auto j = nlohmann::json::parse(f);
  for (const char* k : {"A", "A_up", "A_down", "E", "E_up", "E_down", "M", "R", "R_up", "R_down",
                        "B", "B_mean", "targets", "standard", "cycles", "pass"})
    EXPECT_TRUE(j.contains(k)) << k;
  EXPECT_EQ(j["standard"], "ISO 230-2:2014");
  EXPECT_EQ(j["kind"], "positioning");
  EXPECT_EQ(j["targets"].size(), 3u);
  for (const char* k : {"position", "mean_up", "mean_down", "s_up", "s_down", "B", "R"})
    EXPECT_TRUE(j["targets"][0].contains(k)) << k;
  EXPECT_NEAR(j["E"].get<double>(), r.iso.E * 1e3, 1e-9);
  EXPECT_TRUE(j["temperature"]["corrected"].get<bool>());
  EXPECT_TRUE(j["pass"].get<bool>());
  io::write_positioning_result(dir + "/v.json", r, positioning::Standard::Vdi3441);
  std::ifstream g(dir + "/v.json");
  const auto jv = nlohmann::json::parse(g);
  EXPECT_EQ(jv["standard"], "VDI/DGQ 3441");
  EXPECT_NEAR(jv["P"].get<double>(), r.vdi.P * 1e3, 1e-9);
  EXPECT_TRUE(jv["pass"].is_null());
}

TEST(PositioningIo, ResultReadsBackForTheReport) {
  std::vector<positioning::Reading> rs;
  for (int c = 1; c <= 3; ++c)
    for (double p : {0.0, 100.0, 200.0}) {
      rs.push_back({p, c, positioning::Direction::Up, 1e-3 * (p / 100 + 0.3 * c), 20.5 + 0.1 * c});
      rs.push_back(
          {p, c, positioning::Direction::Down, -1e-3 * (p / 50 - 0.2 * c), 20.5 + 0.1 * c});
    }
  const auto r = positioning::evaluate(rs);
  const auto verdicts = positioning::check(r, {{"A", 5e-3}, {"B", 1e-3}});
  const std::string dir = test::temp_dir();
  for (auto standard : {positioning::Standard::Iso230_2, positioning::Standard::Vdi3441}) {
    io::write_positioning_result(dir + "/p.json", r, standard, verdicts);
    const auto f = io::read_positioning_result(dir + "/p.json");
    EXPECT_EQ(f.standard, standard);
    const bool vdi = standard == positioning::Standard::Vdi3441;
    for (const auto& name : positioning::parameter_names()) {
      const bool iso_name = name != "P" && name != "Pa" && name != "Ps" && name != "U";
      const double back = positioning::parameter(f.result, name);
      if (iso_name == vdi)
        EXPECT_TRUE(std::isnan(back)) << name;  // the other standard's parameters are not written
      else
        EXPECT_NEAR(back, positioning::parameter(r, name), 1e-15) << name;
    }
    ASSERT_EQ(f.result.targets.size(), 3u);
    EXPECT_NEAR(f.result.targets[2].mean_down, r.targets[2].mean_down, 1e-15);
    EXPECT_NEAR(f.result.targets[1].s_up, r.targets[1].s_up, 1e-15);
    ASSERT_EQ(f.result.readings.size(), rs.size());
    EXPECT_EQ(f.result.readings[5].direction, positioning::Direction::Down);
    EXPECT_NEAR(f.result.readings[5].deviation, r.readings[5].deviation, 1e-15);
    EXPECT_TRUE(f.result.temperature_corrected);
    EXPECT_DOUBLE_EQ(f.result.material_max, 20.8);
    ASSERT_EQ(f.verdicts.size(), 2u);
    EXPECT_EQ(f.verdicts[1].name, "B");
    EXPECT_EQ(f.verdicts[1].pass, verdicts[1].pass);
    EXPECT_EQ(f.result.warnings, r.warnings);
  }
  const std::string bad = test::temp_file(
      "bad.json", "{\"kind\": \"positioning\",\n \"standard\": \"ISO 9999\", \"targets\": []}");
  EXPECT_EQ(test::error_of([&] { io::read_positioning_result(bad); }),
            bad + ":2:14: unknown standard 'ISO 9999'");
  const std::string empty = test::temp_file(
      "empty.json", "{\"kind\": \"positioning\", \"standard\": \"VDI/DGQ 3441\", \"targets\": []}");
  EXPECT_NE(test::error_of([&] { io::read_positioning_result(empty); }).find("no targets"),
            std::string::npos);
  const std::string cyc = test::temp_file(
      "cyc.json",
      "{\"standard\": \"VDI/DGQ 3441\", \"cycles\": 2.5, \"targets\": [{\"position\": 0}]}");
  EXPECT_NE(test::error_of([&] { io::read_positioning_result(cyc); }).find("whole number"),
            std::string::npos);
}

TEST(PositioningIo, LogReadsAndRefuses) {
  const auto log =
      io::read_log(test::temp_file("log.csv", "time_s,reading_mm\n0,0.001\n0.1,0.002\n0.2,0.5\n"));
  ASSERT_EQ(log.time.size(), 3u);
  EXPECT_DOUBLE_EQ(log.reading[2], 0.5);
  const std::string back = test::temp_dir() + "/back.csv";
  io::write_log(back, log);
  EXPECT_EQ(io::read_log(back).reading, log.reading);
  auto err = [](const std::string& text) {
    const std::string p = test::temp_file("bad.csv", text);
    const std::string e = test::error_of([&] { io::read_log(p); });
    return e.substr(e.find("bad.csv"));
  };
  EXPECT_EQ(err("time_s,reading_mm\n0,1\n0,2\n"),
            "bad.csv:3:1: time 0 s does not increase (previous sample: 0 s)");
  EXPECT_EQ(err("time_s,reading_mm,x\n0,1,2\n1,2,3\n"),
            "bad.csv:1:1: a log has two columns, time_s and reading_mm (3 found)");
  EXPECT_EQ(err("time_s,reading_mm\n0,1\n"), "bad.csv: a log needs at least two samples");
  EXPECT_NE(err("stamp,reading_mm\n0,1\n1,2\n").find("missing column 'time'"), std::string::npos);
  // Units written in the names convert; a unit of another kind is refused at its place.
  const auto ms =
      io::read_log(test::temp_file("log_ms.csv", "time [ms],reading (um)\n0,1\n100,2\n200,500\n"));
  EXPECT_DOUBLE_EQ(ms.time[1], 0.1);
  EXPECT_DOUBLE_EQ(ms.reading[2], 0.5);
  EXPECT_EQ(err("time_s,reading [s]\n0,1\n1,2\n"),
            "bad.csv:1:8: column 'reading [s]' is in s, a time; reading holds a length (for "
            "example in mm)");
}
