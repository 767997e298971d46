// SVG figures (heat maps, distorted grids) and the surface/space report sections.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "../test_util.hpp"
#include "trueaxis/ballgauge/lengths.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/surface/surface.hpp"
#include "trueaxis/report/ballgauge.hpp"
#include "trueaxis/report/html.hpp"
#include "trueaxis/report/surface.hpp"
#include "trueaxis/sim/machine.hpp"

using namespace trueaxis;

namespace {

std::size_t count(const std::string& s, const std::string& what) {
  std::size_t n = 0;
  for (auto p = s.find(what); p != std::string::npos; p = s.find(what, p + 1)) ++n;
  return n;
}

// The fill colour of the element whose tooltip is `title`.
std::string fill_of(const std::string& svg, const std::string& title) {
  const auto t = svg.find("<title>" + title + "</title>");
  if (t == std::string::npos) return "";
  const auto f = svg.rfind("fill=\"", t);
  return svg.substr(f + 6, 7);
}

}  // namespace

TEST(Svg, NiceMagnificationIsOneTwoOrFiveTimesAPowerOfTen) {
  // 10 µm drawn as at most 40 % of 50 mm: 20 mm / 0.01 mm = 2000.
  EXPECT_DOUBLE_EQ(report::nice_magnification(10, 50), 2000);
  EXPECT_DOUBLE_EQ(report::nice_magnification(13, 50), 1000);  // 1538 → 1000
  EXPECT_DOUBLE_EQ(report::nice_magnification(3, 50), 5000);   // 6667 → 5000
  EXPECT_DOUBLE_EQ(report::nice_magnification(0, 50), 1);
}

TEST(Svg, HeatMapDrawsEveryCellAndPointWithItsValue) {
  report::HeatMap h;
  h.title = "t <1>";
  h.grid_x = Eigen::VectorXd{{0, 10, 20}};
  h.grid_y = Eigen::VectorXd{{0, 5}};
  h.grid_value.resize(2, 3);
  h.grid_value << -2, 0, 1, 2, 0.5, -1;
  h.px = Eigen::VectorXd{{3, 4}};
  h.py = Eigen::VectorXd{{1, 2}};
  h.pvalue = Eigen::VectorXd{{0.25, -0.25}};
  h.lines = {{0, 1}};
  const std::string s = report::svg(h);
  EXPECT_EQ(count(s, "<svg"), 1u);
  EXPECT_EQ(count(s, "<title>"), 6u + 2u);
  EXPECT_EQ(count(s, "<polyline"), 1u);
  EXPECT_NE(s.find("aria-label=\"t &lt;1&gt;\""), std::string::npos);
  // Diverging scale symmetric about 0: the extremes take the end colours, zero the middle.
  EXPECT_EQ(fill_of(s, "0, 5: 2"), "#b2182b");
  EXPECT_EQ(fill_of(s, "0, 0: -2"), "#2166ac");
  EXPECT_EQ(fill_of(s, "10, 0: 0"), "#f7f7f7");
  // A shared scale set by the caller.
  h.vmin = -4;
  h.vmax = 4;
  EXPECT_NE(fill_of(report::svg(h), "0, 5: 2"), "#b2182b");
  // Sequential scale: min → viridis' dark end, max → yellow.
  h.symmetric = false;
  h.vmin = h.vmax = NAN;
  const std::string q = report::svg(h);
  EXPECT_EQ(fill_of(q, "0, 0: -2"), "#440154");
  EXPECT_EQ(fill_of(q, "0, 5: 2"), "#fde725");
}

TEST(Svg, RefusesInconsistentShapes) {
  report::HeatMap h;
  h.grid_x = Eigen::VectorXd{{0, 1, 2}};
  h.grid_y = Eigen::VectorXd{{0, 1}};
  h.grid_value = Eigen::MatrixXd::Zero(3, 2);
  EXPECT_NE(test::error_of([&] { report::svg(h); }).find("len(y) x len(x)"), std::string::npos);
  EXPECT_NE(test::error_of([] { report::svg(report::HeatMap{}); }).find("no data"),
            std::string::npos);
  report::DistortedGrid g;
  g.u = Eigen::VectorXd{{0, 1}};
  g.v = Eigen::VectorXd{{0, 1}};
  g.du = g.dv = Eigen::MatrixXd::Zero(2, 2);
  g.normal = Eigen::MatrixXd::Zero(2, 3);
  EXPECT_NE(test::error_of([&] { report::svg(g); }).find("len(v) x len(u)"), std::string::npos);
}

