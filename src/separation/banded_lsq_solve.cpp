// The banded least-squares solver's second half (banded_lsq.hpp): new right-hand sides on a kept
// factorisation, the back-substitution, and the unknowns' covariances.
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <utility>

#include "../common/eigen_instances.hpp"
#include "../common/memory.hpp"
#include "banded_lsq.hpp"
#include "banded_lsq_blocks.hpp"

namespace trueaxis::separation::detail {

void BandedLsq::refactor_rhs(const Eigen::MatrixXd& readings, const Eigen::RowVectorXd& mu,
                             const Eigen::VectorXd& angle_mm, const Unknowns& v) {
  if (!keep_rotations_) {
    factor(readings, mu, angle_mm, v);
    return;
  }
  with_width(m_, [&]<int W>() { refactor_rhs_impl<W>(readings, mu, angle_mm, v); });
}

template <int Width>
void BandedLsq::refactor_rhs_impl(const Eigen::MatrixXd& readings, const Eigen::RowVectorXd& mu,
                                  const Eigen::VectorXd& angle_mm, const Unknowns& v) {
  on_chains([&](std::size_t i) {
    if (!with_narrow<Width>(
            [&]<int NB>() { refold_narrow<Width, NB>(chains_[i], readings, mu, angle_mm, &v); }))
      refold_rhs(chains_[i], readings, mu, angle_mm, &v);
  });
  join();
}

template <int Width, int NB>
void BandedLsq::refold_narrow(Chain& ch, const Eigen::MatrixXd& readings,
                              const Eigen::RowVectorXd& mu, const Eigen::VectorXd& angle_mm,
                              const Unknowns* v) {
  // refold_rhs for a window of Width columns (its mask one byte), NB of them the band's: the
  // window's right-hand sides and weights are local arrays indexed by constants, in registers
  // across a block's stations.
  constexpr int m = Width, s = Width + 1;
  static_assert(NB >= 1 && NB <= Width && Width + 1 <= 8, "one mask byte");
  constexpr double kEmpty = std::numeric_limits<double>::infinity();
  const int L = L_, nred = M_ - L_;
  const double* rot = ch.rot.data();
  const unsigned char* mask_in = ch.rot_mask.data();
  std::array<double, m> window{}, inv_d;
  inv_d.fill(kEmpty);
  for_each_block(ch, readings, mu, angle_mm, v, [&](long K0, int B, const double* bt) {
    auto w = window;  // in registers for the block
    auto e = inv_d;
    const double* rp = rot;
    const unsigned char* mp = mask_in;
    for (int i = 0; i < B; ++i) {
      const int k = ch.in_block(i, B);
      for (int r = 0; r < nred; ++r) {
        double x = bt[static_cast<std::size_t>((L + r) * B + k)], delta = 1;
        const unsigned bits = *mp++;
        const unsigned cols = bits & ((1u << m) - 1);
        // With bit m, the row ended in an empty row of the window, at its last column.
        const int placed = (bits >> m) & 1 ? 31 - std::countl_zero(cols) : m;
        unroll<m>([&](auto jc) {
          constexpr int j = decltype(jc)::value;
          if (!((cols >> j) & 1)) return;
          if (j == placed) {
            const double inv = rp[0];
            ++rp;
            w[j] = inv * x;
            e[j] = inv * inv / delta;
            return;
          }
          const double cb = rp[0], xj = rp[1], u = w[j];
          rp += kRotationValues;
          e[j] *= cb;
          const double sb = delta * xj * e[j];
          delta *= cb;
          w[j] = cb * u + sb * x;
          x -= xj * u;
        });
      }
      qb_[static_cast<std::size_t>(K0 + k)] = w[0];
      unroll<NB>([&](auto jc) {  // the slide; the globals' entries stay
        constexpr int j = decltype(jc)::value;
        if constexpr (j + 1 < NB) {
          w[j] = w[j + 1];
          e[j] = e[j + 1];
        } else {
          w[j] = 0;
          e[j] = kEmpty;
        }
      });
    }
    window = w;
    inv_d = e;
    rot = rp;
    mask_in = mp;
  });
  for (int c = 0; c < m; ++c)
    ch.W[static_cast<std::size_t>(c * s + m)] = window[static_cast<std::size_t>(c)];
}

void BandedLsq::refold_rhs(Chain& ch, const Eigen::MatrixXd& readings, const Eigen::RowVectorXd& mu,
                           const Eigen::VectorXd& angle_mm, const Unknowns* v) {
  // The same rotations applied to the new right-hand side only: the window's last column, ū's
  // right-hand side per row, by the kept rotations (c̄, x_j). s̄ = δ·x_j/d' is formed again from
  // the window's weights, which the pass follows as 1/d (1/d' = c̄/d; a placement sets
  // d = δ·x_j²), and the row's δ (δ' = c̄·δ): products only, so s̄ comes back to a few units of
  // round-off relative, where storing it cost a third of the rotations' memory. (Rebuilding c̄ as
  // 1 − s̄·x_j instead would lose ε·|ū| where the old row's ū is large and c̄ small: a row entry
  // that is zero but for rounding, placed into an empty row, has |ū| ~ 1/ε.)
  constexpr double kEmpty = std::numeric_limits<double>::infinity();
  const int m = m_, s = m + 1, nb = nb_, nred = M_ - L_;
  const double* rot = ch.rot.data();
  const unsigned char* mask_in = ch.rot_mask.data();
  std::vector<double> wr(static_cast<std::size_t>(m), 0.0), e(static_cast<std::size_t>(m), kEmpty);
  for_each_station(ch, readings, mu, angle_mm, v, [&](long, long K, auto&& reduced) {
    for (int r = 0; r < nred; ++r) {
      double x = reduced(r), delta = 1;
      auto place = [&](std::size_t j, double inv) {
        wr[j] = inv * x;
        e[j] = inv * inv / delta;
      };
      auto apply = [&](std::size_t j) {
        const double cb = rot[0], xj = rot[1], u = wr[j];
        rot += kRotationValues;
        if (xj == 0) return;   // an identity (windows without masks)
        if (e[j] == kEmpty) {  // a placement (windows without masks)
          place(j, 1 / xj);
          return;
        }
        e[j] *= cb;
        const double sb = delta * xj * e[j];
        delta *= cb;
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
          const auto j = static_cast<std::size_t>(std::countr_zero(mask));
          if (placed && (mask & (mask - 1)) == 0) {
            place(j, rot[0]);
            ++rot;
          } else {
            apply(j);
          }
        }
      } else {
        for (std::size_t j = 0; j < static_cast<std::size_t>(m); ++j) apply(j);
      }
    }
    qb_[static_cast<std::size_t>(K)] = wr[0];
    for (std::size_t t = 0; t + 1 < static_cast<std::size_t>(nb); ++t) {
      wr[t] = wr[t + 1];
      e[t] = e[t + 1];
    }
    wr[static_cast<std::size_t>(nb - 1)] = 0;
    e[static_cast<std::size_t>(nb - 1)] = kEmpty;
  });
  for (int c = 0; c < m; ++c)
    ch.W[static_cast<std::size_t>(c * s + m)] = wr[static_cast<std::size_t>(c)];
}

