// Private: sequential (square-root information) least squares for long chain-structured systems.
//
// The system is ||A v - b||² over variables v identified by integer ids in [0, nvars). Rows are
// added in batches; after each batch the caller names the variables that no later row touches
// and the engine eliminates them with a small dense Householder QR (Eigen) of the batch stacked
// on the information carried so far. "Global" variables (probe offsets) stay in the carried
// information until finish(). This is a banded QR with a dense border: backward stable (errors
// like the seed's own recurrences, not the squared condition of normal equations), O(n) time,
// and the stored triangular rows give the solution, the exact diagonal of (AᵀA)⁻¹ by a backward
// selected-inversion pass, and (AᵀA)⁻¹V for a few columns V.
#pragma once

#include <Eigen/Dense>
#include <span>
#include <utility>
#include <vector>

namespace trueaxis::separation::detail {

class SequentialLsq {
 public:
  SequentialLsq(int nvars, std::vector<int> globals);

  // Forgets every row and factor but keeps the storage, so a second pass over a system of the
  // same shape (iterative refinement) allocates nothing.
  void reset();

  // Adds one row sum_j coef_j * v[id_j] = rhs. Ids must be distinct within a row.
  void add_row(std::span<const std::pair<int, double>> coefs, double rhs);
  // Eliminates `ids` (in this order) using the pending rows and the carried information.
  void eliminate(const std::vector<int>& ids);
  // Eliminates everything still open, globals last.
  void finish();

  double ssr() const { return ssr_; }
  long rows() const { return rows_; }
  long unknowns() const { return unknowns_; }
  // Smallest |R_ii| relative to its block's scale, and the variable where it occurred.
  double min_pivot_ratio() const { return min_pivot_; }
  int weakest_variable() const { return weakest_; }

  // Least-squares solution (ids never eliminated stay 0).
  Eigen::VectorXd solve() const;
  // diag((AᵀA)⁻¹) for every eliminated id (others 0).
  Eigen::VectorXd covariance_diagonal() const;
  // (AᵀA)⁻¹ V for V with nvars rows (rows of never-eliminated ids are ignored/0).
  Eigen::MatrixXd solve_normal(const Eigen::MatrixXd& V) const;

 private:
  struct Step {
    int nelim = 0;       // eliminated ids are cols[0..nelim)
    int ncols = 0;       // columns of the block (excluding rhs)
    std::size_t id_at;   // offset into ids_
    std::size_t val_at;  // offset into vals_: nelim rows of (ncols + 1) values (last = rhs)
  };
  void factor_block(const std::vector<int>& elim, bool all);

  int nvars_;
  std::vector<int> globals_;
  std::vector<char> is_global_;  // by id
  std::vector<int> active_;      // open non-global ids carried in prior_
  Eigen::MatrixXd prior_;        // rows x (active_ + globals_ + 1)
  // Pending rows, flat: row r has entries [pend_start_[r], pend_start_[r + 1]).
  std::vector<int> pend_ids_;
  std::vector<double> pend_coef_, pend_rhs_;
  std::vector<std::size_t> pend_start_{0};
  std::vector<Step> steps_;
  std::vector<int> ids_;
  std::vector<double> vals_;
  std::vector<int> col_of_;  // scratch: id -> block column, -1 when absent
  double ssr_ = 0;
  long rows_ = 0, unknowns_ = 0;
  double min_pivot_ = 1;
  int weakest_ = -1;
  // Scratch reused by every block (no allocation per station once warm).
  std::vector<int> cols_;
  std::vector<double> block_;
  Eigen::VectorXd work_;
};

}  // namespace trueaxis::separation::detail
