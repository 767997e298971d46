// The search of the spikes' decay and the reversals' delays (see search.hpp).
#include "search.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <vector>

namespace trueaxis::circular::detail {
namespace {

// The residual sum of squares at (decay, delay), for the search: the normal equations of
// Z = [fixed columns | varying columns | y], the fixed part's products computed once and the
// varying columns' products (one matrix product) per call, over a subset of the samples: every
// k-th in the trace's order, each weighted by k so the sum stands for the whole trace; and, when
// `near` gives the reversals' delays found so far, every sample within `half_width` of where each
// axis reverses (weight 1), because a backlash step's place can only be told to the spacing of
// the samples searched over. The decay and delay are found from them; the sizes are then fitted
// over every sample.
class Search {
 public:
  using Delays = std::array<double, 2>;
  Search(const Trace& t, const Samples& all, const Options& o, bool ccw, bool cw, std::size_t cap,
         const std::optional<Delays>& near = std::nullopt, double half_width = 0)
      : ccw_(ccw), cw_(cw) {
    const auto n = static_cast<std::size_t>(all.size());
    const std::size_t step = (n + cap - 1) / cap;
    // Within half_width of where either axis reverses, on either side.
    Eigen::Array<bool, Eigen::Dynamic, 1> window =
        Eigen::Array<bool, Eigen::Dynamic, 1>::Zero(all.size());
    if (near)
      for (int axis = 0; axis < 2; ++axis) {
        const Eigen::ArrayXd d = since_reversal(all, axis, (*near)[static_cast<std::size_t>(axis)]);
        window = window || (d <= half_width) || (d >= kPi - half_width);
      }
    auto in_window = [&](std::size_t k) { return window[static_cast<Eigen::Index>(k)]; };
    std::vector<Eigen::Index> idx;
    std::vector<double> weight;
    for (std::size_t k = 0; k < n; ++k) {
      if (in_window(k)) {
        idx.push_back(static_cast<Eigen::Index>(k));
        weight.push_back(1);
      } else if (k % step == 0) {
        idx.push_back(static_cast<Eigen::Index>(k));
        weight.push_back(static_cast<double>(std::min(step, n - k)));
      }
    }
    spacing_ = 4 * kPi / static_cast<double>(std::max<std::size_t>(n, 1)) * (near ? 1.0 : step);
    x_ = all.subset(idx);
    root_w_ =
        Eigen::Map<const Eigen::VectorXd>(weight.data(), static_cast<Eigen::Index>(weight.size()))
            .cwiseSqrt();
    pf_ = fixed_count(o);
    pv_ = varying_count(ccw, cw);
    Z_.resize(x_.size(), pf_ + pv_ + 1);
    fixed_columns(x_, o, Z_.leftCols(pf_));
    for (Eigen::Index i = 0; i < x_.size(); ++i)
      Z_(i, pf_ + pv_) = t.deviation[idx[static_cast<std::size_t>(i)]];
    Z_.leftCols(pf_).array().colwise() *= root_w_.array();
    Z_.rightCols(1).array().colwise() *= root_w_.array();
    const auto F = Z_.leftCols(pf_);
    FF_ = F.transpose() * F;
    Fy_ = F.transpose() * Z_.rightCols(1);
    yy_ = Z_.rightCols(1).squaredNorm();
    P_.resize(pf_ + pv_ + 1, pv_);
  }
  double rss(double decay, const Delays& delay) { return residual(decay, delay).squaredNorm(); }
  // The residual at (decay, delay) of each sample searched over, times √(its weight).
  Eigen::VectorXd residual(double decay, const Delays& delay) {
    // Only the columns whose decay or delay changed since the last call are made again, with
    // their products: a search moves one of them at a time.
    const Eigen::Index per_axis = varying_count(ccw_, cw_) / 2 - 1;  // spike columns per axis
    std::vector<Eigen::Index> changed;
    for (int axis = 0; axis < 2; ++axis) {
      const auto a = static_cast<std::size_t>(axis);
      const bool moved = !made_ || delay[a] != delay_[a];
      if (!moved && decay == decay_) continue;
      const Eigen::Index first = spike_column(axis, ccw_, cw_);
      auto V = Z_.middleCols(pf_, pv_);
      if (moved) {
        backlash_column(x_, axis, delay[a], V.col(axis));
        changed.push_back(axis);
      }
      spike_columns(x_, axis, decay, delay[a], ccw_, cw_, V, first);
      for (Eigen::Index j = first; j < first + per_axis; ++j) changed.push_back(j);
    }
    made_ = true;
    decay_ = decay;
    delay_ = delay;
    const Eigen::Index p = pf_ + pv_;
    std::vector<bool> is_new(static_cast<std::size_t>(pv_), false);
    for (const Eigen::Index j : changed) Z_.col(pf_ + j).array() *= root_w_.array();
    for (const Eigen::Index j : changed) {
      P_.col(j).noalias() = Z_.transpose() * Z_.col(pf_ + j);  // (p + 1) products
      is_new[static_cast<std::size_t>(j)] = true;
    }
    // The products of an unchanged column with a changed one, from the changed one's.
    for (const Eigen::Index j : changed)
      for (Eigen::Index k = 0; k < pv_; ++k)
        if (!is_new[static_cast<std::size_t>(k)]) P_(pf_ + j, k) = P_(pf_ + k, j);
    Eigen::MatrixXd N(p, p);
    N.topLeftCorner(pf_, pf_) = FF_;
    N.rightCols(pv_) = P_.topRows(p);
    N.bottomLeftCorner(pv_, pf_) = P_.topRows(pf_).transpose();
    Eigen::VectorXd c(p);
    c.head(pf_) = Fy_;
    c.tail(pv_) = P_.row(p).transpose();
    // The sizes from the normal equations, the RSS from the residual itself: yᵀy − βᵀJᵀy loses
    // the digits a noise-free trace's search needs near its minimum.
    const Eigen::VectorXd beta = solve_normal(N, c, yy_, false).beta.unaryExpr([](double b) {
      return std::isnan(b) ? 0.0 : b;
    });
    return Z_.rightCols(1) - Z_.leftCols(p) * beta;
  }
  // The standard uncertainty of ln(decay) as found by this search at (decay, delay), the sizes
  // refitted at each decay (σ: the residuals' standard deviation, mm). With g the change of
  // the residuals with ln(decay) and w the samples' weights, the weighted least squares' own:
  // u² = σ²·Σw²g² / (Σwg²)² (σ²/Σg² when every sample is searched over); infinite when the
  // decay changes nothing.
  double u_log_decay(double decay, const Delays& delay, double sigma) {
    const double h = 0.02;
    const Eigen::VectorXd g =  // √w·g
        (residual(decay * std::exp(h), delay) - residual(decay * std::exp(-h), delay)) / (2 * h);
    const double sum = g.squaredNorm();
    if (!(sum > 0)) return INFINITY;
    return sigma * std::sqrt((root_w_.array().square() * g.array().square()).sum()) / sum;
  }
  // The finest angle between the samples searched over where the axes reverse (rad): finer
  // delays cannot be told apart.
  double spacing() const { return spacing_; }
  double yy() const { return yy_; }  // the searched samples' weighted sum of squares (mm²)

