// Private: the ls reference as linear algebra, for the uncertainty propagation. A reported value
// is its raw unknown less the reference's line (and parabola), each a linear functional of the
// raw unknowns; its variance follows from the raw unknowns' covariance Z through those
// functionals (the columns of V). The rows of U and V are formed in closed form from each
// point's position, so no n-long matrix is ever built.
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <tuple>
#include <utility>
#include <vector>

#include "../common/memory.hpp"
#include "banded_lsq.hpp"
#include "solution.hpp"

namespace trueaxis::separation::detail {

// A least-squares problem's grids (as in Raw) as views: of a Raw's arrays, or of the data's own
// stations where a grid is the stations.
struct GridViews {
  using View = Eigen::Map<const Eigen::VectorXd>;
  View xw, xg, xt;
  bool parabola_free = false, xg_increasing = false;
  static GridViews of(const Raw& r) {
    return {View(r.xw.data(), r.xw.size()), View(r.xg.data(), r.xg.size()),
            View(r.xt.data(), r.xt.size()), r.parabola_free, r.xg_increasing};
  }
};

// The ls reference as linear algebra. Each reported value is y = scale·x_u − U_i·(Vᵀx): the raw
// unknown x_u less its reference (line, and the parabola gauge), with V's columns the functionals
// that define the reference: [w line (2), g line (2), parabola, pitch mean]. With Z the
// covariance of the raw unknowns (per unit reading variance),
//   var(y) = scale²·Z_uu − 2·scale·U_i·(ZV)_u + U_i·(VᵀZV)·U_iᵀ.
// The three profiles share one V (the parabola's column is common). With `with_pitch` false
// (only the noise gain is wanted, which is about the profiles) the pitch is left out. U's and V's
// rows are formed in closed form from each point's x (no n-long matrices); a profile's U has up
// to 3 columns, padded with zeros.
struct ReferenceAlgebra {
  static constexpr int kW0 = 0, kG0 = 2, kMaxCols = 6;
  using Row = Eigen::Matrix<double, kMaxCols, 1>;  // a row of V or ZV
  using Cols = std::array<int, 3>;                 // the V columns a profile's U refers to

  // The orthonormal basis of {1, x} on a grid: (1/√m, (x − x̄)/‖x − x̄‖).
  struct Line {
    double b0 = 1, mean = 0, inv = 1;
    explicit Line(Eigen::Ref<const Eigen::VectorXd> x) {
      const double m = static_cast<double>(x.size());
      b0 = 1 / std::sqrt(m);
      mean = x.mean();
      const double nn = (x.array() - mean).matrix().norm();
      inv = nn > 0 ? 1 / nn : 1.0;
    }
    double b1(double x) const { return (x - mean) * inv; }
  };

  const GridViews r;
  Scale s;
  Line lw, lg;
  bool par = false, pitch = false;
  int k = 4, kPhi = -1, kT = -1;
  Eigen::Index mw = 0, mg = 0, mt = 0;
  double h = 1;
  Eigen::Vector3d e = Eigen::Vector3d::Zero();  // the parabola functional's coefficients
  double pw0 = 0, pw1 = 0, pg0 = 0, pg1 = 0;    // t² on each grid's line basis
  double lin_mean = 0;                          // mean of the parabola's slope on the θ grid
  Cols cw{}, cg{}, ct{};

  // Whether the pitch is among the reported values (then V has the pitch's column), and on how
  // many points (mt; 0 if not).
  static bool reports_pitch(Eigen::Index xt_points, bool with_pitch, bool has_pitch_unknowns) {
    return with_pitch && xt_points && has_pitch_unknowns;
  }
  static Eigen::Index pitch_points(Eigen::Index xt_points, bool with_pitch,
                                   bool has_pitch_unknowns) {
    return reports_pitch(xt_points, with_pitch, has_pitch_unknowns) ? xt_points : 0;
  }

