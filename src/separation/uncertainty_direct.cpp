// Uncertainties of the least-squares separation of the layout without redundancy (three probes at
// 0, 1 and 2 steps), by exact propagation of every reading through its recurrence, in blocks of
// stations that fit the first-level cache. They need the grids only, so they run while the
// solve does.
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <memory>
#include <stdexcept>
#include <vector>

#include "reference_algebra.hpp"
#include "solution.hpp"

namespace trueaxis::separation::detail {
namespace {

// Standard uncertainties (for noise variance noise_var per reading) of the least-squares results
// of the layout without redundancy (solve_lsq_direct), on its grids, by exact propagation of
// every reading as recurrence_uncertainties does. With the gauge w_0 = w_1 = 0, β = 0 and zero
// offsets (the reference removes the difference, as there) the map T from the readings a, b, c of
// probes A, B, C to the raw unknowns is
//   w_{K+2} = 2w_{K+1} − w_K + a_K − 2b_K + c_K,  g_K = a_K − w_K,  t_K = b_K − a_K − w_{K+1} + w_K
// (t the pitch unknown θ·h). Adjoint: X_K = W̄_{K+2} = λ_{K+2} + 2X_{K+1} − X_{K+2} (from
// X_n = X_{n+1} = 0) with λ_j = vw_j − vg_j + vt_j − vt_{j−1}; the adjoint vectors are
// z_a[K] = P_K + X_K, z_b[K] = vt_K − 2X_K and z_c[K] = X_K (P = vg − vt), so that
//   VᵀZV = Σ z·zᵀ = Σ (P·Pᵀ + vt·vtᵀ) + Σ (Q·Xᵀ + X·Qᵀ) + 6·Σ X·Xᵀ,  Q = vg − 3vt,
// and (ZV) = T·(TᵀV) runs forwards as y_{K+2} = 2y_{K+1} − y_K + Q_K + 6X_K (y_0 = y_1 = 0),
// the row of w_K being y_K. Diagonal: var w_j = (j − 1)·j·(2j − 1), var g_K = 1 + var w_K,
// var t_K = 2 + 6K. It uses the grids only (not the readings): the solve can run meanwhile.
//
// Each of V's columns is its own recurrence, and every station's variance is independent once the
// recurrences have reached it: the stations are taken in blocks that fit the first-level cache,
// one array per column. Per block, the recurrences run station by station (two additions per
// column and station, as X_K − X_{K+1} and y_{K+1} − y_K are sums), and everything else (V's
// entries, the Gram sums, the variances and their square roots) runs across stations, four at a
// time. The backward pass keeps only each block's starting state; the forward pass runs the
// block's backward recurrence again from it (the same code on the same numbers, so the same X)
// instead of keeping an n × k array of adjoint vectors.
template <bool Par, bool Pitch>
class DirectPropagation {
 public:
  static constexpr int kW0 = ReferenceAlgebra::kW0, kW1 = kW0 + 1, kG0 = ReferenceAlgebra::kG0,
                       kG1 = kG0 + 1, kPhi = Par ? 4 : -1, kT = Pitch ? 4 + Par : -1,
                       kCols = 4 + Par + Pitch, kBlock = 256;
  // The block's columns after X's: ones, the guide's line slope b1(x_K) and φ(x_K).
  static constexpr int kOnes = kCols, kB1 = kCols + 1, kPhiX = kCols + 2;

  DirectPropagation(const ReferenceAlgebra& ra, double h)
      : ra_(ra), n_(ra.mg), xg_(ra.r.xg.data()), h_(h) {
    for (int i = 0; i < kBlock; ++i) {
      m_[kOnes][i] = 1.0;
      m_[kPhiX][i] = 0.0;  // without the parabola
    }
    if (ra.kPhi != kPhi || ra.kT != kT || ra.mw != n_ + 2 || (Pitch && ra.mt != n_))
      throw std::logic_error("direct propagation: grids or columns do not match the layout");
  }

