// Uncertainties of the two- and three-point separations by exact propagation of every reading
// through the recurrence: the diagonal of Z = T·Tᵀ in closed form, ZV by the adjoint recurrence
// backwards and the recurrence forwards, k columns at once. O(n·k) work.
#include <Eigen/Dense>
#include <Eigen/StdVector>
#include <algorithm>
#include <vector>

#include "reference_algebra.hpp"
#include "solution.hpp"

namespace trueaxis::separation::detail {
namespace {

// Σ z·zᵀ over the adjoint vectors z of a propagation (k ≤ kMaxCols entries each), summed a block
// of z at a time: a 6 × 6 outer product per z loaded and stored all of the sum for 36
// multiply-adds, which dominated the adjoint pass.
class GramSum {
 public:
  using Row = ReferenceAlgebra::Row;
  explicit GramSum(int k) : k_(k) { G_.setZero(); }
  void add(const Row& z) {
    zs_.col(zn_++) = z;
    if (zn_ == kBlock) flush();
  }
  // The sum restricted to a profile's columns.
  Eigen::Matrix3d restricted(const ReferenceAlgebra::Cols& c) {
    flush();
    return ReferenceAlgebra::restrict(G_.topLeftCorner(k_, k_), c);
  }

 private:
  static constexpr int kBlock = 192;
  // The k·(k+1)/2 distinct entries, as dot products of contiguous rows. Out of line: inlined into
  // the two-point propagation's loop it made that loop 38 % slower.
  [[gnu::noinline]] void flush() {
    if (zn_ == 0) return;
    // Each dot product as four independent sums over the block's quarters: one sum was a chain
    // of dependent vector additions (latency, not throughput, bound).
    const int q = zn_ / 4;
    for (int i = 0; i < k_; ++i)
      for (int j = 0; j <= i; ++j) {
        const double* a = zs_.row(i).data();
        const double* b = zs_.row(j).data();
        double a0 = 0, a1 = 0, a2 = 0, a3 = 0;
#pragma omp simd reduction(+ : a0, a1, a2, a3)
        for (int c = 0; c < q; ++c) {
          a0 += a[c] * b[c];
          a1 += a[c + q] * b[c + q];
          a2 += a[c + 2 * q] * b[c + 2 * q];
          a3 += a[c + 3 * q] * b[c + 3 * q];
        }
        for (int c = 4 * q; c < zn_; ++c) a0 += a[c] * b[c];
        const double acc = (a0 + a1) + (a2 + a3);
        G_(i, j) += acc;
        if (j != i) G_(j, i) += acc;
      }
    zn_ = 0;
  }
  int k_;
  int zn_ = 0;
  Eigen::Matrix<double, ReferenceAlgebra::kMaxCols, ReferenceAlgebra::kMaxCols> G_;
  Eigen::Matrix<double, ReferenceAlgebra::kMaxCols, kBlock, Eigen::RowMajor> zs_;
};

}  // namespace

// Standard uncertainties (for noise variance noise_var per reading) of the two- and three-point
// results by exact propagation of every reading through the recurrence. T, the map from readings
// to the raw unknowns, is taken with the gauge X_0 = X_1 = 0 and without the first-reading
// offsets: it differs from the method's own map only by lines (and, for three-point, a parabola)
// that the reference removes, so the reported values, and their variances, are the same.
// Z = T·Tᵀ:
// - diag(Z) in closed form (sums of squared integer coefficients);
// - ZV = T·(TᵀV): the adjoint recurrence backwards, then the recurrence forwards, k columns at
//   once; VᵀZV = (TᵀV)ᵀ(TᵀV), the Gram matrix of the adjoint vectors, is summed in the backward
//   pass.
// O(n·k) work and one n × k array, where the least-squares covariance needs a banded
// factorisation, a selected inversion and a solve over all 3n unknowns.
void recurrence_uncertainties(const ProbeData& d, Method method, const Raw& r, bool with_pitch,
                              double noise_var, Eigen::VectorXd& uw, Eigen::VectorXd& ug,
                              Eigen::VectorXd& ut) {
  using Row = ReferenceAlgebra::Row;
  const long n = d.x.size();
  const ReferenceAlgebra ra(r, with_pitch, true, d.step());
  GramSum gram(ra.k);
  // The adjoint state per station (written from the last station back, every entry before it is
  // read) and the variances, their pages committed on another core meanwhile.
  std::vector<Row, Eigen::aligned_allocator<Row>> back(
      static_cast<std::size_t>(method == Method::TwoPoint ? n + 1 : std::max<long>(n - 2, 0)));
  const detail::Prefault prefault =
      results_committed(ra.mw, ra.mg, ra.mt, uw, ug, ut,
                        detail::Prefault::Region{back.data(), sizeof(Row) * back.size()});

  if (method == Method::TwoPoint) {
    // w_0 = 0, w_{K+1} = w_K + B_K − A_K (K < n); g_K = A_K − w_K. Var w_j = 2j, var g_K = 1 + 2K.
    // Adjoint: w̄_j = vw_j − vg_j + w̄_{j+1}; z_B[K] = w̄_{K+1}, z_A[K] = vg_K − w̄_{K+1}.
    Row wb = Row::Zero();
    for (long j = n; j >= 1; --j) {
      wb += ra.vw(j) - ra.vg(j);
      back[static_cast<std::size_t>(j)] = wb;
      gram.add(wb);                 // z_B[j − 1]
      gram.add(ra.vg(j - 1) - wb);  // z_A[j − 1]
    }
    const Eigen::Matrix3d Sw = gram.restricted(ra.cw), Sg = gram.restricted(ra.cg);
    Row Y = Row::Zero();  // (T z) at w_j
    for (long j = 0; j <= n; ++j) {
      uw[j] = ReferenceAlgebra::point_uncertainty<false>(
          ra.uw(j), ra.cw, Sw, 2.0 * static_cast<double>(j), Y.data(), 1.0, noise_var);
      if (j == n) break;
      const Row zB = back[static_cast<std::size_t>(j + 1)];
      const Row zA = ra.vg(j) - zB;
      const Row gz = zA - Y;
      ug[j] = ReferenceAlgebra::point_uncertainty<false>(
          ra.ug(j), ra.cg, Sg, 1.0 + 2.0 * static_cast<double>(j), gz.data(), 1.0, noise_var);
      Y += zB - zA;
    }
    take_square_roots(uw, ug, ut);
    return;
  }

  // Three-point: X_0 = X_1 = 0, X_{K+2} = 2X_{K+1} − X_K + r_K with
  // r_K = −2A_{K+1} + A_{K+2} + 2B_K − C_K; w_K = A_K − X_K, g_K = X_K and the pitch unknown
  // (θ·h) t_K = B_K − A_{K+1} + X_{K+1} − X_K.
  // Adjoint: X̄_K = λ_K + 2X̄_{K+1} − X̄_{K+2} (K ≥ 2) with λ_K = −vw_K + vg_K + vt_{K−1} − vt_K;
  // r̄_K = X̄_{K+2}; z_A[i] = vw_i − vt_{i−1} − 2r̄_{i−1} + r̄_{i−2}, z_B[i] = vt_i + 2r̄_i,
  // z_C[i] = −r̄_i.
  // back holds r̄_0..r̄_{n−3}.
  auto rb = [&](long K) -> Row {
    return K >= 0 && K + 2 < n ? back[static_cast<std::size_t>(K)] : Row(Row::Zero());
  };
  auto zA = [&](long i) -> Row { return ra.vw(i) - ra.vt(i - 1) - 2 * rb(i - 1) + rb(i - 2); };
  auto zB = [&](long i) -> Row { return ra.vt(i) + 2 * rb(i); };
  {
    // Each z is summed into the Gram matrix as soon as the r̄ it needs are known: z_B and z_C at
    // K − 2 with r̄_{K−2}, z_A at K with r̄_{K−1} and r̄_{K−2}; the first two z_A and the last
    // two z_B (no r̄ of their own) after the loop.
    Row x1 = Row::Zero(), x2 = Row::Zero();  // X̄_{K+1} = r̄_{K−1}, X̄_{K+2}
    for (long K = n - 1; K >= 2; --K) {
      const Row x = ra.vg(K) - ra.vw(K) + ra.vt(K - 1) - ra.vt(K) + 2 * x1 - x2;
      back[static_cast<std::size_t>(K - 2)] = x;
      gram.add(ra.vt(K - 2) + 2 * x);  // z_B[K − 2]
      gram.add(x);                     // z_C[K − 2] = −r̄: sign irrelevant here
      gram.add(ra.vw(K) - ra.vt(K - 1) - 2 * x1 + x);  // z_A[K]
      x2 = x1;
      x1 = x;
    }
    for (long i : {0L, 1L}) gram.add(zA(i));
    for (long i : {n - 2, n - 1}) gram.add(zB(i));
  }
  const Eigen::Matrix3d Sw = gram.restricted(ra.cw), Sg = gram.restricted(ra.cg),
                        St = ra.pitch ? gram.restricted(ra.ct) : Eigen::Matrix3d::Zero();
  // Var X_K = the sum of its squared reading coefficients: B_j 2(K−1−j) and C_j −(K−1−j)
  // (j ≤ K−2), A_1 −2(K−1), A_i −(K−1−i) (2 ≤ i ≤ K), for K ≥ 2. Var w_K = var X_K − 1 (the
  // coefficient of A_K in X_K is 1), var t_K = 6K + 4 (K ≥ 1).
  auto s2 = [](double m) { return m * (m + 1) * (2 * m + 1) / 6; };
  auto var_x = [&](long K) {
    if (K < 2) return 0.0;
    const double q = static_cast<double>(K);
    return 5 * s2(q - 1) + 1 + s2(q - 3) + 4 * (q - 1) * (q - 1);
  };
  Row y0 = Row::Zero(), y1 = Row::Zero();  // (T z) at X_K, X_{K+1}
  Row a0 = zA(0), a1 = zA(1);              // z_A[K], z_A[K+1]
  for (long K = 0; K < n; ++K) {
    const Row a2 = zA(K + 2);
    const Row w = a0 - y0;
    uw[K] = ReferenceAlgebra::point_uncertainty<false>(
        ra.uw(K), ra.cw, Sw, K < 2 ? 1.0 : var_x(K) - 1, w.data(), 1.0, noise_var);
    ug[K] = ReferenceAlgebra::point_uncertainty<false>(ra.ug(K), ra.cg, Sg, var_x(K), y0.data(),
                                                       1.0, noise_var);
    const Row b = zB(K);
    if (K < ra.mt) {
      const Row t = b - a1 + y1 - y0;
      ut[K] = ReferenceAlgebra::point_uncertainty<false>(
          ra.ut(K), ra.ct, St, K == 0 ? 2.0 : 6.0 * static_cast<double>(K) + 4, t.data(),
          1.0 / ra.h, noise_var);
    }
    const Row y2 = K + 2 < n ? Row(2 * y1 - y0 - 2 * a1 + a2 + 2 * b + rb(K)) : Row(Row::Zero());
    y0 = y1;
    y1 = y2;
    a0 = a1;
    a1 = a2;
  }
  take_square_roots(uw, ug, ut);
}

}  // namespace trueaxis::separation::detail
