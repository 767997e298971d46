// Noisy data: the reported uncertainty must describe the actual errors.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "../../src/common/figures.hpp"
#include "../../src/separation/banded_lsq.hpp"
#include "trueaxis/geometry/straightness.hpp"
#include "trueaxis/separation/separation.hpp"
#include "trueaxis/sim/straightness.hpp"

using namespace trueaxis;
using separation::Method;
using separation::Options;
using separation::Profile;
using separation::detail::BandedLsq;

namespace {

constexpr int kLongRuns = 30;  // independent long runs (their points are correlated)

struct Stats {
  double within2 = 0;  // fraction of |error| <= 2u
  double rms_z = 0;    // RMS of error/u
  double rms_err = 0;  // RMS error (mm)
  double mean_u = 0;
};

// Repeats a noisy campaign over `runs` seeds and compares errors against the stated uncertainty
// at every workpiece point (runs are independent; points within a run are correlated).
Stats run(Method m, std::vector<double> offsets, bool angle, bool given_sigma, int runs = 120,
          long stations = 60) {
  long cnt = 0, in = 0;
  double z2 = 0, e2 = 0, u = 0;
  for (int s = 0; s < runs; ++s) {
    sim::StraightnessOptions so;
    so.stations = stations;
    so.step = 10;
    so.offsets = offsets;
    so.noise = 0.1e-3;
    so.angle = angle;
    so.angle_noise = 0.5e-6;
    so.seed = 1000 + static_cast<std::uint64_t>(s);
    const auto camp = sim::simulate_straightness(so);
    Options o;
    o.method = m;
    if (given_sigma) o.sigma = so.noise;
    o.angle_sigma = so.angle_noise;
    const auto r = separation::separate(camp.data, o);
    EXPECT_EQ(r.workpiece.uncertainty.size(), r.workpiece.value.size());
    const separation::Result t = camp.truth.like(r);  // same grids, reference and gauge
    const Profile& tw = t.workpiece;
    for (Eigen::Index i = 0; i < tw.x.size(); ++i) {
      const double uu = r.workpiece.uncertainty[i];
      if (!(uu > 0)) continue;  // pinned/degenerate points carry zero uncertainty
      const double e = r.workpiece.value[i] - tw.value[i];
      ++cnt;
      in += std::abs(e) <= 2 * uu;
      z2 += (e / uu) * (e / uu);
      e2 += e * e;
      u += uu;
    }
  }
  return {static_cast<double>(in) / cnt, std::sqrt(z2 / cnt), std::sqrt(e2 / cnt), u / cnt};
}

}  // namespace

// About 95 % of the errors within ±2u, and error/u of unit RMS, for each method.
TEST(SeparationNoise, ErrorsAgreeWithStatedUncertainty) {
  struct Case {
    const char* name;
    Method m;
    std::vector<double> off;
    bool angle, given;
  };
  for (const Case& c :
       {Case{"two-point", Method::TwoPoint, {0, 10}, false, true},
        Case{"three-point", Method::ThreePoint, {0, 10, 20}, false, true},
        Case{"lsq 3 probes + level", Method::Lsq, {0, 10, 20}, true, true},
        Case{"lsq 5 probes, sigma estimated", Method::Lsq, {0, 10, 20, 30, 40}, false, false}}) {
    const Stats s = run(c.m, c.off, c.angle, c.given);
    EXPECT_GT(s.within2, 0.90) << c.name;
    EXPECT_LT(s.within2, 0.99) << c.name;
    EXPECT_NEAR(s.rms_z, 1.0, 0.2) << c.name;
  }
}

// Long runs are solved as two chains joined in the middle, on two threads, and their uncertainty
// likewise: the stated uncertainty must still describe the errors there.
TEST(SeparationNoise, ErrorsAgreeWithStatedUncertaintyOnLongRuns) {
  constexpr long kStations = BandedLsq::kSplitStations + 10000;
  for (const bool angle : {false, true}) {
    const char* name = angle ? "lsq 3 probes + level" : "lsq 5 probes, sigma estimated";
    const Stats s = angle
                        ? run(Method::Lsq, {0, 10, 20}, true, true, kLongRuns, kStations)
                        : run(Method::Lsq, {0, 10, 20, 30, 40}, false, false, kLongRuns, kStations);
    std::printf("%s, %ld stations: within 2u %.3f, RMS error/u %.3f\n", name, kStations, s.within2,
                s.rms_z);
    EXPECT_GT(s.within2, 0.90) << name;
    EXPECT_LT(s.within2, 0.99) << name;
    EXPECT_NEAR(s.rms_z, 1.0, 0.2) << name;
  }
}