  ReferenceAlgebra(const Raw& raw, bool with_pitch, bool has_pitch_unknowns, double step)
      : ReferenceAlgebra(GridViews::of(raw), with_pitch, has_pitch_unknowns, step) {}
  ReferenceAlgebra(const GridViews& grids, bool with_pitch, bool has_pitch_unknowns, double step)
      : r(grids),
        s(scale_of(grids.xg, grids.xg_increasing)),
        lw(grids.xw),
        lg(grids.xg),
        par(grids.parabola_free),
        h(step) {
    pitch = reports_pitch(grids.xt.size(), with_pitch, has_pitch_unknowns);
    if (par) kPhi = k++;
    if (pitch) kT = k++;
    mw = r.xw.size();
    mg = r.xg.size();
    mt = pitch_points(grids.xt.size(), with_pitch, has_pitch_unknowns);
    cw = {kW0, kW0 + 1, par ? kPhi : 0};
    cg = {kG0, kG0 + 1, par ? kPhi : 0};
    ct = {pitch ? kT : 0, par ? kPhi : 0, 0};
    e_w0 = unit(kW0);
    e_w1 = unit(kW0 + 1);
    e_g0 = unit(kG0);
    e_g1 = unit(kG0 + 1);
    e_phi = unit(kPhi);
    e_t = unit(kT);
    if (par) {
      e = quad_coefficients_from(moments_of(r.xg, r.xg, s));  // (the y sums unused)
      std::tie(pw0, pw1) = t2_on_line(r.xw, lw);
      pw0 *= lw.b0;
      std::tie(pg0, pg1) = t2_on_line(r.xg, lg);
      pg0 *= lg.b0;
      const double* xt = r.xt.data();
      double sum = 0;
#pragma omp simd reduction(+ : sum)
      for (Eigen::Index K = 0; K < mt; ++K) sum += lin(xt[K]);
      if (mt) lin_mean = sum / static_cast<double>(mt);
    }
  }
  // Σt² and Σb1·t² over a grid, in one vectorised pass.
  std::pair<double, double> t2_on_line(Eigen::Ref<const Eigen::VectorXd> x, const Line& l) const {
    const double* xp = x.data();
    double s0 = 0, s1 = 0;
#pragma omp simd reduction(+ : s0, s1)
    for (Eigen::Index j = 0; j < x.size(); ++j) {
      const double q = t2(xp[j]);
      s0 += q;
      s1 += l.b1(xp[j]) * q;
    }
    return {s0, s1};
  }
  // Per point, multiplications by these instead of divisions (the rows are formed ~5 times per
  // station).
  double invL = 1 / s.L, lin_k = 2.0 / (s.L * s.L);
  double t2(double x) const {
    const double t = (x - s.xc) * invL;
    return t * t;
  }
  double lin(double x) const {
    return (x - s.xc) * lin_k;
  }
  // φ(x), the parabola functional's row entry at a guide point (with the parabola free).
  double phi(double x) const {
    const double t = (x - s.xc) * invL;
    return e[0] + t * (e[1] + t * e[2]);
  }

