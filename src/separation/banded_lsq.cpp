#include "banded_lsq.hpp"

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

// GCC's vectoriser pairs loads in the Givens fold that clang leaves alone (clang has no such
// attribute).
#if defined(__clang__)
#define TA_NO_VECTORIZE
#else
#define TA_NO_VECTORIZE __attribute__((optimize("no-tree-vectorize")))
#endif

namespace trueaxis::separation::detail {

BandedLsq::BandedLsq(const Design& design, long split_stations) : D_(design) {
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
  scale_ = std::max({1.0, Aloc.cwiseAbs().maxCoeff(), Awin.cwiseAbs().maxCoeff()});
  for (const auto& pin : D.pins)  // a few: not a pass over all Q positions
    if (const auto at = D.place(pin.first); at.kind == Design::Kind::w) pinned_w_.push_back(at.i);
  std::sort(pinned_w_.begin(), pinned_w_.end());
  rows_ = D.n * M_;
  unknowns_ = D.nvars - static_cast<long>(D.pins.size());

  // The chains. The mirrored one's window column c holds the station's band column span − c.
  auto make_chain = [&](long first_station, long first_pos, long steps, int dir) {
    Chain ch;
    ch.first_station = first_station;
    ch.first_pos = first_pos;
    ch.steps = steps;
    ch.dir = dir;
    Eigen::MatrixXd Tc = T;
    if (dir < 0)
      for (int c = 0; c < nb_; ++c) Tc.col(c) = T.col(nb_ - 1 - c);
    ch.Cloc = Tc.topRows(L_);
    ch.Cred = Tc.bottomRows(M_ - L_);
    for (const long pos : pinned_w_) ch.pinned.push_back(dir * (pos - first_pos));
    std::sort(ch.pinned.begin(), ch.pinned.end());
    return ch;
  };
  const long n = D.n;
  const bool two = n >= split_stations && n / 2 > nb_ && n - n / 2 > nb_;
  h_ = two ? n / 2 : n;
  chains_.push_back(make_chain(0, 0, h_, 1));
  if (two) chains_.push_back(make_chain(n - 1, D.Q - 1, n - h_, -1));
}

int BandedLsq::final_id(int c) const {
  if (c >= nb_) return globals_[static_cast<std::size_t>(c - nb_)];
  if (c == nb_ - 1) return -1;  // the position past the chains' windows
  return h_ + c < D_.Q ? D_.w(h_ + c) : -1;
}

int BandedLsq::chain_col(const Chain& ch, int c) const {
  if (c >= nb_) return c;
  const int id = final_id(c);
  if (id < 0) return -1;
  const long cc = ch.dir * (id - D_.w(0) - ch.first_pos) - ch.steps;
  return cc >= 0 && cc < nb_ ? static_cast<int>(cc) : -1;
}

bool BandedLsq::active(int id) const {
  return id >= 0 && !D_.pinned[static_cast<std::size_t>(id)];
}

namespace {

constexpr int kBlock = 256;  // stations whose right-hand sides are formed together

// Right-hand sides b − A·v of stations [K0, K0 + B), transformed by the constant Qᵀ (row-major
// qt): bt[r·B + k] is row r (the L local ones first) of station K0 + k. Formed channel by channel
// over the block, contiguous in the station, so the loops vectorise; b is scratch of M·B. Without
// v, its profiles are 0 (only the offsets `off` count).
void block_rhs(const Design& D, long K0, int B, const Eigen::MatrixXd& readings, const double* mu,
               const Eigen::VectorXd& angle_mm, const Unknowns* v, const double* off,
               const double* qt, int M, double* b, double* bt) {
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

}  // namespace

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

void BandedLsq::factor(const Eigen::MatrixXd& readings, const Eigen::RowVectorXd& mu,
                       const Eigen::VectorXd& angle_mm, const Unknowns& v, bool only_pins) {
  // The window width as a compile-time constant for the usual narrow windows, so the per-station
  // loops unroll and the window's small copies are moves, not library calls.
  const Unknowns* pv = only_pins ? nullptr : &v;
  with_width(m_, [&]<int W>() { factor_impl<W>(readings, mu, angle_mm, pv); });
}

template <int Width>
void BandedLsq::factor_impl(const Eigen::MatrixXd& readings, const Eigen::RowVectorXd& mu,
                            const Eigen::VectorXd& angle_mm, const Unknowns* v) {
  const Design& D = D_;
  const long n = D.n;
  const int m = Width > 0 ? Width : m_, s = m + 1, L = L_, nred = M_ - L_;
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
  for (Chain& ch : chains_) {
    const auto steps = static_cast<std::size_t>(ch.steps);
    ch.rot.resize(keep_rotations_ ? per_station * steps : 0);
    ch.rot_mask.resize(keep_rotations_ && masked_ ? steps * static_cast<std::size_t>(nred) *
                                                        static_cast<std::size_t>(mask_bytes_)
                                                  : 0);
  }
  on_chains([&](std::size_t i) {
    if (!with_narrow<Width>(
            [&]<int NB>() { fold_narrow<Width, NB>(chains_[i], readings, mu, angle_mm, v); }))
      fold(chains_[i], readings, mu, angle_mm, v);
  });
  ssr_ = join();
  min_pivot_ = 1;
  for (const Chain& ch : chains_) {
    ssr_ += ch.ssr;
    min_pivot_ = std::min(min_pivot_, ch.min_pivot);
  }
  for (int c = 0; c < m; ++c)
    if (active(final_id(c)))
      min_pivot_ =
          std::min(min_pivot_, std::abs(final_[static_cast<std::size_t>(c * s + c)]) / scale_);
}

void BandedLsq::fold(Chain& ch, const Eigen::MatrixXd& readings, const Eigen::RowVectorXd& mu,
                     const Eigen::VectorXd& angle_mm, const Unknowns* v) {
  const Design& D = D_;
  const int m = m_, s = m + 1, nb = nb_, nred = M_ - L_;
  unsigned char* mask_out = ch.rot_mask.data();
  double* rot = ch.rot.data();
  static_assert(kRotationValues == 2);
  auto keep_identity = [&rot] {  // (c̄, x_j) of a rotation that changes nothing
    rot[0] = 1;
    rot[1] = 0;
    rot += kRotationValues;
  };
  std::vector<double>& W = ch.W;
  W.assign(static_cast<std::size_t>(m * s), 0.0);
  std::vector<double> row(static_cast<std::size_t>(s));
  // The smallest d of a free w's row: its √d/scale is the smallest pivot (√ and the division are
  // monotone, so they are taken once, at the end, off the per-station path).
  double ssr = 0, min_d = std::numeric_limits<double>::infinity();
  const std::vector<long>& pins = ch.pinned;
  std::size_t next_pin = 0;  // first pinned position not below t
  // After the first block, when the rotations kept per station are known, the pages the rest of
  // the chain will write are committed on another core. Not with two chains: both cores are busy
  // folding, and a helper only adds switches (measured: the solver 3 ms slower of 45).
  std::optional<Prefault> prefault;
  // The fold is not vectorised: each rotation's row and window updates are read back by the next
  // one, and paired loads of values stored one at a time stall on store forwarding.
  for_each_station(
      ch, readings, mu, angle_mm, v, [&](long t, long K, auto&& reduced) TA_NO_VECTORIZE {
        if (t == kBlock && chains_.size() == 1) prefault.emplace(rest_of_fold(ch, rot));
        while (next_pin < pins.size() && pins[next_pin] < t) ++next_pin;
        const bool pin_in_band = next_pin < pins.size() && pins[next_pin] <= t + nb - 1;
        for (int r = 0; r < nred; ++r) {
          // A reduced row: fold it into the window by square-root-free Givens rotations.
          std::uint64_t mask = 0;
          const double* cr = ch.Cred.data() + static_cast<std::size_t>(r * m);
          for (int c = 0; c < m; ++c) row[static_cast<std::size_t>(c)] = cr[c];
          row[static_cast<std::size_t>(m)] = reduced(r);
          if (pin_in_band)
            for (std::size_t i = next_pin; i < pins.size() && pins[i] <= t + nb - 1; ++i)
              row[static_cast<std::size_t>(pins[i] - t)] = 0;
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
                *rot++ = 0;  // the refinement knows the placement by its empty window row
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
              *rot++ = xi;
              if (masked_) mask |= std::uint64_t{1} << j;
            }
          }
          if (keep_rotations_ && !masked_)
            for (; j < m; ++j) keep_identity();  // after the row found an empty place
          if (keep_rotations_ && masked_)
            for (int i = 0; i < mask_bytes_; ++i)
              *mask_out++ = static_cast<unsigned char>(mask >> (8 * i));
          ssr += delta * row[static_cast<std::size_t>(m)] * row[static_cast<std::size_t>(m)];
        }
        // No later row of the chain touches the eliminated w: its row of R, √d·[1, ū], leaves the
        // window (stored as √d and ū), which slides by one position.
        double* out = rw_.data() + static_cast<std::size_t>(K) * static_cast<std::size_t>(m);
        const double r0 = std::sqrt(W[0]);
        out[0] = r0;
        for (int c = 1; c < m; ++c) out[c] = W[static_cast<std::size_t>(c)];
        qb_[static_cast<std::size_t>(K)] = W[static_cast<std::size_t>(m)];
        if (!D.pinned[static_cast<std::size_t>(D.w(ch.position(t)))]) min_d = std::min(min_d, W[0]);
        for (int tt = 0; tt < m; ++tt) {
          double* dst = W.data() + static_cast<std::size_t>(tt * s);
          if (tt == nb - 1) {
            for (int c = 0; c < s; ++c) dst[c] = 0;
            continue;
          }
          const double* src = tt < nb - 1 ? dst + s : dst;
          for (int c = 0; c + 1 < nb; ++c) dst[c] = src[c + 1];
          dst[nb - 1] = 0;
          if (src != dst)
            for (int c = nb; c < s; ++c) dst[c] = src[c];
        }
      });
  ch.ssr = ssr;
  ch.min_pivot = std::min(1.0, std::sqrt(min_d) / scale_);
}

