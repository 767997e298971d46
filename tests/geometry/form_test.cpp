// The form figure of a fitted element (straightness, flatness, roundness, ...) with its expanded
// uncertainty from the points' stated uncertainty: it covers the figure's error, is marked not
// resolved when the noise hides the form, and is never stated without the points' uncertainty.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "../test_util.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/geometry/fit.hpp"

using namespace trueaxis;

namespace {

// A plate with a known form: heights a·sin(x/15)·cos(y/20) over 100 × 100 mm, at fixed points.
Eigen::Matrix3Xd wavy_plate(double amplitude, int n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> at(0, 100);
  Eigen::Matrix3Xd p(3, n);
  for (int i = 0; i < n; ++i) {
    const double x = at(rng), y = at(rng);
    p.col(i) << x, y, amplitude * std::sin(x / 15) * std::cos(y / 20);
  }
  return p;
}

}  // namespace

TEST(Form, FlatnessUncertaintyCoversTheErrorOfTheFigure) {
  constexpr double kForm = 2e-3;   // mm: the plate's amplitude
  constexpr double kNoise = 4e-4;  // mm: the points' standard uncertainty along the normal
  constexpr int kTrials = 200;
  std::mt19937_64 layout(1);
  const Eigen::Matrix3Xd truth = wavy_plate(kForm, 60, layout);
  const double true_flatness =
      geometry::form_of(geometry::fit(geometry::Element::Plane, truth), NAN).value;
  std::mt19937_64 rng(2);
  std::normal_distribution<double> noise(0, kNoise);
  int covered = 0, resolved = 0;
  for (int t = 0; t < kTrials; ++t) {
    Eigen::Matrix3Xd p = truth;
    for (Eigen::Index i = 0; i < p.cols(); ++i) p(2, i) += noise(rng);
    const auto form = geometry::form_of(geometry::fit(geometry::Element::Plane, p), kNoise);
    ASSERT_TRUE(form.U);
    if (std::abs(form.value - true_flatness) <= *form.U) ++covered;
    if (*form.resolved()) ++resolved;
  }
  // A peak-to-valley figure's U is a bound (Bonferroni): it covers at least 95 %.
  EXPECT_GE(covered, 190) << covered;
  EXPECT_EQ(resolved, kTrials);  // 4 µm of form against U ≈ 2.5 µm
  // The same plate under ten times the noise: the form is not resolved, and said so.
  Eigen::Matrix3Xd p = truth;
  for (Eigen::Index i = 0; i < p.cols(); ++i) p(2, i) += 10 * noise(rng);
  const auto lost = geometry::form_of(geometry::fit(geometry::Element::Plane, p), 10 * kNoise);
  EXPECT_FALSE(*lost.resolved());
  EXPECT_NE(lost.summary().find("flatness (about the least-squares plane): not resolved (U = "),
            std::string::npos)
      << lost.summary();
}

TEST(Form, EachElementNamesItsFormAndNeedsThePointsUncertainty) {
  std::mt19937_64 rng(3);
  const Eigen::Matrix3Xd plate = wavy_plate(1e-3, 40, rng);
  const auto plane = geometry::fit(geometry::Element::Plane, plate);
  const auto form = geometry::form_of(plane, NAN);
  EXPECT_EQ(form.name, "flatness");
  EXPECT_NEAR(form.value, plane.residuals.maxCoeff() - plane.residuals.minCoeff(), 1e-15);
  EXPECT_FALSE(form.U);
  EXPECT_FALSE(form.resolved());
  EXPECT_NE(form.no_uncertainty.find("the points' own uncertainty is not stated"),
            std::string::npos);
  // A minimum-zone fit's form is its zone.
  const auto zone = geometry::fit_min_zone(geometry::Element::Plane, plate);
  const auto zf = geometry::form_of(zone, 1e-4);
  EXPECT_EQ(zf.reference, "minimum zone");
  EXPECT_EQ(zf.value, zone.zone);
  EXPECT_LE(zf.value, form.value);
  // A line's residuals are distances: its straightness is the diameter of the cylinder about it.
  Eigen::Matrix3Xd line(3, 5);
  line << 0, 10, 20, 30, 40, 0, 0.001, 0, -0.001, 0, 0, 0, 0.002, 0, 0;
  const auto lf = geometry::form_of(geometry::fit(geometry::Element::Line, line), NAN);
  EXPECT_EQ(lf.name, "straightness");
  EXPECT_GT(lf.value, 0.002);
  EXPECT_LT(lf.value, 0.005);
  // A circle's form is its roundness.
  Eigen::Matrix3Xd circle(3, 8);
  for (int i = 0; i < 8; ++i) {
    const double a = i * M_PI / 4, r = 10 + (i % 2 ? 0.001 : -0.001);
    circle.col(i) << r * std::cos(a), r * std::sin(a), 0;
  }
  const auto cf = geometry::form_of(geometry::fit(geometry::Element::Circle, circle), 1e-4);
  EXPECT_EQ(cf.name, "roundness");
  EXPECT_NEAR(cf.value, 0.002, 1e-9);
  // The points' uncertainty must be a positive number.
  EXPECT_NE(test::error_of([&] { geometry::form_of(plane, -1e-3); }).find("must be a positive"),
            std::string::npos);
  EXPECT_THROW(geometry::form_of(plane, 0), Error);
  EXPECT_THROW(geometry::form_of(plane, INFINITY), Error);
}