// Redundancy (more probes, or a level) lowers both the stated uncertainty and the actual error.
TEST(SeparationNoise, RedundancyLowersTheError) {
  const Stats three = run(Method::Lsq, {0, 10, 20}, false, true);
  const Stats five = run(Method::Lsq, {0, 10, 20, 30, 40}, false, true);
  const Stats level = run(Method::Lsq, {0, 10, 20}, true, true);
  EXPECT_LT(five.mean_u, three.mean_u);
  EXPECT_LT(five.rms_err, three.rms_err);
  EXPECT_LT(level.mean_u, three.mean_u);
  EXPECT_LT(level.rms_err, three.rms_err);
}

// Stepping by less than the probe spacing: four probes 20, 10 and 20 mm apart, carriage steps of
// 10 mm (each spacing a whole number of steps, no common factor). Every workpiece point is read
// by four probes, so the error is lower than with three probes at one-step spacing, and the
// stated uncertainty still describes it.
TEST(SeparationNoise, StepSmallerThanSpacingIsRedundant) {
  const Stats three = run(Method::Lsq, {0, 10, 20}, false, true);
  const Stats fine = run(Method::Lsq, {0, 20, 30, 50}, false, true);
  EXPECT_GT(fine.within2, 0.90);
  EXPECT_LT(fine.within2, 0.99);
  EXPECT_NEAR(fine.rms_z, 1.0, 0.2);
  EXPECT_LT(fine.mean_u, three.mean_u);
  EXPECT_LT(fine.rms_err, three.rms_err);
  std::printf(
      "3 probes at 0,10,20: RMS error %.3g µm, mean u %.3g µm; 4 probes at 0,20,30,50: "
      "%.3g µm, %.3g µm\n",
      three.rms_err * 1e3, three.mean_u * 1e3, fine.rms_err * 1e3, fine.mean_u * 1e3);
}

