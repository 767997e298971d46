// The circular test's figures (ISO 230-4:2005, clause 3) and the least-squares diagnosis of the
// trace by its causes' signatures (the header states each signature and its sign convention).
#include "trueaxis/circular/circular.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <future>
#include <numeric>
#include <optional>

#include "../common/figures.hpp"
#include "model.hpp"
#include "search.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::circular {

using namespace detail;  // the model and the search (model.hpp, search.hpp)

namespace {

// One direction's samples, by index into the trace, sorted by wrapped angle (`w`: every
// sample's angle wrapped).
std::vector<Eigen::Index> of_direction(const Trace& t, const Eigen::VectorXd& w, Direction d) {
  std::vector<Eigen::Index> idx;
  for (std::size_t k = 0; k < t.direction.size(); ++k)
    if (t.direction[k] == d) idx.push_back(static_cast<Eigen::Index>(k));
  auto less = [&](Eigen::Index p, Eigen::Index q) { return w[p] < w[q]; };
  // A trace in time order is already sorted but for where it passes 0° (and reversed for cw):
  // then a rotation does; anything else is sorted.
  if (d == Direction::Cw) std::reverse(idx.begin(), idx.end());
  const auto cut = std::is_sorted_until(idx.begin(), idx.end(), less);
  if (cut != idx.end() && std::is_sorted(cut, idx.end(), less))
    std::rotate(idx.begin(), cut, idx.end());
  if (!std::is_sorted(idx.begin(), idx.end(), less)) std::stable_sort(idx.begin(), idx.end(), less);
  return idx;
}

std::string where(const Trace& t, Eigen::Index k) {
  const auto K = static_cast<std::size_t>(k);
  return K < t.where.size() ? t.where[K] : fmt::format("sample {}: ", k + 1);
}

// `cs`, `sn`: every sample's cos θ and sin θ.
DirectionFigures figures(const Trace& t, const Eigen::VectorXd& cs, const Eigen::VectorXd& sn,
                         const std::vector<Eigen::Index>& idx, double R) {
  DirectionFigures f;
  if (idx.empty()) return f;
  f.present = true;
  f.samples = static_cast<long>(idx.size());
  const auto n = static_cast<Eigen::Index>(idx.size());
  // The least-squares circle of the path's points: linear in its centre and radius to first
  // order in δr/R for a start, then Gauss–Newton on the orthogonal distances (two or three
  // steps reach round-off); each step's 3 × 3 normal equations summed over the points.
  Eigen::VectorXd y(n);
  Eigen::Matrix2Xd p(2, n);
  Eigen::Matrix3d AA = Eigen::Matrix3d::Zero();
  Eigen::Vector3d Ay = Eigen::Vector3d::Zero();
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index k = idx[static_cast<std::size_t>(i)];
    const Eigen::Vector3d a(1, cs[k], sn[k]);
    y[i] = t.deviation[k];
    AA += a * a.transpose();
    Ay += a * y[i];
    p.col(i) = (R + y[i]) * Eigen::Vector2d(cs[k], sn[k]);
  }
  const Eigen::Vector3d lin = AA.ldlt().solve(Ay);
  Eigen::Vector3d c(lin[1], lin[2], R + lin[0]);  // centre a, b; radius
  for (int it = 0; it < 8; ++it) {
    // j = (−qx/d, −qy/d, −1): the six sums of the symmetric JᵀJ and the three of Jᵀr.
    double xx = 0, xy = 0, yy = 0, x1 = 0, y1 = 0, rx = 0, ry = 0, r1 = 0;
    for (Eigen::Index i = 0; i < n; ++i) {
      const double qx = p(0, i) - c[0], qy = p(1, i) - c[1];
      const double d = std::sqrt(qx * qx + qy * qy), ux = qx / d, uy = qy / d, r = d - c[2];
      xx += ux * ux;
      xy += ux * uy;
      yy += uy * uy;
      x1 += ux;
      y1 += uy;
      rx += ux * r;
      ry += uy * r;
      r1 += r;
    }
    Eigen::Matrix3d JJ;
    JJ << xx, xy, x1, xy, yy, y1, x1, y1, static_cast<double>(n);
    const Eigen::Vector3d step = JJ.ldlt().solve(-Eigen::Vector3d(rx, ry, r1));
    c -= step;
    if (step.norm() < 1e-10 * R) break;  // 0.01 nm at R 100 mm: far below what G is given to
  }
  f.centre = c.head<2>();
  double lo = INFINITY, hi = -INFINITY;
  for (Eigen::Index i = 0; i < n; ++i) {
    const double d = (p.col(i) - f.centre).norm();
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  f.G = hi - lo;
  f.F_min = y.minCoeff();
  f.F_max = y.maxCoeff();
  return f;
}

// The deviation of one direction at the wrapped angle w, linear between its samples (periodic):
// `upper` is the position in `idx` of the first sample at w or after it (idx.size(): none).
double interpolate(const Trace& t, const Eigen::VectorXd& wrapped,
                   const std::vector<Eigen::Index>& idx, double w, std::size_t upper) {
  const auto n = idx.size();
  const std::size_t j = upper % n, i = (j + n - 1) % n;
  double a0 = wrapped[idx[i]], a1 = wrapped[idx[j]], x = w;
  if (a1 <= a0) a1 += kTwoPi;
  if (x < a0) x += kTwoPi;
  const double s = a1 > a0 ? (x - a0) / (a1 - a0) : 0.0;
  return (1 - s) * t.deviation[idx[i]] + s * t.deviation[idx[j]];
}

}  // namespace

