#include "sphere_kernels.hpp"

#include <cmath>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define TRUEAXIS_SPHERE_AVX2 1
#endif

namespace trueaxis::geometry::detail {
namespace {

using Ld = long double;

double normal_portable(const Coords& q, const double c[3], double r, double JtJ[16],
                       double Jtr[4]) {
  double a00 = 0, a01 = 0, a02 = 0, a11 = 0, a12 = 0, a22 = 0, s0 = 0, s1 = 0, s2 = 0;
  double b0 = 0, b1 = 0, b2 = 0, sr = 0, cost = 0;
  for (Eigen::Index i = 0; i < q.n; ++i) {
    const double dx = q.x[i] - c[0], dy = q.y[i] - c[1], dz = q.z[i] - c[2];
    const double rho = std::sqrt(dx * dx + dy * dy + dz * dz), inv = -1 / rho, res = rho - r;
    const double j0 = dx * inv, j1 = dy * inv, j2 = dz * inv;
    a00 += j0 * j0;
    a01 += j0 * j1;
    a02 += j0 * j2;
    a11 += j1 * j1;
    a12 += j1 * j2;
    a22 += j2 * j2;
    s0 += j0;
    s1 += j1;
    s2 += j2;
    b0 += res * j0;
    b1 += res * j1;
    b2 += res * j2;
    sr += res;
    cost += res * res;
  }
  const double n = static_cast<double>(q.n);
  const double M[16] = {a00, a01, a02, -s0, a01, a11, a12, -s1,
                        a02, a12, a22, -s2, -s0, -s1, -s2, n};
  for (int k = 0; k < 16; ++k) JtJ[k] = M[k];
  Jtr[0] = b0;
  Jtr[1] = b1;
  Jtr[2] = b2;
  Jtr[3] = -sr;
  return cost;
}

// In 80-bit arithmetic (x87 on x86-64): ρ to 2⁻⁶⁴ and 64-bit sums.
Ld gradient_portable(const Coords& q, const Ld c[3], Ld r, Ld g[4]) {
  Ld gx = 0, gy = 0, gz = 0, gr = 0, cost = 0;
  for (Eigen::Index i = 0; i < q.n; ++i) {
    const Ld dx = q.x[i] - c[0], dy = q.y[i] - c[1], dz = q.z[i] - c[2];
    const Ld rho = std::sqrt(dx * dx + dy * dy + dz * dz), res = rho - r;
    const Ld w = res / rho;  // one x87 division per point, not one per coordinate
    cost += res * res;
    gx -= w * dx;
    gy -= w * dy;
    gz -= w * dz;
    gr -= res;
  }
  g[0] = gx;
  g[1] = gy;
  g[2] = gz;
  g[3] = gr;
  return cost / 2;
}

void hessian_portable(const Coords& q, const double c[3], double r, double H[16]) {
  double h00 = 0, h01 = 0, h02 = 0, h11 = 0, h12 = 0, h22 = 0, diag = 0, u0 = 0, u1 = 0, u2 = 0;
  for (Eigen::Index i = 0; i < q.n; ++i) {
    const double dx = q.x[i] - c[0], dy = q.y[i] - c[1], dz = q.z[i] - c[2];
    const double rho = std::sqrt(dx * dx + dy * dy + dz * dz), inv = 1 / rho;
    const double ux = dx * inv, uy = dy * inv, uz = dz * inv, k = r * inv;
    h00 += k * ux * ux;
    h01 += k * ux * uy;
    h02 += k * ux * uz;
    h11 += k * uy * uy;
    h12 += k * uy * uz;
    h22 += k * uz * uz;
    diag += 1 - k;
    u0 += ux;
    u1 += uy;
    u2 += uz;
  }
  const double n = static_cast<double>(q.n);
  const double M[16] = {h00 + diag, h01, h02,        u0, h01, h11 + diag, h12, u1,
                        h02,        h12, h22 + diag, u2, u0,  u1,         u2,  n};
  for (int k = 0; k < 16; ++k) H[k] = M[k];
}

#ifdef TRUEAXIS_SPHERE_AVX2
#define TA_AVX2 __attribute__((target("avx2,fma")))
#define TA_AVX2_INLINE __attribute__((target("avx2,fma"), always_inline)) inline

// Four points from i on: whole vectors, or the last 1–3 padded with zero points whose lanes
// `keep` (all bits set for real points) clears from every sum.
struct Four {
  __m256d x, y, z, keep;
};

TA_AVX2_INLINE Four load_four(const Coords& q, Eigen::Index i) {
  if (i + 4 <= q.n)
    return {_mm256_loadu_pd(q.x + i), _mm256_loadu_pd(q.y + i), _mm256_loadu_pd(q.z + i),
            _mm256_castsi256_pd(_mm256_set1_epi64x(-1))};
  alignas(32) double x[4] = {0, 0, 0, 0}, y[4] = {0, 0, 0, 0}, z[4] = {0, 0, 0, 0};
  alignas(32) long long k[4] = {0, 0, 0, 0};
  for (Eigen::Index j = 0; i + j < q.n; ++j) {
    x[j] = q.x[i + j];
    y[j] = q.y[i + j];
    z[j] = q.z[i + j];
    k[j] = -1;
  }
  return {_mm256_load_pd(x), _mm256_load_pd(y), _mm256_load_pd(z),
          _mm256_castsi256_pd(_mm256_load_si256(reinterpret_cast<const __m256i*>(k)))};
}

// The four lanes' sum, always in the same order.
TA_AVX2_INLINE double lanes(__m256d v) {
  alignas(32) double a[4];
  _mm256_store_pd(a, v);
  return (a[0] + a[1]) + (a[2] + a[3]);
}

// The four points' offsets d from the centre c and their lengths ρ (in double precision).
TA_AVX2_INLINE __m256d distance(const Four& p, __m256d cx, __m256d cy, __m256d cz, __m256d& dx,
                                __m256d& dy, __m256d& dz) {
  dx = _mm256_sub_pd(p.x, cx);
  dy = _mm256_sub_pd(p.y, cy);
  dz = _mm256_sub_pd(p.z, cz);
  return _mm256_sqrt_pd(_mm256_fmadd_pd(dx, dx, _mm256_fmadd_pd(dy, dy, _mm256_mul_pd(dz, dz))));
}

TA_AVX2 double normal_avx2(const Coords& q, const double c[3], double r, double JtJ[16],
                           double Jtr[4]) {
  const __m256d cx = _mm256_set1_pd(c[0]), cy = _mm256_set1_pd(c[1]), cz = _mm256_set1_pd(c[2]);
  const __m256d rr = _mm256_set1_pd(r), minus_one = _mm256_set1_pd(-1);
  __m256d a00 = _mm256_setzero_pd(), a01 = a00, a02 = a00, a11 = a00, a12 = a00, a22 = a00;
  __m256d s0 = a00, s1 = a00, s2 = a00, b0 = a00, b1 = a00, b2 = a00, sr = a00, cost = a00;
  for (Eigen::Index i = 0; i < q.n; i += 4) {
    const Four p = load_four(q, i);
    __m256d dx, dy, dz;
    const __m256d rho = distance(p, cx, cy, cz, dx, dy, dz);
    const __m256d inv = _mm256_and_pd(_mm256_div_pd(minus_one, rho), p.keep);
    const __m256d res = _mm256_and_pd(_mm256_sub_pd(rho, rr), p.keep);
    const __m256d j0 = _mm256_mul_pd(dx, inv), j1 = _mm256_mul_pd(dy, inv),
                  j2 = _mm256_mul_pd(dz, inv);
    a00 = _mm256_fmadd_pd(j0, j0, a00);
    a01 = _mm256_fmadd_pd(j0, j1, a01);
    a02 = _mm256_fmadd_pd(j0, j2, a02);
    a11 = _mm256_fmadd_pd(j1, j1, a11);
    a12 = _mm256_fmadd_pd(j1, j2, a12);
    a22 = _mm256_fmadd_pd(j2, j2, a22);
    s0 = _mm256_add_pd(s0, j0);
    s1 = _mm256_add_pd(s1, j1);
    s2 = _mm256_add_pd(s2, j2);
    b0 = _mm256_fmadd_pd(res, j0, b0);
    b1 = _mm256_fmadd_pd(res, j1, b1);
    b2 = _mm256_fmadd_pd(res, j2, b2);
    sr = _mm256_add_pd(sr, res);
    cost = _mm256_fmadd_pd(res, res, cost);
  }
  const double n = static_cast<double>(q.n);
  const double h00 = lanes(a00), h01 = lanes(a01), h02 = lanes(a02), h11 = lanes(a11),
               h12 = lanes(a12), h22 = lanes(a22), t0 = lanes(s0), t1 = lanes(s1), t2 = lanes(s2);
  const double M[16] = {h00, h01, h02, -t0, h01, h11, h12, -t1,
                        h02, h12, h22, -t2, -t0, -t1, -t2, n};
  for (int k = 0; k < 16; ++k) JtJ[k] = M[k];
  Jtr[0] = lanes(b0);
  Jtr[1] = lanes(b1);
  Jtr[2] = lanes(b2);
  Jtr[3] = -lanes(sr);
  return lanes(cost);
}

// Error-free transformations (Knuth's TwoSum: a + b = s + e exactly).
TA_AVX2_INLINE __m256d two_sum(__m256d a, __m256d b, __m256d& e) {
  const __m256d s = _mm256_add_pd(a, b), bb = _mm256_sub_pd(s, a);
  e = _mm256_add_pd(_mm256_sub_pd(a, _mm256_sub_pd(s, bb)), _mm256_sub_pd(b, bb));
  return s;
}

// A compensated running sum: hi + lo.
struct Sum2 {
  __m256d hi, lo;
};

TA_AVX2_INLINE void add(Sum2& s, __m256d t) {
  __m256d e;
  s.hi = two_sum(s.hi, t, e);
  s.lo = _mm256_add_pd(s.lo, e);
}

TA_AVX2_INLINE Ld total(const Sum2& s) {
  alignas(32) double hi[4], lo[4];
  _mm256_store_pd(hi, s.hi);
  _mm256_store_pd(lo, s.lo);
  Ld t = 0;
  for (int k = 0; k < 4; ++k) t += static_cast<Ld>(hi[k]) + static_cast<Ld>(lo[k]);
  return t;
}

// Each residual in double-double arithmetic: d = q − c exactly as s + t (TwoSum against c's
// high part, then its low part), ρ² = Σ(s + t)² with the squares' rounding errors from FMA,
// ρ = √ρ² with one Newton correction, res = (ρ₀ − r_hi) + (δρ − r_lo). The cancellation in
// ρ − r, which costs double precision all its digits near a shallow cap's minimum, happens on
// exact parts; res comes out to about 2⁻⁵³ of itself plus 2⁻¹⁰⁰ of ρ.
TA_AVX2 Ld gradient_avx2(const Coords& q, const Ld c[3], Ld r, Ld g[4]) {
  const double chx = static_cast<double>(c[0]), chy = static_cast<double>(c[1]),
               chz = static_cast<double>(c[2]), rh = static_cast<double>(r);
  const __m256d cxh = _mm256_set1_pd(chx), cyh = _mm256_set1_pd(chy), czh = _mm256_set1_pd(chz);
  const __m256d cxl = _mm256_set1_pd(static_cast<double>(c[0] - chx)),
                cyl = _mm256_set1_pd(static_cast<double>(c[1] - chy)),
                czl = _mm256_set1_pd(static_cast<double>(c[2] - chz));
  const __m256d rhv = _mm256_set1_pd(rh), rlv = _mm256_set1_pd(static_cast<double>(r - rh));
  const __m256d one = _mm256_set1_pd(1), half = _mm256_set1_pd(0.5), two = _mm256_set1_pd(2);
  const __m256d zero = _mm256_setzero_pd();
  Sum2 gx{zero, zero}, gy = gx, gz = gx, gr = gx, cost = gx;
  for (Eigen::Index i = 0; i < q.n; i += 4) {
    const Four p = load_four(q, i);
    __m256d tx, ty, tz;
    const __m256d sx = two_sum(p.x, _mm256_sub_pd(zero, cxh), tx);
    const __m256d sy = two_sum(p.y, _mm256_sub_pd(zero, cyh), ty);
    const __m256d sz = two_sum(p.z, _mm256_sub_pd(zero, czh), tz);
    tx = _mm256_sub_pd(tx, cxl);
    ty = _mm256_sub_pd(ty, cyl);
    tz = _mm256_sub_pd(tz, czl);
    const __m256d px = _mm256_mul_pd(sx, sx), py = _mm256_mul_pd(sy, sy),
                  pz = _mm256_mul_pd(sz, sz);
    const __m256d ex = _mm256_fmsub_pd(sx, sx, px), ey = _mm256_fmsub_pd(sy, sy, py),
                  ez = _mm256_fmsub_pd(sz, sz, pz);
    __m256d e1, e2;
    const __m256d s1 = two_sum(px, py, e1);
    const __m256d s2 = two_sum(s1, pz, e2);
    // The low part: the products' and sums' errors and the cross terms 2·s·t (t² is ~2⁻¹⁰⁶).
    const __m256d cross = _mm256_fmadd_pd(sx, tx, _mm256_fmadd_pd(sy, ty, _mm256_mul_pd(sz, tz)));
    const __m256d low = _mm256_fmadd_pd(
        two, cross, _mm256_add_pd(_mm256_add_pd(ex, ey), _mm256_add_pd(ez, _mm256_add_pd(e1, e2))));
    const __m256d rho0 = _mm256_sqrt_pd(s2);
    const __m256d inv = _mm256_div_pd(one, rho0);
    const __m256d rem =
        _mm256_add_pd(_mm256_fnmadd_pd(rho0, rho0, s2), low);  // ρ² − ρ₀², exact + low
    const __m256d corr = _mm256_mul_pd(_mm256_mul_pd(half, rem), inv);
    const __m256d res =
        _mm256_and_pd(_mm256_add_pd(_mm256_sub_pd(rho0, rhv), _mm256_sub_pd(corr, rlv)), p.keep);
    const __m256d w = _mm256_and_pd(_mm256_mul_pd(res, inv), p.keep);
    add(gx, _mm256_mul_pd(w, sx));
    add(gy, _mm256_mul_pd(w, sy));
    add(gz, _mm256_mul_pd(w, sz));
    add(gr, res);
    add(cost, _mm256_mul_pd(res, res));
  }
  g[0] = -total(gx);
  g[1] = -total(gy);
  g[2] = -total(gz);
  g[3] = -total(gr);
  return total(cost) / 2;
}

TA_AVX2 void hessian_avx2(const Coords& q, const double c[3], double r, double H[16]) {
  const __m256d cx = _mm256_set1_pd(c[0]), cy = _mm256_set1_pd(c[1]), cz = _mm256_set1_pd(c[2]);
  const __m256d rr = _mm256_set1_pd(r), one = _mm256_set1_pd(1);
  __m256d h00 = _mm256_setzero_pd(), h01 = h00, h02 = h00, h11 = h00, h12 = h00, h22 = h00;
  __m256d diag = h00, u0 = h00, u1 = h00, u2 = h00;
  for (Eigen::Index i = 0; i < q.n; i += 4) {
    const Four p = load_four(q, i);
    __m256d dx, dy, dz;
    const __m256d rho = distance(p, cx, cy, cz, dx, dy, dz);
    const __m256d inv = _mm256_and_pd(_mm256_div_pd(one, rho), p.keep);
    const __m256d ux = _mm256_mul_pd(dx, inv), uy = _mm256_mul_pd(dy, inv),
                  uz = _mm256_mul_pd(dz, inv), k = _mm256_mul_pd(rr, inv);
    const __m256d kx = _mm256_mul_pd(k, ux), ky = _mm256_mul_pd(k, uy);
    h00 = _mm256_fmadd_pd(kx, ux, h00);
    h01 = _mm256_fmadd_pd(kx, uy, h01);
    h02 = _mm256_fmadd_pd(kx, uz, h02);
    h11 = _mm256_fmadd_pd(ky, uy, h11);
    h12 = _mm256_fmadd_pd(ky, uz, h12);
    h22 = _mm256_fmadd_pd(_mm256_mul_pd(k, uz), uz, h22);
    diag = _mm256_add_pd(diag, _mm256_and_pd(_mm256_sub_pd(one, k), p.keep));
    u0 = _mm256_add_pd(u0, ux);
    u1 = _mm256_add_pd(u1, uy);
    u2 = _mm256_add_pd(u2, uz);
  }
  const double n = static_cast<double>(q.n), d = lanes(diag);
  const double v0 = lanes(u0), v1 = lanes(u1), v2 = lanes(u2), a01 = lanes(h01), a02 = lanes(h02),
               a12 = lanes(h12);
  const double M[16] = {lanes(h00) + d,
                        a01,
                        a02,
                        v0,
                        a01,
                        lanes(h11) + d,
                        a12,
                        v1,
                        a02,
                        a12,
                        lanes(h22) + d,
                        v2,
                        v0,
                        v1,
                        v2,
                        n};
  for (int k = 0; k < 16; ++k) H[k] = M[k];
}
#endif

}  // namespace

SphereKernels sphere_kernels_portable() {
  return {normal_portable, gradient_portable, hessian_portable};
}

SphereKernels sphere_kernels_avx2() {
#ifdef TRUEAXIS_SPHERE_AVX2
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"))
    return {normal_avx2, gradient_avx2, hessian_avx2};
#endif
  return {nullptr, nullptr, nullptr};
}

const SphereKernels& sphere_kernels() {
  static const SphereKernels best = [] {
    const SphereKernels k = sphere_kernels_avx2();
    return k.normal ? k : sphere_kernels_portable();
  }();
  return best;
}

}  // namespace trueaxis::geometry::detail
