// The sphere fit's passes over the points, portable and AVX2 (where the processor has it),
// against the plain definitions of their sums computed here with Eigen.
#include "../../src/geometry/sphere_kernels.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

using namespace trueaxis::geometry::detail;

namespace {

using Ld = long double;

// Points on a ±3° cap of a 50 mm radius sphere centred at (0.3, −0.2, −49.9) mm (the cap near
// the origin), with 2 µm noise, as three coordinate arrays.
struct Cloud {
  std::vector<double> x, y, z;
  Coords coords() const {
    return {x.data(), y.data(), z.data(), static_cast<Eigen::Index>(x.size())};
  }
};

Cloud cap(int n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> noise(0, 2e-3);
  Cloud c;
  const double a = 3 * M_PI / 180;
  for (int i = 0; i < n; ++i) {
    const double th = a * std::sqrt(u(rng)), ph = 2 * M_PI * u(rng), r = 50 + noise(rng);
    c.x.push_back(r * std::sin(th) * std::cos(ph) + 0.3);
    c.y.push_back(r * std::sin(th) * std::sin(ph) - 0.2);
    c.z.push_back(r * std::cos(th) - 49.9);
  }
  return c;
}

std::vector<SphereKernels> kernel_sets() {
  std::vector<SphereKernels> k{sphere_kernels_portable()};
  if (sphere_kernels_avx2().normal) k.push_back(sphere_kernels_avx2());
  return k;
}

const char* name(std::size_t k) {
  return k == 0 ? "portable" : "AVX2";
}

}  // namespace

// JᵀJ, Jᵀr and Σr², and the Hessian, for every count from 1 to 9 (the AVX2 versions take four
// points at a time and pad the rest) and for 1001 points.
TEST(SphereKernels, GaussNewtonSumsAndHessianMatchTheirDefinitions) {
  std::mt19937_64 rng(3);
  for (int n : {1, 2, 3, 4, 5, 6, 7, 8, 9, 1001}) {
    const Cloud cl = cap(n, rng);
    const double c[3] = {0.31, -0.19, -49.88}, r = 50.002;
    Eigen::Matrix4d JtJ = Eigen::Matrix4d::Zero(), H = Eigen::Matrix4d::Zero();
    Eigen::Vector4d Jtr = Eigen::Vector4d::Zero();
    double cost = 0;
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d d = Eigen::Vector3d(cl.x[i], cl.y[i], cl.z[i]) - Eigen::Vector3d(c);
      const double rho = d.norm(), res = rho - r;
      const Eigen::Vector4d j(-d.x() / rho, -d.y() / rho, -d.z() / rho, -1);
      JtJ += j * j.transpose();
      Jtr += res * j;
      cost += res * res;
      const Eigen::Vector3d u = d / rho;
      H.topLeftCorner<3, 3>() +=
          u * u.transpose() + res / rho * (Eigen::Matrix3d::Identity() - u * u.transpose());
      H.topRightCorner<3, 1>() += u;
      H.bottomLeftCorner<1, 3>() += u.transpose();
      H(3, 3) += 1;
    }
    const auto sets = kernel_sets();
    for (std::size_t k = 0; k < sets.size(); ++k) {
      Eigen::Matrix<double, 4, 4, Eigen::RowMajor> A, B;
      Eigen::Vector4d b;
      const double ck = sets[k].normal(cl.coords(), c, r, A.data(), b.data());
      sets[k].hessian(cl.coords(), c, r, B.data());
      // JᵀJ and H: sums of n terms of order 1, reordered. Jᵀr and Σr²: each residual ρ − r
      // carries ρ's rounding (~2⁻⁵³·50 mm, and FMA rounds ρ² differently).
      constexpr double kSums = 1e-13;
      const double per_residual = 8 * std::numeric_limits<double>::epsilon() * 50;  // mm
      EXPECT_LT((A - JtJ).cwiseAbs().maxCoeff(), kSums * n) << name(k) << ", n " << n;
      EXPECT_LT((b - Jtr).cwiseAbs().maxCoeff(), per_residual * n) << name(k) << ", n " << n;
      EXPECT_NEAR(ck, cost, 2 * std::sqrt(n * cost) * per_residual) << name(k) << ", n " << n;
      EXPECT_LT((B - H).cwiseAbs().maxCoeff(), kSums * n) << name(k) << ", n " << n;
    }
  }
}

// The polish's gradient at a state given beyond double precision, near the minimum of a ±3° cap
// (where ρ − r keeps only the last few digits of ρ in double precision): against the same sums
// in 80-bit arithmetic here, to 2⁻⁶² of ρ per point, which a gradient from double-precision
// residuals (errors ~2⁻⁵³ of ρ each) misses by far.
TEST(SphereKernels, PolishGradientResolvesResidualsBeyondDoublePrecision) {
  std::mt19937_64 rng(4);
  for (int n : {1, 5, 7, 1003}) {
    const Cloud cl = cap(n, rng);
    // The centre and radius with parts below a double's last bit.
    const Ld c[3] = {0.3L + 1e-19L, -0.2L - 3e-19L, -49.9L + 7e-20L}, r = 50.0L + 2e-18L;
    Ld gx = 0, gy = 0, gz = 0, gr = 0, cost = 0;
    for (int i = 0; i < n; ++i) {
      const Ld dx = cl.x[i] - c[0], dy = cl.y[i] - c[1], dz = cl.z[i] - c[2];
      const Ld rho = std::sqrt(dx * dx + dy * dy + dz * dz), res = rho - r;
      cost += res * res;
      gx -= res * dx / rho;
      gy -= res * dy / rho;
      gz -= res * dz / rho;
      gr -= res;
    }
    const Ld tolerance = std::ldexp(50.0L, -62) * n;  // mm: 2⁻⁶² of ρ per point
    const auto sets = kernel_sets();
    for (std::size_t k = 0; k < sets.size(); ++k) {
      Ld g[4];
      const Ld half_cost = sets[k].gradient(cl.coords(), c, r, g);
      EXPECT_LT(std::abs(g[0] - gx), tolerance) << name(k) << ", n " << n;
      EXPECT_LT(std::abs(g[1] - gy), tolerance) << name(k) << ", n " << n;
      EXPECT_LT(std::abs(g[2] - gz), tolerance) << name(k) << ", n " << n;
      EXPECT_LT(std::abs(g[3] - gr), tolerance) << name(k) << ", n " << n;
      // ½Σr² to the same 2⁻⁶² of ρ per residual (Σ|r| ≤ √(n·Σr²)).
      EXPECT_LT(std::abs(half_cost - cost / 2), std::sqrt(n * cost) * std::ldexp(50.0L, -62))
          << name(k) << ", n " << n;
    }
  }
}
