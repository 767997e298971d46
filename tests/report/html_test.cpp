#include "trueaxis/report/html.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "trueaxis/geometry/fit.hpp"
#include "trueaxis/geometry/straightness.hpp"
#include "trueaxis/report/fit.hpp"

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

// A straightness profile is drawn with the lines its figures are about (ISO 12780-1): the
// least-squares line, and the minimum zone's two lines that enclose every point, touch it, and
// are as far apart as the minimum-zone straightness the table states.
TEST(Report, StraightnessProfilesCarryTheirLeastSquaresLineAndMinimumZone) {
  constexpr double kTol = 1e-9;  // µm: round-off of lines evaluated at 200 points
  const Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(200, 0, 995);
  Eigen::VectorXd y(x.size());
  for (Eigen::Index i = 0; i < x.size(); ++i)
    y[i] = 2e-3 * std::sin(x[i] / 90) + 1e-6 * x[i] + 0.4e-3 * std::cos(x[i] / 7);
  separation::Result r;
  r.workpiece = {x, y, {}};
  r.guide = {x, -y, {}};
  r.workpiece_straightness.min_zone = geometry::min_zone(x, y).width;
  const report::Section s = report::separation_section("s", r);
  ASSERT_GE(s.plots.size(), 2u);
  const report::Plot& p = s.plots.front();
  ASSERT_EQ(p.series.size(), 4u);  // profile, LS line, the zone's two lines
  EXPECT_EQ(p.series[1].label, "least-squares line");
  EXPECT_EQ(p.series[2].label, "minimum zone");
  EXPECT_TRUE(p.series[2].in_legend);
  EXPECT_FALSE(p.series[3].in_legend);  // one legend entry for the pair
  // Each line is given at the profile's ends (the plot spans the gaps between).
  EXPECT_TRUE(p.span_gaps);
  for (std::size_t k = 1; k <= 3; ++k) {
    EXPECT_TRUE(std::isfinite(p.series[k].y[0]) && std::isfinite(p.series[k].y[199]));
    EXPECT_TRUE(std::isnan(p.series[k].y[100]));
  }
  const auto at = [&](std::size_t k, Eigen::Index i) {  // series k's line at x[i]
    const double t = (x[i] - x[0]) / (x[199] - x[0]);
    return (1 - t) * p.series[k].y[0] + t * p.series[k].y[199];
  };
  const geometry::Line ls = geometry::fit_line(x, y);
  const Eigen::VectorXd prof = y * 1e3;
  double touch_lower = INFINITY, touch_upper = INFINITY;
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    EXPECT_NEAR(at(1, i), ls(x[i]) * 1e3, kTol);
    EXPECT_GE(prof[i], at(2, i) - kTol);
    EXPECT_LE(prof[i], at(3, i) + kTol);
    touch_lower = std::min(touch_lower, prof[i] - at(2, i));
    touch_upper = std::min(touch_upper, at(3, i) - prof[i]);
  }
  EXPECT_NEAR(touch_lower, 0, kTol);  // each line touches the profile
  EXPECT_NEAR(touch_upper, 0, kTol);
  // Vertical gap × cos(slope) = the zone's width, as tabulated.
  const double slope = (p.series[2].y[199] - p.series[2].y[0]) / (x[199] - x[0]);
  EXPECT_NEAR((p.series[3].y[0] - p.series[2].y[0]) / std::sqrt(1 + slope * slope * 1e-6),
              r.workpiece_straightness.min_zone * 1e3, kTol);
  const std::string h = report::render("t", {s});
  EXPECT_NE(h.find("label:\"minimum zone, upper line\",stroke:'#2ca02c',width:1.5,dash:[6,4],"
                   "spanGaps:true,edge:true}"),
            std::string::npos);
}

// A fit's report shows its residuals point by point, so a pattern the element does not describe
// (here a three-lobed form on a circle) can be seen, not only its RMS.
TEST(Report, FitSectionPlotsEveryResidual) {
  constexpr double kTol = 1e-9;  // µm
  Eigen::Matrix3Xd pts(3, 90);
  for (int i = 0; i < 90; ++i) {
    const double t = 2 * M_PI * i / 90, r = 10 + 2e-3 * std::cos(3 * t);
    pts.col(i) = Eigen::Vector3d(r * std::cos(t), r * std::sin(t), 0);
  }
  const geometry::Fit f = geometry::fit(geometry::Element::Circle, pts);
  const report::Section s = report::fit_section("circle", f);
  ASSERT_EQ(s.plots.size(), 1u);
  const report::Plot& p = s.plots.front();
  EXPECT_EQ(p.title, "residuals: orthogonal distance of each point to the fitted circle");
  ASSERT_EQ(p.x.size(), 90);
  EXPECT_EQ(p.x[0], 1);
  EXPECT_EQ(p.x[89], 90);
  ASSERT_EQ(p.series.size(), 1u);
  EXPECT_TRUE(p.series[0].points);
  EXPECT_NEAR((p.series[0].y - f.residuals * 1e3).cwiseAbs().maxCoeff(), 0, kTol);
  EXPECT_NEAR(p.series[0].y.maxCoeff(), 2, 1e-3);  // the lobes' 2 µm
}

// Printed, a table fits the page: many columns in a smaller type (class "wide"), a cell of prose
// wraps (class "txt"), a value does not (the print stylesheet keeps other cells on one line).
TEST(Report, PrintedTablesFitThePage) {
  report::Section s;
  s.table = {{"quantity", "value"},
             {"flatness", "4.5"},
             {"uncertainty", "U = 1.5 µm (95 %): reading noise 0.18 arc-second, from the closure"}};
  std::vector<std::string> head{"line"}, row{"NW_SE"};
  for (int k = 0; k < 21; ++k) {
    head.push_back("station " + std::to_string(k));
    row.push_back("1.58");
  }
  s.more_tables.push_back({"Union Jack", {head, row}});
  const std::string h = report::render("t", {s});
  EXPECT_NE(h.find("<table><tr><th>quantity</th>"), std::string::npos);
  EXPECT_NE(h.find("<td>4.5</td>"), std::string::npos);
  EXPECT_NE(h.find("<td class=\"txt\">U = 1.5 µm (95 %)"), std::string::npos);
  EXPECT_NE(h.find("<table class=\"wide\"><tr><th>line</th>"), std::string::npos);
  EXPECT_NE(h.find("td{white-space:nowrap} td.txt{white-space:normal"), std::string::npos);
}
