// Internal to the banded least-squares solver (banded_lsq.hpp): the stations' right-hand sides,
// formed a block of stations at a time, shared by the factorisation (banded_lsq.cpp) and the
// solve and covariances (banded_lsq_solve.cpp).
#pragma once

#include <algorithm>
#include <vector>

#include "banded_lsq.hpp"

// GCC's vectoriser pairs loads in the Givens fold that clang leaves alone (clang has no such
// attribute).
#if defined(__clang__)
#define TA_NO_VECTORIZE
#else
#define TA_NO_VECTORIZE __attribute__((optimize("no-tree-vectorize")))
#endif

namespace trueaxis::separation::detail {

inline constexpr int kBlock = 256;  // stations whose right-hand sides are formed together

// Right-hand sides b − A·v of stations [K0, K0 + B), transformed by the constant Qᵀ (row-major
// qt): bt[r·B + k] is row r (the L local ones first) of station K0 + k. Formed channel by channel
// over the block, contiguous in the station, so the loops vectorise; b is scratch of M·B. Without
// v, its profiles are 0 (only the offsets `off` count).
inline void block_rhs(const Design& D, long K0, int B, const Eigen::MatrixXd& readings,
                      const double* mu, const Eigen::VectorXd& angle_mm, const Unknowns* v,
                      const double* off, const double* qt, int M, double* b, double* bt) {
  const double* g = v ? v->g + K0 : nullptr;
  const double* t = v && D.pitch ? v->t + K0 : nullptr;
  for (int i = 0; i < D.N; ++i) {
    const double* rd = readings.col(i).data() + K0;
    const double mi = mu[i], oi = off[i];
    double* bi = b + static_cast<std::ptrdiff_t>(i) * B;
    if (!v) {
      for (int k = 0; k < B; ++k) bi[k] = rd[k] - mi - oi;
      continue;
    }
    const double* w = v->w + (K0 + D.q[static_cast<std::size_t>(i)]);
    const double pi = static_cast<double>(D.p[static_cast<std::size_t>(i)]);
    if (t)
      for (int k = 0; k < B; ++k) bi[k] = rd[k] - mi - w[k] - g[k] - pi * t[k] - oi;
    else
      for (int k = 0; k < B; ++k) bi[k] = rd[k] - mi - w[k] - g[k] - oi;
  }
  if (D.angle) {
    const double* an = angle_mm.data() + K0;
    const double oa = off[D.N], wa = D.wa;
    double* bi = b + static_cast<std::ptrdiff_t>(D.N) * B;
    if (t)
      for (int k = 0; k < B; ++k) bi[k] = wa * (an[k] - t[k] - oa);
    else
      for (int k = 0; k < B; ++k) bi[k] = wa * (an[k] - oa);
  }
  for (int r = 0; r < M; ++r) {
    double* o = bt + static_cast<std::ptrdiff_t>(r) * B;
    const double q0 = qt[r * M];
    for (int k = 0; k < B; ++k) o[k] = q0 * b[k];
    for (int c = 1; c < M; ++c) {
      const double qc = qt[r * M + c];
      const double* bc = b + static_cast<std::ptrdiff_t>(c) * B;
      for (int k = 0; k < B; ++k) o[k] += qc * bc[k];
    }
  }
}

template <class Fn>
void BandedLsq::for_each_block(const Chain& ch, const Eigen::MatrixXd& readings,
                               const Eigen::RowVectorXd& mu, const Eigen::VectorXd& angle_mm,
                               const Unknowns* v, Fn&& fn) {
  const Design& D = D_;
  const int L = L_, M = M_;
  std::vector<double> b(static_cast<std::size_t>(M * kBlock)),
      bt(static_cast<std::size_t>(M * kBlock));
  // o_i, free or pinned; without v, the pins' values (0 for a free offset)
  std::vector<double> off(static_cast<std::size_t>(M));
  for (int i = 0; i < M; ++i) off[static_cast<std::size_t>(i)] = v ? v->o[i] : D.pin_value(D.o(i));
  // Blocks in the chain's direction.
  const long lo = ch.lowest_station(), hi = lo + ch.steps;
  auto block = [&](long K0, int B) {
    block_rhs(D, K0, B, readings, mu.data(), angle_mm, v, off.data(), Qt_.data(), M, b.data(),
              bt.data());
    for (int l = 0; l < L; ++l) {
      const double* src = bt.data() + static_cast<std::size_t>(l * B);
      double* dst = bloc_.data() + static_cast<std::size_t>(K0) * static_cast<std::size_t>(L) +
                    static_cast<std::size_t>(l);
      for (int k = 0; k < B; ++k) dst[static_cast<std::size_t>(k * L)] = src[k];
    }
    fn(K0, B, static_cast<const double*>(bt.data()));
  };
  if (ch.dir > 0) {
    for (long K0 = lo; K0 < hi; K0 += kBlock)
      block(K0, static_cast<int>(std::min<long>(kBlock, hi - K0)));
  } else {
    for (long end = hi; end > lo;) {
      const long K0 = std::max(lo, end - kBlock);
      block(K0, static_cast<int>(end - K0));
      end = K0;
    }
  }
}

template <class Fn>
void BandedLsq::for_each_station(const Chain& ch, const Eigen::MatrixXd& readings,
                                 const Eigen::RowVectorXd& mu, const Eigen::VectorXd& angle_mm,
                                 const Unknowns* v, Fn&& fn) {
  const int L = L_;
  for_each_block(ch, readings, mu, angle_mm, v, [&](long K0, int B, const double* bt) {
    for (int i = 0; i < B; ++i) {
      const int k = ch.in_block(i, B);
      const long K = K0 + k;
      fn(ch.dir * (K - ch.first_station), K,
         [&](int r) { return bt[static_cast<std::size_t>((L + r) * B + k)]; });
    }
  });
}

}  // namespace trueaxis::separation::detail
