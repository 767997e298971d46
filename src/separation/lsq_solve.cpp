// The least-squares solve of straightness separation. Every layout with redundancy goes to the
// banded QR of BandedLsq (see banded_lsq.hpp for why it is fast), with iterative refinement
// against the long chain's rounding; the layout without redundancy (three probes at 0, 1, 2 steps,
// no angle channel) has an exact solution, found by its recurrence in two vectorised passes.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <future>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include "../common/memory.hpp"
#include "banded_lsq.hpp"
#include "solution.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::separation::detail {
namespace {

// The least-squares grids for n stations at x (workpiece positions 0..Q−1 at x_0 + (j + pmin)·h,
// guide and pitch at the stations), into r's arrays (sized by the caller).
void fill_lsq_grids(const Eigen::VectorXd& x, long pmin, double h, Raw& r) {
  for (Eigen::Index j = 0; j < r.xw.size(); ++j)
    r.xw[j] = workpiece_position(x[0], static_cast<double>(j + pmin), h);
  r.xg = x;
  if (r.xt.size()) r.xt = x;
}

}  // namespace

LsqState::LsqState() = default;
LsqState::~LsqState() = default;

// Each station's three readings determine its three new unknowns (the workpiece under probe C,
// the guide, the pitch); with the gauge pins the system is square (dof = 0).
bool direct_layout(const std::vector<long>& p, bool angle) {
  return !angle && p == std::vector<long>{0, 1, 2};
}

Raw solve_lsq(const ProbeData& data, const Options& opt, LsqState& st) {
  const long n = data.x.size();
  const double h = data.step();
  std::vector<long> p;
  for (double s : data.offsets) p.push_back(std::lround(s / h));
  const bool angle = data.angle.size() == n;
  const double sp = opt.sigma.value_or(opt.nominal_sigma);
  const double wa = sp / (opt.angle_sigma * h);
  // Centre every channel: only the (nuisance) offsets change, and the pinned offsets then sit
  // close to their true values, so no large parabola enters the pinned solution.
  const Eigen::RowVectorXd mu = data.readings.colwise().mean();
  const double mu_a = angle ? data.angle.mean() : 0.0;
  std::optional<double> e = opt.zero_difference;
  // e refers to the raw offsets; the centred offsets are o_i − μ_i.
  if (e && p.size() == 3) *e -= zero_difference_weights(p).dot(mu.transpose());
  st.D = make_design(p, n, angle, e, wa);
  st.h = h;
  const Design& D = st.D;
  // Iterative refinement: each pass factorises the system with right-hand side b − A·v and
  // corrects v. A single pass carries the error the long chain's conditioning puts into any
  // backward-stable solve (~1e-4 relative at a million stations); a second one removes it.
  // The profiles' arrays hold the unknowns; their pages are committed on another core while the
  // first pass factorises.
  Raw r;
  r.xw.resize(D.Q);
  r.w.resize(D.Q);
  r.xg.resize(n);
  r.g.resize(n);
  if (D.pitch) {
    r.xt.resize(n);
    r.theta.resize(n);
  }
  const detail::Prefault prefault(
      {{r.w.data(), sizeof(double) * static_cast<std::size_t>(D.Q)},
       {r.g.data(), sizeof(double) * static_cast<std::size_t>(n)},
       {r.theta.data(), sizeof(double) * static_cast<std::size_t>(r.theta.size())}});
  // The grids depend on x alone: filled on another core meanwhile.
  for (const Eigen::VectorXd* grid : {&r.xw, &r.xg, &r.xt})
    trueaxis::detail::advise_huge_pages(grid->data(),
                                        sizeof(double) * static_cast<std::size_t>(grid->size()));
  const long pmin = *std::min_element(p.begin(), p.end());
  auto grids = std::async(policy_for(r), [&] { fill_lsq_grids(data.x, pmin, h, r); });
  st.engine = std::make_unique<detail::BandedLsq>(D);
  Eigen::VectorXd angle_mm;
  if (angle) angle_mm = (data.angle.array() - mu_a) * h;
  // The unknowns are solved straight into the profiles' arrays (θ as θ·h until the end). The
  // first pass starts from zero without writing it: it forms the right-hand side from the
  // readings and the pins, and then sets every free unknown.
  std::vector<double> offsets(static_cast<std::size_t>(D.N + (angle ? 1 : 0)), 0.0);
  const detail::Unknowns v{r.w.data(), r.g.data(), D.pitch ? r.theta.data() : nullptr,
                           offsets.data()};
  double pin_size = 0;  // the largest pinned |value|: the refinement never changes those
  for (const auto& [id, value] : D.pins) {
    v(D, id) = value;
    pin_size = std::max(pin_size, std::abs(value));
  }
  double ssr0 = 0, last = 0;
  const double round_off =
      std::max(1e-14, static_cast<double>(n) * std::numeric_limits<double>::epsilon());
  for (int iter = 0; iter < 4; ++iter) {
    if (iter == 0)
      st.engine->factor(data.readings, mu, angle_mm, v, true);
    else
      st.engine->refactor_rhs(data.readings, mu, angle_mm, v);
    if (iter == 0) {
      if (st.engine->min_pivot_ratio() < 1e-10) {
        const LayoutAnalysis a = analyze_layout(p, angle, opt.zero_difference.has_value(), n);
        throw Error(a.observable ? "the data do not determine the solution (rank-deficient system)"
                                 : a.message);
      }
      ssr0 = st.engine->ssr();
    }
    const detail::BandedLsq::Update up = st.engine->solve_add(v, iter == 0);
    // Refinement converges linearly: the next correction is about (this one)²/(the last one).
    // Stop when that is below the round-off floor: the residual b − A·v is itself rounded
    // (~ε of its terms per row) and the long chain carries that into every correction, so after
    // the first refinement the corrections stop falling, at 0.1–0.5·n·ε of the profile (measured
    // at 10⁴–10⁶ stations). A pass predicted to move the result by less than n·ε of it (and never
    // less than 1e-14) would only move it within that noise.
    const double size = std::max({1e-300, up.max_value, pin_size});
    const double now = up.max_correction;
    const double next = iter == 0 ? now : now * (now / std::max(1e-300, last));
    if (now <= round_off * size || next <= round_off * size) break;
    last = now;
  }
  st.ssr = ssr0;
  st.rows = st.engine->rows();
  st.dof = st.rows - st.engine->unknowns();
  if (D.pitch) r.theta /= h;
  grids.get();
  r.parabola_free = D.parabola_free;
  return r;
}

