// Private: the least-squares solver of straightness separation, specialised to its structure.
//
// Station K contributes one row per probe (and one for the angle channel) over: the station's
// own guide g(K) and pitch θ(K), the workpiece at positions K + q_i (a band of span + 1
// positions), and a few global unknowns (the free probe offsets). So:
//   1. g(K) and θ(K) appear in no other station's rows. One constant orthogonal transform Qᵀ
//      (the QR of the rows' [1, p_i] columns, computed once) splits each station's rows into L
//      local equations that give g(K), θ(K) once the rest is known, and M − L reduced rows over
//      the band and the globals only. Their coefficients are the same at every station; only the
//      right-hand side changes.
//   2. The reduced rows are folded into a small upper-triangular window over [w(K..K+span),
//      globals, rhs] by Givens rotations in their square-root-free form (Gentleman 1973, "Least
//      squares computations by Givens transformations without square roots", J. Inst. Maths
//      Applics 12; the updates of Miller's AS 274): the window holds R = D^½·Ū, Ū unit upper
//      triangular, as d and Ū. A rotation then waits for one division instead of a square root
//      and a division. For windows of up to six columns the window and the row are kept in
//      registers across a block of stations (the widths are compile-time constants), so a
//      station costs its arithmetic and the stores of its outputs, not the window's traffic.
//      Once station K is in, no later row touches w(K): the window's first row gives w(K)'s row
//      of R, √d·[1, ū], stored, and the window slides by one position.
// This is the QR factorisation of the whole system in the order (g, θ, w)(K) station by station,
// globals last: backward stable, O(n·(span + G)²) time, O(n·(span + G)) memory, no allocation per
// station.
//
// Long runs are factorised as two chains at once, on two cores: stations 0..h−1 forward as above,
// and stations n−1 down to h mirrored (the same fold with positions counted from the top, so the
// band's columns reversed), each towards the middle. Neither touches the other's eliminated
// unknowns, so this is the same QR with the columns in another order: the lower chain's, the upper
// chain's, then the unknowns both still hold (w(h..h+span−1) and the globals). Their two final
// windows are stacked and joined by a small Householder QR (Golub & Van Loan, "Matrix
// Computations", 4th ed., §5.2), which also gives the residual's last part. Back-substitutions
// then run outward from the joined solution, both chains at once. The stored rows give the solution
// (iterative refinement reapplies the kept rotations to new right-hand sides), the exact diagonal
// of (AᵀA)⁻¹ (a backward selected inversion), and (AᵀA)⁻¹V for a few columns, row by row.
//
// The unknowns are numbered as in Design; pinned unknowns are held at their pin values.
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cstdint>
#include <future>
#include <memory>
#include <system_error>
#include <utility>
#include <vector>

#include "../common/memory.hpp"
#include "design.hpp"
#include "prefault.hpp"

namespace trueaxis::separation::detail {

// A vector whose resize leaves new elements uninitialised, its large blocks in huge pages (see
// HugePageAllocator): buffers that are written before they are read cost no zeroing pass and few
// page faults.
template <class T>
using Uninitialized = std::vector<T, trueaxis::detail::HugePageAllocator<T>>;

// Calls fn.template operator()<W>() with W = w for the usual narrow widths (2 to 6) and W = 0
// (any width, read at run time) otherwise: a compile-time width lets the per-station loops unroll
// and keep their small arrays in registers.
template <class Fn>
decltype(auto) with_width(int w, Fn&& fn) {
  switch (w) {
    case 2:
      return fn.template operator()<2>();
    case 3:
      return fn.template operator()<3>();
    case 4:
      return fn.template operator()<4>();
    case 5:
      return fn.template operator()<5>();
    case 6:
      return fn.template operator()<6>();
    default:
      return fn.template operator()<0>();
  }
}

// Calls f(std::integral_constant<int, I>{}) for I = 0 … N − 1: a loop over a narrow window's
// columns with compile-time indices, so that the window can stay in registers.
template <int N, class F>
[[gnu::always_inline]] inline void unroll(F&& f) {
  if constexpr (N > 0) [&]<int... I>(std::integer_sequence<int, I...>) {
      (f(std::integral_constant<int, I>{}), ...);
    }
  (std::make_integer_sequence<int, N>{});
}

// Runs first() here and, at the same time, second() on another thread (both must finish before
// it returns); one after the other if no thread can be started.
template <class First, class Second>
void at_once(First&& first, Second&& second) {
  std::future<void> other;
  try {
    other = std::async(std::launch::async, second);
  } catch (const std::system_error&) {
    first();
    second();
    return;
  }
  first();
  other.get();
}

// Where the solver's unknowns live (ids as Design numbers them): the workpiece at w[pos], the
// guide at g[K], θ·h at t[K] (null without pitch), the offsets at o[i] (probes, then the angle
// channel). Separate arrays, so a caller can solve straight into its result arrays.
struct Unknowns {
  double* w = nullptr;
  double* g = nullptr;
  double* t = nullptr;
  double* o = nullptr;
  // The unknowns as one vector by id (nvars long).
  static Unknowns in(const Design& D, Eigen::VectorXd& v) {
    double* p = v.data();
    return {p + D.w(0), p + D.g(0), D.pitch ? p + D.t(0) : nullptr, p + D.o(0)};
  }
  double& operator()(const Design& D, int id) const {
    const auto [kind, i] = D.place(id);
    switch (kind) {
      case Design::Kind::w:
        return w[i];
      case Design::Kind::g:
        return g[i];
      case Design::Kind::t:
        return t[i];
      default:
        return o[i];
    }
  }
};

class BandedLsq {
 public:
  // Runs of at least this many stations are factorised as two chains on two cores.
  static constexpr long kSplitStations = 20000;