template <int NB>
void BandedLsq::back_substitute(const Chain& ch, const std::vector<double>& xc, const Unknowns& v,
                                bool set_free, double* mc, double* mv) const {
  const int m = m_, nb = NB > 0 ? NB : nb_, L = L_, G = G_;
  // Largest |correction| and |value| per stream (separate maxima: no chain of them per station),
  // kept here and written out at the end: the other chain's maxima share their cache line.
  double lc[3] = {0, 0, 0}, lv[3] = {0, 0, 0};
  auto add = [&](int stream, double& u, double dx) {
    const double x = set_free ? dx : u + dx;
    u = x;
    lc[stream] = std::max(lc[stream], std::abs(dx));
    lv[stream] = std::max(lv[stream], std::abs(x));
  };
  const double* xg = xc.data() + nb;  // the globals' corrections
  // The globals' share of each station's local equations is the same at every station.
  double lg[2] = {0, 0};
  for (int l = 0; l < L; ++l)
    for (int k = 0; k < G; ++k) lg[l] += ch.Cloc(l, nb + k) * xg[k];
  const double inv00 = 1 / Rloc_(0, 0), r01 = L == 2 ? Rloc_(0, 1) : 0.0,
               inv11 = L == 2 ? 1 / Rloc_(1, 1) : 0.0;
  // The workpiece corrections the back-substitution still needs, d[j] = Δw at the chain's
  // position t + j: a fixed array for a compile-time band, else a ring indexed by position
  // modulo a power of two.
  std::size_t ring_size = 1;
  while (ring_size < static_cast<std::size_t>(nb)) ring_size *= 2;
  const std::size_t mask = ring_size - 1;
  std::vector<double> ring(NB > 0 ? 0 : ring_size, 0.0);
  double d[NB > 0 ? NB : 1] = {};
  auto dw = [&](long t, int j) -> double {
    if constexpr (NB > 0)
      return d[j];
    else
      return ring[static_cast<std::size_t>(t + j) & mask];
  };
  // Start from the final window's positions past the chain's last step.
  for (int j = 1; j < nb; ++j) {
    const long col = ch.position(ch.steps + j - 1) - h_;
    const double x = col >= 0 && col < nb - 1 ? xc[static_cast<std::size_t>(col)] : 0.0;
    if constexpr (NB > 0)
      d[j] = x;
    else
      ring[static_cast<std::size_t>(ch.steps + j - 1) & mask] = x;
  }
  auto next_pin = ch.pinned.rbegin();  // the pinned positions, descending
  while (next_pin != ch.pinned.rend() && *next_pin >= ch.steps) ++next_pin;
  const double* Cl0 = ch.Cloc.data();  // column-major L × m: Cloc(l, j) at j·L + l
  for (long t = ch.steps - 1; t >= 0; --t) {
    const long K = ch.station(t);
    const double* R = rw_.data() + static_cast<std::size_t>(K) * static_cast<std::size_t>(m);
    double dwk = 0;
    const bool pinned = next_pin != ch.pinned.rend() && *next_pin == t;
    if (pinned) ++next_pin;
    if (!pinned) {
      if (R[0] != 0) {
        // The row √d·[1, ū] and its right-hand side √d·b̄: Δw = b̄ − ū·(the later unknowns), no
        // division on the back-substitution's dependency chain.
        double acc = qb_[static_cast<std::size_t>(K)];
        for (int k = 0; k < G; ++k) acc -= R[nb + k] * xg[k];
        for (int j = nb - 1; j >= 1; --j) acc -= R[j] * dw(t, j);
        dwk = acc;
      }
      add(0, v.w[ch.position(t)], dwk);
    }
    if constexpr (NB > 0)
      d[0] = dwk;
    else
      ring[static_cast<std::size_t>(t) & mask] = dwk;
    // Local equations: Rloc·[g θ] = bloc − Cloc·(window).
    const double* bl = bloc_.data() + static_cast<std::size_t>(K) * static_cast<std::size_t>(L);
    double rl[2];
    for (int l = 0; l < L; ++l) {
      double acc = bl[l] - lg[l];
      for (int j = 0; j < nb; ++j) acc -= Cl0[j * L + l] * dw(t, j);
      rl[l] = acc;
    }
    if (L == 2) {
      const double th = rl[1] * inv11;
      add(2, v.t[K], th);
      add(1, v.g[K], (rl[0] - r01 * th) * inv00);
    } else {
      add(1, v.g[K], rl[0] * inv00);
    }
    if constexpr (NB > 0)
      for (int j = NB - 1; j >= 1; --j) d[j] = d[j - 1];
  }
  for (int i = 0; i < 3; ++i) {
    mc[i] = lc[i];
    mv[i] = lv[i];
  }
}