// The least-squares solution for a direct_layout, without a factorisation. With the pins of
// make_design (w_0 = w_{Q−1} = 0, o_A = o_C = 0, and w_m = 0 at m = Q/2 or o_B from the known
// zero difference) and the centred readings a, b, c of probes A, B, C, station K's rows
//   w_K + g_K = a_K,  w_{K+1} + g_K + t_K + o_B = b_K,  w_{K+2} + g_K + 2t_K = c_K
// (t = θ·h) give g_K and t_K from w, and w_{K+2} = 2w_{K+1} − w_K + f_K + β with
// f_K = a_K − 2b_K + c_K and β = 2·o_B. w is that recurrence run from w_0 = 0, w_1 = α, with α
// and (parabola free) β set by the pins at Q − 1 and m. The chain's rounding (~1e-9 of the
// profile at a million stations) is removed as the banded solve removes its own: one refinement
// with the residual of the recurrence, solved by the same recurrence, which leaves the result at
// the residual's own rounding floor.
Raw solve_lsq_direct(const ProbeData& data, const Options& opt) {
  const long n = data.x.size();
  const double h = data.step();
  const long Q = n + 2, m = Q / 2;
  Raw r;
  r.xw.resize(Q);
  r.w.resize(Q);
  r.xg.resize(n);
  r.g.resize(n);
  r.xt.resize(n);
  r.theta.resize(n);
  const detail::Prefault prefault({{r.g.data(), sizeof(double) * static_cast<std::size_t>(n)},
                                   {r.theta.data(), sizeof(double) * static_cast<std::size_t>(n)}});
  auto grids = std::async(policy_for(r), [&] { fill_lsq_grids(data.x, 0, h, r); });
  const Eigen::RowVectorXd mu = data.readings.colwise().mean();
  const double ma = mu[0], mb = mu[1], mc = mu[2];
  const double* A = data.readings.col(0).data();
  const double* B = data.readings.col(1).data();
  const double* C = data.readings.col(2).data();
  const bool beta_known = opt.zero_difference.has_value();
  // With o_A = o_C = 0, o_B = −e'/2 for the zero difference of the centred offsets,
  // e' = e − (μ_A − 2μ_B + μ_C).
  double beta = beta_known ? (ma - 2 * mb + mc) - *opt.zero_difference : 0.0;
  auto forcing = [&](long K) { return (A[K] - ma) - 2 * (B[K] - mb) + (C[K] - mc); };
  // α·j + δβ·j(j − 1)/2 that brings the values at the pins Q − 1 and m (end, mid) to zero.
  const double e1 = static_cast<double>(Q - 1), e2 = e1 * (e1 - 1) / 2;
  const double m1 = static_cast<double>(m), m2 = m1 * (m1 - 1) / 2;
  auto fit = [&](double end, double mid) -> std::pair<double, double> {
    if (beta_known) return {-end / e1, 0.0};
    const double det = e1 * m2 - e2 * m1;
    return {(e2 * mid - m2 * end) / det, (m1 * end - e1 * mid) / det};
  };
  double* w = r.w.data();
  // The recurrence as two sums (the forcing off the chain), from w_0 = w_1 = 0.
  w[0] = w[1] = 0;
  {
    double x = 0, dx = 0;
    for (long K = 0; K < n; ++K) {
      dx += forcing(K) + beta;
      x += dx;
      w[K + 2] = x;
    }
  }
  // The refinement, with the pins' line and parabola of the first pass applied on the fly: the
  // residual ρ_K of each station's recurrence as the values stand, and the correction δ that
  // it drives, run from δ_0 = δ_1 = 0.
  {
    const auto [a1, b1] = fit(w[Q - 1], w[m]);
    beta += b1;
    auto first = [&, a1 = a1, b1 = b1](long j) {
      const double q = static_cast<double>(j);
      return w[j] + (a1 * q + b1 * (q * (q - 1) * 0.5));
    };
    double o0 = first(0), o1 = first(1), d0 = 0, d1 = 0, dd = 0;
    for (long K = 0; K < n; ++K) {
      const double o2 = first(K + 2);
      dd += (forcing(K) + beta) - ((o2 - 2 * o1) + o0);
      const double d2 = d1 + dd;
      w[K] = o0 + d0;
      o0 = o1;
      o1 = o2;
      d0 = d1;
      d1 = d2;
    }
    w[n] = o0 + d0;
    w[n + 1] = o1 + d1;
  }
  // The pins' line and parabola of the correction, then g and t from each station's A and B rows,
  // in one vectorised pass: t_K needs w_{K+1}, formed again before the next step overwrites it.
  // The station number is a double made from a 32-bit offset in blocks, so that the loop
  // vectorises.
  {
    const auto [a2, b2] = fit(w[Q - 1], w[m]);
    beta += b2;
    const double oB = beta / 2;
    auto fixed = [a2 = a2, b2 = b2](double v, double q) {
      return v + (a2 * q + b2 * (q * (q - 1) * 0.5));
    };
    double* __restrict g = r.g.data();
    double* __restrict t = r.theta.data();
    constexpr long kBlock = 1L << 20;
    for (long K0 = 0; K0 < n; K0 += kBlock) {
      const int len = static_cast<int>(std::min(kBlock, n - K0));
      const double base = static_cast<double>(K0);
      const double *Ab = A + K0, *Bb = B + K0;
      double *wb = w + K0, *gb = g + K0, *tb = t + K0;
#pragma omp simd
      for (int i = 0; i < len; ++i) {
        const double q = base + static_cast<double>(i);
        const double wk = fixed(wb[i], q), wk1 = fixed(wb[i + 1], q + 1);
        const double gk = (Ab[i] - ma) - wk;
        wb[i] = wk;
        gb[i] = gk;
        tb[i] = ((Bb[i] - mb) - oB - wk1 - gk) / h;
      }
    }
    w[n] = fixed(w[n], static_cast<double>(n));
    w[n + 1] = fixed(w[n + 1], static_cast<double>(n + 1));
  }
  grids.get();
  r.parabola_free = !beta_known;
  return r;
}

}  // namespace trueaxis::separation::detail