TEST(Svg, DistortedGridMovesNodesByTheMagnifiedError) {
  report::DistortedGrid g;
  g.u = Eigen::VectorXd{{0, 50, 100}};
  g.v = Eigen::VectorXd{{0, 50}};
  g.du = Eigen::MatrixXd::Zero(2, 3);
  g.dv = Eigen::MatrixXd::Zero(2, 3);
  g.normal = Eigen::MatrixXd::Zero(2, 3);
  g.du(1, 2) = 10;  // µm → ×2000 = 20 mm, 40 % of the 50 mm step
  const std::string s = report::svg(g);
  EXPECT_NE(s.find("×2000"), std::string::npos);
  EXPECT_EQ(count(s, "<circle"), 6u);
  EXPECT_EQ(count(s, "<polyline"), 2u + 3u);
  // Node (100, 50) sits 20 mm right of node (100, 0) in x: compare their pixel positions with
  // the pixel scale from nodes (0, 0) and (50, 0).
  std::vector<double> cx;
  for (auto p = s.find("<circle cx=\""); p != std::string::npos; p = s.find("<circle cx=\"", p + 1))
    cx.push_back(std::stod(s.substr(p + 12)));
  ASSERT_EQ(cx.size(), 6u);  // row-major: (0,0) (50,0) (100,0) (0,50) (50,50) (100,50)
  const double px_per_mm = (cx[1] - cx[0]) / 50;
  EXPECT_NEAR((cx[5] - cx[2]) / px_per_mm, 20, 0.05);
}

TEST(Svg, SpaceSectionShowsPlanesLevelsAndTheCompensationCheck) {
  sim::MachineOptions mo;
  mo.range = {{{0, 300}, {0, 200}, {0, 150}}};
  const auto m = sim::random_machine(mo);
  surface::SpacePlan plan;
  plan.probe_noise = 0.05e-3;
  plan.monte_carlo = 3;
  const auto space = surface::measure_space(m, plan);
  const auto v = surface::verify_compensation(m, space.map, 100);
  ASSERT_EQ(v.before.cols(), 100);
  const auto s = report::space_section("space", space, &v);
  EXPECT_EQ(s.grids.size(), 3u);           // XY, XZ, YZ
  EXPECT_EQ(s.heat_maps.size(), 4u + 1u);  // 4 z levels and the uncertainty
  // Three per-axis curves through the centre (positioning and two straightness components, each
  // with its ±2u band), then the compensation check.
  ASSERT_EQ(s.plots.size(), 4u);
  for (int k = 0; k < 3; ++k) {
    ASSERT_EQ(s.plots[k].series.size(), 3u);
    EXPECT_EQ(s.plots[k].series[0].band.size(), s.plots[k].x.size());
    EXPECT_EQ(s.plots[k].x.size(), space.map.size(k));
  }
  EXPECT_EQ(s.plots[0].series[0].label, "ex");  // along x: the positioning error first
  // No angular curves: the page says why rather than leaving a reader to wonder.
  EXPECT_NE(s.intro_html.find("cannot separate them from straightness"), std::string::npos);
  EXPECT_EQ(s.plots[3].series.size(), 3u);  // before, after, expected
  EXPECT_TRUE(s.plots[3].log_y);
  const Eigen::VectorXd& after = s.plots[3].series[1].y;
  EXPECT_NEAR(after[after.size() - 1], v.after_max * 1e3, 1e-9);  // sorted: the max is last
  const std::string html = report::render("t", {s});
  EXPECT_EQ(count(html, "<svg class=\"ta-fig\""), 8u);
  EXPECT_NE(html.find("var TA_FIGURES=8;"), std::string::npos);
}