 private:
  bool ccw_, cw_;
  Samples x_;
  Eigen::VectorXd root_w_;
  double spacing_ = 0;
  Eigen::Index pf_ = 0, pv_ = 0;
  Eigen::MatrixXd Z_, FF_, P_;  // P_ = Zᵀ·(varying columns), (p + 1) × pv
  Eigen::VectorXd Fy_;
  double yy_ = 0;
  bool made_ = false;  // the varying columns hold (decay_, delay_)
  double decay_ = 0;
  Delays delay_{};
};

}  // namespace

Searched search(const Trace& t, const Samples& x, const Options& o, bool ccw, bool cw) {
  // The spikes' decay and the reversals' delay, when not given, are those that fit best: grids
  // of both (over at most kGridSamples samples), then a golden-section search of each in turn
  // about the best (over at most kSearchSamples, and every sample where the axes reverse).
  constexpr std::size_t kGridSamples = 1024, kSearchSamples = 2048;
  auto fine = std::make_shared<std::optional<Search>>();
  using Delays = Search::Delays;
  // The least of f over [a, b] by golden section, starting from `from`: the bracket's ends are
  // tried too (a step-like RSS, as a backlash step's place between samples gives, or a minimum
  // at an end, is kept), and `from` is left only for an RSS lower by more than `slack` (what
  // the data cannot tell apart, such as a delay within one sample interval, stays as it was).
  auto golden = [](auto f, double from, double a, double b, double tol, double slack) {
    const double g = (std::sqrt(5.0) - 1) / 2;
    double best_x = from, best_f = f(from);
    for (const double end : {a, b})
      if (const double fe = f(end); fe < best_f - slack) {
        best_x = end;
        best_f = fe;
      }
    double x1 = b - g * (b - a), x2 = a + g * (b - a);
    double f1 = f(x1), f2 = f(x2);
    for (int it = 0; it < 60 && b - a > tol; ++it) {
      if (f1 < f2) {
        b = x2;
        x2 = x1;
        f2 = f1;
        x1 = b - g * (b - a);
        f1 = f(x1);
      } else {
        a = x1;
        x1 = x2;
        f1 = f2;
        x2 = a + g * (b - a);
        f2 = f(x2);
      }
    }
    const double x = f1 < f2 ? x1 : x2, fx = std::min(f1, f2);
    return fx < best_f - slack ? x : best_x;
  };
  const double lo = std::log(0.5 * kPi / 180), hi = std::log(30 * kPi / 180);
  const double max_delay = 5 * kPi / 180;
  const bool find_decay = o.spike_decay == 0, find_delay = o.reversal_delay < 0;
  constexpr int kScan = 12, kDelays = 20;
  double log_decay = find_decay ? 0.5 * (lo + hi) : std::log(o.spike_decay);
  Delays delay{find_delay ? 0 : o.reversal_delay, find_delay ? 0 : o.reversal_delay};
  if (find_decay || find_delay) {
    Search coarse(t, x, o, ccw, cw, kGridSamples);
    // Grids with one delay for both axes: the delay at a middle decay (a backlash step's
    // place hardly depends on the decay), the decay at that delay, the delay again at that
    // decay; then each axis' own.
    auto grid = [&](bool over_decay) {
      if (over_decay ? !find_decay : !find_delay) return;
      double best = INFINITY, best_at = 0;
      for (int i = 0; i <= (over_decay ? kScan : kDelays); ++i) {
        const double ld = over_decay ? lo + (hi - lo) * i / kScan : log_decay;
        const double dl = over_decay ? delay[0] : max_delay * i / kDelays;
        if (const double v = coarse.rss(std::exp(ld), {dl, dl}); v < best) {
          best = v;
          best_at = over_decay ? ld : dl;
        }
      }
      if (over_decay)
        log_decay = best_at;
      else
        delay = {best_at, best_at};
    };
    grid(false);
    grid(true);
    grid(false);
    // Two rounds: the first over the grid's samples, the second over the finer set.
    for (int round = 0; round < 2; ++round) {
      // Each axis' delay is searched about the grid's within its step, then about the first
      // round's within twice the spacing of the samples it searched over (when wider).
      const double reach =
          round == 0 ? max_delay / kDelays : std::max(max_delay / kDelays, 2 * coarse.spacing());
      if (round == 1)  // every sample where the axes reverse, over the delays' search range
        fine->emplace(t, x, o, ccw, cw, kSearchSamples, delay, reach + kPi / 1800);
      auto f = [&](double d, const Delays& dl) {
        return round == 0 ? coarse.rss(d, dl) : (*fine)->rss(d, dl);
      };
      // Differences below 10⁻¹⁰ of the trace's sum of squares are round-off, not evidence.
      const double slack = 1e-10 * (round == 0 ? coarse : **fine).yy();
      if (find_decay)
        log_decay = golden([&](double ld) { return f(std::exp(ld), delay); }, log_decay,
                           std::max(lo, log_decay - (hi - lo) / kScan),
                           std::min(hi, log_decay + (hi - lo) / kScan), 1e-5, slack);
      if (find_delay) {
        const double spacing = (round == 0 ? coarse : **fine).spacing();
        for (std::size_t axis = 0; axis < 2; ++axis)
          delay[axis] = golden(
              [&](double at) {
                Delays d = delay;
                d[axis] = at;
                return f(std::exp(log_decay), d);
              },
              delay[axis], std::max(0.0, delay[axis] - reach),
              std::min(max_delay, delay[axis] + reach), spacing / 8, slack);
      }
    }
  }
  Searched s;
  s.decay = std::exp(log_decay);
  s.delay = delay;
  if (!find_decay) {
    s.decay_note = "given, not found from the data";
  } else if (log_decay <= lo + 1e-3 || log_decay >= hi - 1e-3) {
    s.decay_note = "not resolved: the best fit is at the end of the range searched";
  } else {
    s.u_log_decay = [fine, decay = s.decay, delay](double sigma) {
      return (*fine)->u_log_decay(decay, delay, sigma);
    };
  }
  return s;
}

}  // namespace trueaxis::circular::detail