  // The design must outlive the solver. Runs of at least split_stations stations (and long enough
  // for two chains of more than a band each) are factorised as two chains.
  explicit BandedLsq(const Design& design, long split_stations = kSplitStations);
  bool split() const { return chains_.size() == 2; }

  // Factorises the system for the right-hand side b − A·v: b holds, per station, the probe
  // readings minus `mu` (n × N) and, with an angle channel, wa·angle_mm[K]. v holds a value for
  // every unknown (pinned ones at their pin values). Afterwards solve_add() adds the correction
  // to v.
  // With only_pins, v's free unknowns are taken as 0 without being read (they may hold anything)
  // and its pinned workpiece positions must be 0, as make_design pins them: the right-hand side
  // is then formed from the readings and the pinned offsets alone. Follow it with
  // solve_add(v, true).
  void factor(const Eigen::MatrixXd& readings, const Eigen::RowVectorXd& mu,
              const Eigen::VectorXd& angle_mm, const Unknowns& v, bool only_pins = false);

  // The same for a new v, reusing the last factorisation's rotations when they were kept (the
  // coefficients do not change): only the right-hand side is transformed.
  void refactor_rhs(const Eigen::MatrixXd& readings, const Eigen::RowVectorXd& mu,
                    const Eigen::VectorXd& angle_mm, const Unknowns& v);

  double ssr() const { return ssr_; }  // squared residual norm at the last factor()
  long rows() const { return rows_; }
  long unknowns() const { return unknowns_; }
  // Smallest |R_ii| relative to the coefficients' scale (small: a mode the data do not fix).
  double min_pivot_ratio() const { return min_pivot_; }

  // Adds the least-squares correction to v (pinned unknowns unchanged), without a vector of
  // corrections; with set_free, writes it into every free unknown instead (after
  // factor(…, only_pins)). Returns the largest |correction| and the largest |v| after the update,
  // both over the free unknowns.
  struct Update {
    double max_correction = 0;
    double max_value = 0;
  };
  Update solve_add(const Unknowns& v, bool set_free = false) const;
  // (AᵀA)⁻¹V for a V of k columns (a compile-time constant) given row by row, without storing
  // either, and the diagonal of (AᵀA)⁻¹ (a backward selected inversion, meanwhile): v_row(id, out)
  // writes the k values of a free unknown's row of V; use(id, zv, z) then receives that unknown's
  // row of (AᵀA)⁻¹V and its diagonal entry of (AᵀA)⁻¹, once per free unknown, the final window and
  // the globals first, then outward along each chain. With two chains, both callbacks are called
  // from two threads at once (for different unknowns). With `gram` (k × k, row-major), also adds
  // Vᵀ(AᵀA)⁻¹V to it: with Y = R⁻ᵀV the forward solve, VᵀR⁻¹R⁻ᵀV = YᵀY, the sum of its rows'
  // outer products; it is complete when ready() is called, after the forward solve and before
  // the first use() (so use() may read it).
  // With `local_vv` (3 · k × k, row-major), the caller gives the local unknowns' share of V's
  // rows as three sums over every free g and θ: Σ v_g·v_gᵀ, Σ v_g·v_θᵀ (v_g and v_θ of the same
  // station) and Σ v_θ·v_θᵀ (zeros without θ). The local rows of Y are V's rows through the
  // constant Rloc⁻ᵀ, so their Gram follows from these without a product per station; the forward
  // solve then sums only the workpiece rows' products (a third of them).
  // It works in the factorisation's memory that only solve_add and refactor_rhs read: the forward
  // solve's workpiece rows (Q × k values) in the kept rotations where they fit, the diagonal in
  // the right-hand sides. So after it, a solve_add needs a factor() first (refactor_rhs() then
  // factorises again).
  template <int k, class VRow, class Use, class Ready>
  void solve_normal_rows(VRow&& v_row, Use&& use, double* gram, Ready&& ready,
                         const double* local_vv = nullptr);
  template <int k, class VRow, class Use>
  void solve_normal_rows(VRow&& v_row, Use&& use, double* gram = nullptr) {
    solve_normal_rows<k>(std::forward<VRow>(v_row), std::forward<Use>(use), gram, [] {});
  }
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

 private:
  // One chain of the factorisation: `steps` stations from first_station in direction dir (+1,
  // or −1 for the mirrored upper chain). Its own numbering of the workpiece positions, pp, runs
  // from first_pos in the same direction: step t eliminates pp = t and its window holds pp =
  // t..t+span (band column c at t + c), then the globals. Its rows of R, right-hand sides and
  // local right-hand sides are stored at the station's index K, in the chain's column order.
  struct Chain {
    long first_station = 0, first_pos = 0, steps = 0;
    int dir = 1;
    RowMajor Cred;                          // reduced rows over the chain's window columns
    Eigen::MatrixXd Cloc;                   // local equations over them
    std::vector<long> pinned;               // pinned positions as pp, ascending
    Uninitialized<double> rot;              // the kept rotations, in the order applied
    Uninitialized<unsigned char> rot_mask;  // per station and reduced row: mask_bytes_ bytes
    std::vector<double> W;  // the window after the last step: m × (m + 1), d and ū
    double ssr = 0, min_pivot = 1;
    long station(long t) const { return first_station + dir * t; }
    long lowest_station() const { return dir > 0 ? first_station : first_station - steps + 1; }
    long position(long pp) const { return first_pos + dir * pp; }
    // The i-th station of a block of B, in the chain's order, as its offset in the block.
    int in_block(int i, int B) const { return dir > 0 ? i : B - 1 - i; }
  };

