// Private: the passes over the points that a sphere fit repeats (Gauss–Newton sums, the exact
// gradient for the extended-precision polish, its Hessian), portable and, on x86-64 processors
// that have them, with AVX2 and FMA (chosen once at run time).
//
// The points are three coordinate arrays (x, y, z, each n long), in mm, centred by the caller.
// A sphere is its centre c and radius r; for point i, dᵢ = qᵢ − c, ρᵢ = |dᵢ|, resᵢ = ρᵢ − r.
#pragma once

#include <Eigen/Core>

namespace trueaxis::geometry::detail {

struct Coords {
  const double* x;
  const double* y;
  const double* z;
  Eigen::Index n;
};

// Gauss–Newton sums with jᵢ = ∂resᵢ/∂(c, r) = (−dᵢ/ρᵢ, −1): JᵀJ (4 × 4, row-major) and Jᵀr;
// returns Σresᵢ².
using SphereNormalFn = double (*)(const Coords& q, const double c[3], double r, double JtJ[16],
                                  double Jtr[4]);

// ½Σresᵢ² and its gradient g (4) with respect to (c, r), for the extended-precision polish: c and
// r are given to more than double precision, and each residual is computed to about 2⁻¹⁰⁰ of ρ
// (the portable version: to 80-bit precision), so that the gradient resolves the minimum
// beyond double precision. The sums are compensated.
using SphereGradientFn = long double (*)(const Coords& q, const long double c[3], long double r,
                                         long double g[4]);

// The Hessian of ½Σresᵢ² with the residuals' curvature, H (4 × 4, row-major):
// H_cc = Σ uᵢuᵢᵀ + resᵢ(I − uᵢuᵢᵀ)/ρᵢ with uᵢ = dᵢ/ρᵢ, H_cr = Σuᵢ, H_rr = n.
using SphereHessianFn = void (*)(const Coords& q, const double c[3], double r, double H[16]);

struct SphereKernels {
  SphereNormalFn normal;
  SphereGradientFn gradient;
  SphereHessianFn hessian;
};

SphereKernels sphere_kernels_portable();
// The AVX2 + FMA versions, or all nullptr where the processor (or the compiler) lacks them.
SphereKernels sphere_kernels_avx2();
// The ones fits use: AVX2 where available, else the portable ones.
const SphereKernels& sphere_kernels();

}  // namespace trueaxis::geometry::detail
