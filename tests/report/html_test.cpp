#include "trueaxis/report/html.hpp"

#include <gtest/gtest.h>

using namespace trueaxis;

TEST(Report, EmbedsPlottingLibraryAndData) {
  separation::Result r;
  r.workpiece = {Eigen::VectorXd::LinSpaced(3, 0, 20), Eigen::Vector3d(1e-3, -1e-3, 0),
                 Eigen::Vector3d(1e-4, 1e-4, 1e-4)};
  r.guide = {Eigen::VectorXd::LinSpaced(2, 0, 10), Eigen::Vector2d(0, 0), {}};
  r.unobservable = {"line"};
  r.gauge = "a <gauge> & more";
  const std::string h = report::render("t", {report::separation_section("s", r)});
  EXPECT_NE(h.find("uPlot"), std::string::npos);
  EXPECT_EQ(h.find("<script src="), std::string::npos);  // nothing loaded from outside
  EXPECT_NE(h.find("a &lt;gauge&gt; &amp; more"), std::string::npos);
  EXPECT_NE(h.find("[1,-1,0]"), std::string::npos);              // workpiece in µm
  EXPECT_NE(h.find("u:{1:[0.1,0.1,0.1],}"), std::string::npos);  // u, the page draws ±2u
}

TEST(Report, DecimatesLongSeriesKeepingExtremes) {
  report::Plot p;
  p.x = Eigen::VectorXd::LinSpaced(100000, 0, 1);
  Eigen::VectorXd y = Eigen::VectorXd::Zero(100000);
  y[54321] = 7;
  p.series.push_back({"y", y, {}, "", false});
  report::Section s;
  s.plots.push_back(p);
  const std::string h = report::render("t", {s}, 1000);
  EXPECT_NE(h.find("of 100000 points shown"), std::string::npos);
  EXPECT_NE(h.find(",7,"), std::string::npos);  // the peak survives decimation
  EXPECT_LT(h.size(), 200000u);
  // The curve's CSV: the points drawn (the page stays small), and it says so.
  EXPECT_NE(h.find("download=\".csv\""), std::string::npos);
  EXPECT_NE(h.find("(the points drawn; every point is in the result file)"), std::string::npos);
}

// A report a metrologist would sign: its header (date, what it is about, the coverage factor),
// every table and curve as CSV, the references.
TEST(Report, HeaderCsvLinksAndReferences) {
  report::Section s;
  s.title = "Gauge blocks";
  s.table = {{"quantity", "value"}, {"after, grid", "1.5"}};
  report::Plot p;
  p.title = "error, with bands";
  p.x_label = "x (mm)";
  p.x = Eigen::VectorXd::LinSpaced(3, 0, 2);
  p.series.push_back(
      {"after, grid", Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(0.1, 0.1, 0.1), "", false});
  s.plots.push_back(p);
  s.references = {report::refs::kIso10360_2, report::refs::kGum, report::refs::kIso10360_2};
  const std::string h =
      report::render("t", {s}, 4000, {{"machine", "Prismo <7>"}, {"operator", "K. Tanaka"}});
  EXPECT_NE(h.find("<th>machine</th><td>Prismo &lt;7&gt;</td>"), std::string::npos);
  EXPECT_NE(h.find("<th>operator</th><td>K. Tanaka</td>"), std::string::npos);
  EXPECT_NE(h.find("<th>date</th><td>20"), std::string::npos);
  EXPECT_NE(h.find("k = 2"), std::string::npos);
  EXPECT_NE(h.find("download=\"gauge-blocks-table.csv\" href=\"data:text/csv;charset=utf-8,"
                   "quantity,value%0A%22after,%20grid%22,1.5%0A\""),
            std::string::npos);
  // The curve's CSV is made by the page from the plot's data (the browser test reads it): its
  // link, and the band carried once, as u, not as two edges.
  EXPECT_NE(h.find("download=\"error-with-bands.csv\" data-plot=\"0\">CSV</a>"), std::string::npos);
  EXPECT_NE(h.find("data:[[0,1,2],[1,2,3]],u:{1:[0.1,0.1,0.1],}"), std::string::npos);
  EXPECT_EQ(h.find("upper edge\"},"), std::string::npos);
  // References listed once each.
  const auto first = h.find("ISO 10360-2:2009");
  ASSERT_NE(first, std::string::npos);
  EXPECT_EQ(h.find("ISO 10360-2:2009", first + 1), std::string::npos);
}
