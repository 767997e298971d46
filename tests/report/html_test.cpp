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
  EXPECT_NE(h.find("[1,-1,0]"), std::string::npos);        // workpiece in µm
  EXPECT_NE(h.find("[1.2,-0.8,0.2]"), std::string::npos);  // +2u band
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
}