// The README's own three-point run (500 stations, 0.05 um noise) gives a 35 um "straightness"
// against a true 6.3 um: the result must say that it cannot resolve that, in words, and must not
// warn for a layout that resolves its profile.
TEST(Noise, UnresolvedStraightnessIsSaidInWords) {
  sim::StraightnessOptions so;
  so.stations = 500;
  so.step = 10;
  so.offsets = {0, 10, 20};
  so.noise = 0.05e-3;
  const auto camp = sim::simulate_straightness(so);
  Options o;
  o.method = Method::ThreePoint;
  separation::Result r = separation::separate(camp.data, o);
  ASSERT_TRUE(r.noise_gain.has_value());  // no sigma and no redundancy: no uncertainty stated
  EXPECT_EQ(r.workpiece.uncertainty.size(), 0);
  ASSERT_EQ(r.warnings().size(), 1u);
  EXPECT_NE(r.warnings()[0].find("no uncertainty is stated"), std::string::npos);
  // Its gain is what a given sigma produces: u = gain * sigma.
  o.sigma = 0.05e-3;
  r = separation::separate(camp.data, o);
  ASSERT_GT(r.workpiece.uncertainty.size(), 0);
  EXPECT_FALSE(r.noise_gain.has_value());
  const auto w = r.warnings();
  ASSERT_GE(w.size(), 1u);
  EXPECT_NE(w[0].find("workpiece straightness is not resolved"), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("--method lsq"), std::string::npos) << w[0];  // the user used threepoint
  ASSERT_TRUE(r.workpiece_straightness.U.has_value());
  // U = 2·z·max u with z = Φ⁻¹(1 − 0.025/n): z = 3.89 for 500 points.
  EXPECT_NEAR(*r.workpiece_straightness.U / (2 * r.workpiece.uncertainty.maxCoeff()), 3.890592,
              1e-6);
  EXPECT_GT(*r.workpiece_straightness.U, r.workpiece_straightness.ls);
  EXPECT_EQ(r.workpiece_straightness.resolved(), false);
  // The summary gives no number for it: "not resolved (U = … µm, k = 2)".
  const std::string sum = r.summary();
  EXPECT_NE(sum.find("workpiece straightness: not resolved (U = "), std::string::npos) << sum;
  EXPECT_NE(sum.find(", 95 %)"), std::string::npos) << sum;
  EXPECT_EQ(sum.find(fmt::format("{:.4f}", r.workpiece_straightness.ls * 1e3)), std::string::npos)
      << sum;
  // With --method lsq on the same three probes, the advice no longer offers lsq.
  Options lsq;
  lsq.sigma = 0.05e-3;
  const auto wl = separation::separate(camp.data, lsq).warnings();
  ASSERT_GE(wl.size(), 1u);
  EXPECT_EQ(wl[0].find("--method lsq"), std::string::npos) << wl[0];

  // Five probes and an angle channel on the same surface resolve it: no warning.
  so.offsets = {0, 10, 30, 60, 100};
  so.angle = true;
  so.angle_noise = 0.2e-6;
  const auto good = sim::simulate_straightness(so);
  Options lo;
  lo.method = Method::Lsq;
  lo.sigma = 0.05e-3;
  lo.angle_sigma = 0.2e-6;
  const separation::Result rg = separation::separate(good.data, lo);
  EXPECT_TRUE(rg.warnings().empty()) << rg.warnings()[0];
  EXPECT_EQ(rg.workpiece_straightness.resolved(), true);
  EXPECT_EQ(rg.guide_straightness.resolved(), true);
  // The true profile's straightness lies within U of the figure (k = 2).
  const separation::Result truth = good.truth.like(rg);
  EXPECT_LT(std::abs(rg.workpiece_straightness.ls -
                     geometry::ls_straightness(truth.workpiece.x, truth.workpiece.value)),
            *rg.workpiece_straightness.U);
  EXPECT_NE(
      rg.summary().find(fmt::format(
          "U = {} µm (95 %)", trueaxis::detail::two_digits(*rg.workpiece_straightness.U * 1e3))),
      std::string::npos)
      << rg.summary();
}

// Readings that agree to round-off carry no noise: the uncertainty is absent with that reason,
// never a zero (and no "sigma 0.0000 µm, estimated from residuals").
TEST(Noise, NoiseFreeReadingsStateNoUncertaintyAndSayWhy) {
  sim::StraightnessOptions so;
  so.stations = 200;
  so.step = 5;
  so.offsets = {0, 5, 15, 30};  // redundant: the residuals would estimate the noise
  so.noise = 0;
  const auto camp = sim::simulate_straightness(so);
  const separation::Result r = separation::separate(camp.data);
  EXPECT_GT(r.dof, 0);
  EXPECT_FALSE(r.sigma.has_value());
  EXPECT_FALSE(r.sigma_estimated);
  EXPECT_EQ(r.workpiece.uncertainty.size(), 0);
  EXPECT_FALSE(r.workpiece_straightness.U.has_value());
  EXPECT_FALSE(r.workpiece_straightness.resolved().has_value());
  EXPECT_EQ(r.no_uncertainty.rfind("noise-free input", 0), 0u) << r.no_uncertainty;
  EXPECT_EQ(r.summary().find("0.0000"), std::string::npos) << r.summary();
  EXPECT_NE(r.summary().find("no uncertainty stated"), std::string::npos) << r.summary();
  // The same layout with probe noise estimates it from the residuals.
  so.noise = 0.05e-3;
  const separation::Result noisy = separation::separate(sim::simulate_straightness(so).data);
  ASSERT_TRUE(noisy.sigma.has_value());
  EXPECT_TRUE(noisy.sigma_estimated);
  EXPECT_TRUE(noisy.no_uncertainty.empty());
  EXPECT_NEAR(*noisy.sigma, so.noise, 0.3 * so.noise);  // ~600 degrees of freedom
}