std::string Plane::name() const {
  const char* axes = "XYZ";
  return {axes[a], axes[b]};
}

Plane Plane::parse(const std::string& text) {
  std::string t;
  for (char ch : text) t += static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
  if (t == "XY") return {0, 1};
  if (t == "YZ") return {1, 2};
  if (t == "ZX") return {2, 0};
  throw Error(fmt::format("plane '{}': a circular test runs in XY, YZ or ZX", text));
}

void Options::validate() const {
  if (!(radius > 0) || !std::isfinite(radius))
    throw Error("circular test: the radius (the ballbar's calibrated length) must be > 0 mm");
  if (!(feed > 0) || !std::isfinite(feed))
    throw Error("circular test: the feed must be > 0 mm/min");
  if (!(spike_decay >= 0) || !std::isfinite(spike_decay))
    throw Error("circular test: the spike decay must be >= 0 (0: found from the data)");
  if (!std::isfinite(reversal_delay) || reversal_delay > 0.5)
    throw Error(
        "circular test: the reversal delay must be below 0.5 rad (< 0: found from the data)");
  if (!(pitch_a >= 0) || !(pitch_b >= 0) || !std::isfinite(pitch_a) || !std::isfinite(pitch_b))
    throw Error("circular test: a cyclic error's pitch must be >= 0 mm (0: none)");
  if (min_samples < 8) throw Error("circular test: at least 8 samples per direction");
  if (!(max_gap > 0)) throw Error("circular test: the largest gap must be > 0");
}

