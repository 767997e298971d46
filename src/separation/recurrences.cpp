// The recurrences of two- and three-probe straightness separation: two probes one step apart
// give the workpiece by summing the differences of their readings; three probes at 0, 1 and 2
// steps give it by the second-order recurrence of JPH0464003B2 (eqs. 12–17), whose two free
// constants (slope and parabola) are fitted in closed form. Each runs as two running sums with
// the forcing formed off the chain, so a station waits for two additions.
#include <fmt/format.h>

#include <Eigen/Dense>
#include <cmath>
#include <future>
#include <initializer_list>
#include <optional>
#include <string>
#include <vector>

#include "solution.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::separation::detail {
namespace {

void require_offsets(const ProbeData& d, std::initializer_list<long> want, const char* method) {
  const double h = d.step();
  bool ok = d.offsets.size() == want.size();
  std::size_t i = 0;
  for (long w : want) {
    if (!ok) break;
    ok = std::lround(d.offsets[i++] / h) == w;
  }
  if (!ok) {
    std::string s;
    for (long w : want)
      s += (s.empty() ? "" : ", ") + fmt::format("{}", static_cast<double>(w) * h);
    throw Error(fmt::format(
        "method {} needs probes at offsets {} mm (spacing equal to the step {} mm); use --method "
        "lsq for other layouts",
        method, s, h));
  }
  if (d.angle.size() != 0)
    throw Error(fmt::format("method {} does not use an angle channel; use --method lsq", method));
}

}  // namespace

// The arrays a recurrence fills for n stations, and their regions for Prefault.
Raw recurrence_arrays(Method m, long n) {
  Raw r;
  const long nw = m == Method::TwoPoint ? n + 1 : n;
  r.xw.resize(nw);
  r.w.resize(nw);
  r.xg.resize(n);
  r.g.resize(n);
  if (m == Method::ThreePoint && n > 0) {
    r.xt.resize(n - 1);
    r.theta.resize(n - 1);
  }
  return r;
}

std::vector<detail::Prefault::Region> regions_of(const Raw& r) {
  std::vector<detail::Prefault::Region> out;
  for (const Eigen::VectorXd* v : {&r.g, &r.w, &r.theta, &r.xw, &r.xg, &r.xt})
    out.push_back({v->data(), sizeof(double) * static_cast<std::size_t>(v->size())});
  return out;
}

// Fills r (sized by recurrence_arrays).
void two_point(const ProbeData& d, Raw& r) {
  require_offsets(d, {0, 1}, "two-point");
  const long n = d.x.size();
  const double h = d.step();
  r.xw = Eigen::VectorXd::LinSpaced(n + 1, d.x[0], d.x[0] + static_cast<double>(n) * h);
  r.w = Eigen::VectorXd::Zero(n + 1);
  r.xg = d.x;
  r.g.resize(n);
  const auto mA = d.readings.col(0);
  const auto mB = d.readings.col(1);
  // The sequential two-probe method (Whitehouse, "Some theoretical aspects of error separation
  // techniques in surface metrology", J. Phys. E 9, 1976) with w_0 = g_0 = 0 and the unknown
  // slope w_1 = 0 (the reference line is applied later).
  for (long K = 0; K < n; ++K) {
    if (K + 1 <= n) r.w[K + 1] = r.w[K] + (mB[K] - mB[0]) - (mA[K] - mA[0]);
    r.g[K] = mA[K] - mA[0] - r.w[K];
  }
}

