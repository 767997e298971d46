// Five guideway errors from QPD spots: truth from smooth error motions, readings from
// the spec's formulas written out independently of Layout::design().
#include "trueaxis/guideway/guideway.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "../test_util.hpp"
#include "trueaxis/error.hpp"

using namespace trueaxis;
using guideway::Detector;
using guideway::Kind;
using guideway::Layout;

namespace {

constexpr double kRoundOff = 1e-12;  // relative to the errors' size

struct Truth {
  Eigen::VectorXd s;
  std::array<Eigen::VectorXd, 5> q;  // δx, δy (mm), εx, εy, εz (rad)
};

Truth truth(long n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ph(0, 6.28);
  Truth t;
  t.s = Eigen::VectorXd::LinSpaced(n, 0, 1000);
  const double amp[5] = {3e-3, 2e-3, 8e-6, 6e-6, 5e-6};
  for (int j = 0; j < 5; ++j) {
    const double p1 = ph(rng), p2 = ph(rng);
    t.q[static_cast<std::size_t>(j)] =
        amp[j] * (0.7 * (t.s.array() / 400 + p1).sin() + 0.3 * (t.s.array() / 90 + p2).cos());
  }
  return t;
}

// Readings from the spec's model: dx = −(δx + εy z − εz y), dy = −(δy + εz x − εx z); an angle
// detector reads f·(εy, −εx).
Eigen::MatrixXd readings(const Layout& l, const Truth& t) {
  const auto n = t.s.size();
  Eigen::MatrixXd m(n, 2 * static_cast<Eigen::Index>(l.detectors.size()));
  for (Eigen::Index k = 0; k < n; ++k)
    for (std::size_t i = 0; i < l.detectors.size(); ++i) {
      const auto& d = l.detectors[i];
      const double dx = t.q[0][k], dy = t.q[1][k], ex = t.q[2][k], ey = t.q[3][k], ez = t.q[4][k];
      const auto c = 2 * static_cast<Eigen::Index>(i);
      if (d.kind == Kind::Angle) {
        m(k, c) = d.focal_length * ey;
        m(k, c + 1) = -d.focal_length * ex;
      } else {
        const double x = d.position.x(), y = d.position.y(), z = d.position.z();
        m(k, c) = -(dx + ey * z - ez * y);
        m(k, c + 1) = -(dy + ez * x - ex * z);
      }
    }
  return m;
}

Layout triangle(double z_a, double z_b, double z_c) {
  Layout l;
  l.detectors = {{"a", Kind::Position, {-60, 0, z_a}, 0},
                 {"b", Kind::Position, {60, 0, z_b}, 0},
                 {"c", Kind::Position, {0, 80, z_c}, 0}};
  return l;
}

double max_abs(const Eigen::VectorXd& v) {
  return v.cwiseAbs().maxCoeff();
}

}  // namespace

TEST(Guideway, NoiseFreeRecoversAllFiveErrorsToRoundOff) {
  const Layout l = triangle(0, 150, 300);
  const Truth t = truth(500, 1);
  const auto r = guideway::solve(l, t.s, readings(l, t));
  for (int j = 0; j < 5; ++j) {
    ASSERT_TRUE(r.layout.observable[static_cast<std::size_t>(j)]) << guideway::kErrorNames[j];
    const auto& v = r.value[static_cast<std::size_t>(j)];
    EXPECT_LT(max_abs(v - t.q[static_cast<std::size_t>(j)]),
              kRoundOff * max_abs(t.q[static_cast<std::size_t>(j)]))
        << guideway::kErrorNames[j];
  }
  EXPECT_LT(max_abs(r.residual), 1e-15);
  EXPECT_TRUE(r.layout.message.empty());
  EXPECT_TRUE(std::isfinite(r.layout.condition_number));
  // Straightness against the LS line: PV of the detrended truth.
  EXPECT_NEAR(r.pv[0], r.horizontal_straightness.maxCoeff() - r.horizontal_straightness.minCoeff(),
              1e-18);
  // Readings that agree to round-off: no noise to estimate, so no uncertainty (never "u 0.000"),
  // and the reason.
  EXPECT_EQ(r.sigma, 0);
  EXPECT_FALSE(r.sigma_estimated);
  EXPECT_EQ(r.no_uncertainty.rfind("noise-free input", 0), 0u) << r.no_uncertainty;
  EXPECT_FALSE(r.pv_U(0).has_value());
  EXPECT_FALSE(r.resolved(0).has_value());
  EXPECT_EQ(r.summary().find("0.000"), std::string::npos) << r.summary();
  EXPECT_NE(r.summary().find("no uncertainty: noise-free input"), std::string::npos) << r.summary();
}

