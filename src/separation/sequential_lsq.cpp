#include "sequential_lsq.hpp"

#include <algorithm>
#include <cmath>

#include "trueaxis/error.hpp"

namespace trueaxis::separation::detail {

SequentialLsq::SequentialLsq(int nvars, std::vector<int> globals)
    : nvars_(nvars),
      globals_(std::move(globals)),
      is_global_(static_cast<std::size_t>(nvars), 0),
      col_of_(static_cast<std::size_t>(nvars), -1) {
  for (int id : globals_) is_global_[static_cast<std::size_t>(id)] = 1;
  prior_.resize(0, static_cast<Eigen::Index>(globals_.size()) + 1);
}

void SequentialLsq::reset() {
  active_.clear();
  prior_.resize(0, static_cast<Eigen::Index>(globals_.size()) + 1);
  pend_ids_.clear();
  pend_coef_.clear();
  pend_rhs_.clear();
  pend_start_.assign(1, 0);
  steps_.clear();
  ids_.clear();
  vals_.clear();
  ssr_ = 0;
  rows_ = unknowns_ = 0;
  min_pivot_ = 1;
  weakest_ = -1;
}

void SequentialLsq::add_row(std::span<const std::pair<int, double>> coefs, double rhs) {
  for (const auto& [id, c] : coefs) {
    pend_ids_.push_back(id);
    pend_coef_.push_back(c);
  }
  pend_start_.push_back(pend_ids_.size());
  pend_rhs_.push_back(rhs);
  ++rows_;
}

void SequentialLsq::eliminate(const std::vector<int>& ids) {
  factor_block(ids, false);
}

void SequentialLsq::finish() {
  std::vector<int> all = active_;
  for (int id : pend_ids_)
    if (!is_global_[static_cast<std::size_t>(id)] &&
        std::find(all.begin(), all.end(), id) == all.end())
      all.push_back(id);
  all.insert(all.end(), globals_.begin(), globals_.end());
  factor_block(all, true);
}

void SequentialLsq::factor_block(const std::vector<int>& elim, bool all) {
  // Column order: eliminated ids, then the other open ids, then globals (unless eliminated).
  std::vector<int>& cols = cols_;
  cols.assign(elim.begin(), elim.end());
  for (int id : cols) col_of_[static_cast<std::size_t>(id)] = 0;
  auto add_col = [&](int id) {
    if (col_of_[static_cast<std::size_t>(id)] < 0) {
      col_of_[static_cast<std::size_t>(id)] = 0;
      cols.push_back(id);
    }
  };
  for (int id : active_) add_col(id);
  for (int id : pend_ids_)
    if (!is_global_[static_cast<std::size_t>(id)]) add_col(id);
  for (int id : globals_) add_col(id);
  const int ncols = static_cast<int>(cols.size());
  for (int j = 0; j < ncols; ++j)
    col_of_[static_cast<std::size_t>(cols[static_cast<std::size_t>(j)])] = j;

  // The block [carried information; pending rows | rhs], column-major in reused storage.
  const Eigen::Index prow = prior_.rows();
  const Eigen::Index npend = static_cast<Eigen::Index>(pend_rhs_.size());
  const Eigen::Index nrows = prow + npend;
  block_.assign(static_cast<std::size_t>(nrows * (ncols + 1)), 0.0);
  Eigen::Map<Eigen::MatrixXd> B(block_.data(), nrows, ncols + 1);
  const int na = static_cast<int>(active_.size());
  if (prow > 0) {
    for (int j = 0; j < na; ++j)
      B.col(col_of_[static_cast<std::size_t>(active_[static_cast<std::size_t>(j)])]).head(prow) =
          prior_.col(j);
    for (std::size_t g = 0; g < globals_.size(); ++g)
      B.col(col_of_[static_cast<std::size_t>(globals_[g])]).head(prow) =
          prior_.col(na + static_cast<Eigen::Index>(g));
    B.col(ncols).head(prow) = prior_.col(prior_.cols() - 1);
  }
  for (Eigen::Index r = 0; r < npend; ++r) {
    const std::size_t r0 = pend_start_[static_cast<std::size_t>(r)];
    const std::size_t r1 = pend_start_[static_cast<std::size_t>(r) + 1];
    for (std::size_t k = r0; k < r1; ++k)
      B(prow + r, col_of_[static_cast<std::size_t>(pend_ids_[k])]) += pend_coef_[k];
    B(prow + r, ncols) = pend_rhs_[static_cast<std::size_t>(r)];
  }
  pend_ids_.clear();
  pend_coef_.clear();
  pend_rhs_.clear();
  pend_start_.assign(1, 0);
  for (int id : cols) col_of_[static_cast<std::size_t>(id)] = -1;

  // Unblocked Householder QR of the coefficient columns, applied to the rhs as well. The blocks
  // are small (~10 x 10), where Eigen's blocked HouseholderQR spends its time on set-up.
  const double scale = std::max(1e-300, B.leftCols(ncols).cwiseAbs().maxCoeff());
  const Eigen::Index nref = std::min<Eigen::Index>(nrows, ncols);
  if (work_.size() < ncols + 1) work_.resize(ncols + 1);
  for (Eigen::Index k = 0; k < nref; ++k) {
    double tau = 0, beta = 0;
    B.col(k).tail(nrows - k).makeHouseholderInPlace(tau, beta);
    B(k, k) = beta;
    if (nrows - k > 1)
      B.bottomRightCorner(nrows - k, ncols - k)
          .applyHouseholderOnTheLeft(B.col(k).tail(nrows - k - 1), tau, work_.data());
  }
  // Residual: rhs part below the triangle.
  if (nrows > ncols) ssr_ += B.col(ncols).tail(nrows - ncols).squaredNorm();
  const auto& R = B;
  const Eigen::Index rank_rows = nref;
  const int nelim = static_cast<int>(elim.size());

  Step s;
  s.nelim = nelim;
  s.ncols = ncols;
  s.id_at = ids_.size();
  s.val_at = vals_.size();
  ids_.insert(ids_.end(), cols.begin(), cols.end());
  for (int l = 0; l < nelim; ++l) {
    const double d = l < rank_rows ? std::abs(R(l, l)) : 0.0;
    const double ratio = d / scale;
    if (ratio < min_pivot_) {
      min_pivot_ = ratio;
      weakest_ = elim[static_cast<std::size_t>(l)];
    }
    for (int j = 0; j <= ncols; ++j) vals_.push_back(l < rank_rows && j >= l ? R(l, j) : 0.0);
  }
  unknowns_ += nelim;
  steps_.push_back(s);

  if (all) {
    active_.clear();
    prior_.resize(0, 1);
    return;
  }
  // New carried information: rows nelim.. of R over the remaining columns (and the rhs).
  active_.assign(cols.begin() + nelim, cols.end() - static_cast<long>(globals_.size()));
  const Eigen::Index keep_rows = std::max<Eigen::Index>(0, nref - nelim);
  const Eigen::Index keep_cols = ncols - nelim;
  prior_.resize(keep_rows, keep_cols + 1);
  for (Eigen::Index j = 0; j <= keep_cols; ++j)
    for (Eigen::Index i = 0; i < keep_rows; ++i) {
      const Eigen::Index jj = nelim + j;
      prior_(i, j) = (nelim + i <= jj) ? R(nelim + i, jj) : 0.0;
    }
}

Eigen::VectorXd SequentialLsq::solve() const {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(nvars_);
  for (auto it = steps_.rbegin(); it != steps_.rend(); ++it) {
    const int* ids = ids_.data() + it->id_at;
    const double* v = vals_.data() + it->val_at;
    const int w = it->ncols + 1;
    for (int l = it->nelim - 1; l >= 0; --l) {
      const double* row = v + static_cast<std::size_t>(l) * static_cast<std::size_t>(w);
      double acc = row[it->ncols];
      for (int j = l + 1; j < it->ncols; ++j) acc -= row[j] * x[ids[j]];
      x[ids[l]] = row[l] != 0 ? acc / row[l] : 0.0;
    }
  }
  return x;
}

Eigen::MatrixXd SequentialLsq::solve_normal(const Eigen::MatrixXd& V) const {
  // Forward: Rᵀ y = V (rows in elimination order), then back: R z = y.
  const Eigen::Index k = V.cols();
  Eigen::MatrixXd acc = V;
  Eigen::MatrixXd y = Eigen::MatrixXd::Zero(nvars_, k);
  for (const Step& s : steps_) {
    const int* ids = ids_.data() + s.id_at;
    const double* v = vals_.data() + s.val_at;
    const int w = s.ncols + 1;
    for (int l = 0; l < s.nelim; ++l) {
      const double* row = v + static_cast<std::size_t>(l) * static_cast<std::size_t>(w);
      if (row[l] == 0) continue;
      y.row(ids[l]) = acc.row(ids[l]) / row[l];
      for (int j = l + 1; j < s.ncols; ++j) acc.row(ids[j]) -= row[j] * y.row(ids[l]);
    }
  }
  Eigen::MatrixXd z = Eigen::MatrixXd::Zero(nvars_, k);
  for (auto it = steps_.rbegin(); it != steps_.rend(); ++it) {
    const int* ids = ids_.data() + it->id_at;
    const double* v = vals_.data() + it->val_at;
    const int w = it->ncols + 1;
    for (int l = it->nelim - 1; l >= 0; --l) {
      const double* row = v + static_cast<std::size_t>(l) * static_cast<std::size_t>(w);
      if (row[l] == 0) continue;
      Eigen::RowVectorXd a = y.row(ids[l]);
      for (int j = l + 1; j < it->ncols; ++j) a -= row[j] * z.row(ids[j]);
      z.row(ids[l]) = a / row[l];
    }
  }
  return z;
}

Eigen::VectorXd SequentialLsq::covariance_diagonal() const {
  // Backward selected inversion. For a step with triangular rows [R11 R12] over
  // (eliminated e, later-eliminated r): Z_er = -R11⁻¹ R12 Z_rr,
  // Z_ee = R11⁻¹ R11⁻ᵀ + R11⁻¹ R12 Z_rr R12ᵀ R11⁻ᵀ. Z_rr is carried as a dense window over the ids
  // that earlier steps still reference.
  Eigen::VectorXd diag = Eigen::VectorXd::Zero(nvars_);
  std::vector<int> win_ids;  // ids of the carried window
  Eigen::MatrixXd win;       // their covariance
  std::vector<int> pos(static_cast<std::size_t>(nvars_), -1);
  for (auto it = steps_.rbegin(); it != steps_.rend(); ++it) {
    const int* ids = ids_.data() + it->id_at;
    const double* v = vals_.data() + it->val_at;
    const int e = it->nelim, nc = it->ncols, w = nc + 1, nr = nc - e;
    Eigen::MatrixXd R11 = Eigen::MatrixXd::Zero(e, e), R12(e, nr);
    for (int l = 0; l < e; ++l) {
      const double* row = v + static_cast<std::size_t>(l) * static_cast<std::size_t>(w);
      for (int j = l; j < e; ++j) R11(l, j) = row[j];
      for (int j = 0; j < nr; ++j) R12(l, j) = row[e + j];
      if (R11(l, l) == 0) R11(l, l) = 1e300;  // unidentifiable: reported elsewhere, keep finite
    }
    Eigen::MatrixXd Zrr(nr, nr);
    for (int a = 0; a < nr; ++a)
      for (int b = 0; b < nr; ++b) {
        const int pa = pos[static_cast<std::size_t>(ids[e + a])];
        const int pb = pos[static_cast<std::size_t>(ids[e + b])];
        if (pa < 0 || pb < 0) throw Error("internal: selected inversion lost a window variable");
        Zrr(a, b) = win(pa, pb);
      }
    const auto U = R11.triangularView<Eigen::Upper>();
    const Eigen::MatrixXd Rinv = U.solve(Eigen::MatrixXd::Identity(e, e));
    Eigen::MatrixXd Zee = Rinv * Rinv.transpose();
    Eigen::MatrixXd T(e, nr);  // R11⁻¹ R12; empty for the last block (Eigen must not see 0 columns)
    if (nr > 0) {
      T = U.solve(R12);
      Zee += T * Zrr * T.transpose();
    }
    for (int l = 0; l < e; ++l) diag[ids[l]] = Zee(l, l);
    // New window: eliminated ids followed by the old window (all of it: later steps may need any).
    std::vector<int> nids(ids, ids + e);
    for (int id : win_ids) nids.push_back(id);
    Eigen::MatrixXd nwin(static_cast<Eigen::Index>(nids.size()),
                         static_cast<Eigen::Index>(nids.size()));
    const Eigen::Index ow = static_cast<Eigen::Index>(win_ids.size());
    nwin.topLeftCorner(e, e) = Zee;
    if (ow > 0) {
      nwin.bottomRightCorner(ow, ow) = win;
      // Cross terms between eliminated ids and the whole old window: Z_e,old = -T Z_r,old.
      Eigen::MatrixXd Zr_old(nr, ow);
      for (int a = 0; a < nr; ++a)
        Zr_old.row(a) = win.row(pos[static_cast<std::size_t>(ids[e + a])]);
      Eigen::MatrixXd Ze_old = -T * Zr_old;
      nwin.topRightCorner(e, ow) = Ze_old;
      nwin.bottomLeftCorner(ow, e) = Ze_old.transpose();
    }
    // Prune: keep only ids that earlier steps reference (their non-eliminated columns).
    // The next step (earlier in elimination order) references ids among its columns e..nc; we
    // keep any id that appears as a non-eliminated column of some earlier step. Cheap rule for
    // chain structure: keep ids that are not local to this step (i.e. every id that appears as a
    // later column in the previous step). We look ahead one step.
    std::vector<int> keep;
    if (std::next(it) != steps_.rend()) {
      const Step& prev = *std::next(it);
      const int* pids = ids_.data() + prev.id_at;
      for (int j = prev.nelim; j < prev.ncols; ++j) keep.push_back(pids[j]);
    }
    for (int id : win_ids) pos[static_cast<std::size_t>(id)] = -1;
    std::vector<int> kept_idx;
    for (std::size_t i = 0; i < nids.size(); ++i)
      if (std::find(keep.begin(), keep.end(), nids[i]) != keep.end())
        kept_idx.push_back(static_cast<int>(i));
    win_ids.clear();
    win.resize(static_cast<Eigen::Index>(kept_idx.size()),
               static_cast<Eigen::Index>(kept_idx.size()));
    for (std::size_t a = 0; a < kept_idx.size(); ++a) {
      win_ids.push_back(nids[static_cast<std::size_t>(kept_idx[a])]);
      for (std::size_t b = 0; b < kept_idx.size(); ++b)
        win(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)) =
            nwin(kept_idx[a], kept_idx[b]);
    }
    for (std::size_t i = 0; i < win_ids.size(); ++i)
      pos[static_cast<std::size_t>(win_ids[i])] = static_cast<int>(i);
  }
  return diag;
}

}  // namespace trueaxis::separation::detail
