#include "trueaxis/map/error_map.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "../../src/map/tricubic.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::map {
namespace {

constexpr double kRoundOff = 1e-12;  // mm, values of order 1e-2 mm on ~1000 mm grids

std::array<Eigen::VectorXd, 3> uniform_axes() {
  return {Eigen::VectorXd::LinSpaced(9, 0, 800), Eigen::VectorXd::LinSpaced(7, -300, 300),
          Eigen::VectorXd::LinSpaced(5, 0, 400)};
}

std::array<Eigen::VectorXd, 3> uneven_axes() {
  Eigen::VectorXd x(6), y(4), z(5);
  x << 0, 50, 170, 300, 420, 800;
  y << -300, -100, 120, 300;
  z << 0, 30, 150, 320, 400;
  return {x, y, z};
}

Eigen::Matrix3Xd random_points(const ErrorMap& m, int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  Eigen::Matrix3Xd p(3, n);
  for (int i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) {
      const auto& x = m.axes[a];
      p(a, i) = x[0] + (x[x.size() - 1] - x[0]) * U(rng);
    }
  return p;
}

// Per component: a trilinear function (a + b x + c y + d z + e xy + f yz + g xz + h xyz) in µm.
Eigen::Vector3d trilinear(const Eigen::Vector3d& p) {
  const double x = p.x() / 1000, y = p.y() / 1000, z = p.z() / 1000;
  return 1e-3 * Eigen::Vector3d(
                    1 + 2 * x - 3 * y + 4 * z + 5 * x * y - 6 * y * z + 7 * x * z + 8 * x * y * z,
                    -2 + x * y * z, 3 * x - y + 0.5 * x * z);
}

// Biquadratic per axis: what the cubic Hermite with parabola slopes reproduces exactly.
Eigen::Vector3d quadratic(const Eigen::Vector3d& p) {
  const double x = p.x() / 1000, y = p.y() / 1000, z = p.z() / 1000;
  return 1e-3 * Eigen::Vector3d(x * x + y * z - 2 * z * z, x * x * y * y * z * z + x,
                                3 * y * y - x * z + 1);
}

TEST(ErrorMap, TrilinearReproducesTrilinearFunctionsOnAnyGrid) {
  for (const auto& axes : {uniform_axes(), uneven_axes()}) {
    const ErrorMap m = sample(axes, trilinear);
    const Eigen::Matrix3Xd p = random_points(m, 500, 1);
    const Eigen::Matrix3Xd e = evaluate(m, p);
    for (Eigen::Index i = 0; i < p.cols(); ++i)
      EXPECT_LT((e.col(i) - trilinear(p.col(i))).norm(), kRoundOff);
  }
}

TEST(ErrorMap, UnevenAxesFindTheRightCell) {
  // A field that is not trilinear, so a wrong cell shows; the reference finds the cell by a
  // plain scan and interpolates by hand. Axes: uneven, and nearly uniform like a measured grid.
  auto wavy = [](const Eigen::Vector3d& p) {
    return Eigen::Vector3d(std::sin(p.x() / 37), std::cos(p.y() / 23), std::sin(p.z() / 41 + 1));
  };
  std::array<Eigen::VectorXd, 3> near = uniform_axes();
  for (auto& a : near)
    for (Eigen::Index i = 1; i + 1 < a.size(); ++i) a[i] += 0.3 * std::sin(3.0 * i);
  for (const auto& axes : {uneven_axes(), near}) {
    const ErrorMap m = sample(axes, wavy);
    const Eigen::Matrix3Xd p = random_points(m, 2000, 4);
    const Eigen::Matrix3Xd e = evaluate(m, p);
    for (Eigen::Index i = 0; i < p.cols(); ++i) {
      Eigen::Index c[3];
      double t[3];
      for (int a = 0; a < 3; ++a) {
        const auto& x = m.axes[static_cast<std::size_t>(a)];
        c[a] = 0;
        while (c[a] + 2 < x.size() && p(a, i) >= x[c[a] + 1]) ++c[a];
        t[a] = (p(a, i) - x[c[a]]) / (x[c[a] + 1] - x[c[a]]);
      }
      Eigen::Vector3d ref = Eigen::Vector3d::Zero();
      for (int corner = 0; corner < 8; ++corner) {
        double w = 1;
        Eigen::Index n[3];
        for (int a = 0; a < 3; ++a) {
          const int up = (corner >> a) & 1;
          w *= up ? t[a] : 1 - t[a];
          n[a] = c[a] + up;
        }
        ref += w * m.error.col(m.index(n[0], n[1], n[2]));
      }
      EXPECT_LT((e.col(i) - ref).norm(), kRoundOff);
    }
  }
}

TEST(ErrorMap, CubicReproducesQuadraticsAndBeatsLinearOnSmoothFields) {
  for (const auto& axes : {uniform_axes(), uneven_axes()}) {
    const ErrorMap m = sample(axes, quadratic);
    const Eigen::Matrix3Xd p = random_points(m, 500, 2);
    const Eigen::Matrix3Xd e = evaluate(m, p, {Interpolation::Cubic});
    for (Eigen::Index i = 0; i < p.cols(); ++i)
      EXPECT_LT((e.col(i) - quadratic(p.col(i))).norm(), kRoundOff);
  }
  // A smooth, non-polynomial field: cubic error well below linear error.
  auto wave = [](const Eigen::Vector3d& p) {
    return Eigen::Vector3d(1e-3 * std::sin(p.x() / 150) * std::cos(p.y() / 200),
                           1e-3 * std::cos(p.z() / 120), 1e-3 * std::sin((p.x() + p.z()) / 180));
  };
  const ErrorMap m = sample(uniform_axes(), wave);
  const Eigen::Matrix3Xd p = random_points(m, 2000, 3);
  const Eigen::Matrix3Xd lin = evaluate(m, p), cub = evaluate(m, p, {Interpolation::Cubic});
  double el = 0, ec = 0;
  for (Eigen::Index i = 0; i < p.cols(); ++i) {
    el = std::max(el, (lin.col(i) - wave(p.col(i))).norm());
    ec = std::max(ec, (cub.col(i) - wave(p.col(i))).norm());
  }
  EXPECT_LT(ec, 0.5 * el) << "linear " << el << " cubic " << ec;
}

TEST(ErrorMap, NodesAreInterpolatedExactly) {
  const ErrorMap m = sample(uneven_axes(), quadratic);
  for (auto how : {Interpolation::Linear, Interpolation::Cubic}) {
    const Interpolator f(m, {how});
    for (Eigen::Index n = 0; n < m.nodes(); ++n)
      EXPECT_LT((f(m.node(n)) - m.error.col(n)).norm(), kRoundOff);
  }
}

TEST(ErrorMap, OutsideTheGridIsRefusedOrClampedNeverExtrapolated) {
  const ErrorMap m = sample(uniform_axes(), trilinear);
  Eigen::Matrix3Xd p(3, 3);
  p << 100, 100, 900,  //
      0, 0, 0,         //
      100, 100, 100;
  try {
    evaluate(m, p);
    FAIL() << "should refuse";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("point 3 (900.000, 0.000, 100.000) mm is outside"),
              std::string::npos)
        << e.what();
  }
  const Eigen::Matrix3Xd c = evaluate(m, p, {Interpolation::Linear, Outside::Clamp});
  EXPECT_LT((c.col(2) - trilinear({800, 0, 100})).norm(), kRoundOff);  // the edge value
  Eigen::Matrix3Xd q = p;
  EXPECT_THROW(compensate(m, q), Error);
  EXPECT_THROW(correct(m, q), Error);
}