BandedLsq::Update BandedLsq::solve_add(const Unknowns& v, bool set_free) const {
  const int m = m_, s = m_ + 1;
  // Per chain and stream, the largest |correction| and |value|; stream 3 the final window's.
  double mc[2][4] = {}, mv[2][4] = {};
  // The final window [w(h..h+span−1), none, globals] by back-substitution (inactive columns 0).
  std::vector<double> xc(static_cast<std::size_t>(m), 0.0);
  for (int c = m - 1; c >= 0; --c) {
    const int id = final_id(c);
    if (!active(id)) continue;
    const double* F = final_.data() + static_cast<std::size_t>(c * s);
    double dx = 0;
    if (F[c] != 0) {
      double acc = F[m];
      for (int k = c + 1; k < m; ++k) acc -= F[k] * xc[static_cast<std::size_t>(k)];
      dx = acc / F[c];
    }
    xc[static_cast<std::size_t>(c)] = dx;
    double& u = v(D_, id);
    u = set_free ? dx : u + dx;
    mc[0][3] = std::max(mc[0][3], std::abs(dx));
    mv[0][3] = std::max(mv[0][3], std::abs(u));
  }
  // Both chains outward at once (they write different unknowns). The band width as a
  // compile-time constant for the usual narrow bands: the corrections the back-substitution
  // still needs then stay in registers.
  with_width(nb_, [&]<int NB>() {
    on_chains(
        [&](std::size_t i) { back_substitute<NB>(chains_[i], xc, v, set_free, mc[i], mv[i]); });
  });
  Update u;
  for (int c = 0; c < 2; ++c)
    for (int i = 0; i < 4; ++i) {
      u.max_correction = std::max(u.max_correction, mc[c][i]);
      u.max_value = std::max(u.max_value, mv[c][i]);
    }
  return u;
}