std::vector<Prefault::Region> BandedLsq::rest_of_fold(const Chain& ch, const double* rot) const {
  const long lo = ch.lowest_station();
  const auto span_of = [&](const auto& buf, std::size_t per) {
    return Prefault::Region{buf.data() + static_cast<std::size_t>(lo) * per,
                            static_cast<std::size_t>(ch.steps) * per * sizeof(buf[0])};
  };
  const auto used = static_cast<std::size_t>(rot - ch.rot.data());
  const std::size_t expect =
      std::min(ch.rot.size(), used / static_cast<std::size_t>(kBlock) *
                                  static_cast<std::size_t>(ch.steps) * 9 / 8);
  return {span_of(rw_, static_cast<std::size_t>(m_)),
          span_of(qb_, 1),
          span_of(bloc_, static_cast<std::size_t>(L_)),
          {rot, (expect > used ? expect - used : 0) * sizeof(double)},
          {ch.rot_mask.data(), ch.rot_mask.size()}};
}

template <int Width, int NB>
void BandedLsq::fold_narrow(Chain& ch, const Eigen::MatrixXd& readings,
                            const Eigen::RowVectorXd& mu, const Eigen::VectorXd& angle_mm,
                            const Unknowns* v) {
  // The same rotations as fold, in the same order and arithmetic (the results are identical),
  // with the window's columns and the band's width known at compile time: the window and the
  // row are local arrays indexed by constants, which the compiler keeps in registers across the
  // stations of a block, and its slide is a renaming of registers, not copies through memory.
  // Only the window's upper triangle is kept (the rest is zero and never read).
  constexpr int m = Width, s = Width + 1;
  static_assert(NB >= 1 && NB <= Width && Width + 1 <= 8, "one mask byte");
  const int L = L_, nred = M_ - L_;
  const bool keep = keep_rotations_;
  unsigned char* mask_out = ch.rot_mask.data();
  double* rot = ch.rot.data();
  std::array<double, m * s> window{};
  double ssr = 0, min_d = std::numeric_limits<double>::infinity();
  const std::vector<long>& pins = ch.pinned;
  std::size_t next_pin = 0;          // first pinned position not below t
  std::optional<Prefault> prefault;  // as in fold
  for_each_block(ch, readings, mu, angle_mm, v, [&](long K0, int B, const double* bt) {
    const long t0 = ch.dir > 0 ? K0 - ch.first_station : ch.first_station - (K0 + B - 1);
    if (t0 == kBlock && chains_.size() == 1) prefault.emplace(rest_of_fold(ch, rot));
    auto W = window;  // in registers for the block
    double* rp = rot;
    unsigned char* mp = mask_out;
    double ss = ssr, md = min_d;
    for (int i = 0; i < B; ++i) {
      const int k = ch.in_block(i, B);
      const long K = K0 + k, t = t0 + i;
      while (next_pin < pins.size() && pins[next_pin] < t) ++next_pin;
      unsigned pinned = 0;  // the band's columns whose w is pinned
      for (std::size_t p = next_pin; p < pins.size() && pins[p] <= t + NB - 1; ++p)
        pinned |= 1u << (pins[p] - t);
      for (int r = 0; r < nred; ++r) {
        const double* cr = ch.Cred.data() + static_cast<std::size_t>(r * m);
        std::array<double, s> row;
        unroll<m>([&](auto c) { row[c] = cr[c]; });
        if (pinned != 0) [[unlikely]]
          unroll<m>([&](auto c) {
            if ((pinned >> c) & 1) row[c] = 0;
          });
        row[m] = bt[static_cast<std::size_t>((L + r) * B + k)];
        double delta = 1;
        unsigned mask = 0;
        unroll<m>([&](auto jc) {
          constexpr int j = decltype(jc)::value;
          const double xi = row[j];
          if (xi == 0) return;
          const double d = W[j * s + j];
          if (d == 0) {
            // An empty row of the window: the row takes its place, and nothing of it is left.
            const double inv = 1 / xi;
            W[j * s + j] = delta * xi * xi;
            unroll<m - j>([&](auto cc) {
              constexpr int c = j + 1 + decltype(cc)::value;
              W[j * s + c] = row[c] * inv;
              if constexpr (c < m) row[c] = 0;
            });
            if (keep) *rp++ = inv;
            mask |= (1u << j) | (1u << m);
            delta = 0;
            return;
          }
          const double dp = d + delta * xi * xi;
          const double inv = 1 / dp;
          const double cb = d * inv, sb = delta * xi * inv;
          delta *= cb;
          W[j * s + j] = dp;
          unroll<m - j>([&](auto cc) {
            constexpr int c = j + 1 + decltype(cc)::value;
            const double u = W[j * s + c], x = row[c];
            row[c] = x - xi * u;
            W[j * s + c] = cb * u + sb * x;
          });
          if (keep) {
            rp[0] = cb;
            rp[1] = xi;
            rp += kRotationValues;
          }
          mask |= 1u << j;
        });
        if (keep) *mp++ = static_cast<unsigned char>(mask);
        ss += delta * row[m] * row[m];
      }
      double* out = rw_.data() + static_cast<std::size_t>(K) * static_cast<std::size_t>(m);
      out[0] = std::sqrt(W[0]);
      unroll<m - 1>([&](auto c) { out[c + 1] = W[c + 1]; });
      qb_[static_cast<std::size_t>(K)] = W[m];
      if (!(pinned & 1)) md = std::min(md, W[0]);
      // The slide: row tt takes row tt + 1 one column left; row NB − 1 starts empty. The globals'
      // rows do not move (their band columns are left of the diagonal).
      unroll<NB>([&](auto ttc) {
        constexpr int tt = decltype(ttc)::value;
        unroll<s - tt>([&](auto cc) {
          constexpr int c = tt + decltype(cc)::value;
          if constexpr (tt == NB - 1 || c == NB - 1)
            W[tt * s + c] = 0;
          else if constexpr (c + 1 < NB)
            W[tt * s + c] = W[(tt + 1) * s + c + 1];
          else
            W[tt * s + c] = W[(tt + 1) * s + c];
        });
      });
    }
    window = W;
    rot = rp;
    mask_out = mp;
    ssr = ss;
    min_d = md;
  });
  ch.W.assign(window.begin(), window.end());
  ch.ssr = ssr;
  ch.min_pivot = std::min(1.0, std::sqrt(min_d) / scale_);
}