Result evaluate(const Trace& t, const Options& o) {
  o.validate();
  const auto n = t.angle.size();
  if (t.deviation.size() != n || static_cast<Eigen::Index>(t.direction.size()) != n)
    throw Error("circular test: direction, angle and deviation differ in length");
  for (Eigen::Index k = 0; k < n; ++k)
    if (!std::isfinite(t.angle[k]) || !std::isfinite(t.deviation[k]))
      throw Error(where(t, k) + "the angle and the deviation must be finite numbers");
  std::vector<Eigen::Index> all(static_cast<std::size_t>(n));
  std::iota(all.begin(), all.end(), Eigen::Index{0});
  const Samples x = Samples::of(t, all);  // every sample's wrapped angle, cos and sin, once
  const Eigen::VectorXd& wrapped = x.w;
  const auto ccw = of_direction(t, wrapped, Direction::Ccw),
             cw = of_direction(t, wrapped, Direction::Cw);
  if (ccw.empty() && cw.empty()) throw Error("circular test: no samples");
  for (const auto* idx : {&ccw, &cw}) {
    if (idx->empty()) continue;
    const char* d = idx == &ccw ? "ccw" : "cw";
    if (static_cast<long>(idx->size()) < o.min_samples)
      throw Error(
          fmt::format("circular test: {} samples {}; a test needs at least {} per direction",
                      idx->size(), d, o.min_samples));
    // The angles must go round the circle: no gap larger than max_gap, the wrap included.
    double gap = 0;
    Eigen::Index after = (*idx)[0];
    for (std::size_t k = 0; k < idx->size(); ++k) {
      const double a0 = wrapped[(*idx)[k]];
      const double a1 = k + 1 < idx->size() ? wrapped[(*idx)[k + 1]] : wrapped[(*idx)[0]] + kTwoPi;
      if (a1 - a0 > gap) {
        gap = a1 - a0;
        after = (*idx)[k];
      }
    }
    if (gap > o.max_gap)
      throw Error(fmt::format(
          "{}the {} samples leave {:.1f}° of the circle without data after {:.1f}° (at most "
          "{:.1f}°): not a circular test over 360°",
          where(t, after), d, gap * 180 / kPi, wrap(t.angle[after]) * 180 / kPi,
          o.max_gap * 180 / kPi));
  }
  Result r;
  r.plane = o.plane;
  r.radius = o.radius;
  r.feed = o.feed;
  // What does not depend on the search runs beside it, on a second thread: the figures of
  // ISO 230-4, and the fit's fixed columns over every sample with their products.
  const Eigen::Index pf = fixed_count(o);
  Eigen::MatrixXd design;
  Eigen::MatrixXd FF;
  Eigen::VectorXd Fy;
  std::vector<Column> cols;
  auto beside = std::async(std::launch::async, [&] {
    r.ccw = figures(t, x.cs, x.sn, ccw, o.radius);
    r.cw = figures(t, x.cs, x.sn, cw, o.radius);
    if (!ccw.empty() && !cw.empty()) {
      // Both directions sorted by angle: the cw sample after each ccw one moves forward only.
      double h = 0;
      std::size_t upper = 0;
      for (Eigen::Index k : ccw) {
        while (upper < cw.size() && wrapped[cw[upper]] < wrapped[k]) ++upper;
        h = std::max(h, std::abs(t.deviation[k] - interpolate(t, wrapped, cw, wrapped[k], upper)));
      }
      r.H = h;
    }
    design.resize(n, pf + varying_count(!ccw.empty(), !cw.empty()));
    cols = fixed_columns(x, o, design.leftCols(pf));
    // FᵀF by a symmetric rank update (half the work of the full product).
    FF = Eigen::MatrixXd::Zero(pf, pf);
    FF.selfadjointView<Eigen::Lower>().rankUpdate(design.leftCols(pf).transpose());
    FF = FF.selfadjointView<Eigen::Lower>();
    Fy = design.leftCols(pf).transpose() * t.deviation;
  });

  // The diagnosis: the decay and delays searched (when not given), then every cause sized over
  // every sample.
  const bool has_ccw = !ccw.empty(), has_cw = !cw.empty();
  const Searched searched = search(t, x, o, has_ccw, has_cw);
  const double decay = searched.decay;
  const auto delay = searched.delay;
  r.spike_decay = decay;
  r.reversal_delay = delay;
  {
    std::vector<double> step;
    for (std::size_t k = 1; k < t.direction.size(); ++k)
      if (t.direction[k] == t.direction[k - 1])
        step.push_back(std::abs(t.angle[static_cast<Eigen::Index>(k)] -
                                t.angle[static_cast<Eigen::Index>(k - 1)]));
    if (!step.empty()) {
      std::nth_element(step.begin(), step.begin() + static_cast<long>(step.size() / 2), step.end());
      r.reversal_delay_resolution = step[step.size() / 2];
    }
  }
  const Eigen::Index pv = varying_count(has_ccw, has_cw);
  beside.get();
  for (auto& c : varying_columns(o, has_ccw, has_cw)) cols.push_back(std::move(c));
  varying_matrix(x, decay, delay, has_ccw, has_cw, design.rightCols(pv));
  // JᵀJ and Jᵀy: the fixed part's from beside, the varying columns' products now.
  Eigen::MatrixXd normal(pf + pv, pf + pv);
  const Eigen::MatrixXd P = design.transpose() * design.rightCols(pv);
  normal.topLeftCorner(pf, pf) = FF;
  normal.rightCols(pv) = P;
  normal.bottomLeftCorner(pv, pf) = P.topRows(pf).transpose();
  Eigen::VectorXd Jy(pf + pv);
  Jy.head(pf) = Fy;
  Jy.tail(pv) = design.rightCols(pv).transpose() * t.deviation;
  Fit fit = solve_normal(normal, Jy, t.deviation.squaredNorm());
  const auto p = static_cast<Eigen::Index>(fit.kept.size());
  const double dof = static_cast<double>(n - p);
  r.model = design * fit.beta.unaryExpr([](double b) { return std::isnan(b) ? 0.0 : b; });
  r.residual = t.deviation - r.model;
  fit.rss = r.residual.squaredNorm();  // from the residual itself: no cancellation
  r.sigma = dof > 0 ? std::sqrt(fit.rss / dof) : 0.0;
  r.unexplained_rms = std::sqrt(r.residual.squaredNorm() / static_cast<double>(n));
  r.spike_decay_note = searched.decay_note;
  if (searched.u_log_decay) {
    const double u_log = r.sigma > 0 ? searched.u_log_decay(r.sigma) : INFINITY;
    if (u_log < std::log(2.0))  // within a factor of 2 (1σ)
      r.spike_decay_u = decay * u_log;
    else
      r.spike_decay_note = "not resolved: no reversal spike stands out of the noise";
  }
  const double G = std::max(r.ccw.G, r.cw.G);
  auto position = [&](int j) {
    return static_cast<Eigen::Index>(std::find(fit.kept.begin(), fit.kept.end(), j) -
                                     fit.kept.begin());
  };
  auto share = [&](const Eigen::VectorXd& contribution) {
    return G > 0 ? (contribution.maxCoeff() - contribution.minCoeff()) / G : 0.0;
  };
  for (std::size_t j = 0; j < cols.size(); ++j) {
    const Column& c = cols[j];
    if (c.key.rfind("cyclic_cos.", 0) == 0) continue;  // with its sine, below
    const auto v = design.col(static_cast<Eigen::Index>(j));
    if (v.cwiseAbs().maxCoeff() == 0) continue;  // no effect on these samples
    Cause cause;
    cause.key = c.key;
    cause.name = c.name;
    cause.unit = c.unit;
    const int J = static_cast<int>(j);
    if (c.key.rfind("cyclic_sin.", 0) == 0) {
      // The amplitude of the sine and cosine pair, its u by first-order propagation.
      const char axis = c.key.back();
      cause.key = fmt::format("cyclic_error.{}", axis);
      cause.name = fmt::format("cyclic error of {}", axis);
      const int Jc = J + 1;
      const double s = fit.beta[J], co = fit.beta[Jc];
      const double amp = std::hypot(s, co);
      cause.value = amp * c.to_unit;
      const Eigen::Index i = position(J), k = position(Jc);
      if (i < p && k < p && amp > 0 && r.sigma > 0) {
        const double var = (s * s * fit.cov_unit(i, i) + co * co * fit.cov_unit(k, k) +
                            2 * s * co * fit.cov_unit(i, k)) /
                           (amp * amp);
        cause.u = r.sigma * std::sqrt(std::max(var, 0.0)) * c.to_unit;
      }
      cause.share = share(v * s + design.col(Jc) * co);
      r.causes.push_back(cause);
      continue;
    }
    for (const auto& group : fit.confused)
      if (std::find(group.begin(), group.end(), J) != group.end()) {
        cause.separated = false;
        for (int other : group)
          if (other != J)
            cause.confused_with += (cause.confused_with.empty() ? "" : ", ") +
                                   cols[static_cast<std::size_t>(other)].name;
      }
    const Eigen::Index i = position(J);
    if (i < p) {
      cause.value = fit.beta[J] * c.to_unit;
      if (r.sigma > 0) cause.u = r.sigma * std::sqrt(fit.cov_unit(i, i)) * c.to_unit;
      cause.share = G > 0 ? std::abs(fit.beta[J]) * (v.maxCoeff() - v.minCoeff()) / G : 0.0;
      // Estimates the data barely tell apart (|correlation| ≥ 0.995) are named as such too.
      for (Eigen::Index k = 0; k < p; ++k) {
        if (k == i) continue;
        const double corr = fit.cov_unit(i, k) / std::sqrt(fit.cov_unit(i, i) * fit.cov_unit(k, k));
        if (std::abs(corr) >= 0.995) {
          cause.separated = false;
          cause.confused_with +=
              (cause.confused_with.empty() ? "" : ", ") +
              cols[static_cast<std::size_t>(fit.kept[static_cast<std::size_t>(k)])].name;
        }
      }
    } else {
      cause.value = NAN;
    }
    r.causes.push_back(cause);
  }
  // Set-up first (centre and radius), then the machine's causes by share.
  std::stable_sort(
      r.causes.begin() + std::min<std::ptrdiff_t>(3, static_cast<std::ptrdiff_t>(r.causes.size())),
      r.causes.end(), [](const Cause& x, const Cause& y) { return x.share > y.share; });
  if (!has_ccw || !has_cw)
    r.warnings.push_back(
        "one direction only: the lag mismatch cannot be told from squareness, nor backlash from "
        "a centre offset's share; run both directions");
  // The u assume independent residuals. Correlated ones (lag-1 autocorrelation of successive
  // samples of one direction, well above what independent noise gives) hold an error that none
  // of the causes models, and then the u understate.
  {
    double num = 0, den = r.residual.squaredNorm();
    long pairs = 0;
    for (std::size_t k = 1; k < t.direction.size(); ++k)
      if (t.direction[k] == t.direction[k - 1]) {
        num +=
            r.residual[static_cast<Eigen::Index>(k)] * r.residual[static_cast<Eigen::Index>(k - 1)];
        ++pairs;
      }
    const double rho = den > 0 ? num / den : 0.0;
    if (pairs > 0 && rho > std::max(0.2, 4 / std::sqrt(static_cast<double>(pairs))))
      r.warnings.push_back(fmt::format(
          "the residual is correlated from one sample to the next (lag-1 autocorrelation {:.2f}): "
          "it holds an error that none of the causes models (unexplained RMS {:.3f} µm), and the "
          "stated u, which assume independent residuals, understate",
          rho, r.unexplained_rms * 1e3));
  }
  return r;
}

