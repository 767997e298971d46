// The report of any result file (report::file_report) over the one reader dispatch by kind
// (io::read_result_file), with the files that are not results.
#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <variant>

#include "../test_util.hpp"
#include "trueaxis/io/result_file.hpp"
#include "trueaxis/io/separation/probes.hpp"
#include "trueaxis/report/files.hpp"
#include "trueaxis/separation/separation.hpp"
#include "trueaxis/sim/straightness.hpp"

using namespace trueaxis;

namespace {

std::string written(const std::string& name, const std::string& text) {
  const std::string path = test::temp_dir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

}  // namespace

TEST(FileReport, AResultFileIsReadByItsKindAndDrawnWithItsFileNamed) {
  sim::StraightnessOptions so;
  so.stations = 60;
  so.step = 5;
  so.offsets = {0, 5, 10};
  const auto camp = sim::simulate_straightness(so);
  separation::Options opt;
  opt.method = separation::Method::ThreePoint;
  const auto r = separation::separate(camp.data, opt);
  const std::string path = test::temp_dir() + "/straight.json";
  io::write_result(path, r);
  const io::ResultFile f = io::read_result_file(path);
  EXPECT_EQ(f.kind, "separation");
  ASSERT_TRUE(std::holds_alternative<separation::Result>(f.result));
  EXPECT_EQ(std::get<separation::Result>(f.result).workpiece.value.size(),
            r.workpiece.value.size());
  const report::FileReport fr = report::file_report(path);
  EXPECT_EQ(fr.kind, "separation");
  EXPECT_EQ(fr.title, "trueaxis straightness report");
  EXPECT_EQ(fr.section.source, "straight.json");
  ASSERT_GE(fr.section.plots.size(), 2u);  // workpiece, guide (and pitch)
  EXPECT_EQ(fr.section.plots.front().title, "workpiece");
}

TEST(FileReport, WhatIsNotAResultIsRefusedInWords) {
  EXPECT_NE(test::error_of([] { io::read_result_file(written("k.json", R"({"kind": "spline"})")); })
                .find("k.json: a 'spline' file is not a result trueaxis writes (results: "
                      "separation, surface"),
            std::string::npos);
  EXPECT_NE(test::error_of([] {
              io::read_result_file(written("n.json", R"({"x": [1, 2]})"));
            }).find("n.json:1:1: not a trueaxis result file"),
            std::string::npos);
  EXPECT_NE(test::error_of([] {
              report::file_report(written("t.json", "not json"));
            }).find("t.json:1:2: invalid JSON"),
            std::string::npos);
  // A kind's own reader checks the rest of the file.
  EXPECT_NE(test::error_of([] {
              io::read_result_file(written("f.json", R"({"kind": "fit", "element": "sphere"})"));
            }).find("f.json"),
            std::string::npos);
}