// What a Moody report shows: the numeric Union Jack (every line's heights, station by station,
// with its CSV), and closure markers that do not hide each other where four lines cross.
TEST(Svg, MoodySectionHasTheUnionJackTableAndSpreadsCoincidentClosures) {
  const auto plate = surface::moody(io::read_moody(std::string(TRUEAXIS_TEST_DATA) + "/moody"));
  const auto s = report::surface_section("plate", plate);
  ASSERT_EQ(s.more_tables.size(), 1u);
  const auto& t = s.more_tables[0].second;
  ASSERT_EQ(t.size(), 9u);  // header and the eight lines
  EXPECT_EQ(t[1][0], plate.lines[0]);
  std::size_t filled = 0;
  for (std::size_t r = 1; r < t.size(); ++r)
    for (std::size_t c = 1; c < t[r].size(); ++c) filled += !t[r][c].empty();
  EXPECT_EQ(filled, plate.points.size());
  ASSERT_EQ(s.heat_maps.size(), 2u);
  const auto& c = s.heat_maps[1];
  for (Eigen::Index a = 0; a < c.px.size(); ++a)
    for (Eigen::Index b = a + 1; b < c.px.size(); ++b)
      EXPECT_GT(std::hypot(c.px[a] - c.px[b], c.py[a] - c.py[b]), 1.0) << a << " " << b;
  const std::string html = report::render("t", {s});
  EXPECT_NE(html.find("download=\"plate-union-jack-heights-along-every-line-m.csv\""),
            std::string::npos);
}

// The 3-D view a surface-plate report shows: the eight lines at their heights, one coloured
// segment per pair of neighbouring stations, over the same lines in grey, with the
// magnification written out; every station's height appears in a hover title.
TEST(Svg, MoodySectionHasAnIsometricViewOfEveryLine) {
  const auto plate = surface::moody(io::read_moody(std::string(TRUEAXIS_TEST_DATA) + "/moody"));
  const auto s = report::surface_section("plate", plate);
  ASSERT_EQ(s.views.size(), 1u);
  const auto& v = s.views[0];
  ASSERT_EQ(v.lines.size(), plate.lines.size());
  std::size_t points = 0;
  for (const auto& l : v.lines) points += static_cast<std::size_t>(l.cols());
  EXPECT_EQ(points, plate.points.size());
  const std::string out = report::svg(v);
  std::size_t segments = 0, greys = 0;
  for (auto at = out.find("stroke-width=\"2.2\""); at != std::string::npos;
       at = out.find("stroke-width=\"2.2\"", at + 1))
    ++segments;
  for (auto at = out.find("stroke=\"#ccc\""); at != std::string::npos;
       at = out.find("stroke=\"#ccc\"", at + 1))
    ++greys;
  EXPECT_EQ(segments, points - plate.lines.size());
  EXPECT_EQ(greys, plate.lines.size());
  EXPECT_NE(out.find("heights ×"), std::string::npos);
  // The highest station's height is in a title, to the 4 digits shown.
  double top = 0;
  for (const auto& p : plate.points) top = std::max(top, p.height * 1e3);
  EXPECT_NE(out.find(fmt::format("{:.4g}", top)), std::string::npos);
  report::SurfaceView bad;
  bad.lines.push_back(Eigen::Matrix3Xd::Zero(3, 1));
  EXPECT_NE(test::error_of([&] { report::svg(bad); }).find("a line of < 2 points"),
            std::string::npos);
}

// Gauge-block scatter: the sets before and after each correction at one nominal length are drawn
// side by side, so that equal errors do not hide each other; every length appears once per set,
// and x stays ascending (as the plotting library needs).
TEST(Report, LengthScatterHidesNoPoint) {
  ballgauge::LengthVerification a, b;
  a.correction = "grid";
  b.correction = "parametric";
  for (double L : {100.0, 100.0, 300.0, 500.0}) {
    ballgauge::LengthRow r;
    r.nominal = L;
    r.before = 2e-3;
    r.after = 1e-4;  // both corrections leave the same error: the worst case for overlap
    a.rows.push_back(r);
    b.rows.push_back(r);
  }
  const ballgauge::Mpe mpe = ballgauge::Mpe::parse("1.5+L/300");
  const auto s = report::lengths_section("lengths", {a, b}, &mpe);
  ASSERT_EQ(s.plots.size(), 1u);
  const auto& p = s.plots[0];
  ASSERT_EQ(p.series.size(), 5u);  // before, two afters, ±MPE
  for (Eigen::Index i = 1; i < p.x.size(); ++i) EXPECT_LE(p.x[i - 1], p.x[i]);
  std::vector<std::pair<double, double>> drawn;
  for (std::size_t k = 0; k < 3; ++k) {
    int shown = 0;
    for (Eigen::Index i = 0; i < p.x.size(); ++i)
      if (std::isfinite(p.series[k].y[i])) {
        ++shown;
        drawn.emplace_back(p.x[i], p.series[k].y[i]);
      }
    EXPECT_EQ(shown, 4) << p.series[k].label;
  }
  // No two markers of different sets at one spot (the repeats of one set may coincide).
  for (std::size_t i = 0; i < drawn.size(); ++i)
    for (std::size_t j = i + 1; j < drawn.size(); ++j)
      if (i / 4 != j / 4) {
        EXPECT_NE(drawn[i], drawn[j]) << i << " " << j;
      }
  EXPECT_NE(p.title.find("drawn"), std::string::npos);
}