// The three-point recurrence of JPH0464003B2 (eqs. 12–17), which also defines the "patent"
// reference.
// Fills r (sized by recurrence_arrays).
void three_point(const ProbeData& d, std::optional<double> zero_difference, Raw& r) {
  require_offsets(d, {0, 1, 2}, "three-point");
  const long n = d.x.size();  // stations K = 0..n-1
  if (n < 4) throw Error(fmt::format("three-point needs at least 4 stations, got {}", n));
  const double l = d.step();
  const double* A = d.readings.col(0).data();
  const double* B = d.readings.col(1).data();
  const double* C = d.readings.col(2).data();
  const double a0 = A[0], b0 = B[0], c0 = C[0];
  // The profiles' station grids are copies of x: made on another core meanwhile.
  auto grids = std::async(policy_for(r), [&] {
    r.xt = d.x.head(n - 1);
    r.xg = d.x;
    r.xw = d.x;
  });
  // Eq. 12 run from X_0 = 0, X_1 = α with the constant β: X_K = K·α + K(K−1)/2·β + C_K (eq. 15),
  // with D_K = m(K) − m(0) per probe formed on the fly. Returns b = −Σ_{K≥2} a_K·X_K with
  // a_K = (K, K(K−1)/2), for the fit below.
  Eigen::VectorXd& X = r.g;  // the guide is X itself (eq. 13)
  // Run as two sums, ΔX_{K+1} = ΔX_K + f_K and X_{K+2} = X_{K+1} + ΔX_{K+1}, with the forcing f_K
  // formed off the chain: each station waits for two additions, not for the whole expression.
  auto recurrence = [&](double alpha, double beta) {
    X[0] = 0;
    X[1] = alpha;
    double x = alpha, dx = alpha, b0s = 0, b1s = 0;
    for (long K = 0; K + 2 < n; ++K) {
      const double f = (A[K + 2] - a0) - 2 * (A[K + 1] - a0) + 2 * (B[K] - b0) - (C[K] - c0) + beta;
      dx += f;
      x += dx;
      X[K + 2] = x;
      const double k = static_cast<double>(K + 2);
      b0s -= k * x;
      b1s -= k * (k - 1) / 2 * x;
    }
    return Eigen::Vector2d(b0s, b1s);
  };
  // α, β (or α alone when β is known) minimising Σ_{K=2}^{n−1} (X_K + K·α + K(K−1)/2·β)²: the
  // 2×2 normal equations whose closed form is the patent's eqs. 16–17.
  const bool beta_known = zero_difference.has_value();
  // β = 2Y_1 − Y_2 = e − (D_0A − 2D_0B + D_0C) when the zero difference e is known.
  const double beta0 =
      beta_known ? *zero_difference - (d.readings(0, 0) - 2 * d.readings(0, 1) + d.readings(0, 2))
                 : 0.0;
  // Two fits, identical in exact arithmetic to the one-shot formula: C_K can grow like K²·β
  // (1e9 mm at a million stations), so the first fit is used to run the recurrence near its
  // final size and the second fit corrects the small remainder. The first needs only b, a linear
  // function of the forcing: with α = 0 and f_j the forcing (β included), X_K = Σ_{j≤K−2}
  // (K−1−j)·f_j, so b_i = −Σ_j f_j·W_i(j) with W_0(j) = Σ_{K=j+2}^{n−1} K·(K−1−j) and W_1(j) the
  // same with K(K−1)/2. In m = K−1−j ∈ [1, M], M = n−2−j, c = j+1 these are sums of powers of
  // m, which with S1 = M(M+1)/2 close to W_0 = S1·(3n−2−M)/3 and
  // W_1 = S1·(3·S1 + (2c−1)(2M+1) + 3c(c−1))/6 (integers below 2⁵³ up to the last product; the
  // common divisors are applied once). The same pass sums the fit's normal matrix Σ a·aᵀ over
  // K = j+2 into Mn. One vectorised pass, not a recurrence: the counts are doubles made from 32-bit
  // offsets in blocks (64-bit integers do not convert to doubles in vector registers).
  Eigen::Matrix2d Mn;
  auto forcing_moments = [&](double beta) {
    double s0 = 0, s1 = 0, s11 = 0, s12 = 0, s22 = 0;
    const double n1 = static_cast<double>(n - 2), n3 = 3.0 * static_cast<double>(n) - 2;
    constexpr long kBlock = 1L << 20;
    for (long j0 = 0; j0 < n - 2; j0 += kBlock) {
      const int m = static_cast<int>(std::min(kBlock, n - 2 - j0));
      const double base = static_cast<double>(j0);
      const double *Ab = A + j0, *Bb = B + j0, *Cb = C + j0;
#pragma omp simd reduction(+ : s0, s1, s11, s12, s22)
      for (int i = 0; i < m; ++i) {
        const double f =
            (Ab[i + 2] - a0) - 2 * (Ab[i + 1] - a0) + 2 * (Bb[i] - b0) - (Cb[i] - c0) + beta;
        const double j = base + static_cast<double>(i), M = n1 - j, c = j + 1;
        const double S1 = M * (M + 1) * 0.5;
        s0 -= f * (S1 * (n3 - M));
        s1 -= f * (S1 * (3 * S1 + (2 * c - 1) * (2 * M + 1) + 3 * c * (c - 1)));
        const double k = c + 1, t = k * c * 0.5;  // K = j + 2 and K(K−1)/2
        s11 += k * k;
        s12 += k * t;
        s22 += t * t;
      }
    }
    Mn << s11, s12, s12, s22;
    return Eigen::Vector2d(s0 / 3, s1 / 6);
  };
  auto fit = [&](const Eigen::Vector2d& b) {
    if (beta_known) return Eigen::Vector2d(b[0] / Mn(0, 0), 0.0);
    return Eigen::Vector2d(Mn.ldlt().solve(b));
  };
  const Eigen::Vector2d ab1 = fit(forcing_moments(beta0));
  const Eigen::Vector2d ab2 = fit(recurrence(ab1[0], beta0 + ab1[1]));
  // The corrected guide, w (eq. 13) and θ (eq. 14) in one pass: θ_K needs w_{K+1}, which is
  // formed again from X_{K+1} before the next step overwrites it. The station number is a double
  // made from a 32-bit offset in blocks, so that the loop vectorises.
  {
    const double c0 = ab2[0], c1 = ab2[1];
    auto fixed = [c0, c1](double x, double k) { return x + (k * c0 + k * (k - 1) / 2 * c1); };
    double* __restrict Xp = X.data();
    double* __restrict wp = r.w.data();
    double* __restrict tp = r.theta.data();
    const double w1 = (A[1] - a0) - fixed(Xp[1], 1);
    constexpr long kBlock = 1L << 20;
    for (long K0 = 0; K0 + 1 < n; K0 += kBlock) {
      const int m = static_cast<int>(std::min(kBlock, n - 1 - K0));
      const double base = static_cast<double>(K0);
      const double *Ab = A + K0, *Bb = B + K0;
      double *Xb = Xp + K0, *wb = wp + K0, *tb = tp + K0;
#pragma omp simd
      for (int i = 0; i < m; ++i) {
        const double k = base + static_cast<double>(i);
        const double xk = fixed(Xb[i], k), xk1 = fixed(Xb[i + 1], k + 1);
        Xb[i] = xk;
        wb[i] = (Ab[i] - a0) - xk;
        tb[i] = ((Bb[i] - b0) - ((Ab[i + 1] - a0) - xk1) - xk + w1) / l;
      }
    }
    Xp[n - 1] = fixed(Xp[n - 1], static_cast<double>(n - 1));
    wp[n - 1] = (A[n - 1] - a0) - Xp[n - 1];
  }
  grids.get();
  r.parabola_free = !zero_difference.has_value();
}

}  // namespace trueaxis::separation::detail