std::vector<double> BandedLsq::final_covariance() const {
  // The inverse of the final window's R over its active columns, R⁻¹R⁻ᵀ.
  const int m = m_, s = m_ + 1;
  std::vector<double> Fj(static_cast<std::size_t>(m * m), 0.0);
  std::vector<int> act;
  for (int c = 0; c < m; ++c)
    if (active(final_id(c)) && final_[static_cast<std::size_t>(c * s + c)] != 0) act.push_back(c);
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
      Fj[static_cast<std::size_t>(act[static_cast<std::size_t>(a)] * m +
                                  act[static_cast<std::size_t>(b)])] = Zf(a, b);
  return Fj;
}

void BandedLsq::chain_covariance(const Chain& ch, const std::vector<double>& Fj, double* zw,
                                 double* zloc) const {
  const bool narrow = with_width(m_, [&]<int W>() {
    return with_band<W>([&]<int NB>() { chain_covariance_narrow<W, NB>(ch, Fj, zw, zloc); });
  });
  if (!narrow) chain_covariance_any(ch, Fj, zw, zloc);
}

namespace {

// (Rloc⁻¹·Cloc, diag(Rloc⁻¹Rloc⁻ᵀ)) for the local unknowns' covariance.
std::pair<Eigen::MatrixXd, Eigen::VectorXd> local_maps(const Eigen::MatrixXd& Rloc,
                                                       const Eigen::MatrixXd& Cloc) {
  const auto L = Rloc.rows();
  const Eigen::MatrixXd RlocInv =
      Rloc.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(L, L));
  return {RlocInv * Cloc, (RlocInv * RlocInv.transpose()).diagonal()};
}

}  // namespace

std::vector<double> BandedLsq::in_chain_order(const Chain& ch,
                                              const std::vector<double>& Fj) const {
  const int m = m_;
  std::vector<double> F(static_cast<std::size_t>(m * m), 0.0);
  for (int a = 0; a < m; ++a)
    if (const int ca = chain_col(ch, a); ca >= 0)
      for (int b = 0; b < m; ++b)
        if (const int cb = chain_col(ch, b); cb >= 0)
          F[static_cast<std::size_t>(ca * m + cb)] = Fj[static_cast<std::size_t>(a * m + b)];
  return F;
}

void BandedLsq::chain_covariance_any(const Chain& ch, const std::vector<double>& Fj, double* zw,
                                     double* zloc) const {
  // For the eliminated w's row [d, r] over the window [the next span positions, globals] with
  // covariance Z: Z_w,window = −(Z rᵀ)/d and Z_ww = 1/d² − r·Z_w,window/d. The local unknowns
  // x_loc = Rloc⁻¹(b − Cloc·window) then have Rloc⁻¹Rloc⁻ᵀ + P·F·Pᵀ, P = Rloc⁻¹Cloc, with F the
  // covariance over the full window [w(t..t+span), globals].
  const Design& D = D_;
  const int m = m_, nb = nb_, L = L_, mw = m - 1;
  // The final window's covariance in the chain's column order.
  std::vector<double> F = in_chain_order(ch, Fj), Z(F.size(), 0.0),
                      zk(static_cast<std::size_t>(m), 0.0);
  auto f = [&](int a, int b) -> double& { return F[static_cast<std::size_t>(a * m + b)]; };
  auto z = [&](int a, int b) -> double& { return Z[static_cast<std::size_t>(a * mw + b)]; };
  const auto [P, S] = local_maps(Rloc_, ch.Cloc);
  // Z: covariance over [the next span positions, globals] (size m − 1): F without its band
  // column span.
  auto drop_last_band = [&] {
    for (int a = 0; a < mw; ++a)
      for (int b = 0; b < mw; ++b) z(a, b) = f(skip_band_end(a, nb), skip_band_end(b, nb));
  };
  drop_last_band();
  for (long t = ch.steps - 1; t >= 0; --t) {
    const long K = ch.station(t);
    const int idw = D.w(ch.position(t));
    const double* R = rw_.data() + static_cast<std::size_t>(K) * static_cast<std::size_t>(m);
    double zkk = 0;
    if (!D.pinned[static_cast<std::size_t>(idw)] && R[0] != 0) {
      // The row is √d·[1, ū] (stored as √d, ū): Z_w,window = −Z ū, Z_ww = 1/d − ū·Z_w,window.
      double rz = 0;
      for (int a = 0; a < mw; ++a) {
        double v = 0;
        for (int b = 0; b < mw; ++b) v += z(a, b) * R[b + 1];
        zk[static_cast<std::size_t>(a)] = -v;
        rz += R[a + 1] * zk[static_cast<std::size_t>(a)];
      }
      const double inv = 1 / R[0];
      zkk = inv * inv - rz;
    } else {
      std::fill(zk.begin(), zk.end(), 0.0);
    }
    zw[K] = zkk;
    f(0, 0) = zkk;
    for (int a = 0; a < mw; ++a) {
      f(0, a + 1) = f(a + 1, 0) = zk[static_cast<std::size_t>(a)];
      for (int b = 0; b < mw; ++b) f(a + 1, b + 1) = z(a, b);
    }
    for (int l = 0; l < L; ++l) {
      double v = S[l];
      for (int a = 0; a < m; ++a) {
        double tt = 0;
        for (int b = 0; b < m; ++b) tt += f(a, b) * P(l, b);
        v += P(l, a) * tt;
      }
      zloc[K * L + l] = v;
    }
    drop_last_band();
  }
}