// A scanned contour of 20 000 points is drawn at screen resolution: a polygon whose chords stay
// within 0.2 px of the curve (plus the 0.05 px of rounding), and one dot per pixel the points
// land on, so a page of such figures stays small without losing what the eye can see.
TEST(Svg, PlaneViewDrawsLongCurvesAtScreenResolution) {
  constexpr int kPoints = 20000;
  constexpr double kChordPx = 0.2 + 0.1;  // the drawing's tolerance and the coordinates' rounding
  report::PlaneView v;
  v.title = "contour";
  v.x_label = "x (mm)";
  v.y_label = "y (mm)";
  Eigen::Matrix2Xd xy(2, kPoints);
  for (int k = 0; k < kPoints; ++k) {
    const double t = 2 * M_PI * k / kPoints;
    xy.col(k) << 40 * std::cos(t), 40 * std::sin(t);
  }
  v.curves.push_back({"design", xy, "#333", false, false, true});
  v.curves.push_back({"measured", xy, "#1f77b4", false, true, false});
  const std::string s = report::svg(v);
  EXPECT_LT(s.size(), 60000u);  // 20 000 circles took about a megabyte
  // The polygon's vertices in pixels.
  const auto at = s.find("<polygon");
  ASSERT_NE(at, std::string::npos);
  const auto p0 = s.find("points=\"", at) + 8;
  std::vector<Eigen::Vector2d> px;
  {
    std::istringstream in(s.substr(p0, s.find('"', p0) - p0));
    double x, y;
    char comma;
    while (in >> x >> comma >> y) px.emplace_back(x, y);
  }
  ASSERT_GE(px.size(), 30u);
  EXPECT_LT(px.size(), 1000u);
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  for (const auto& p : px) c += p;
  c /= static_cast<double>(px.size());
  double r = 0;
  for (const auto& p : px) r += (p - c).norm();
  r /= static_cast<double>(px.size());
  // Each chord's sagitta: how far the circle strays from the straight line drawn.
  for (std::size_t i = 0; i < px.size(); ++i) {
    const Eigen::Vector2d a = px[i] - c, b = px[(i + 1) % px.size()] - c;
    const double half = 0.5 * std::acos(std::clamp(a.dot(b) / (a.norm() * b.norm()), -1.0, 1.0));
    EXPECT_LE(r * (1 - std::cos(half)), kChordPx) << "chord " << i;
  }
  // One dot per pixel: about as many as the circle is long in pixels, never one per point.
  const double length_px = 2 * M_PI * r;
  const auto dots = static_cast<double>(count(s, "h0"));
  EXPECT_GT(dots, 0.7 * length_px);
  EXPECT_LT(dots, 2.1 * length_px);
}

// Colour-bar ends read as numbers, not exponents: ±2210 µm is "2210", not "2.21e+03".
TEST(Svg, ColourBarEndsHaveNoExponent) {
  report::HeatMap h;
  h.title = "t";
  h.px = Eigen::VectorXd{{0.0, 1.0, 2.0}};
  h.py = Eigen::VectorXd{{0.0, 1.0, 0.0}};
  h.pvalue = Eigen::VectorXd{{-2210.0, 5.0, 2210.0}};
  std::string s = report::svg(h);
  EXPECT_NE(s.find(">2210</text>"), std::string::npos);
  EXPECT_NE(s.find(">-2210</text>"), std::string::npos);
  EXPECT_EQ(s.find("e+"), std::string::npos);
  h.pvalue = Eigen::VectorXd{{-0.0123, 0.0, 0.0123}};
  s = report::svg(h);
  EXPECT_NE(s.find(">0.0123</text>"), std::string::npos);
}