TEST(Guideway, CoplanarLayoutLosesPitchAndYawButKeepsRollAndStraightness) {
  const double z0 = 100;
  const Layout l = triangle(z0, z0, z0);
  const Truth t = truth(200, 2);
  const auto r = guideway::solve(l, t.s, readings(l, t));
  EXPECT_FALSE(r.layout.observable[2]);
  EXPECT_FALSE(r.layout.observable[3]);
  EXPECT_EQ(r.value[2].size(), 0);
  EXPECT_EQ(r.value[3].size(), 0);
  EXPECT_FALSE(std::isfinite(r.layout.condition_number));
  EXPECT_NE(r.layout.message.find("pitch, yaw"), std::string::npos) << r.layout.message;
  EXPECT_NE(r.layout.message.find("z = 100 mm"), std::string::npos) << r.layout.message;
  EXPECT_LT(max_abs(r.value[4] - t.q[4]), kRoundOff * max_abs(t.q[4]));
  // The straightness of the detectors' cross-section: the motion of the point (0, 0, z0).
  const Eigen::VectorXd hx = t.q[0] + z0 * t.q[3], vy = t.q[1] - z0 * t.q[2];
  EXPECT_LT(max_abs(r.value[0] - hx), kRoundOff * max_abs(hx));
  EXPECT_LT(max_abs(r.value[1] - vy), kRoundOff * max_abs(vy));
  EXPECT_NE(r.summary().find("pitch      not observable"), std::string::npos) << r.summary();
}

TEST(Guideway, AnAngleChannelMakesACoplanarLayoutSeePitchAndYaw) {
  Layout l = triangle(0, 0, 0);
  l.detectors.push_back({"f", Kind::Angle, {}, 200});
  const Truth t = truth(200, 3);
  const auto r = guideway::solve(l, t.s, readings(l, t));
  for (int j = 0; j < 5; ++j) {
    ASSERT_TRUE(r.layout.observable[static_cast<std::size_t>(j)]);
    EXPECT_LT(max_abs(r.value[static_cast<std::size_t>(j)] - t.q[static_cast<std::size_t>(j)]),
              kRoundOff * max_abs(t.q[static_cast<std::size_t>(j)]));
  }
}

TEST(Guideway, OnePositionDetectorAndALensSeeOnlyWhatFourReadingsCan) {
  // Four readings for five unknowns: the full design is rank-deficient however it is placed.
  Layout l;
  l.detectors = {{"a", Kind::Position, {10, 20, 0}, 0}, {"f", Kind::Angle, {}, 100}};
  const auto r = guideway::analyze_layout(l);
  EXPECT_FALSE(std::isfinite(r.condition_number));
  EXPECT_FALSE(r.observable[4]);  // roll needs two transverse positions
  EXPECT_TRUE(r.observable[0] && r.observable[1] && r.observable[2] && r.observable[3]);
  EXPECT_TRUE(std::isfinite(r.observable_condition_number));
}