std::string Result::summary() const {
  std::string s = fmt::format("circular test in {}, radius {:g} mm, feed {:g} mm/min\n",
                              plane.name(), radius, feed);
  for (const auto* d : {&ccw, &cw}) {
    if (!d->present) continue;
    s += fmt::format("  {:<4} G {:.2f} µm, F {:+.2f} … {:+.2f} µm ({} samples)\n",
                     d == &ccw ? "ccw" : "cw", d->G * 1e3, d->F_min * 1e3, d->F_max * 1e3,
                     d->samples);
  }
  if (H) s += fmt::format("  H {:.2f} µm\n", *H * 1e3);
  s += "  diagnosis (share of G):\n";
  for (const auto& c : causes) {
    if (!c.separated) {
      s += fmt::format("    {:<40} not separated from {}\n", c.name, c.confused_with);
      continue;
    }
    s += fmt::format(
        "    {:<40} {} {}{} ({:.0f} %)\n", c.name,
        c.u ? trueaxis::detail::rounded_to(c.value, *c.u) : fmt::format("{:.3g}", c.value), c.unit,
        c.u ? fmt::format(", u {} {}", trueaxis::detail::two_digits(*c.u), c.unit)
            : std::string(", u not stated"),
        100 * c.share);
  }
  s += fmt::format("    unexplained: RMS {:.3f} µm\n", unexplained_rms * 1e3);
  for (const auto& w : warnings) s += "  warning: " + w + "\n";
  return s;
}

}  // namespace trueaxis::circular