  // U's rows. Workpiece: its line, and the parabola the gauge moves into it (t² less its line).
  [[gnu::always_inline]] Eigen::Vector3d uw(Eigen::Index j) const {
    const double x = r.xw[j], b1 = lw.b1(x);
    return {lw.b0, b1, par ? -(t2(x) - lw.b0 * pw0 - b1 * pw1) : 0.0};
  }
  [[gnu::always_inline]] Eigen::Vector3d ug(Eigen::Index K) const {
    const double x = r.xg[K], b1 = lg.b1(x);
    return {lg.b0, b1, par ? t2(x) - lg.b0 * pg0 - b1 * pg1 : 0.0};
  }
  // Pitch (its unknown is θ·h): about its mean, and the parabola's slope about its mean.
  [[gnu::always_inline]] Eigen::Vector3d ut(Eigen::Index K) const {
    return {1.0 / (h * static_cast<double>(mt)), par ? lin(r.xt[K]) - lin_mean : 0.0, 0.0};
  }
  // V's row of point i of a profile (zero beyond the profile's grid) into out[0..Cols), with the
  // parabola's and the pitch's columns cphi and ct (−1: none). The least-squares solve's callback
  // passes them as compile-time constants, so its rows are indexed by constants only.
  template <int Cols>
  [[gnu::always_inline]] void v_into(Design::Kind kind, Eigen::Index i, int cphi, int ct,
                                     double* out) const {
#pragma GCC unroll 8
    for (int j = 0; j < Cols; ++j) out[j] = 0.0;
    switch (kind) {
      case Design::Kind::w:
        if (i >= 0 && i < mw) {
          out[kW0] = lw.b0;
          out[kW0 + 1] = lw.b1(r.xw[i]);
        }
        break;
      case Design::Kind::g:
        if (i >= 0 && i < mg) {
          out[kG0] = lg.b0;
          out[kG0 + 1] = lg.b1(r.xg[i]);
          if (cphi >= 0) out[cphi] = phi(r.xg[i]);
        }
        break;
      case Design::Kind::t:
        if (ct >= 0 && i >= 0 && i < mt) out[ct] = 1.0;
        break;
      default:
        break;
    }
  }
  // The same rows as whole vectors, as sums of unit rows: v_into's store at a run-time column
  // followed by the row's vector loads stalled each time (a load cannot take its data from a
  // narrower store still in flight). Each entry is the same number (x·1 + 0).
  static Row unit(int c) {
    return c >= 0 ? Row(Row::Unit(c)) : Row(Row::Zero());
  }
  Row e_w0, e_w1, e_g0, e_g1, e_phi, e_t;  // set once the columns are known
  [[gnu::always_inline]] Row vw(Eigen::Index j) const {
    if (j < 0 || j >= mw) return Row::Zero();
    return lw.b0 * e_w0 + lw.b1(r.xw[j]) * e_w1;
  }
  [[gnu::always_inline]] Row vg(Eigen::Index K) const {
    if (K < 0 || K >= mg) return Row::Zero();
    const double x = r.xg[K];
    return lg.b0 * e_g0 + lg.b1(x) * e_g1 + (kPhi >= 0 ? phi(x) : 0.0) * e_phi;
  }
  [[gnu::always_inline]] Row vt(Eigen::Index K) const {
    return kT >= 0 && K >= 0 && K < mt ? e_t : Row(Row::Zero());
  }

  // V's guide and pitch rows' share of VᵀV, as the least-squares solve takes it (see
  // BandedLsq::solve_normal_rows): Σ v_g·v_gᵀ, Σ v_g·v_θᵀ (the same station's) and Σ v_θ·v_θᵀ over
  // every guide and pitch point, three Cols × Cols blocks, row-major, with the parabola's and the
  // pitch's columns cphi and ct (−1: none). A guide row is [b0, b1(x), φ(x)] in its columns, a
  // pitch row a 1 in ct: the sums are moments of the guide's grid, in one vectorised pass.
  template <int Cols>
  std::array<double, 3 * Cols * Cols> local_gram(int cphi, int ct) const {
    const Eigen::Index mgt = ct >= 0 ? std::min(mg, mt) : 0;  // stations with both rows
    const double* x = r.xg.data();
    const bool with_phi = cphi >= 0;
    double s1 = 0, s11 = 0, sp = 0, s1p = 0, spp = 0, c1 = 0, cp = 0;
#pragma omp simd reduction(+ : s1, s11, sp, s1p, spp, c1, cp)
    for (Eigen::Index K = 0; K < mg; ++K) {
      const double b1 = lg.b1(x[K]), phi = with_phi ? this->phi(x[K]) : 0.0;
      const double both = K < mgt ? 1.0 : 0.0;
      s1 += b1;
      s11 += b1 * b1;
      sp += phi;
      s1p += b1 * phi;
      spp += phi * phi;
      c1 += both * b1;
      cp += both * phi;
    }
    std::array<double, 3 * Cols * Cols> out{};
    auto at = [&](int block, int a, int b) -> double& {
      return out[static_cast<std::size_t>(block * Cols * Cols + a * Cols + b)];
    };
    const double b0 = lg.b0;
    auto sym = [&](int a, int b, double v) { at(0, a, b) = at(0, b, a) = v; };
    sym(kG0, kG0, b0 * b0 * static_cast<double>(mg));
    sym(kG0, kG0 + 1, b0 * s1);
    sym(kG0 + 1, kG0 + 1, s11);
    if (with_phi) {
      sym(kG0, cphi, b0 * sp);
      sym(kG0 + 1, cphi, s1p);
      sym(cphi, cphi, spp);
    }
    if (ct >= 0) {
      at(1, kG0, ct) = b0 * static_cast<double>(mgt);
      at(1, kG0 + 1, ct) = c1;
      if (with_phi) at(1, cphi, ct) = cp;
      at(2, ct, ct) = static_cast<double>(mt);
    }
    return out;
  }

