#include "trueaxis/geometry/straightness.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "../../src/geometry/profile_min_zone.hpp"

using namespace trueaxis::geometry;

namespace {
constexpr double kRoundOff = 1e-12;

// Width by brute force: the minimum width is attained with one side through two of the points.
double brute_width(const Eigen::VectorXd& x, const Eigen::VectorXd& y) {
  double best = INFINITY;
  for (Eigen::Index i = 0; i < x.size(); ++i)
    for (Eigen::Index j = i + 1; j < x.size(); ++j) {
      const double dx = x[j] - x[i], dy = y[j] - y[i], len = std::hypot(dx, dy);
      if (len == 0) continue;
      double lo = INFINITY, hi = -INFINITY;
      for (Eigen::Index k = 0; k < x.size(); ++k) {
        const double d = (dx * (y[k] - y[i]) - dy * (x[k] - x[i])) / len;
        lo = std::min(lo, d);
        hi = std::max(hi, d);
      }
      best = std::min(best, hi - lo);
    }
  return best;
}
}  // namespace

TEST(Straightness, MinZoneEqualsBruteForceOnRandomSets) {
  std::mt19937_64 rng(42);
  std::normal_distribution<double> N(0, 1);
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 3 + trial % 40;
    Eigen::VectorXd x(n), y(n);
    for (int i = 0; i < n; ++i) {
      x[i] = trial % 2 ? static_cast<double>(i) * 10 : 100 * N(rng);  // profiles and scattered sets
      y[i] = (trial % 3 ? 1e-3 : 1.0) * N(rng);
    }
    const double bw = brute_width(x, y);
    EXPECT_NEAR(min_zone(x, y).width, bw, kRoundOff * std::max(1.0, bw)) << "trial " << trial;
  }
}

TEST(Straightness, MinZoneMiddleLineCentresTheZone) {
  Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(101, 0, 1000), y(101);
  for (int i = 0; i < 101; ++i) y[i] = 0.002 * std::sin(x[i] / 50) + 1e-5 * x[i] + 3;
  const MinZone z = min_zone(x, y);
  const Eigen::VectorXd r = residuals(x, y, z.middle);
  EXPECT_NEAR(r.maxCoeff(), -r.minCoeff(), 1e-12);
  EXPECT_LE(z.width, ls_straightness(x, y) + 1e-15);  // min zone never exceeds the LS value
  // The in-place form gives the same residuals, to the bit.
  Eigen::VectorXd yr = y;
  subtract_line(x, yr, z.middle);
  EXPECT_EQ(yr, r);
}

TEST(Straightness, LineHasZeroStraightness) {
  Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(50, 1000, 1490);
  Eigen::VectorXd y = 0.3 + 2e-4 * x.array();
  EXPECT_NEAR(ls_straightness(x, y), 0, 1e-13);
  EXPECT_NEAR(min_zone(x, y).width, 0, 1e-13);
  const Line l = fit_line(x, y);
  EXPECT_NEAR(l.slope, 2e-4, 1e-15);
}

TEST(Straightness, GaussianFilterTransmitsHalfAtCutoff) {
  const double dx = 0.01, cutoff = 0.8;
  const int n = 4001;
  Eigen::VectorXd y(n);
  for (int i = 0; i < n; ++i) y[i] = std::sin(2 * M_PI * i * dx / cutoff);
  const Eigen::VectorXd m = gaussian_filter(y, dx, cutoff);
  // Amplitude in the middle, away from the ends.
  const double amp = m.segment(1000, 2000).cwiseAbs().maxCoeff();
  EXPECT_NEAR(amp, 0.5, 2e-3);
  // A straight line passes unchanged in the interior; constants everywhere.
  Eigen::VectorXd c = Eigen::VectorXd::Constant(n, 2.5);
  EXPECT_NEAR((gaussian_filter(c, dx, cutoff).array() - 2.5).abs().maxCoeff(), 0, 1e-12);
}

