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
//      globals, rhs] by Givens rotations. Once station K is in, no later row touches w(K): the
//      window's first row is w(K)'s row of R, stored, and the window slides by one position.
// This is the QR factorisation of the whole system in the order (g, θ, w)(K) station by station,
// globals last: backward stable, O(n·(span + G)²) time, O(n·(span + G)) memory, no allocation per
// station. The stored rows give the solution, the exact diagonal of (AᵀA)⁻¹ (a backward selected
// inversion), and (AᵀA)⁻¹V for a few columns.
//
// The unknowns are numbered as in Design; pinned unknowns are held at their pin values.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "design.hpp"

namespace trueaxis::separation::detail {

// A vector whose resize leaves new elements uninitialised: large buffers that are written before
// they are read cost no zeroing pass, and pages never written are never committed.
template <class T>
struct DefaultInitAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = DefaultInitAllocator<U>;
  };
  using std::allocator<T>::allocator;
  template <class U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};
template <class T>
using Uninitialized = std::vector<T, DefaultInitAllocator<T>>;

class BandedLsq {
 public:
  // The design must outlive the solver.
  explicit BandedLsq(const Design& design);

  // Factorises the system for the right-hand side b − A·v: b holds, per station, the probe
  // readings minus `mu` (n × N) and, with an angle channel, wa·angle_mm[K]. v holds a value for
  // every unknown (pinned ones at their pin values). Afterwards solve() gives the correction to v.
  void factor(const Eigen::MatrixXd& readings, const Eigen::RowVectorXd& mu,
              const Eigen::VectorXd& angle_mm, const Eigen::VectorXd& v);

  // The same for a new v, reusing the last factorisation's rotations when they were kept (the
  // coefficients do not change): only the right-hand side is transformed.
  void refactor_rhs(const Eigen::MatrixXd& readings, const Eigen::RowVectorXd& mu,
                    const Eigen::VectorXd& angle_mm, const Eigen::VectorXd& v);

  double ssr() const { return ssr_; }  // squared residual norm of the last factorisation
  long rows() const { return rows_; }
  long unknowns() const { return unknowns_; }
  // Smallest |R_ii| relative to the coefficients' scale (small: a mode the data do not fix).
  double min_pivot_ratio() const { return min_pivot_; }

  // Adds the least-squares correction to v (pinned unknowns unchanged), without a vector of
  // corrections. Returns the largest |correction| and the largest |v| after the update, both over
  // the free unknowns.
  struct Update {
    double max_correction = 0;
    double max_value = 0;
  };
  Update solve_add(Eigen::VectorXd& v) const;
  // diag((AᵀA)⁻¹) over the free unknowns (pinned 0).
  Eigen::VectorXd covariance_diagonal() const;
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  // Overwrites V (one row per unknown, a few columns) with (AᵀA)⁻¹ V; rows of pinned unknowns
  // are ignored and returned 0. Row-major, so one unknown's values are adjacent.
  void solve_normal_in_place(RowMajor& V) const;

 private:
  // Forms the right-hand sides b − A·v block by block, stores each station's local ones and
  // calls fn(K, reduced) in station order, reduced(r) giving its reduced right-hand side r.
  template <class Fn>
  void for_each_station(const Eigen::MatrixXd& readings, const Eigen::RowVectorXd& mu,
                        const Eigen::VectorXd& angle_mm, const Eigen::VectorXd& v, Fn&& fn);
  template <int Width>  // window width, 0: any
  void factor_impl(const Eigen::MatrixXd& readings, const Eigen::RowVectorXd& mu,
                   const Eigen::VectorXd& angle_mm, const Eigen::VectorXd& v);
  int id_of(long K, int c) const;  // unknown at window column c when the window starts at w(K)
  bool active(int id) const;       // a free unknown that exists
  template <int Cols>              // 0: any
  void solve_normal_impl(RowMajor& z) const;

  const Design& D_;
  int L_ = 0;                   // local unknowns per station: g (and θ)
  int M_ = 0;                   // rows per station
  int nb_ = 0;                  // band width: span + 1
  int G_ = 0;                   // free globals
  int m_ = 0;                   // window columns: nb + G
  std::vector<int> globals_;    // their ids
  RowMajor Qt_;                 // M × M: the constant row transform
  Eigen::MatrixXd Rloc_;        // L × L, upper triangular
  Eigen::MatrixXd Cloc_;        // L × m: local equations over the window columns
  RowMajor Cred_;               // (M − L) × m: reduced rows over the window columns
  std::vector<long> pinned_w_;  // pinned workpiece positions, ascending

  // Factorisation: per station, w(K)'s row of R over the window (m values, the same for every
  // right-hand side), its transformed right-hand side and the local equations' right-hand sides;
  // the final window over [w(n..n+span), globals] with its right-hand side.
  Uninitialized<double> rw_;    // n × m
  Uninitialized<double> qb_;    // n
  Uninitialized<double> bloc_;  // n × L
  std::vector<double> final_;   // m × (m + 1)
  // The Givens rotations (cos, sin) in the order applied: per station and reduced row, those
  // whose row entry was nonzero, with a mask of their window columns (masked_), or all of them
  // (windows wider than 64 columns).
  static constexpr std::size_t kRotationBudgetBytes = std::size_t{256} << 20;
  bool keep_rotations_ = false;
  bool masked_ = true;
  int mask_bytes_ = 1;
  Uninitialized<double> rot_;
  Uninitialized<unsigned char> rot_mask_;  // per station and reduced row: mask_bytes_ bytes
  double ssr_ = 0;
  long rows_ = 0, unknowns_ = 0;
  double min_pivot_ = 1;
  double scale_ = 1;
};

}  // namespace trueaxis::separation::detail