  void run(double noise_var, Eigen::VectorXd& uw, Eigen::VectorXd& ug, Eigen::VectorXd& ut) {
    const long blocks = (n_ + kBlock - 1) / kBlock;
    std::vector<State> starts(static_cast<std::size_t>(blocks));
    // Backward: the adjoint, block by block from the last station, and the Gram sums.
    State s;
    Sums sums;
    for (long b = blocks - 1; b >= 0; --b) {
      const long lo = b * kBlock;
      const int len = static_cast<int>(std::min<long>(kBlock, n_ - lo));
      starts[static_cast<std::size_t>(b)] = s;
      lambda(lo, len);
      backward(s, len);
      guide_entries(lo, len);
      sums.add(m_, len);
    }
    gram(sums);
    // Forward: y, and every station's variances.
    std::array<double, kCols> y{}, dy{};  // y_K and y_{K+1} − y_K
    double* __restrict pw = uw.data();
    double* __restrict pg = ug.data();
    double* __restrict pt = Pitch ? ut.data() : nullptr;
    for (long b = 0; b < blocks; ++b) {
      const long lo = b * kBlock;
      const int len = static_cast<int>(std::min<long>(kBlock, n_ - lo));
      State x0 = starts[static_cast<std::size_t>(b)];
      lambda(lo, len);
      backward(x0, len);
      guide_entries(lo, len);
      forward(y, dy, len);
      variances(lo, len, noise_var, pw, pg, pt);
    }
    // The two workpiece points beyond the last station: y_n and y_{n+1}.
    ReferenceAlgebra::Row yn = ReferenceAlgebra::Row::Zero();
    for (long j : {n_, n_ + 1}) {
      for (int c = 0; c < kCols; ++c) yn[c] = j == n_ ? y[c] : y[c] + dy[c];
      const double q = static_cast<double>(j);
      uw[j] = ReferenceAlgebra::point_uncertainty(ra_.uw(j), ra_.cw, sw_, (q - 1) * q * (2 * q - 1),
                                                  yn.data(), 1.0, noise_var);
    }
  }

 private:
  struct State {
    std::array<double, kCols> x{}, d{};  // X_K and X_K − X_{K+1} at a block's end
  };
  // Σ X·Xᵀ, Σ X, Σ X·b1(x) and Σ X·φ(x) over the stations (X·Qᵀ's parts): each of X's columns
  // against the block's [X, 1, b1, φ], all kCols + 3 sums in one pass over the block (a general
  // matrix product spent more time packing these small blocks than multiplying).
  struct Sums {
    static constexpr int kM = kCols + 3;
    Eigen::Matrix<double, kCols, kM> xm = Eigen::Matrix<double, kCols, kM>::Zero();
    // Named accumulators: an array reduction was summed in order, one lane at a time.
    void add(const double (&m)[kM][kBlock], int len) {
      static_assert(kM >= 7 && kM <= 9);
      for (int c = 0; c < kCols; ++c) {
        const double* a = m[c];
        double s0 = 0, s1 = 0, s2 = 0, s3 = 0, s4 = 0, s5 = 0, s6 = 0, s7 = 0, s8 = 0;
#pragma omp simd reduction(+ : s0, s1, s2, s3, s4, s5, s6, s7, s8)
        for (int i = 0; i < len; ++i) {
          const double v = a[i];
          s0 += v * m[0][i];
          s1 += v * m[1][i];
          s2 += v * m[2][i];
          s3 += v * m[3][i];
          s4 += v * m[4][i];
          s5 += v * m[5][i];
          s6 += v * m[6][i];
          if constexpr (kM > 7) s7 += v * m[7][i];
          if constexpr (kM > 8) s8 += v * m[8][i];
        }
        const double sum[] = {s0, s1, s2, s3, s4, s5, s6, s7, s8};
        for (int d = 0; d < kM; ++d) xm(c, d) += sum[d];
      }
    }
  };