// Long profiles go through a prefilter that drops points which cannot be hull vertices (below
// the hull of blocks' highest points, above that of their lowest; whole blocks at a time where a
// bound allows). The same points in reverse order (not increasing: sorted, then the plain
// monotone chain) must give the same zone: white noise, noise on a form, steps, isolated spikes
// up and down, a smooth curve, a line with noise at round-off level, a parabola (every point on
// the hull), a steep line far from zero with nanometre noise, heights quantised to a 0.1 µm
// resolution (many ties for a block's highest point) and a spike out of order deep inside (the
// order check, made on the way through the blocks, must send it to the sorting path).
TEST(Straightness, MinZoneOfALongProfileEqualsThePlainHulls) {
  std::mt19937_64 rng(8);
  std::normal_distribution<double> N(0, 1);
  std::uniform_real_distribution<double> U(0, 1);
  const int n = 20011;  // not a whole number of blocks
  for (int kind = 0; kind < 10; ++kind) {
    Eigen::VectorXd x(n), y(n);
    for (int i = 0; i < n; ++i) {
      const double t = static_cast<double>(i) / (n - 1);
      x[i] = 12.5 + 0.01 * i;
      switch (kind) {
        case 0:
          y[i] = 1e-3 * N(rng);
          break;
        case 1:
          y[i] = 5e-3 * std::sin(7 * t) + 4e-3 * t * t + 1e-4 * N(rng);
          break;
        case 2:
          y[i] = (i > n / 3 ? 2e-3 : 0) - (i > 2 * n / 3 ? 5e-3 : 0) + 1e-4 * N(rng);
          break;
        case 3:
          y[i] = 1e-4 * N(rng) + (U(rng) < 1e-3 ? (U(rng) < 0.5 ? 1 : -1) * 1e-2 * U(rng) : 0);
          break;
        case 4:
          y[i] = 3e-3 * std::sin(3 * t) + 2e-3 * t * t * t;
          break;
        case 5:
          y[i] = 1e-6 * x[i] + 1e-15 * N(rng);
          break;
        case 6:  // every point a vertex of the lower chain
          y[i] = 1e-2 * (t - 0.3) * (t - 0.3);
          break;
        case 7:  // far from zero, steep, and noisy: the block test's rounding margin
          y[i] = 1000 + 0.5 * x[i] + 1e-9 * N(rng);
          break;
        case 8:
          y[i] = 1e-4 * std::round(3 * N(rng));
          break;
        case 9:
          y[i] = 2e-3 * t * t + 1e-4 * N(rng);
          break;
      }
    }
    if (kind == 9) {  // a point far out of line, its x swapped with one near the start
      y[n / 2] += 5e-2;
      std::swap(x[n / 2], x[100]);
    }
    const MinZone a = min_zone(x, y), b = min_zone(x.reverse().eval(), y.reverse().eval());
    if (kind != 9) {  // x increasing: the path without the order check is the same, to the bit
      const MinZone c = detail::min_zone_of_increasing(x, y);
      EXPECT_EQ(c.width, a.width) << "kind " << kind;
      EXPECT_EQ(c.middle.slope, a.middle.slope) << "kind " << kind;
      EXPECT_EQ(c.middle.intercept, a.middle.intercept) << "kind " << kind;
    }
    EXPECT_NEAR(a.width, b.width, kRoundOff * std::max(1e-3, b.width)) << "kind " << kind;
    EXPECT_NEAR(a.middle.slope, b.middle.slope, kRoundOff) << "kind " << kind;
    EXPECT_NEAR(a.middle.intercept, b.middle.intercept, kRoundOff * 100) << "kind " << kind;
    // And the zone holds every point: a hull vertex wrongly dropped would stick out of it.
    const double c = 1 / std::hypot(1.0, a.middle.slope);
    double worst = 0;
    for (int i = 0; i < n; ++i)
      worst = std::max(
          worst, std::abs(y[i] - a.middle.intercept - a.middle.slope * x[i]) * c - a.width / 2);
    // (up to the rounding of the heights themselves, ~1e-13 mm at 1000 mm)
    const double heights = 8 * std::numeric_limits<double>::epsilon() *
                           (y.cwiseAbs().maxCoeff() + std::abs(a.middle.slope) * x.maxCoeff());
    EXPECT_LT(worst, kRoundOff * std::max(1e-3, a.width) + heights) << "kind " << kind;
  }
}
