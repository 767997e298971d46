// The virtual guideway carriage (one axis of the virtual machine): its truth is the axis' own
// errors, its readings follow the spec's model (or the exact geometry), and the solver gets the
// truth back.
#include <gtest/gtest.h>

#include <cmath>

#include "../test_util.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/sim/guideway.hpp"

using namespace trueaxis;
using guideway::Kind;

namespace {

guideway::Layout layout3d() {
  guideway::Layout l;
  l.detectors = {{"a", Kind::Position, {-60, 0, 0}, 0},
                 {"b", Kind::Position, {60, 0, 150}, 0},
                 {"c", Kind::Position, {0, 80, 300}, 0}};
  return l;
}

sim::Machine machine(std::uint64_t seed = 3) {
  sim::MachineOptions o;
  o.seed = seed;
  return sim::random_machine(o);
}

double max_abs(const Eigen::VectorXd& v) {
  return v.cwiseAbs().maxCoeff();
}

}  // namespace

TEST(GuidewaySim, CarriageFramesAreRightHanded) {
  for (int a = 0; a < 3; ++a) {
    const Eigen::Matrix3d m = sim::carriage_axes(a);
    EXPECT_NEAR(m.determinant(), 1.0, 1e-15);
    EXPECT_TRUE(m.col(2).isApprox(Eigen::Vector3d::Unit(a)));  // z along the travel
  }
}

TEST(GuidewaySim, TruthIsTheAxisOwnErrorsAndTheSolverRecoversIt) {
  const auto mc = machine();
  const auto l = layout3d();
  for (int axis = 0; axis < 3; ++axis) {
    sim::GuidewayOptions o;
    o.axis = axis;
    o.positions = 101;
    const auto c = sim::simulate_guideway(mc, l, o);
    if (axis == 0) {
      // X axis: carriage (x, y, z) = machine (Y, Z, X): δx = EYX, δy = EZX, εx = EBX, εy = ECX,
      // εz = EAX.
      const auto& f = mc.errors[0];
      for (Eigen::Index k = 0; k < c.s.size(); k += 10) {
        const double u = c.s[k];
        EXPECT_DOUBLE_EQ(c.truth[0][k], f[1](u));
        EXPECT_DOUBLE_EQ(c.truth[1][k], f[2](u));
        EXPECT_DOUBLE_EQ(c.truth[2][k], f[4](u));
        EXPECT_DOUBLE_EQ(c.truth[3][k], f[5](u));
        EXPECT_DOUBLE_EQ(c.truth[4][k], f[3](u));
      }
    }
    const auto r = guideway::solve(l, c.s, c.spots);
    for (std::size_t j = 0; j < 5; ++j)
      EXPECT_LT(max_abs(r.value[j] - c.truth[j]), 1e-12 * max_abs(c.truth[j]))
          << "axis " << axis << " " << guideway::kErrorNames[j];
  }
}

TEST(GuidewaySim, ExactGeometryDiffersFromTheSmallAngleModelOnlyToSecondOrder) {
  const auto mc = machine(5);
  const auto l = layout3d();
  sim::GuidewayOptions o;
  o.exact = true;
  const auto c = sim::simulate_guideway(mc, l, o);
  const auto r = guideway::solve(l, c.s, c.spots);
  double eps = 0;  // largest rotation (rad)
  for (std::size_t j = 2; j < 5; ++j) eps = std::max(eps, max_abs(c.truth[j]));
  const double arm = 320;  // mm, the farthest detector from the carriage origin (≤ |p|)
  // Second-order bound: spot errors ≲ ε²·|p|; the solve amplifies them by its condition.
  double worst_lin = 0;
  for (std::size_t j = 0; j < 2; ++j)
    worst_lin = std::max(worst_lin, max_abs(r.value[j] - c.truth[j]));
  EXPECT_LT(worst_lin, 10 * eps * eps * arm);
  EXPECT_GT(worst_lin, 0.0);  // the exact path is really different
  std::printf("exact vs small-angle: eps %.3g rad, straightness difference %.3g mm (bound %.3g)\n",
              eps, worst_lin, 10 * eps * eps * arm);
  // A carriage that only translates: exact and small-angle readings coincide.
  sim::Machine t = mc;
  for (int c2 = 3; c2 < 6; ++c2) t.errors[0][static_cast<std::size_t>(c2)] = {};
  const auto a = sim::simulate_guideway(t, l, o);
  o.exact = false;
  const auto b = sim::simulate_guideway(t, l, o);
  EXPECT_LT((a.spots - b.spots).cwiseAbs().maxCoeff(), 1e-13);  // round-off of ~300 mm
}

TEST(GuidewaySim, NoisyReadingsGiveErrorsWithinTheirUncertainty) {
  const auto mc = machine(7);
  const auto l = layout3d();
  sim::GuidewayOptions o;
  o.positions = 3000;
  o.noise = 0.3e-3;
  o.pointing_noise = 0.4e-3;
  o.seed = 11;
  const auto c = sim::simulate_guideway(mc, l, o);
  guideway::Options so;
  so.sigma = std::hypot(o.noise, o.pointing_noise);  // per reading, independent
  const auto r = guideway::solve(l, c.s, c.spots, so);
  for (std::size_t j = 0; j < 5; ++j) {
    const Eigen::ArrayXd z = (r.value[j] - c.truth[j]).array() / r.uncertainty[j];
    EXPECT_NEAR(std::sqrt(z.square().mean()), 1.0, 0.08) << guideway::kErrorNames[j];
  }
}