TEST(ErrorMap, CompensationInvertsTheMapAndCorrectionSubtractsIt) {
  // e(c) of tens of µm with gradients ~1e-4: two iterations leave ~|∇e|²·|e| ≈ 1e-10 mm.
  auto field = [](const Eigen::Vector3d& p) {
    return Eigen::Vector3d(2e-2 * std::sin(p.x() / 300), 1e-2 * std::cos(p.y() / 250),
                           1.5e-2 * std::sin(p.z() / 200 + p.x() / 500));
  };
  const ErrorMap m = sample(uniform_axes(), field);
  // Wanted positions inside, away from the edges by more than |e| so no clamping is involved.
  Eigen::Matrix3Xd c = random_points(m, 1000, 4);
  c.row(0) = c.row(0).cwiseMax(1).cwiseMin(799);
  c.row(1) = c.row(1).cwiseMax(-299).cwiseMin(299);
  c.row(2) = c.row(2).cwiseMax(1).cwiseMin(399);
  Eigen::Matrix3Xd cp = c;
  compensate(m, cp);
  const Interpolator f(m);
  double worst = 0;
  for (Eigen::Index i = 0; i < c.cols(); ++i)
    worst = std::max(worst, (cp.col(i) + f(cp.col(i)) - c.col(i)).norm());
  EXPECT_LT(worst, 1e-9);
  Eigen::Matrix3Xd once = c;
  compensate(m, once, {{}, 1});  // one iteration: |∇e|·|e| ≈ 1e-6 mm left
  double worst1 = 0;
  for (Eigen::Index i = 0; i < c.cols(); ++i)
    worst1 = std::max(worst1, (once.col(i) + f(once.col(i)) - c.col(i)).norm());
  EXPECT_GT(worst1, 10 * worst);
  Eigen::Matrix3Xd x = c;
  correct(m, x);
  for (Eigen::Index i = 0; i < c.cols(); i += 37)
    EXPECT_LT((x.col(i) - (c.col(i) - f(c.col(i)))).norm(), kRoundOff);
}

