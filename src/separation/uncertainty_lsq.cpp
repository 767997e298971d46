// Uncertainties of the least-squares separation from its covariance Z = (AᵀA)⁻¹: the banded
// factorisation hands out, row by row in its backward pass, each unknown's Z_uu and its row of ZV
// (V: the reference's functionals), after the Gram matrix VᵀZV from its forward rows; each
// reported point's variance is then written once, as its row arrives.
#include <Eigen/Dense>
#include <algorithm>
#include <array>

#include "banded_lsq.hpp"
#include "reference_algebra.hpp"
#include "solution.hpp"

namespace trueaxis::separation::detail {

// Standard uncertainties (for noise variance noise_var per row) of the reported w, g, θ under
// the ls reference from the least-squares covariance Z = (AᵀA)⁻¹, on the lsq grids.
void lsq_uncertainties(LsqState& st, const Raw& r, bool with_pitch, double noise_var,
                       Eigen::VectorXd& uw, Eigen::VectorXd& ug, Eigen::VectorXd& ut) {
  const Design& D = st.D;
  // The results are written by the solve's backward pass on both cores. Their pages are committed
  // by another core from here on, while the reference algebra's sums below use only this one.
  const detail::Prefault prefault = results_committed(
      r.xw.size(), r.xg.size(), ReferenceAlgebra::pitch_points(r.xt.size(), with_pitch, D.pitch),
      uw, ug, ut);
  const ReferenceAlgebra ra(r, with_pitch, D.pitch, st.h);
  // Each reported point's variance is u·S·u + s²·Z_uu − 2s·u·(ZV)_u (see point_uncertainty), with
  // S = VᵀZV. S comes from the solve's forward rows (their Gram matrix) and is complete before
  // the backward solve hands out (ZV)_u and Z_uu row by row (the selected inversion runs
  // alongside), so each point's variance is written once, as its row arrives, and its square
  // root taken in one vectorised pass at the end. Pinned unknowns have no Z_uu and no (ZV)_u:
  // their variance is u·S·u alone, set after the solve.
  using Kind = Design::Kind;
  // VᵀZV restricted to each profile's columns: workpiece, guide, pitch.
  std::array<Eigen::Matrix3d, 3> S;
  const double inv_h = 1.0 / st.h;  // the pitch unknown is θ·h
  // V here always has six columns, the parabola's at 4 and the pitch's at 5, as compile-time
  // constants: the rows of V and ZV are then indexed by constants only and stay in registers in
  // the solve's loops (which inline both callbacks, each called up to three times per station).
  // Without a parabola or a reported pitch, that column is zero (φ's coefficients are zero, and
  // no point lies on an empty pitch grid) and its u entries too: the numbers are those of the
  // narrower V. One instantiation of the solve's normal-row pass instead of one per column count:
  // the zero columns cost a two-probe layout ~(6/4)² of that pass, and the file compiles in a
  // quarter of the time.
  constexpr int kCols = ReferenceAlgebra::kMaxCols, kPhi = 4, kT = 5;
  static constexpr ReferenceAlgebra::Cols cw{ReferenceAlgebra::kW0, ReferenceAlgebra::kW0 + 1,
                                             kPhi};
  static constexpr ReferenceAlgebra::Cols cg{ReferenceAlgebra::kG0, ReferenceAlgebra::kG0 + 1,
                                             kPhi};
  static constexpr ReferenceAlgebra::Cols ct{kT, kPhi, 0};
  Eigen::Matrix<double, kCols, kCols, Eigen::RowMajor> gram;
  gram.setZero();
  // The guide's and pitch's rows' share of the Gram matrix from their moments, when every one
  // of those unknowns is free (make_design pins only workpiece points and offsets).
  const bool locals_free = std::none_of(D.pins.begin(), D.pins.end(), [&](const auto& pin) {
    const Kind kind = D.place(pin.first).kind;
    return kind == Kind::g || kind == Kind::t;
  });
  const auto local_vv = ra.local_gram<kCols>(kPhi, kT);
  // A point's uncertainty from its Z_uu and row of ZV (null for a pinned unknown).
  auto use = [&](int id, const double* zv, double zuu) __attribute__((always_inline)) {
    const auto [kind, i] = D.place(id);
    switch (kind) {
      case Kind::w:
        uw[i] =
            ReferenceAlgebra::point_uncertainty<false>(ra.uw(i), cw, S[0], zuu, zv, 1.0, noise_var);
        break;
      case Kind::g:
        ug[i] =
            ReferenceAlgebra::point_uncertainty<false>(ra.ug(i), cg, S[1], zuu, zv, 1.0, noise_var);
        break;
      case Kind::t:
        if (i < ra.mt)
          ut[i] = ReferenceAlgebra::point_uncertainty<false>(ra.ut(i), ct, S[2], zuu, zv, inv_h,
                                                             noise_var);
        break;
      default:
        break;  // an offset: no row of V
    }
  };
  st.engine->solve_normal_rows<kCols>(
      [&](int id, double* out) __attribute__((always_inline)) {
        const auto [kind, i] = D.place(id);
        ra.v_into<kCols>(kind, i, kPhi, kT, out);
      },
      use, gram.data(),
      [&] {
        const Eigen::MatrixXd VZV = gram;
        S[0] = ReferenceAlgebra::restrict(VZV, cw);
        S[1] = ReferenceAlgebra::restrict(VZV, cg);
        S[2] = ReferenceAlgebra::restrict(VZV, ct);
      },
      locals_free ? local_vv.data() : nullptr);
  for (const auto& pin : D.pins) use(pin.first, nullptr, 0.0);
  take_square_roots(uw, ug, ut);
}

}  // namespace trueaxis::separation::detail