  // Calls fn(i) for each chain i, the second on another thread.
  template <class Fn>
  void on_chains(Fn&& fn) const {
    if (chains_.size() == 1)
      fn(std::size_t{0});
    else
      at_once([&] { fn(std::size_t{0}); }, [&] { fn(std::size_t{1}); });
  }

  // Forms the right-hand sides b − A·v block by block (v null: its free unknowns 0, only the
  // offsets pinned), stores each station's local ones and calls fn(K0, B, bt) per block of
  // stations [K0, K0 + B) in the chain's order; bt[(L + r)·B + k] is the reduced right-hand side
  // r of station K0 + k, and the block's stations are to be taken in the chain's direction.
  template <class Fn>
  void for_each_block(const Chain& ch, const Eigen::MatrixXd& readings,
                      const Eigen::RowVectorXd& mu, const Eigen::VectorXd& angle_mm,
                      const Unknowns* v, Fn&& fn);
  // for_each_block station by station: fn(t, K, reduced) in the chain's order, reduced(r) giving
  // the station's reduced right-hand side r.
  template <class Fn>
  void for_each_station(const Chain& ch, const Eigen::MatrixXd& readings,
                        const Eigen::RowVectorXd& mu, const Eigen::VectorXd& angle_mm,
                        const Unknowns* v, Fn&& fn);
  // For a compile-time window width Width (not 0: any), calls fn.template operator()<NB>() with
  // the band's width NB as a constant too and returns true; false for Width 0 or a band width
  // without an instance (the general passes then run).
  template <int Width, class Fn>
  bool with_band(Fn&& fn) const {
    if constexpr (Width == 0) {
      return false;
    } else {
      return with_width(nb_, [&]<int NB>() {
        if constexpr (NB > 0 && NB <= Width) {
          fn.template operator()<NB>();
          return true;
        } else {
          return false;
        }
      });
    }
  }
  // with_band for the factorisation's passes, which also need the rotations' column masks.
  template <int Width, class Fn>
  bool with_narrow(Fn&& fn) const {
    return masked_ && with_band<Width>(std::forward<Fn>(fn));
  }
  // Folds the chain's rows into R by Givens rotations, station by station (any window width).
  void fold(Chain& ch, const Eigen::MatrixXd& readings, const Eigen::RowVectorXd& mu,
            const Eigen::VectorXd& angle_mm, const Unknowns* v);
  // The pages a chain's fold writes from here on (the kept rotations from rot), committed on
  // another core: started after the first block, when the rotations per station are known.
  std::vector<Prefault::Region> rest_of_fold(const Chain& ch, const double* rot) const;
  // fold for a window of Width columns, NB of them the band's (both compile-time constants).
  template <int Width, int NB>
  void fold_narrow(Chain& ch, const Eigen::MatrixXd& readings, const Eigen::RowVectorXd& mu,
                   const Eigen::VectorXd& angle_mm, const Unknowns* v);
  // The kept rotations applied to a new right-hand side (any window width).
  void refold_rhs(Chain& ch, const Eigen::MatrixXd& readings, const Eigen::RowVectorXd& mu,
                  const Eigen::VectorXd& angle_mm, const Unknowns* v);
  // refold_rhs for a window of Width columns, NB of them the band's.
  template <int Width, int NB>
  void refold_narrow(Chain& ch, const Eigen::MatrixXd& readings, const Eigen::RowVectorXd& mu,
                     const Eigen::VectorXd& angle_mm, const Unknowns* v);
  // final_ from the chains' last windows (one chain: converted; two: joined by a QR). Returns the
  // residual's share left by the join.
  double join();
  template <int k, int Width, class VRow, class Use, class Ready>  // window width, 0: any
  void solve_normal_rows_impl(VRow& v_row, Use& use, double* gram, Ready& ready,
                              const double* local_vv, Uninitialized<double> (&yw)[2], long split);
  template <int NB>  // band width, 0: any
  void back_substitute(const Chain& ch, const std::vector<double>& xc, const Unknowns& v,
                       bool set_free, double* mc, double* mv) const;
  // (AᵀA)⁻¹ over the final window's columns (m × m, row-major; inactive columns 0).
  std::vector<double> final_covariance() const;
  // diag((AᵀA)⁻¹) along a chain, outward from the final window's covariance Fj: per station K,
  // that of its eliminated w at zw[K] (0 where w is pinned) and of its local unknowns at
  // zloc[K·L + l].
  void chain_covariance(const Chain& ch, const std::vector<double>& Fj, double* zw,
                        double* zloc) const;
  // A chain's window after station t is [w(t+1..t+span), globals]; station t − 1's is the same
  // without w(t+span), the band's last column (nb: the band's width). Its column i in the full
  // window [w(t..t+span), globals]:
  static constexpr int skip_band_end(int i, int nb) { return i < nb - 1 ? i : i + 1; }
  // Fj (m × m, row-major) in the chain's column order (0 where the chain has no column).
  std::vector<double> in_chain_order(const Chain& ch, const std::vector<double>& Fj) const;
  void chain_covariance_any(const Chain& ch, const std::vector<double>& Fj, double* zw,
                            double* zloc) const;
  // The same for a window of W columns, NB of them the band's (compile-time constants): the
  // window's small matrices are local arrays indexed by constants only, so they stay in
  // registers and dropping the band's last column is a renaming. Same arithmetic, in the same
  // order.
  template <int W, int NB>
  void chain_covariance_narrow(const Chain& ch, const std::vector<double>& Fj, double* zw,
                               double* zloc) const;
  template <int Width>  // window width, 0: any
  void factor_impl(const Eigen::MatrixXd& readings, const Eigen::RowVectorXd& mu,
                   const Eigen::VectorXd& angle_mm, const Unknowns* v);
  template <int Width>  // window width, 0: any
  void refactor_rhs_impl(const Eigen::MatrixXd& readings, const Eigen::RowVectorXd& mu,
                         const Eigen::VectorXd& angle_mm, const Unknowns& v);
  // The unknown at column c of the final (joined) window: w(h..h+span−1), none, the globals.
  int final_id(int c) const;
  // The chain's column of the final window's column c (its window after the last step), or −1.
  int chain_col(const Chain& ch, int c) const;
  bool active(int id) const;  // a free unknown that exists