  // λ_{K+2} of every column for the block's stations K = lo … lo + len − 1, into m_. The guide's
  // rows end at station n − 1; the pitch's part is a single −1, at K + 2 = mt.
  void lambda(long lo, int len) {
    const int inside = static_cast<int>(std::clamp<long>(n_ - 2 - lo, 0, len));
    const double* xg = xg_ + lo + 2;
    const double bw = ra_.lw.b0, bg = ra_.lg.b0, base = static_cast<double>(lo + 2);
#pragma omp simd
    for (int i = 0; i < len; ++i) {
      m_[kW0][i] = bw;
      m_[kW1][i] = ra_.lw.b1(workpiece_x(base + static_cast<double>(i)));
    }
#pragma omp simd
    for (int i = 0; i < inside; ++i) {
      m_[kG0][i] = -bg;
      m_[kG1][i] = -ra_.lg.b1(xg[i]);
      if constexpr (Par) m_[kPhi][i] = -ra_.phi(xg[i]);
      if constexpr (Pitch) m_[kT][i] = 0.0;
    }
    for (int i = inside; i < len; ++i)
      for (int c = kG0; c < kCols; ++c) m_[c][i] = 0.0;
    if constexpr (Pitch)
      if (const long spike = ra_.mt - 2 - lo; spike >= 0 && spike < len) m_[kT][spike] = -1.0;
  }
  // X_K = X_{K+1} + (X_K − X_{K+1}) and X_K − X_{K+1} = λ_{K+2} + (X_{K+1} − X_{K+2}), over the
  // block from its last station back, λ replaced by X in m_.
  void backward(State& s, int len) {
    std::array<double, kCols> x = s.x, d = s.d;
    for (int i = len - 1; i >= 0; --i) {
#pragma GCC unroll 8
      for (int c = 0; c < kCols; ++c) {
        d[c] += m_[c][i];
        x[c] += d[c];
        m_[c][i] = x[c];
      }
    }
    s.x = x;
    s.d = d;
  }
  // The guide's line slope b1(x_K) and φ(x_K) at the block's stations.
  void guide_entries(long lo, int len) {
    const double* xg = xg_ + lo;
#pragma omp simd
    for (int i = 0; i < len; ++i) {
      m_[kB1][i] = ra_.lg.b1(xg[i]);
      if constexpr (Par) m_[kPhiX][i] = ra_.phi(xg[i]);
    }
  }
  // VᵀZV from the sums, and its restrictions to the three profiles' columns.
  void gram(const Sums& sums) {
    const auto local = ra_.local_gram<kCols>(kPhi, kT);  // Σ vg·vgᵀ, Σ vg·vtᵀ, Σ vt·vtᵀ
    Eigen::MatrixXd G(kCols, kCols);
    for (int a = 0; a < kCols; ++a)
      for (int b = 0; b < kCols; ++b) {
        auto at = [&](int block, int i, int j) {
          return local[static_cast<std::size_t>(block * kCols * kCols + i * kCols + j)];
        };
        G(a, b) = at(0, a, b) - at(1, a, b) - at(1, b, a) + 2 * at(2, a, b) + 6 * sums.xm(a, b);
      }
    // Q·Xᵀ + X·Qᵀ with Q = (b0, b1(x), φ(x), −3) in the guide's, parabola's and pitch's columns.
    auto add_q = [&](int q, int sum, double scale) {
      for (int c = 0; c < kCols; ++c) {
        G(q, c) += scale * sums.xm(c, sum);
        G(c, q) += scale * sums.xm(c, sum);
      }
    };
    add_q(kG0, kOnes, ra_.lg.b0);
    add_q(kG1, kB1, 1.0);
    if constexpr (Par) add_q(kPhi, kPhiX, 1.0);
    if constexpr (Pitch) add_q(kT, kOnes, -3.0);
    sw_ = ReferenceAlgebra::restrict(G, ra_.cw);
    sg_ = ReferenceAlgebra::restrict(G, ra_.cg);
    if constexpr (Pitch) st_ = ReferenceAlgebra::restrict(G, ra_.ct);
  }
  // y_K for the block's stations and the one after (y_{K+1} − y_K = previous + Q_K + 6X_K).
  void forward(std::array<double, kCols>& y, std::array<double, kCols>& dy, int len) {
    const double bg = ra_.lg.b0;
    for (int i = 0; i < len; ++i) {
#pragma GCC unroll 8
      for (int c = 0; c < kCols; ++c) {
        double q = 0.0;
        if (c == kG0) q = bg;
        if (c == kG1) q = m_[kB1][i];
        if (c == kPhi) q = m_[kPhiX][i];
        if (c == kT) q = -3.0;
        y_[c][i] = y[c];
        y[c] += dy[c];
        dy[c] += q + 6 * m_[c][i];
      }
    }
    for (int c = 0; c < kCols; ++c) y_[c][len] = y[c];
  }
  // The block's standard uncertainties: u·S·u + scale²·var − 2·scale·u·(ZV)_u for each profile
  // (see ReferenceAlgebra::point_uncertainty), written out across stations.
  void variances(long lo, int len, double noise_var, double* __restrict pw, double* __restrict pg,
                 double* __restrict pt) const {
    const ReferenceAlgebra& ra = ra_;
    const Eigen::Matrix3d &Sw = sw_, &Sg = sg_, &St = st_;
    const double w00 = Sw(0, 0), w01 = Sw(0, 1), w02 = Sw(0, 2), w11 = Sw(1, 1), w12 = Sw(1, 2),
                 w22 = Sw(2, 2);
    const double g00 = Sg(0, 0), g01 = Sg(0, 1), g02 = Sg(0, 2), g11 = Sg(1, 1), g12 = Sg(1, 2),
                 g22 = Sg(2, 2);
    const double t00 = St(0, 0), t01 = St(0, 1), t11 = St(1, 1);
    auto quad = [](double a, double b, double c, double s00, double s01, double s02, double s11,
                   double s12, double s22) {
      return a * (s00 * a + 2 * (s01 * b + s02 * c)) + b * (s11 * b + 2 * s12 * c) + c * s22 * c;
    };
    const double bw = ra.lw.b0, bg = ra.lg.b0, inv_h = 1 / h_;
    const double tu0 = Pitch ? 1.0 / (h_ * static_cast<double>(ra.mt)) : 0.0;
    const double* xg = xg_ + lo;
    const double base = static_cast<double>(lo);
    double *w = pw + lo, *g = pg + lo, *t = Pitch ? pt + lo : nullptr;
#pragma omp simd
    for (int i = 0; i < len; ++i) {
      const double q = base + static_cast<double>(i);
      const double var_w = (q - 1) * q * (2 * q - 1);
      // Workpiece point K: its row of ZV is y_K.
      const double xw = workpiece_x(q);
      const double u1 = ra.lw.b1(xw);
      const double u2 = Par ? -(ra.t2(xw) - bw * ra.pw0 - u1 * ra.pw1) : 0.0;
      double uy = bw * y_[kW0][i] + u1 * y_[kW1][i];
      if constexpr (Par) uy += u2 * y_[kPhi][i];
      const double vw = quad(bw, u1, u2, w00, w01, w02, w11, w12, w22) + var_w - 2 * uy;
      w[i] = std::max(0.0, vw) * noise_var;
      // Guide point K: z_a[K] − y_K.
      const double g1 = m_[kB1][i];
      const double g2 = Par ? ra.t2(xg[i]) - bg * ra.pg0 - g1 * ra.pg1 : 0.0;
      double gz = bg * (bg + m_[kG0][i] - y_[kG0][i]) + g1 * (g1 + m_[kG1][i] - y_[kG1][i]);
      if constexpr (Par) gz += g2 * (m_[kPhiX][i] + m_[kPhi][i] - y_[kPhi][i]);
      const double vg = quad(bg, g1, g2, g00, g01, g02, g11, g12, g22) + 1 + var_w - 2 * gz;
      g[i] = std::max(0.0, vg) * noise_var;
      // Pitch at K: z_b[K] − z_a[K] − y_{K+1} + y_K.
      if constexpr (Pitch) {
        const double tu1 = Par ? ra.lin(xg[i]) - ra.lin_mean : 0.0;
        double tz = tu0 * (2 - 3 * m_[kT][i] - y_[kT][i + 1] + y_[kT][i]);
        if constexpr (Par)
          tz += tu1 * (-m_[kPhiX][i] - 3 * m_[kPhi][i] - y_[kPhi][i + 1] + y_[kPhi][i]);
        const double vt = tu0 * (t00 * tu0 + 2 * t01 * tu1) + tu1 * t11 * tu1 +
                          inv_h * inv_h * (2 + 6 * q) - 2 * inv_h * tz;
        t[i] = std::max(0.0, vt) * noise_var;
      }
    }
    // The square roots, four per instruction (std::sqrt in the loop above kept it scalar).
    auto roots = [len](double* v) {
      Eigen::Map<Eigen::ArrayXd> a(v, len);
      a = a.sqrt();
    };
    roots(w);
    roots(g);
    if constexpr (Pitch) roots(t);
  }

