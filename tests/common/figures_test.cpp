// Figures printed to the resolution their uncertainty supports, and the expanded uncertainty of
// a peak-to-valley figure.
#include "../../src/common/figures.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace trueaxis::detail;

TEST(Figures, TwoSignificantDigitsAndTheValueRoundedToMatch) {
  EXPECT_EQ(two_digits(0.2134), "0.21");
  EXPECT_EQ(two_digits(1.234), "1.2");
  EXPECT_EQ(two_digits(35.47), "35");
  EXPECT_EQ(two_digits(111.3), "111");
  EXPECT_EQ(two_digits(0.0996), "0.10");  // rounds up into the next decade
  EXPECT_EQ(two_digits(9.96), "10");
  EXPECT_EQ(two_digits(0), "0");
  EXPECT_EQ(rounded_to(2.749206676242011, 0.21), "2.75");
  EXPECT_EQ(rounded_to(35.47, 111), "35");
  EXPECT_EQ(rounded_to(6.3125, 0.0996), "6.31");
  EXPECT_EQ(rounded_to(-0.0004, 0.23), "0.00");  // no "-0.00" for what rounds to zero
  EXPECT_EQ(rounded_to(-0.004, 0.023), "-0.004");
  EXPECT_EQ(rounded_to(-3e-5, 12), "0");
}

// U of a PV covers the figure's error at least 95 % of the time, for independent points (where
// the extremes of the noise matter most): simulated against a known profile.
TEST(Figures, PeakToValleyUncertaintyCoversTheFiguresError) {
  constexpr int kTrials = 2000;
  constexpr long kPoints = 400;
  constexpr double kU = 0.1;  // standard uncertainty of each point
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0, kU);
  const double U = peak_to_valley_U(kU, kPoints);
  EXPECT_NEAR(U / (2 * kU), 3.836107, 1e-6);  // Φ⁻¹(1 − 0.025/400)
  int covered = 0;
  for (int t = 0; t < kTrials; ++t) {
    double lo = INFINITY, hi = -INFINITY;
    for (long i = 0; i < kPoints; ++i) {
      const double truth = std::sin(2 * M_PI * static_cast<double>(i) / kPoints);  // PV 2
      const double v = truth + noise(rng);
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
    covered += std::abs((hi - lo) - 2.0) <= U;
  }
  EXPECT_GE(covered, 0.95 * kTrials);
  // A plain 2u would not: the noise's extremes over 400 points lie near ±3u.
  EXPECT_GT(peak_to_valley_U(kU, kPoints), 2 * 2 * kU);
  EXPECT_NEAR(peak_to_valley_U(kU, 1) / (2 * kU), 1.95996, 1e-4);
}
