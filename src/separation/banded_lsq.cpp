#include "banded_lsq.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <optional>

#include "../common/eigen_instances.hpp"
#include "../common/memory.hpp"

// GCC's vectoriser pairs loads in the Givens fold that clang leaves alone (clang has no such
// attribute).
#if defined(__clang__)
#define TA_NO_VECTORIZE
#else
#define TA_NO_VECTORIZE __attribute__((optimize("no-tree-vectorize")))
#endif

namespace trueaxis::separation::detail {

BandedLsq::BandedLsq(const Design& design) : D_(design) {
  const Design& D = D_;
  L_ = D.pitch ? 2 : 1;
  M_ = D.N + (D.angle ? 1 : 0);
  nb_ = static_cast<int>(D.span) + 1;
  for (int i = 0; i < M_; ++i)
    if (!D.pinned[static_cast<std::size_t>(D.o(i))]) globals_.push_back(D.o(i));
  G_ = static_cast<int>(globals_.size());
  m_ = nb_ + G_;
  auto global_col = [&](int id) {
    const auto it = std::find(globals_.begin(), globals_.end(), id);
    return it == globals_.end() ? -1 : nb_ + static_cast<int>(it - globals_.begin());
  };
  // One station's rows over [g, θ] and over the window [w(K..K+span), globals].
  Eigen::MatrixXd Aloc = Eigen::MatrixXd::Zero(M_, L_), Awin = Eigen::MatrixXd::Zero(M_, m_);
  for (int i = 0; i < D.N; ++i) {
    Aloc(i, 0) = 1;
    if (D.pitch) Aloc(i, 1) = static_cast<double>(D.p[static_cast<std::size_t>(i)]);
    Awin(i, D.q[static_cast<std::size_t>(i)]) = 1;
    if (const int c = global_col(D.o(i)); c >= 0) Awin(i, c) = 1;
  }
  if (D.angle) {
    Aloc(D.N, 1) = D.wa;
    if (const int c = global_col(D.oa()); c >= 0) Awin(D.N, c) = D.wa;
  }
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(Aloc);
  Qt_ = Eigen::MatrixXd(qr.householderQ()).transpose();  // row-major: read row by row below
  Rloc_ = (Qt_ * Aloc).topRows(L_).triangularView<Eigen::Upper>();
  const Eigen::MatrixXd T = Qt_ * Awin;
  Cloc_ = T.topRows(L_);
  Cred_ = T.bottomRows(M_ - L_);
  scale_ = std::max({1.0, Aloc.cwiseAbs().maxCoeff(), Awin.cwiseAbs().maxCoeff()});
  for (long j = 0; j < D.Q; ++j)
    if (D.pinned[static_cast<std::size_t>(D.w(j))]) pinned_w_.push_back(j);
  rows_ = D.n * M_;
  unknowns_ = static_cast<long>(std::count(D.pinned.begin(), D.pinned.end(), 0));
}

int BandedLsq::id_of(long K, int c) const {
  if (c >= nb_) return globals_[static_cast<std::size_t>(c - nb_)];
  return K + c < D_.Q ? D_.w(K + c) : -1;
}

bool BandedLsq::active(int id) const {
  return id >= 0 && !D_.pinned[static_cast<std::size_t>(id)];
}

namespace {

constexpr int kBlock = 256;  // stations whose right-hand sides are formed together

// Right-hand sides b − A·v of stations [K0, K0 + B), transformed by the constant Qᵀ (row-major
// qt): bt[r·B + k] is row r (the L local ones first) of station K0 + k. Formed channel by channel
// over the block, contiguous in the station, so the loops vectorise; b is scratch of M·B.
void block_rhs(const Design& D, long K0, int B, const Eigen::MatrixXd& readings, const double* mu,
               const Eigen::VectorXd& angle_mm, const Eigen::VectorXd& v, const double* off,
               const double* qt, int M, double* b, double* bt) {
  const double* g = v.data() + D.g(K0);
  const double* t = D.pitch ? v.data() + D.t(K0) : nullptr;
  for (int i = 0; i < D.N; ++i) {
    const double* rd = readings.col(i).data() + K0;
    const double* w = v.data() + D.w(K0 + D.q[static_cast<std::size_t>(i)]);
    const double mi = mu[i], oi = off[i];
    const double pi = static_cast<double>(D.p[static_cast<std::size_t>(i)]);
    double* bi = b + static_cast<std::ptrdiff_t>(i) * B;
    if (t)
      for (int k = 0; k < B; ++k) bi[k] = rd[k] - mi - w[k] - g[k] - pi * t[k] - oi;
    else
      for (int k = 0; k < B; ++k) bi[k] = rd[k] - mi - w[k] - g[k] - oi;
  }
  if (D.angle) {
    const double* an = angle_mm.data() + K0;
    const double oa = off[D.N], wa = D.wa;
    double* bi = b + static_cast<std::ptrdiff_t>(D.N) * B;
    for (int k = 0; k < B; ++k) bi[k] = wa * (an[k] - t[k] - oa);
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

}  // namespace

template <class Fn>
void BandedLsq::for_each_station(const Eigen::MatrixXd& readings, const Eigen::RowVectorXd& mu,
                                 const Eigen::VectorXd& angle_mm, const Eigen::VectorXd& v,
                                 Fn&& fn) {
  const Design& D = D_;
  const int L = L_, M = M_;
  std::vector<double> b(static_cast<std::size_t>(M * kBlock)),
      bt(static_cast<std::size_t>(M * kBlock));
  std::vector<double> off(static_cast<std::size_t>(M));  // o_i, free or pinned
  for (int i = 0; i < M; ++i) off[static_cast<std::size_t>(i)] = v[D.o(i)];
  for (long K0 = 0; K0 < D.n; K0 += kBlock) {
    const int B = static_cast<int>(std::min<long>(kBlock, D.n - K0));
    block_rhs(D, K0, B, readings, mu.data(), angle_mm, v, off.data(), Qt_.data(), M, b.data(),
              bt.data());
    for (int k = 0; k < B; ++k) {
      const long K = K0 + k;
      double* bl = bloc_.data() + static_cast<std::size_t>(K) * static_cast<std::size_t>(L);
      for (int l = 0; l < L; ++l) bl[l] = bt[static_cast<std::size_t>(l * B + k)];
      fn(K, [&](int r) { return bt[static_cast<std::size_t>((L + r) * B + k)]; });
    }
  }
}

void BandedLsq::factor(const Eigen::MatrixXd& readings, const Eigen::RowVectorXd& mu,
                       const Eigen::VectorXd& angle_mm, const Eigen::VectorXd& v) {
  // The window width as a compile-time constant for the usual narrow windows, so the per-station
  // loops unroll and the window's small copies are moves, not library calls.
  with_width(m_, [&]<int W>() { factor_impl<W>(readings, mu, angle_mm, v); });
}

template <int Width>
void BandedLsq::factor_impl(const Eigen::MatrixXd& readings, const Eigen::RowVectorXd& mu,
                            const Eigen::VectorXd& angle_mm, const Eigen::VectorXd& v) {
  const Design& D = D_;
  const long n = D.n;
  const int m = Width > 0 ? Width : m_, s = m + 1, nb = nb_, L = L_, nred = M_ - L_;
  rw_.resize(static_cast<std::size_t>(n) * static_cast<std::size_t>(m));
  qb_.resize(static_cast<std::size_t>(n));
  bloc_.resize(static_cast<std::size_t>(n) * static_cast<std::size_t>(L));
  // The rotations depend on the coefficients only, so later right-hand sides can reuse them
  // (iterative refinement) if they fit in a modest amount of memory. Only those that change
  // something are stored, with a mask of their columns per reduced row when the window is narrow
  // enough (most are identities where the row is already zero): the buffer is reserved for all,
  // but memory is only committed where written.
  // The mask's bit m flags a row that ended in an empty row of the window: that placement is
  // kept as one number, 1/x_j (the empty row's right-hand side is 0 on every pass, so the
  // rotation reduces to ū_j = x/x_j).
  masked_ = m <= 63;
  mask_bytes_ = (m + 8) / 8;  // the mask's low bytes: one for windows up to 7 columns
  const std::size_t per_station = static_cast<std::size_t>(kRotationValues * m * nred);
  keep_rotations_ =
      per_station * static_cast<std::size_t>(n) * sizeof(double) <= kRotationBudgetBytes;
  rot_.resize(keep_rotations_ ? per_station * static_cast<std::size_t>(n) : 0);
  rot_mask_.resize(keep_rotations_ && masked_
                       ? static_cast<std::size_t>(n * nred) * static_cast<std::size_t>(mask_bytes_)
                       : 0);
  unsigned char* mask_out = rot_mask_.data();
  double* rot = rot_.data();
  static_assert(kRotationValues == 3);
  auto keep_identity = [&rot] {  // (c̄, s̄, x_j) of a rotation that changes nothing
    rot[0] = 1;
    rot[1] = 0;
    rot[2] = 0;
    rot += kRotationValues;
  };
  std::vector<double> W(static_cast<std::size_t>(m * s), 0.0);
  std::vector<double> row(static_cast<std::size_t>(s));
  ssr_ = 0;
  min_pivot_ = 1;
  std::size_t next_pin = 0;  // first pinned position not below K
  // After the first block, when the rotations kept per station are known, the pages the rest of
  // the factorisation will write are committed on another core.
  std::optional<Prefault> prefault;
  auto start_prefault = [&] {
    const auto used = static_cast<std::size_t>(rot - rot_.data());
    const std::size_t expect = std::min(
        rot_.size(), used / static_cast<std::size_t>(kBlock) * static_cast<std::size_t>(n) * 9 / 8);
    prefault.emplace(
        std::vector<Prefault::Region>{{rw_.data(), rw_.size() * sizeof(double)},
                                      {qb_.data(), qb_.size() * sizeof(double)},
                                      {bloc_.data(), bloc_.size() * sizeof(double)},
                                      {rot, (expect > used ? expect - used : 0) * sizeof(double)},
                                      {rot_mask_.data(), rot_mask_.size()}});
  };
  // The fold is not vectorised: each rotation's row and window updates are read back by the next
  // one, and paired loads of values stored one at a time stall on store forwarding.
  for_each_station(readings, mu, angle_mm, v, [&](long K, auto&& reduced) TA_NO_VECTORIZE {
    if (K == kBlock) start_prefault();
    while (next_pin < pinned_w_.size() && pinned_w_[next_pin] < K) ++next_pin;
    const bool pin_in_band = next_pin < pinned_w_.size() && pinned_w_[next_pin] <= K + nb - 1;
    for (int r = 0; r < nred; ++r) {
      // A reduced row: fold it into the window by square-root-free Givens rotations.
      std::uint64_t mask = 0;
      const double* cr = Cred_.data() + static_cast<std::size_t>(r * m);
      for (int c = 0; c < m; ++c) row[static_cast<std::size_t>(c)] = cr[c];
      row[static_cast<std::size_t>(m)] = reduced(r);
      if (pin_in_band)
        for (std::size_t i = next_pin; i < pinned_w_.size() && pinned_w_[i] <= K + nb - 1; ++i)
          row[static_cast<std::size_t>(pinned_w_[i] - K)] = 0;
      double delta = 1;  // the row's weight
      int j = 0;
      for (; j < m; ++j) {
        const double xi = row[static_cast<std::size_t>(j)];
        if (xi == 0) {
          if (keep_rotations_ && !masked_) keep_identity();
          continue;
        }
        double* Wj = W.data() + static_cast<std::size_t>(j * s);
        const double d = Wj[j];
        if (d == 0) {
          // An empty row of the window: the row takes its place, and nothing of it is left.
          const double inv = 1 / xi;
          Wj[j] = delta * xi * xi;
          for (int c = j + 1; c <= m; ++c) Wj[c] = row[static_cast<std::size_t>(c)] * inv;
          if (keep_rotations_ && masked_) {
            *rot++ = inv;
            mask |= (std::uint64_t{1} << j) | (std::uint64_t{1} << m);
          } else if (keep_rotations_) {
            *rot++ = 0;
            *rot++ = inv;
            *rot++ = xi;
          }
          delta = 0;
          ++j;
          break;
        }
        const double dp = d + delta * xi * xi;
        const double inv = 1 / dp;
        const double cb = d * inv, sb = delta * xi * inv;
        delta *= cb;
        Wj[j] = dp;
        for (int c = j + 1; c <= m; ++c) {
          const double u = Wj[c], x = row[static_cast<std::size_t>(c)];
          row[static_cast<std::size_t>(c)] = x - xi * u;
          Wj[c] = cb * u + sb * x;
        }
        if (keep_rotations_) {
          *rot++ = cb;
          *rot++ = sb;
          *rot++ = xi;
          if (masked_) mask |= std::uint64_t{1} << j;
        }
      }
      if (keep_rotations_ && !masked_)
        for (; j < m; ++j) keep_identity();  // after the row found an empty place
      if (keep_rotations_ && masked_)
        for (int i = 0; i < mask_bytes_; ++i)
          *mask_out++ = static_cast<unsigned char>(mask >> (8 * i));
      ssr_ += delta * row[static_cast<std::size_t>(m)] * row[static_cast<std::size_t>(m)];
    }
    // No later row touches w(K): its row of R, √d·[1, ū], leaves the window (stored as √d and
    // ū), which slides by one position.
    double* out = rw_.data() + static_cast<std::size_t>(K) * static_cast<std::size_t>(m);
    const double r0 = std::sqrt(W[0]);
    out[0] = r0;
    for (int c = 1; c < m; ++c) out[c] = W[static_cast<std::size_t>(c)];
    qb_[static_cast<std::size_t>(K)] = W[static_cast<std::size_t>(m)];
    if (!D.pinned[static_cast<std::size_t>(D.w(K))]) min_pivot_ = std::min(min_pivot_, r0 / scale_);
    for (int t = 0; t < m; ++t) {
      double* dst = W.data() + static_cast<std::size_t>(t * s);
      if (t == nb - 1) {
        for (int c = 0; c < s; ++c) dst[c] = 0;
        continue;
      }
      const double* src = t < nb - 1 ? dst + s : dst;
      for (int c = 0; c + 1 < nb; ++c) dst[c] = src[c + 1];
      dst[nb - 1] = 0;
      if (src != dst)
        for (int c = nb; c < s; ++c) dst[c] = src[c];
    }
  });
  // The final window in the same form: row c is √d_c·[0…0, 1, ū_c].
  final_.assign(W.size(), 0.0);
  for (int c = 0; c < m; ++c) {
    const double* Wc = W.data() + static_cast<std::size_t>(c * s);
    double* Fc = final_.data() + static_cast<std::size_t>(c * s);
    const double rc = std::sqrt(Wc[c]);
    Fc[c] = rc;
    for (int i = c + 1; i < s; ++i) Fc[i] = rc * Wc[i];
  }
  for (int c = 0; c < m; ++c)
    if (active(id_of(n, c)))
      min_pivot_ =
          std::min(min_pivot_, std::abs(final_[static_cast<std::size_t>(c * s + c)]) / scale_);
}

void BandedLsq::refactor_rhs(const Eigen::MatrixXd& readings, const Eigen::RowVectorXd& mu,
                             const Eigen::VectorXd& angle_mm, const Eigen::VectorXd& v) {
  if (!keep_rotations_) {
    factor(readings, mu, angle_mm, v);
    return;
  }
  with_width(m_, [&]<int W>() { refactor_rhs_impl<W>(readings, mu, angle_mm, v); });
}

template <int Width>
void BandedLsq::refactor_rhs_impl(const Eigen::MatrixXd& readings, const Eigen::RowVectorXd& mu,
                                  const Eigen::VectorXd& angle_mm, const Eigen::VectorXd& v) {
  // The same rotations applied to the new right-hand side only: the window's last column, ū's
  // right-hand side per row, by the kept rotations (c̄, s̄, x_j). (Rebuilding c̄ as 1 − s̄·x_j would
  // keep one number fewer but loses ε·|ū| where the old row's ū is large and c̄ small: a row entry
  // that is zero but for rounding, placed into an empty row, has |ū| ~ 1/ε.)
  const int m = Width > 0 ? Width : m_, s = m + 1, nb = nb_, nred = M_ - L_;
  std::vector<double> wr_heap(Width > 0 ? 0 : static_cast<std::size_t>(m), 0.0);
  double wr_fixed[Width > 0 ? Width : 1] = {};
  double* wr = Width > 0 ? wr_fixed : wr_heap.data();
  const double* rot = rot_.data();
  const unsigned char* mask_in = rot_mask_.data();
  for_each_station(readings, mu, angle_mm, v, [&](long K, auto&& reduced) {
    for (int r = 0; r < nred; ++r) {
      double x = reduced(r);
      auto apply = [&](int j) {
        const double cb = rot[0], sb = rot[1], xj = rot[2];
        rot += kRotationValues;
        const double u = wr[j];
        wr[j] = cb * u + sb * x;
        x -= xj * u;
      };
      if (masked_) {
        std::uint64_t mask = 0;
        for (int i = 0; i < mask_bytes_; ++i)
          mask |= static_cast<std::uint64_t>(*mask_in++) << (8 * i);
        const bool placed = (mask >> m) & 1;  // the last one placed the row into an empty row
        mask &= (std::uint64_t{1} << m) - 1;
        for (; mask != 0; mask &= mask - 1) {
          const int j = std::countr_zero(mask);
          if (placed && (mask & (mask - 1)) == 0) {
            wr[j] = rot[0] * x;
            ++rot;
          } else {
            apply(j);
          }
        }
      } else {
        for (int j = 0; j < m; ++j) apply(j);
      }
    }
    qb_[static_cast<std::size_t>(K)] = wr[0];
    for (int t = 0; t + 1 < nb; ++t) wr[t] = wr[t + 1];
    wr[nb - 1] = 0;
  });
  for (int c = 0; c < m; ++c)
    final_[static_cast<std::size_t>(c * s + m)] =
        final_[static_cast<std::size_t>(c * s + c)] * wr[c];
}

template <int NB>
BandedLsq::Update BandedLsq::solve_add_impl(Eigen::VectorXd& v) const {
  const Design& D = D_;
  const int m = m_, s = m_ + 1, nb = NB > 0 ? NB : nb_, L = L_, G = G_;
  // Largest |correction| and |value| per stream (separate maxima: no chain of them per station).
  double mc[4] = {0, 0, 0, 0}, mv[4] = {0, 0, 0, 0};
  auto add = [&](int stream, int id, double dx) {
    const double x = v[id] + dx;
    v[id] = x;
    mc[stream] = std::max(mc[stream], std::abs(dx));
    mv[stream] = std::max(mv[stream], std::abs(x));
  };
  // The final window [w(n..n+span), globals] by back-substitution (inactive columns 0).
  std::vector<double> xc(static_cast<std::size_t>(m), 0.0);
  for (int c = m - 1; c >= 0; --c) {
    const int id = id_of(D.n, c);
    const double* F = final_.data() + static_cast<std::size_t>(c * s);
    if (!active(id) || F[c] == 0) continue;
    double acc = F[m];
    for (int k = c + 1; k < m; ++k) acc -= F[k] * xc[static_cast<std::size_t>(k)];
    xc[static_cast<std::size_t>(c)] = acc / F[c];
    add(3, id, xc[static_cast<std::size_t>(c)]);
  }
  const double* xg = xc.data() + nb;  // the globals' corrections
  // The globals' share of each station's local equations is the same at every station.
  double lg[2] = {0, 0};
  for (int l = 0; l < L; ++l)
    for (int k = 0; k < G; ++k) lg[l] += Cloc_(l, nb + k) * xg[k];
  const double inv00 = 1 / Rloc_(0, 0), r01 = L == 2 ? Rloc_(0, 1) : 0.0,
               inv11 = L == 2 ? 1 / Rloc_(1, 1) : 0.0;
  // The workpiece corrections the back-substitution still needs, d[j] = Δw(K + j): a fixed
  // array for a compile-time band, else a ring indexed by position modulo a power of two.
  std::size_t ring_size = 1;
  while (ring_size < static_cast<std::size_t>(nb)) ring_size *= 2;
  const std::size_t mask = ring_size - 1;
  std::vector<double> ring(NB > 0 ? 0 : ring_size, 0.0);
  double d[NB > 0 ? NB : 1] = {};
  auto dw = [&](long K, int j) -> double {
    if constexpr (NB > 0)
      return d[j];
    else
      return ring[static_cast<std::size_t>(K + j) & mask];
  };
  for (int c = 0; c < nb; ++c) {
    if constexpr (NB > 0) {
      if (c + 1 < nb) d[c + 1] = xc[static_cast<std::size_t>(c)];
    } else {
      ring[static_cast<std::size_t>(D.n + c) & mask] = xc[static_cast<std::size_t>(c)];
    }
  }
  auto next_pin = pinned_w_.rbegin();  // the pinned positions, descending
  while (next_pin != pinned_w_.rend() && *next_pin >= D.n) ++next_pin;
  const double* Cl0 = Cloc_.data();  // column-major L × m: Cloc(l, j) at j·L + l
  for (long K = D.n - 1; K >= 0; --K) {
    const double* R = rw_.data() + static_cast<std::size_t>(K) * static_cast<std::size_t>(m);
    double dwk = 0;
    const bool pinned = next_pin != pinned_w_.rend() && *next_pin == K;
    if (pinned) ++next_pin;
    if (!pinned && R[0] != 0) {
      // The row √d·[1, ū] and its right-hand side √d·b̄: Δw(K) = b̄ − ū·(the later unknowns), no
      // division on the back-substitution's dependency chain.
      double acc = qb_[static_cast<std::size_t>(K)];
      for (int k = 0; k < G; ++k) acc -= R[nb + k] * xg[k];
      for (int j = nb - 1; j >= 1; --j) acc -= R[j] * dw(K, j);
      dwk = acc;
      add(0, D.w(K), dwk);
    }
    if constexpr (NB > 0)
      d[0] = dwk;
    else
      ring[static_cast<std::size_t>(K) & mask] = dwk;
    // Local equations: Rloc·[g θ] = bloc − Cloc·(window).
    const double* bl = bloc_.data() + static_cast<std::size_t>(K) * static_cast<std::size_t>(L);
    double rl[2];
    for (int l = 0; l < L; ++l) {
      double acc = bl[l] - lg[l];
      for (int j = 0; j < nb; ++j) acc -= Cl0[j * L + l] * dw(K, j);
      rl[l] = acc;
    }
    if (L == 2) {
      const double th = rl[1] * inv11;
      add(2, D.t(K), th);
      add(1, D.g(K), (rl[0] - r01 * th) * inv00);
    } else {
      add(1, D.g(K), rl[0] * inv00);
    }
    if constexpr (NB > 0)
      for (int j = NB - 1; j >= 1; --j) d[j] = d[j - 1];
  }
  Update u;
  for (int i = 0; i < 4; ++i) {
    u.max_correction = std::max(u.max_correction, mc[i]);
    u.max_value = std::max(u.max_value, mv[i]);
  }
  return u;
}

BandedLsq::Update BandedLsq::solve_add(Eigen::VectorXd& v) const {
  // The band width as a compile-time constant for the usual narrow bands: the corrections the
  // back-substitution still needs then stay in registers.
  return with_width(nb_, [&]<int W>() { return solve_add_impl<W>(v); });
}

Uninitialized<double> BandedLsq::covariance_diagonal() const {
  // Backward selected inversion. For w(K)'s row [d, r] over the window [w(K+1..K+span),
  // globals] with covariance Z: Z_K,window = −(Z rᵀ)/d and Z_KK = 1/d² − r·Z_K,window/d. The local
  // unknowns x_loc = Rloc⁻¹(b − Cloc·window) then have Rloc⁻¹Rloc⁻ᵀ + P·F·Pᵀ, P = Rloc⁻¹Cloc,
  // with F the covariance over the full window [w(K..K+span), globals].
  const Design& D = D_;
  const int m = m_, s = m_ + 1, nb = nb_, L = L_;
  Uninitialized<double> diag(static_cast<std::size_t>(D.nvars), 0.0);
  std::vector<double> F(static_cast<std::size_t>(m * m), 0.0);
  auto f = [&](int a, int b) -> double& { return F[static_cast<std::size_t>(a * m + b)]; };
  {
    // The final window's covariance (inactive columns 0).
    std::vector<int> act;
    for (int c = 0; c < m; ++c)
      if (active(id_of(D.n, c)) && final_[static_cast<std::size_t>(c * s + c)] != 0)
        act.push_back(c);
    const int na = static_cast<int>(act.size());
    Eigen::MatrixXd Rf = Eigen::MatrixXd::Zero(na, na);
    for (int a = 0; a < na; ++a)
      for (int b = a; b < na; ++b)
        Rf(a, b) = final_[static_cast<std::size_t>(act[static_cast<std::size_t>(a)] * s +
                                                   act[static_cast<std::size_t>(b)])];
    const Eigen::MatrixXd Ri =
        Rf.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(na, na));
    const Eigen::MatrixXd Zf = Ri * Ri.transpose();
    for (int a = 0; a < na; ++a)
      for (int b = 0; b < na; ++b)
        f(act[static_cast<std::size_t>(a)], act[static_cast<std::size_t>(b)]) = Zf(a, b);
    for (int c = 0; c < m; ++c)
      if (const int id = id_of(D.n, c); id >= 0) diag[static_cast<std::size_t>(id)] = f(c, c);
  }
  const Eigen::MatrixXd RlocInv =
      Rloc_.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(L, L));
  const Eigen::MatrixXd P = RlocInv * Cloc_;
  const Eigen::VectorXd S = (RlocInv * RlocInv.transpose()).diagonal();
  // Z: covariance over [w(K+1..K+span), globals] (size m − 1): F without its band column span.
  const int mw = m - 1;
  std::vector<double> Z(static_cast<std::size_t>(mw * mw)), zk(static_cast<std::size_t>(mw)),
      pf(static_cast<std::size_t>(m));
  auto drop_last_band = [&] {
    for (int a = 0, ia = 0; a < m; ++a) {
      if (a == nb - 1) continue;
      for (int b = 0, ib = 0; b < m; ++b) {
        if (b == nb - 1) continue;
        Z[static_cast<std::size_t>(ia * mw + ib++)] = f(a, b);
      }
      ++ia;
    }
  };
  drop_last_band();
  for (long K = D.n - 1; K >= 0; --K) {
    const double* R = rw_.data() + static_cast<std::size_t>(K) * static_cast<std::size_t>(m);
    double zkk = 0;
    if (!D.pinned[static_cast<std::size_t>(D.w(K))] && R[0] != 0) {
      // The row is √d·[1, ū] (stored as √d, ū): Z_K,window = −Z ū, Z_KK = 1/d − ū·Z_K,window.
      double rz = 0;
      for (int a = 0; a < mw; ++a) {
        double v = 0;
        for (int b = 0; b < mw; ++b) v += Z[static_cast<std::size_t>(a * mw + b)] * R[b + 1];
        zk[static_cast<std::size_t>(a)] = -v;
        rz += R[a + 1] * zk[static_cast<std::size_t>(a)];
      }
      const double inv = 1 / R[0];
      zkk = inv * inv - rz;
    } else {
      std::fill(zk.begin(), zk.end(), 0.0);
    }
    diag[static_cast<std::size_t>(D.w(K))] = zkk;
    f(0, 0) = zkk;
    for (int a = 0; a < mw; ++a) {
      f(0, a + 1) = f(a + 1, 0) = zk[static_cast<std::size_t>(a)];
      for (int b = 0; b < mw; ++b) f(a + 1, b + 1) = Z[static_cast<std::size_t>(a * mw + b)];
    }
    for (int l = 0; l < L; ++l) {
      double v = S[l];
      for (int a = 0; a < m; ++a) {
        double t = 0;
        for (int b = 0; b < m; ++b) t += f(a, b) * P(l, b);
        v += P(l, a) * t;
      }
      diag[static_cast<std::size_t>(l == 0 ? D.g(K) : D.t(K))] = v;
    }
    drop_last_band();
  }
  return diag;
}

}  // namespace trueaxis::separation::detail