double BandedLsq::join() {
  const int m = m_, s = m + 1;
  final_.assign(static_cast<std::size_t>(m * s), 0.0);
  if (chains_.size() == 1) {
    // The last window in R's form: row c is √d_c·[0…0, 1, ū_c].
    const std::vector<double>& W = chains_[0].W;
    for (int c = 0; c < m; ++c) {
      const double* Wc = W.data() + static_cast<std::size_t>(c * s);
      double* Fc = final_.data() + static_cast<std::size_t>(c * s);
      const double rc = std::sqrt(Wc[c]);
      Fc[c] = rc;
      for (int i = c + 1; i < s; ++i) Fc[i] = rc * Wc[i];
    }
    return 0;
  }
  // Both chains' last windows as rows of R over the final window's active columns (and the
  // right-hand side), stacked; their QR is the final window's R, and the part of the right-hand
  // side it leaves over is the residual's last share.
  std::vector<int> act;
  for (int c = 0; c < m; ++c)
    if (active(final_id(c))) act.push_back(c);
  const int na = static_cast<int>(act.size());
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(2 * m, na + 1);
  for (std::size_t ci = 0; ci < chains_.size(); ++ci) {
    const Chain& ch = chains_[ci];
    for (int c = 0; c < m; ++c) {
      const double* Wc = ch.W.data() + static_cast<std::size_t>(c * s);
      if (Wc[c] == 0) continue;
      const double rc = std::sqrt(Wc[c]);
      const auto r = static_cast<Eigen::Index>(ci) * m + c;
      for (int a = 0; a < na; ++a) {
        const int cc = chain_col(ch, act[static_cast<std::size_t>(a)]);
        if (cc == c)
          S(r, a) = rc;
        else if (cc > c)
          S(r, a) = rc * Wc[cc];
      }
      S(r, na) = rc * Wc[m];
    }
  }
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(S);
  const Eigen::MatrixXd& R = qr.matrixQR();
  for (int a = 0; a < na; ++a) {
    double* Fa = final_.data() + static_cast<std::size_t>(act[static_cast<std::size_t>(a)] * s);
    for (int b = a; b < na; ++b) Fa[act[static_cast<std::size_t>(b)]] = R(a, b);
    Fa[m] = R(a, na);
  }
  return R(na, na) * R(na, na);
}

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