  const Design& D_;
  int L_ = 0;                   // local unknowns per station: g (and θ)
  int M_ = 0;                   // rows per station
  int nb_ = 0;                  // band width: span + 1
  int G_ = 0;                   // free globals
  int m_ = 0;                   // window columns: nb + G
  std::vector<int> globals_;    // their ids
  RowMajor Qt_;                 // M × M: the constant row transform
  Eigen::MatrixXd Rloc_;        // L × L, upper triangular
  std::vector<long> pinned_w_;  // pinned workpiece positions, ascending
  std::vector<Chain> chains_;   // one, or two (lower, upper mirrored)
  long h_ = 0;                  // the lower chain's stations: the final window starts at w(h)

  // Factorisation: per station, the eliminated position's row of R over its chain's window,
  // √d·[1, ū], stored as [√d, ū_1..ū_m−1] (the same for every right-hand side), its transformed
  // right-hand side divided by √d, and the local equations' right-hand sides;
  // the final window over [w(h..h+span−1), none, globals] with its right-hand side (R, not d/ū).
  Uninitialized<double> rw_;    // n × m
  Uninitialized<double> qb_;    // n
  Uninitialized<double> bloc_;  // n × L
  std::vector<double> final_;   // m × (m + 1)
  // The rotations in the order applied, each as (c̄, x_j): c̄ = d/d' and the row's entry x_j
  // (the refinement forms s̄ = δ·x_j/d' again from them). Per station and reduced row, those
  // whose row entry was nonzero, with a mask of their window columns (masked_), or all of them
  // (windows wider than 63 columns: identities as (1, 0), a placement as (0, x_j)). With the
  // mask, a row's placement into an empty window row is one number, 1/x_j (mask bit m).
  // Reserved, not committed: only the rotations written take memory. At two numbers each, 384 MB
  // keeps rotations for 1.5 times the stations it did at three.
  static constexpr std::size_t kRotationBudgetBytes = std::size_t{384} << 20;
  static constexpr int kRotationValues = 2;
  bool keep_rotations_ = false;
  bool masked_ = true;
  int mask_bytes_ = 1;
  double ssr_ = 0;
  long rows_ = 0, unknowns_ = 0;
  double min_pivot_ = 1;
  double scale_ = 1;
};

template <int k, class VRow, class Use, class Ready>
void BandedLsq::solve_normal_rows(VRow&& v_row, Use&& use, double* gram, Ready&& ready,
                                  const double* local_vv) {
  // The forward solve's workpiece rows: the lower chain's positions (up to the final window's) in
  // one buffer, the upper chain's in another, each in its chain's dead rotations where they fit
  // (pages already committed), else new.
  const bool two = chains_.size() == 2;
  const long split = two ? h_ + nb_ - 1 : D_.Q;
  const std::size_t need[2] = {static_cast<std::size_t>(split) * k,
                               static_cast<std::size_t>(D_.Q - split) * k};
  Uninitialized<double> yw[2];
  for (std::size_t c = 0; c < chains_.size(); ++c) {
    Uninitialized<double>& rot = chains_[c].rot;
    if (rot.capacity() >= need[c]) {
      yw[c].swap(rot);
      keep_rotations_ = false;  // a later refactor_rhs factorises again
    }
    yw[c].resize(need[c]);
  }
  with_width(m_, [&]<int W>() {
    solve_normal_rows_impl<k, W>(v_row, use, gram, ready, local_vv, yw, split);
  });
}

template <int k, int Width, class VRow, class Use, class Ready>  // window width, 0: any
void BandedLsq::solve_normal_rows_impl(VRow& v_row, Use& use, double* gram, Ready& ready,
                                       const double* local_vv, Uninitialized<double> (&yw)[2],
                                       long split) {
  // Rᵀy = V forward in elimination order (per chain and station g, θ, and the eliminated w; then
  // the final window), and R z = y backward. y of an eliminated w is final after its station's
  // step and needed again at that station on the way back, so the workpiece rows are kept; a
  // station's local rows depend only on its own rows of V and are formed again on the way back.
  // Two chains run at once, each way: forward, the upper chain adds its share of the final
  // window's y into a copy of its own (from 0), summed with the lower chain's before the final
  // window; backward, each chain reads only the final window's z. The selected inversion runs on
  // a third thread during the forward solve.
  const Design& D = D_;
  const int m = Width > 0 ? Width : m_, s = m + 1, nb = nb_, L = L_;
  const long Q = D.Q;
  const auto ku = static_cast<std::size_t>(k);
  const Prefault prefault({{yw[0].data(), yw[0].size() * sizeof(double)},
                           {yw[1].data(), yw[1].size() * sizeof(double)}});
  std::vector<double> yg(static_cast<std::size_t>(G_) * ku);
  // diag((AᵀA)⁻¹), in the right-hand sides' memory (below).
  double* const zdiag_w = qb_.data();
  double* const zdiag_loc = bloc_.data();
  const bool two = chains_.size() == 2;
  // The upper chain's share of w(h..h+span−1)'s y, then of the globals'.
  std::vector<double> up_shared(two ? static_cast<std::size_t>(nb - 1 + G_) * ku : 0, 0.0);
  auto wrow = [&](long pos) {
    return pos < split ? yw[0].data() + static_cast<std::size_t>(pos) * ku
                       : yw[1].data() + static_cast<std::size_t>(pos - split) * ku;
  };
  auto is_free = [&](int id) { return D.pinned[static_cast<std::size_t>(id)] == 0; };
  auto v_or_zero = [&](int id, double* out) {
    if (is_free(id))
      v_row(id, out);
    else
      std::fill_n(out, k, 0.0);
  };
  // Divisions by the diagonal as multiplications by reciprocals: a division costs several times
  // a multiplication's throughput, and there would be dozens per station.
  const double rinv[2] = {1 / Rloc_(0, 0), L == 2 ? 1 / Rloc_(1, 1) : 0.0};
  // Σ y·yᵀ over the forward rows, of which the upper triangle is used. Each row of the sum is
  // y[a] times y in whole aligned pairs of y: the triangle's rows start mid-pair, and their loads
  // would span two of y's stores (a stall of a dozen cycles each). The general passes add all
  // k × k products; the narrow ones only the 2 × 2 blocks on or above the diagonal (a third
  // fewer).
  using Gram = std::array<double, k * k>;
  std::array<Gram, 2> yy{};
  // (GCC 12, vectorising this for AVX2 in the general passes, takes a local row that is written
  // before every call for one that may not be.)
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
  auto add_gram = [](Gram& g, const double* y) {
    for (int a = 0; a < k; ++a)
      for (int b = 0; b < k; ++b) g[static_cast<std::size_t>(a * k + b)] += y[a] * y[b];
  };
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif
  // win[c]: the row of y (or z) of window column c, null past the end.
  struct Window {
    std::vector<double*> heap;
    std::array<double*, (Width > 0 ? Width : 1)> fixed{};
    double** p;
    explicit Window(int width)
        : heap(Width > 0 ? 0 : static_cast<std::size_t>(width)),
          p(Width > 0 ? fixed.data() : heap.data()) {}
    double*& operator[](int c) const { return p[c]; }
  };
  // The chain's window at step t (its shares of the final window's rows in `shared`, or in yw/yg).
  auto set_window = [&](Window& win, const Chain& ch, long t, double* shared) {
    for (int c = 0; c < nb; ++c) {
      const long pos = ch.position(t + c);
      if (pos < 0 || pos >= Q)
        win[c] = nullptr;
      else if (shared && pos >= h_ && pos < h_ + nb - 1)
        win[c] = shared + static_cast<std::size_t>(pos - h_) * ku;
      else
        win[c] = wrow(pos);
    }
    double* globals = shared ? shared + static_cast<std::size_t>(nb - 1) * ku : yg.data();
    for (int c = nb; c < m; ++c) win[c] = globals + static_cast<std::size_t>(c - nb) * ku;
  };
  // y0, y1 = Rloc⁻ᵀ·(V's rows of g(K), θ(K)) (y1 0 without θ), with the few coefficients in
  // registers.
  const double rl01 = L == 2 ? Rloc_(0, 1) : 0.0;
  auto local_forward2 = [&](long K, double* y0, double* y1) __attribute__((always_inline)) {
    v_or_zero(D.g(K), y0);
    unroll<k>([&](auto j) { y0[j] *= rinv[0]; });
    if (L == 2) {
      v_or_zero(D.t(K), y1);
      unroll<k>([&](auto j) { y1[j] = (y1[j] - rl01 * y0[j]) * rinv[1]; });
    } else {
      std::fill_n(y1, k, 0.0);
    }
  };
  // The same into yl's rows (2k values).
  auto local_forward = [&](long K, double* yl) { local_forward2(K, yl, yl + ku); };
  // The two passes for a window of Width columns, NB of them the band's (compile-time constants):
  // the window's rows of y (or z) are local arrays indexed by constants only (every loop over
  // columns unrolled), so they stay in registers, the slide by one position is a renaming, and no
  // load waits on a store it only partly overlaps. Same arithmetic, in the same order, as the
  // general passes below.
  using KRow = std::array<double, k>;
  auto chain_cloc = [&](const Chain& ch) {
    std::array<double, 2 * (Width > 0 ? Width : 1)> cloc{};  // 0 for a missing θ
    for (int l = 0; l < L; ++l)
      for (int c = 0; c < m; ++c) cloc[static_cast<std::size_t>(l * m + c)] = ch.Cloc(l, c);
    return cloc;
  };
  // Local: the local rows' products are summed here (no local_vv).
  auto forward_narrow = [&]<int NB, bool Local>(std::size_t ci) {
    constexpr int W = Width, G = W - NB;
    const Chain& ch = chains_[ci];
    const bool upper = ci == 1;
    const auto cloc = chain_cloc(ch);
    Gram g{};
    std::array<KRow, W> a;  // the band's positions t..t+NB−1, then the globals
    // A position's row of V as it enters the window (the final window's positions: the lower
    // chain's; the upper chain sums its share from 0); positions past the ends stay 0.
    auto enter = [&](long pp, KRow& r) {
      const long pos = ch.position(pp);
      if (pos >= 0 && pos < Q && (!upper || pp < ch.steps))
        v_or_zero(D.w(pos), r.data());
      else
        r.fill(0.0);
    };
    unroll<NB - 1>([&](auto c) { enter(c, a[c]); });
    unroll<G>([&](auto gi) {
      constexpr int c = NB + decltype(gi)::value;
      if (upper)
        a[c].fill(0.0);
      else
        std::copy_n(yg.data() + static_cast<std::size_t>(gi) * ku, k, a[c].data());
    });
    for (long t = 0; t < ch.steps; ++t) {
      const long K = ch.station(t), pos = ch.position(t);
      enter(t + NB - 1, a[NB - 1]);
      KRow y0l, y1l;
      local_forward2(K, y0l.data(), y1l.data());
      unroll<W>([&](auto c) {
        const double c0 = cloc[c], c1 = cloc[W + c];
        unroll<k>([&](auto j) { a[c][j] -= c0 * y0l[j]; });
        if (L == 2) unroll<k>([&](auto j) { a[c][j] -= c1 * y1l[j]; });
      });
      const double* R = rw_.data() + static_cast<std::size_t>(K) * static_cast<std::size_t>(W);
      if (is_free(D.w(pos)) && R[0] != 0) {
        unroll<W - 1>([&](auto c1) {
          constexpr int c = decltype(c1)::value + 1;
          const double uc = R[c];
          unroll<k>([&](auto j) { a[c][j] -= uc * a[0][j]; });
        });
        const double inv = 1 / R[0];
        unroll<k>([&](auto j) { a[0][j] *= inv; });
      } else {  // no row of R: 0
        a[0].fill(0.0);
      }
      double* y0 = wrow(pos);
      unroll<k>([&](auto j) { y0[j] = a[0][j]; });
      if (gram)  // the station's rows in one pass over the sum's upper aligned pairs
        unroll<k>([&](auto r) {
          unroll<k>([&](auto c) {
            if constexpr (c / 2 >= r / 2) {
              double& e = g[static_cast<std::size_t>(r * k + c)];
              if constexpr (Local) {
                e += y0l[r] * y0l[c];
                if (L == 2) e += y1l[r] * y1l[c];
              }
              e += a[0][r] * a[0][c];
            }
          });
        });
      unroll<NB - 1>([&](auto c) { a[c] = a[c + 1]; });
    }
    // What the window holds at the end: the final window's positions and the globals.
    unroll<NB - 1>([&](auto c) {
      const long pos = ch.position(ch.steps + c);
      if (pos < 0 || pos >= Q) return;
      double* out = upper ? up_shared.data() + static_cast<std::size_t>(pos - h_) * ku : wrow(pos);
      std::copy_n(a[c].data(), k, out);
    });
    unroll<G>([&](auto gi) {
      double* out = (upper ? up_shared.data() + static_cast<std::size_t>(NB - 1) * ku : yg.data()) +
                    static_cast<std::size_t>(gi) * ku;
      std::copy_n(a[NB + gi].data(), k, out);
    });
    yy[ci] = g;
  };
  auto backward_narrow = [&]<int NB>(std::size_t ci) {
    constexpr int W = Width, G = W - NB;
    const Chain& ch = chains_[ci];
    const auto cloc = chain_cloc(ch);
    std::array<KRow, W> z{};      // the band's positions t..t+NB−1, then the globals
    unroll<NB - 1>([&](auto c) {  // the final window's positions: solved
      const long pos = ch.position(ch.steps + c);
      if (pos >= 0 && pos < Q) std::copy_n(wrow(pos), k, z[c + 1].data());
    });
    unroll<G>([&](auto gi) {
      std::copy_n(yg.data() + static_cast<std::size_t>(gi) * ku, k, z[NB + gi].data());
    });
    for (long t = ch.steps - 1; t >= 0; --t) {
      const long K = ch.station(t), pos = ch.position(t);
      const int idw = D.w(pos);
      const double* R = rw_.data() + static_cast<std::size_t>(K) * static_cast<std::size_t>(W);
      const double* y = wrow(pos);
      if (is_free(idw) && R[0] != 0) {  // z(w) = y/√d − ū·(the later z)
        const double inv = 1 / R[0];
        unroll<k>([&](auto j) { z[0][j] = y[j] * inv; });
        unroll<W - 1>([&](auto c1) {
          constexpr int c = decltype(c1)::value + 1;
          const double uc = R[c];
          unroll<k>([&](auto j) { z[0][j] -= uc * z[c][j]; });
        });
      } else {
        unroll<k>([&](auto j) { z[0][j] = y[j]; });
      }
      if (is_free(idw)) use(idw, static_cast<const double*>(z[0].data()), zdiag_w[K]);
      KRow y0l, y1l, z1{};
      local_forward2(K, y0l.data(), y1l.data());
      if (L == 2) {
        unroll<W>([&](auto c) {
          const double cl = cloc[W + c];
          unroll<k>([&](auto j) { y1l[j] -= cl * z[c][j]; });
        });
        unroll<k>([&](auto j) { z1[j] = y1l[j] * rinv[1]; });
      }
      unroll<W>([&](auto c) {
        const double cl = cloc[c];
        unroll<k>([&](auto j) { y0l[j] -= cl * z[c][j]; });
      });
      if (L == 2) unroll<k>([&](auto j) { y0l[j] -= rl01 * z1[j]; });
      unroll<k>([&](auto j) { y0l[j] *= rinv[0]; });
      if (const int id = D.g(K); is_free(id))
        use(id, static_cast<const double*>(y0l.data()), zdiag_loc[static_cast<std::size_t>(K * L)]);
      if (L == 2)
        if (const int id = D.t(K); is_free(id))
          use(id, static_cast<const double*>(z1.data()),
              zdiag_loc[static_cast<std::size_t>(K * L + 1)]);
      unroll<NB - 1>([&](auto c1) {
        constexpr int c = NB - 1 - decltype(c1)::value;
        z[c] = z[c - 1];
      });
    }
  };
  auto forward = [&](std::size_t ci) {
    if (with_band<Width>([&]<int NB>() {
          if (local_vv)
            forward_narrow.template operator()<NB, false>(ci);
          else
            forward_narrow.template operator()<NB, true>(ci);
        }))
      return;
    const Chain& ch = chains_[ci];
    double* shared = ci == 1 ? up_shared.data() : nullptr;
    Gram g{};  // here, not in yy: yy[0] and yy[1] share a cache line
    Window win(m);
    std::array<double, 2 * k> yl{};
    // A position's row of V is loaded as it enters the chain's window; the final window's
    // positions by the lower chain only.
    auto load = [&](long pp) {
      const long pos = ch.position(pp);
      if (pos >= 0 && pos < Q && (ci == 0 || pp < ch.steps)) v_or_zero(D.w(pos), wrow(pos));
    };
    for (long pp = 0; pp + 1 < nb; ++pp) load(pp);
    for (long t = 0; t < ch.steps; ++t) {
      const long K = ch.station(t);
      load(t + nb - 1);  // enters the window
      set_window(win, ch, t, shared);
      local_forward(K, yl.data());
      if (gram && !local_vv)
        for (int l = 0; l < L; ++l) add_gram(g, yl.data() + static_cast<std::size_t>(l) * ku);
      for (int c = 0; c < m; ++c) {
        double* a = win[c];
        if (!a) continue;
        for (int l = 0; l < L; ++l) {
          const double cl = ch.Cloc(l, c);
          const double* y = yl.data() + static_cast<std::size_t>(l) * ku;
          for (int j = 0; j < k; ++j) a[j] -= cl * y[j];
        }
      }
      const double* R = rw_.data() + static_cast<std::size_t>(K) * static_cast<std::size_t>(m);
      double* y0 = win[0];
      if (!is_free(D.w(ch.position(t))) || R[0] == 0) {  // no row of R: 0
        std::fill_n(y0, k, 0.0);
        continue;
      }
      // The row is √d·[1, ū] (stored as √d, ū): y(w) = a/√d, and the later columns lose
      // √d·ū_c·y(w) = ū_c·a.
      for (int c = 1; c < m; ++c) {
        double* a = win[c];
        if (!a) continue;
        const double uc = R[c];
        for (int j = 0; j < k; ++j) a[j] -= uc * y0[j];
      }
      const double inv = 1 / R[0];
      for (int j = 0; j < k; ++j) y0[j] *= inv;
      if (gram) add_gram(g, y0);
    }
    yy[ci] = g;
  };
  auto backward = [&](std::size_t ci) {
    if (with_band<Width>([&]<int NB>() { backward_narrow.template operator()<NB>(ci); })) return;
    const Chain& ch = chains_[ci];
    Window win(m);
    std::array<double, 2 * k> yl{}, zl{};
    std::array<double, k> acc{};
    for (long t = ch.steps - 1; t >= 0; --t) {
      const long K = ch.station(t);
      const int idw = D.w(ch.position(t));
      set_window(win, ch, t, nullptr);
      const double* R = rw_.data() + static_cast<std::size_t>(K) * static_cast<std::size_t>(m);
      double* z0 = win[0];
      if (is_free(idw) && R[0] != 0) {  // z(w) = y/√d − ū·(the later z)
        const double inv = 1 / R[0];
        for (int j = 0; j < k; ++j) acc[static_cast<std::size_t>(j)] = z0[j] * inv;
        for (int c = 1; c < m; ++c)
          if (const double* zc = win[c])
            for (int j = 0; j < k; ++j) acc[static_cast<std::size_t>(j)] -= R[c] * zc[j];
        for (int j = 0; j < k; ++j) z0[j] = acc[static_cast<std::size_t>(j)];
      }
      if (is_free(idw)) use(idw, static_cast<const double*>(z0), zdiag_w[K]);
      local_forward(K, yl.data());
      for (int l = L - 1; l >= 0; --l) {
        const double* y = yl.data() + static_cast<std::size_t>(l) * ku;
        for (int j = 0; j < k; ++j) acc[static_cast<std::size_t>(j)] = y[j];
        for (int c = 0; c < m; ++c)
          if (const double* zc = win[c]) {
            const double cl = ch.Cloc(l, c);
            for (int j = 0; j < k; ++j) acc[static_cast<std::size_t>(j)] -= cl * zc[j];
          }
        for (int i = l + 1; i < L; ++i)
          for (int j = 0; j < k; ++j)
            acc[static_cast<std::size_t>(j)] -=
                Rloc_(l, i) * zl[static_cast<std::size_t>(i) * ku + j];
        for (int j = 0; j < k; ++j)
          zl[static_cast<std::size_t>(l) * ku + j] = acc[static_cast<std::size_t>(j)] * rinv[l];
      }
      for (int l = 0; l < L; ++l)
        if (const int id = l == 0 ? D.g(K) : D.t(K); is_free(id))
          use(id, static_cast<const double*>(zl.data() + static_cast<std::size_t>(l) * ku),
              zdiag_loc[static_cast<std::size_t>(K * L + l)]);
    }
  };

  for (int g = 0; g < G_; ++g)
    v_or_zero(globals_[static_cast<std::size_t>(g)], yg.data() + static_cast<std::size_t>(g) * ku);
  // diag((AᵀA)⁻¹) by the selected inversion, for long runs on a third thread meanwhile (it and
  // the forward solve only read the factorisation), into the memory of the right-hand sides, dead
  // since the last solve_add (their pages are committed).
  const std::vector<double> Fj = final_covariance();
  auto diagonal = [&] {
    for (const Chain& ch : chains_) chain_covariance(ch, Fj, zdiag_w, zdiag_loc);
  };
  if (two)
    at_once([&] { on_chains(forward); }, diagonal);
  else {
    diagonal();
    forward(0);
  }
  if (gram && local_vv) {
    // The local rows' Gram from V's: y_g = v_g/r00 and y_θ = (v_θ − r01·y_g)/r11, so
    // Σ y_g·y_gᵀ = Σ v_g·v_gᵀ/r00² and Σ y_θ·y_θᵀ = (Σ v_θ·v_θᵀ − r01/r00·(Σ v_g·v_θᵀ + its
    // transpose) + (r01/r00)²·Σ v_g·v_gᵀ)/r11².
    const double* gg = local_vv;
    const double* gt = local_vv + k * k;
    const double* tt = local_vv + 2 * k * k;
    const double q = rl01 * rinv[0];
    for (int a = 0; a < k; ++a)
      for (int b = 0; b < k; ++b) {
        const int ab = a * k + b, ba = b * k + a;
        double e = gg[ab] * rinv[0] * rinv[0];
        if (L == 2) e += (tt[ab] - q * (gt[ab] + gt[ba]) + q * q * gg[ab]) * rinv[1] * rinv[1];
        yy[0][static_cast<std::size_t>(ab)] += e;
      }
  }
  if (two) {  // the upper chain's shares
    for (int c = 0; c + 1 < nb; ++c)
      if (const int id = final_id(c); id >= 0)
        for (std::size_t j = 0; j < ku; ++j)
          wrow(id - D.w(0))[j] += up_shared[static_cast<std::size_t>(c) * ku + j];
    for (std::size_t i = 0; i < static_cast<std::size_t>(G_) * ku; ++i)
      yg[i] += up_shared[static_cast<std::size_t>(nb - 1) * ku + i];
  }
  // The final window: forward, then backward, then its unknowns are done.
  Window win(m);
  for (int c = 0; c < nb; ++c) {
    const int id = final_id(c);
    win[c] = id >= 0 ? wrow(id - D.w(0)) : nullptr;
  }
  for (int c = nb; c < m; ++c) win[c] = yg.data() + static_cast<std::size_t>(c - nb) * ku;
  for (int c = 0; c < m; ++c) {
    double* yc = win[c];
    if (!yc) continue;
    const double* F = final_.data() + static_cast<std::size_t>(c * s);
    if (!active(final_id(c)) || F[c] == 0) {
      std::fill_n(yc, k, 0.0);
      continue;
    }
    for (int j = 0; j < k; ++j) yc[j] /= F[c];
    if (gram) add_gram(yy[0], yc);
    for (int i = c + 1; i < m; ++i)
      if (double* a = win[i])
        for (int j = 0; j < k; ++j) a[j] -= F[i] * yc[j];
  }
  if (gram)
    for (int a = 0; a < k; ++a)
      for (int b = 0; b < k; ++b) {
        const auto ab = static_cast<std::size_t>(a <= b ? a * k + b : b * k + a);
        gram[a * k + b] += yy[0][ab] + yy[1][ab];
      }
  ready();
  std::array<double, k> acc{};
  for (int c = m - 1; c >= 0; --c) {
    const double* F = final_.data() + static_cast<std::size_t>(c * s);
    if (!active(final_id(c)) || F[c] == 0) continue;
    double* zc = win[c];
    for (int j = 0; j < k; ++j) acc[static_cast<std::size_t>(j)] = zc[j];
    for (int i = c + 1; i < m; ++i)
      if (const double* zi = win[i])
        for (int j = 0; j < k; ++j) acc[static_cast<std::size_t>(j)] -= F[i] * zi[j];
    for (int j = 0; j < k; ++j) zc[j] = acc[static_cast<std::size_t>(j)] / F[c];
  }
  for (int c = 0; c < m; ++c)
    if (const int id = final_id(c); id >= 0 && is_free(id))
      use(id, static_cast<const double*>(win[c]), Fj[static_cast<std::size_t>(c * m + c)]);
  // Each chain's stations backward, outward from the final window.
  on_chains(backward);
}

}  // namespace trueaxis::separation::detail