template <int W, int NB>
void BandedLsq::chain_covariance_narrow(const Chain& ch, const std::vector<double>& Fj, double* zw,
                                        double* zloc) const {
  constexpr int MW = W - 1;
  constexpr auto from_f = [](int i) { return skip_band_end(i, NB); };
  const Design& D = D_;
  const int L = L_;
  const std::vector<double> F0 = in_chain_order(ch, Fj);
  using Row = std::array<double, MW>;
  std::array<Row, MW> Z;
  for (int a = 0; a < MW; ++a)
    for (int b = 0; b < MW; ++b)
      Z[static_cast<std::size_t>(a)][static_cast<std::size_t>(b)] =
          F0[static_cast<std::size_t>(from_f(a) * W + from_f(b))];
  const auto [Pm, Sv] = local_maps(Rloc_, ch.Cloc);
  std::array<std::array<double, W>, 2> P{};
  const double S[2] = {Sv[0], L == 2 ? Sv[1] : 0.0};
  for (int l = 0; l < L; ++l)
    for (int a = 0; a < W; ++a)
      P[static_cast<std::size_t>(l)][static_cast<std::size_t>(a)] = Pm(l, a);
  for (long t = ch.steps - 1; t >= 0; --t) {
    const long K = ch.station(t);
    const int idw = D.w(ch.position(t));
    const double* R = rw_.data() + static_cast<std::size_t>(K) * static_cast<std::size_t>(W);
    double zkk = 0;
    Row zk{};
    if (!D.pinned[static_cast<std::size_t>(idw)] && R[0] != 0) {
      double rz = 0;
      unroll<MW>([&](auto a) {
        double v = 0;
        unroll<MW>([&](auto b) { v += Z[a][b] * R[b + 1]; });
        zk[a] = -v;
        rz += R[a + 1] * zk[a];
      });
      const double inv = 1 / R[0];
      zkk = inv * inv - rz;
    }
    zw[K] = zkk;
    // F over [w(t), the window]: [[Z_ww, Z_w,windowᵀ], [Z_w,window, Z]].
    auto f = [&](auto a, auto b) {
      constexpr int ia = decltype(a)::value, ib = decltype(b)::value;
      if constexpr (ia == 0 && ib == 0)
        return zkk;
      else if constexpr (ia == 0)
        return zk[ib - 1];
      else if constexpr (ib == 0)
        return zk[ia - 1];
      else
        return Z[ia - 1][ib - 1];
    };
    for (int l = 0; l < L; ++l) {
      const auto& pl = P[static_cast<std::size_t>(l)];
      double v = S[l];
      unroll<W>([&](auto a) {
        double tt = 0;
        unroll<W>([&](auto b) { tt += f(a, b) * pl[b]; });
        v += pl[a] * tt;
      });
      zloc[K * L + l] = v;
    }
    std::array<Row, MW> next;
    unroll<MW>([&](auto a) {
      unroll<MW>([&](auto b) {
        next[a][b] = f(std::integral_constant<int, from_f(decltype(a)::value)>{},
                       std::integral_constant<int, from_f(decltype(b)::value)>{});
      });
    });
    Z = next;
  }
}

}  // namespace trueaxis::separation::detail