  double workpiece_x(double j) const {
    return workpiece_position(xg_[0], j, h_);
  }

  const ReferenceAlgebra& ra_;
  const long n_;
  const double* xg_;
  const double h_;
  Eigen::Matrix3d sw_, sg_, st_ = Eigen::Matrix3d::Zero();
  // The block's columns: λ, then X, and the columns kOnes, kB1, kPhiX; y (one station more).
  alignas(64) double m_[kCols + 3][kBlock];
  alignas(64) double y_[kCols][kBlock + 1];
};

}  // namespace

// x: the stations; parabola_free: as solve_lsq_direct's (no known zero difference).
void direct_uncertainties(const Eigen::VectorXd& x, bool parabola_free, bool with_pitch, double h,
                          double noise_var, Eigen::VectorXd& uw, Eigen::VectorXd& ug,
                          Eigen::VectorXd& ut) {
  // The guide's and pitch's grids are the stations themselves; only the workpiece's is made.
  const Eigen::Index n = x.size();
  Eigen::VectorXd xw;
  trueaxis::detail::resize_in_huge_pages(xw, n + 2, 1);
  for (Eigen::Index j = 0; j < n + 2; ++j)
    xw[j] = workpiece_position(x[0], static_cast<double>(j), h);
  using View = GridViews::View;
  const GridViews grids{View(xw.data(), xw.size()), View(x.data(), n),
                        View(x.data(), with_pitch ? n : 0), parabola_free,
                        true};  // increasing: used only once the values are checked
  const ReferenceAlgebra ra(grids, with_pitch, true, h);
  // The variances' pages are committed on another core while the backward pass runs.
  const detail::Prefault prefault = results_committed(ra.mw, ra.mg, ra.mt, uw, ug, ut);
  auto go = [&]<bool Par, bool Pitch>() {
    auto p = std::make_unique<DirectPropagation<Par, Pitch>>(ra, h);
    p->run(noise_var, uw, ug, ut);
  };
  if (ra.par && ra.pitch)
    go.template operator()<true, true>();
  else if (ra.par)
    go.template operator()<true, false>();
  else if (ra.pitch)
    go.template operator()<false, true>();
  else
    go.template operator()<false, false>();
}

}  // namespace trueaxis::separation::detail
