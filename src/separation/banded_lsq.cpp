// The banded least-squares solver's first half (banded_lsq.hpp): the layout of the unknowns in
// chains, and the factorisation by Givens folds along each chain and their join.
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
#include "banded_lsq_blocks.hpp"

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

}  // namespace trueaxis::separation::detail