TEST(GuidewaySim, QuantisedReadingsAreWholeMultiplesOfTheResolution) {
  const auto mc = machine(4);
  const auto l = layout3d();
  sim::GuidewayOptions o;
  o.quantisation = 0.05e-3;  // 50 nm
  const auto q = sim::simulate_guideway(mc, l, o);
  o.quantisation = 0;
  const auto raw = sim::simulate_guideway(mc, l, o);
  const Eigen::ArrayXXd steps = q.spots.array() / 0.05e-3;
  EXPECT_LT((steps - steps.round()).abs().maxCoeff(), 1e-6);
  EXPECT_LE((q.spots - raw.spots).cwiseAbs().maxCoeff(), 0.025e-3 * (1 + 1e-9));
  // Rounding acts like uniform noise of q/√12 per reading: the estimated sigma shows it.
  const auto r = guideway::solve(l, q.s, q.spots);
  EXPECT_NEAR(r.sigma, 0.05e-3 / std::sqrt(12.0), 0.4 * 0.05e-3 / std::sqrt(12.0));
}

TEST(GuidewaySim, QuadrantCurrentsOfAGaussianSpotConvertBack) {
  const auto mc = machine(2);
  const auto l = layout3d();
  sim::GuidewayOptions o;
  o.spot_radius = 0.5;
  const auto d = sim::simulate_guideway(mc, l, o);
  o.currents = true;
  const auto c = sim::simulate_guideway(mc, l, o);
  ASSERT_EQ(c.currents.cols(), 12);
  // The exact inverse of the Gaussian response, as a dense calibration table.
  guideway::Qpd q;
  q.table_signal.resize(401);
  q.table_displacement.resize(401);
  for (int i = 0; i < 401; ++i) {
    const double x = -0.2 + 0.4 * i / 400;
    q.table_displacement[i] = x;
    q.table_signal[i] = guideway::gaussian_signal(x, o.spot_radius);
  }
  double worst = 0;
  for (Eigen::Index k = 0; k < c.currents.rows(); ++k)
    for (Eigen::Index i = 0; i < 3; ++i) {
      const auto s = q.spot(c.currents(k, 4 * i), c.currents(k, 4 * i + 1),
                            c.currents(k, 4 * i + 2), c.currents(k, 4 * i + 3));
      worst = std::max(
          {worst, std::abs(s.x() - d.spots(k, 2 * i)), std::abs(s.y() - d.spots(k, 2 * i + 1))});
    }
  // Piecewise-linear table with 1 µm nodes on a 0.5 mm spot: error ~ h²·|x''|/8, far below 1 nm.
  EXPECT_LT(worst, 1e-6);
  EXPECT_NE(test::error_of([&] {
              sim::GuidewayOptions bad;
              bad.axis = 3;
              sim::simulate_guideway(mc, l, bad);
            }).find("axis must be"),
            std::string::npos);
}

// On a machine axis the five errors carry ISO 230-1's names: each named error, with its sign,
// is the machine's own error function of that name (for every axis, so every sign of the
// carriage frames is checked against the machine frame).
TEST(GuidewaySim, Iso230NamesAndSignsGiveTheMachinesOwnErrorFunctions) {
  constexpr double kTol = 1e-15;  // mm or rad: the same numbers, rotated by a signed permutation
  const sim::Machine m = machine();
  const std::array<std::array<const char*, 5>, 3> expected{{
      {"EYX", "EZX", "EBX", "ECX", "EAX"},
      {"EXY", "EZY", "EAY", "ECY", "EBY"},
      {"EXZ", "EYZ", "EAZ", "EBZ", "ECZ"},
  }};
  const std::string components = "XYZABC";
  for (int axis = 0; axis < 3; ++axis) {
    sim::GuidewayOptions o;
    o.axis = axis;
    o.positions = 11;
    const auto c = sim::simulate_guideway(m, layout3d(), o);
    const auto names = guideway::iso_names(axis);
    for (std::size_t j = 0; j < guideway::kErrors; ++j) {
      EXPECT_EQ(names[j].name, expected[static_cast<std::size_t>(axis)][j]);
      const auto comp = components.find(names[j].name[1]);
      const auto& fn = m.errors[static_cast<std::size_t>(axis)][comp];
      for (Eigen::Index k = 0; k < c.s.size(); ++k)
        EXPECT_NEAR(names[j].sign * c.truth[j][k], fn.empty() ? 0.0 : fn(c.s[k]), kTol)
            << names[j].name;
    }
  }
  EXPECT_EQ(guideway::iso_names(1)[0].sign, -1.0);  // carriage x is −X on Y
  guideway::Result r;
  r.axis = 0;
  EXPECT_EQ(r.name(4), "EAX (roll)");
  r.axis = -1;
  EXPECT_EQ(r.name(4), "roll");
}