TEST(Guideway, NoisyErrorsAgreeWithTheirPropagatedUncertainty) {
  const Layout l = triangle(0, 200, 400);
  const double sigma = 0.5e-3;  // mm per spot reading
  std::mt19937 rng(9);
  std::normal_distribution<double> noise(0, sigma);
  const Truth t = truth(4000, 4);
  Eigen::MatrixXd m = readings(l, t);
  for (Eigen::Index i = 0; i < m.size(); ++i) m.data()[i] += noise(rng);
  for (double given : {sigma, 0.0}) {
    guideway::Options o;
    o.sigma = given;
    const auto r = guideway::solve(l, t.s, m, o);
    if (given == 0) {
      EXPECT_TRUE(r.sigma_estimated);
      EXPECT_NEAR(r.sigma, sigma, 0.05 * sigma);  // one redundant reading per position
    }
    for (std::size_t j = 0; j < 5; ++j) {
      const Eigen::ArrayXd z = (r.value[j] - t.q[j]).array() / r.uncertainty[j];
      const double inside = (z.abs() <= 2).cast<double>().mean();
      const double rms_z = std::sqrt(z.square().mean());
      EXPECT_GT(inside, 0.93) << guideway::kErrorNames[j];
      EXPECT_LT(inside, 0.975) << guideway::kErrorNames[j];
      EXPECT_NEAR(rms_z, 1.0, 0.08) << guideway::kErrorNames[j];
      // Each PV beside its U = 2u; the summary names one the noise hides instead of printing it.
      ASSERT_TRUE(r.pv_U(j).has_value());
      // U = 2·z·u with z = Φ⁻¹(1 − 0.025/n): z = 4.3687 for 4000 positions.
      EXPECT_NEAR(*r.pv_U(j) / (2 * r.uncertainty[j]), 4.368680, 1e-6);
      EXPECT_EQ(*r.resolved(j), *r.pv_U(j) < r.pv[j]);
      const std::string line = r.summary().substr(r.summary().find(guideway::kErrorNames[j]));
      EXPECT_EQ(line.find("not resolved") < line.find('\n'), !*r.resolved(j)) << line;
    }
  }
  // Ten times the noise hides the straightness: the PV is then mostly the noise's own extremes
  // over 4000 positions, not resolved, said in words.
  for (Eigen::Index i = 0; i < m.size(); ++i) m.data()[i] += 10 * noise(rng);
  const auto loud = guideway::solve(l, t.s, m);
  EXPECT_EQ(loud.resolved(0), false);
  EXPECT_NE(loud.summary().find("horizontal PV not resolved (U = "), std::string::npos)
      << loud.summary();
}

TEST(Guideway, BadLayoutsAndReadingsAreRefused) {
  auto err = [](const Layout& l) { return test::error_of([&] { guideway::analyze_layout(l); }); };
  EXPECT_NE(err(Layout{}).find("no detectors"), std::string::npos);
  Layout dup = triangle(0, 100, 200);
  dup.detectors[2].name = "a";
  EXPECT_NE(err(dup).find("'a' is used twice"), std::string::npos);
  Layout line = triangle(0, 100, 200);
  line.detectors[2].position = 0.5 * (line.detectors[0].position + line.detectors[1].position);
  EXPECT_NE(err(line).find("lie on one line"), std::string::npos) << err(line);
  Layout two = triangle(0, 100, 200);
  two.detectors.pop_back();
  EXPECT_NE(err(two).find("no angle detector cannot give five errors"), std::string::npos);
  Layout lens = triangle(0, 100, 200);
  lens.detectors.push_back({"f", Kind::Angle, {}, 0});
  EXPECT_NE(err(lens).find("positive focal length"), std::string::npos);
  Layout nan = triangle(0, 100, 200);
  nan.detectors[1].position.x() = NAN;
  EXPECT_NE(err(nan).find("non-finite position"), std::string::npos);

  const Layout l = triangle(0, 100, 200);
  const Truth t = truth(10, 5);
  Eigen::MatrixXd m = readings(l, t);
  EXPECT_NE(test::error_of([&] {
              guideway::solve(l, t.s, m.leftCols(4));
            }).find("4 reading columns for 3 detectors"),
            std::string::npos);
  EXPECT_NE(test::error_of([&] { guideway::solve(l, t.s.head(5), m); }).find("10 rows"),
            std::string::npos);
  m(3, 2) = NAN;
  EXPECT_NE(test::error_of([&] { guideway::solve(l, t.s, m); }).find("finite"), std::string::npos);
  // Axial offsets of a nanometre a metre away: pitch and yaw nearly invisible.
  const Layout thin = triangle(1000, 1000 + 1e-6, 1000 + 2e-6);
  EXPECT_NE(test::error_of([&] {
              guideway::solve(thin, t.s, readings(thin, t));
            }).find("badly conditioned"),
            std::string::npos);
}