  // VᵀZV restricted to a profile's columns (padding columns have zero U).
  static Eigen::Matrix3d restrict(const Eigen::MatrixXd& VZV, const Cols& c) {
    Eigen::Matrix3d S;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        S(a, b) = VZV(c[static_cast<std::size_t>(a)], c[static_cast<std::size_t>(b)]);
    return S;
  }

  // The standard uncertainty √(noise_var·var(y_i)), var(y_i) (unit weight) from Z_uu (`zd`) and
  // the row (ZV)_u (`zv`, all k columns; null when x_u is pinned, which then also ignores zd).
  // Inlined, with u·S·u written out (Eigen's dot stayed a call in the least-squares solve's loop),
  // so that constant columns c index zv by constants. Without Root, the variance
  // max(0, var(y_i))·noise_var instead (its square root taken later, four at a time).
  template <bool Root = true>
  [[gnu::always_inline]] static double point_uncertainty(const Eigen::Vector3d& u, const Cols& c,
                                                         const Eigen::Matrix3d& S, double zd,
                                                         const double* zv, double scale,
                                                         double noise_var) {
    double v = 0;
    for (int a = 0; a < 3; ++a) v += u[a] * (S(a, 0) * u[0] + S(a, 1) * u[1] + S(a, 2) * u[2]);
    if (zv) {
      const double uz = u[0] * zv[c[0]] + u[1] * zv[c[1]] + u[2] * zv[c[2]];
      v += scale * scale * zd - 2 * scale * uz;
    }
    if constexpr (Root)
      return std::sqrt(std::max(0.0, v) * noise_var);
    else
      return std::max(0.0, v) * noise_var;
  }
};

// The standard uncertainties from the variances that point_uncertainty<false> wrote, four per
// instruction, half of each profile on each core for long profiles: in the propagation's loops
// each scalar root held up the instructions after it for its latency (~20 cycles), two or three
// per station.
inline void take_square_roots(Eigen::VectorXd& uw, Eigen::VectorXd& ug, Eigen::VectorXd& ut) {
  auto roots = [](Eigen::VectorXd& u, Eigen::Index begin, Eigen::Index end) {
    u.segment(begin, end - begin) = u.segment(begin, end - begin).cwiseSqrt();
  };
  if (ug.size() < kTwoCorePoints) {  // a thread would cost more than it saves
    roots(uw, 0, uw.size());
    roots(ug, 0, ug.size());
    roots(ut, 0, ut.size());
    return;
  }
  detail::at_once(
      [&] {
        roots(uw, 0, uw.size() / 2);
        roots(ug, 0, ug.size() / 2);
        roots(ut, 0, ut.size() / 2);
      },
      [&] {
        roots(uw, uw.size() / 2, uw.size());
        roots(ug, ug.size() / 2, ug.size());
        roots(ut, ut.size() / 2, ut.size());
      });
}

// Sizes the three profiles' uncertainties uw, ug, ut to mw, mg, mt points, their storage asked
// for in huge pages, and starts committing their pages on another core, after those of `first`
// (a propagation's own work array) if given. The returned helper must outlive the writes' start.
inline Prefault results_committed(Eigen::Index mw, Eigen::Index mg, Eigen::Index mt,
                                  Eigen::VectorXd& uw, Eigen::VectorXd& ug, Eigen::VectorXd& ut,
                                  std::optional<detail::Prefault::Region> first = {}) {
  trueaxis::detail::resize_in_huge_pages(uw, mw, 1);
  trueaxis::detail::resize_in_huge_pages(ug, mg, 1);
  trueaxis::detail::resize_in_huge_pages(ut, mt, 1);
  std::vector<detail::Prefault::Region> regions;
  if (first) regions.push_back(*first);
  for (const Eigen::VectorXd* v : {&uw, &ug, &ut})
    regions.push_back({v->data(), sizeof(double) * static_cast<std::size_t>(v->size())});
  return detail::Prefault(std::move(regions));
}

}  // namespace trueaxis::separation::detail
