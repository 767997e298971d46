// The stated per-point uncertainties against an independent computation: with the least-squares
// reference every reported value is a linear function of the readings, y = J·m, so its standard
// uncertainty is exactly sqrt(Σ_j J_ij²·σ_j²). J is found column by column by separating data
// that hold a single unit reading, which uses none of the solver's covariance code.
#include <gtest/gtest.h>

#include <cmath>

#include "trueaxis/separation/separation.hpp"

using namespace trueaxis;
using separation::Method;
using separation::Options;
using separation::ProbeData;
using separation::Result;

namespace {

// Relative agreement: both sides are round-off-exact on these short chains.
constexpr double kRelTol = 1e-9;

struct Case {
  const char* name;
  Method method;
  std::vector<double> offsets;  // mm (step 10 mm)
  bool angle = false;
  std::optional<double> zero_difference;
};

ProbeData zero_data(long n, const Case& c) {
  ProbeData d;
  d.x = Eigen::VectorXd::LinSpaced(n, 0.0, 10.0 * static_cast<double>(n - 1));
  d.readings = Eigen::MatrixXd::Zero(n, static_cast<Eigen::Index>(c.offsets.size()));
  d.offsets = c.offsets;
  if (c.angle) d.angle = Eigen::VectorXd::Zero(n);
  return d;
}

void expect_uncertainty(const Eigen::VectorXd& stated, const Eigen::VectorXd& var, const char* what,
                        const char* name) {
  ASSERT_EQ(stated.size(), var.size()) << what << " " << name;
  const double scale = var.cwiseSqrt().maxCoeff();
  for (Eigen::Index i = 0; i < var.size(); ++i)
    EXPECT_NEAR(stated[i], std::sqrt(var[i]), kRelTol * scale)
        << what << " point " << i << " " << name;
}

}  // namespace

TEST(SeparationUncertainty, EqualsTheLinearPropagationOfEveryReading) {
  for (const long n : {40L, 5L, 97L}) {
    const double sigma = 0.2e-3, angle_sigma = 0.7e-6;
    const std::vector<Case> cases = {
        {"three probes, parabola by convention", Method::Lsq, {0, 10, 20}, false, {}},
        {"three probes, known zero difference", Method::Lsq, {0, 10, 20}, false, 0.001},
        {"three probes and an angle channel", Method::Lsq, {0, 10, 20}, true, {}},
        {"four probes, uneven spacing", Method::Lsq, {0, 10, 30, 50}, false, {}},
        {"two probes and an angle channel", Method::Lsq, {0, 10}, true, {}},
        {"two-point", Method::TwoPoint, {0, 10}, false, {}},
        {"three-point", Method::ThreePoint, {0, 10, 20}, false, {}},
        {"three-point, known zero difference", Method::ThreePoint, {0, 10, 20}, false, 0.001},
    };
    for (const Case& c : cases) {
      Options o;
      o.method = c.method;
      o.sigma = sigma;
      o.angle_sigma = angle_sigma;
      o.zero_difference = c.zero_difference;
      const ProbeData base = zero_data(n, c);
      const Result stated = separation::separate(base, o);
      Options plain = o;
      plain.compute_uncertainty = false;
      const Result r0 = separation::separate(base, plain);
      Eigen::VectorXd vw = Eigen::VectorXd::Zero(stated.workpiece.x.size());
      Eigen::VectorXd vg = Eigen::VectorXd::Zero(stated.guide.x.size());
      Eigen::VectorXd vt = Eigen::VectorXd::Zero(stated.pitch ? stated.pitch->x.size() : 0);
      auto add_column = [&](const ProbeData& d, double s) {
        const Result r = separation::separate(d, plain);
        vw += ((r.workpiece.value - r0.workpiece.value) * s).cwiseAbs2();
        vg += ((r.guide.value - r0.guide.value) * s).cwiseAbs2();
        if (stated.pitch) vt += ((r.pitch->value - r0.pitch->value) * s).cwiseAbs2();
      };
      for (long K = 0; K < n; ++K) {
        for (Eigen::Index i = 0; i < base.readings.cols(); ++i) {
          ProbeData d = base;
          d.readings(K, i) = 1;
          add_column(d, sigma);
        }
        if (c.angle) {
          ProbeData d = base;
          d.angle[K] = 1;
          add_column(d, angle_sigma);
        }
      }
      expect_uncertainty(stated.workpiece.uncertainty, vw, "workpiece", c.name);
      expect_uncertainty(stated.guide.uncertainty, vg, "guide", c.name);
      if (stated.pitch) expect_uncertainty(stated.pitch->uncertainty, vt, "pitch", c.name);
    }
  }
}