TEST(ErrorMap, ParallelBatchEqualsSinglePoints) {
  const ErrorMap m = sample(uneven_axes(), quadratic);
  const Eigen::Matrix3Xd p = random_points(m, 200000, 5);
  const Eigen::Matrix3Xd e = evaluate(m, p, {Interpolation::Cubic});
  const Interpolator f(m, {Interpolation::Cubic});
  for (Eigen::Index i = 0; i < p.cols(); i += 1013) EXPECT_EQ(e.col(i), f(p.col(i)));
}

TEST(ErrorMap, MalformedMapsAreRefused) {
  ErrorMap m = sample(uniform_axes(), trilinear);
  m.axes[1][3] = m.axes[1][2];
  EXPECT_THROW(m.validate(), Error);
  m = sample(uniform_axes(), trilinear);
  m.error.conservativeResize(3, m.nodes() - 1);
  EXPECT_THROW(Interpolator{m}, Error);
  m = sample(uniform_axes(), trilinear);
  m.error(1, 7) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(m.validate(), Error);
  m = sample(uniform_axes(), trilinear);
  m.axes[2] = Eigen::VectorXd::Constant(1, 0.0);
  EXPECT_THROW(m.validate(), Error);
  EXPECT_THROW(interpolation_from_string("spline"), Error);
}

}  // namespace
}  // namespace trueaxis::map

// The tricubic node sum, SSE2 and (where the processor has them) AVX2 with FMA, against the plain
// triple sum of its definition: equal to round-off (FMA rounds once where the others round
// twice, and the vector versions add in another order).
TEST(ErrorMap, TricubicSumKernelsAgreeWithTheDefinition) {
  const auto avx2 = trueaxis::map::detail::tricubic_sum_avx2();
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> table(12 * 4 * 4 * 2);
  for (double& x : table) x = u(rng) * 1e-2;  // mm, errors of tens of µm
  for (int trial = 0; trial < 100; ++trial) {
    double coef[3][16], t[3], w[3][4], a[3], b[3];
    for (auto& c : coef)
      for (double& x : c) x = u(rng);
    for (double& x : t) x = 0.5 * (u(rng) + 1);  // the local coordinate, 0 .. 1
    for (int ax = 0; ax < 3; ++ax)
      for (int q = 0; q < 4; ++q) {
        w[ax][q] = 0;
        for (int p = 0; p < 4; ++p) w[ax][q] += coef[ax][4 * p + q] * std::pow(t[ax], p);
      }
    double want[3] = {0, 0, 0};
    for (int k = 0; k < 4; ++k)
      for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 4; ++i)
          for (int q = 0; q < 3; ++q)
            want[q] += w[0][i] * w[1][j] * w[2][k] * table[96 * k + 24 * j + 3 * i + q];
    const double* poly[3] = {coef[0], coef[1], coef[2]};
    trueaxis::map::detail::tricubic_sum_portable(table.data(), 24, 96, poly, t, a);
    for (int q = 0; q < 3; ++q) EXPECT_NEAR(a[q], want[q], 1e-14);
    if (!avx2) continue;  // this processor has no AVX2 and FMA: the SSE2 sum is the one used
    avx2(table.data(), 24, 96, poly, t, b);
    for (int q = 0; q < 3; ++q) EXPECT_NEAR(b[q], want[q], 1e-14);
  }
}
