// The circular test's figures (ISO 230-4:2005, clause 3) and the least-squares diagnosis of the
// trace by its causes' signatures (the header states each signature and its sign convention).
#include "trueaxis/circular/circular.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <numeric>

#include "../common/figures.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::circular {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kTwoPi = 2 * kPi;

double wrap(double angle) {  // into [0, 2π)
  double w = std::fmod(angle, kTwoPi);
  return w < 0 ? w + kTwoPi : w;
}

double sign(double v) {
  return v > 0 ? 1.0 : v < 0 ? -1.0 : 0.0;
}

// One direction's samples, by index into the trace, sorted by wrapped angle.
std::vector<Eigen::Index> of_direction(const Trace& t, Direction d) {
  std::vector<Eigen::Index> idx;
  for (std::size_t k = 0; k < t.direction.size(); ++k)
    if (t.direction[k] == d) idx.push_back(static_cast<Eigen::Index>(k));
  std::stable_sort(idx.begin(), idx.end(), [&](Eigen::Index p, Eigen::Index q) {
    return wrap(t.angle[p]) < wrap(t.angle[q]);
  });
  return idx;
}

std::string where(const Trace& t, Eigen::Index k) {
  const auto K = static_cast<std::size_t>(k);
  return K < t.where.size() ? t.where[K] : fmt::format("sample {}: ", k + 1);
}

DirectionFigures figures(const Trace& t, const std::vector<Eigen::Index>& idx, double R) {
  DirectionFigures f;
  if (idx.empty()) return f;
  f.present = true;
  f.samples = static_cast<long>(idx.size());
  const auto n = static_cast<Eigen::Index>(idx.size());
  // The least-squares circle of the path's points: linear in its centre and radius to first
  // order in δr/R for a start, then Gauss–Newton on the orthogonal distances (two or three
  // steps reach round-off).
  Eigen::MatrixXd A(n, 3);
  Eigen::VectorXd y(n);
  Eigen::Matrix2Xd p(2, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index k = idx[static_cast<std::size_t>(i)];
    const double th = t.angle[k];
    A.row(i) << 1, std::cos(th), std::sin(th);
    y[i] = t.deviation[k];
    p.col(i) = (R + y[i]) * Eigen::Vector2d(std::cos(th), std::sin(th));
  }
  const Eigen::Vector3d lin = A.colPivHouseholderQr().solve(y);
  Eigen::Vector3d c(lin[1], lin[2], R + lin[0]);  // centre a, b; radius
  for (int it = 0; it < 8; ++it) {
    Eigen::MatrixXd J(n, 3);
    Eigen::VectorXd r(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      const Eigen::Vector2d q = p.col(i) - c.head<2>();
      const double d = q.norm();
      r[i] = d - c[2];
      J.row(i) << -q.x() / d, -q.y() / d, -1;
    }
    const Eigen::Vector3d step = J.colPivHouseholderQr().solve(r);
    c -= step;
    if (step.norm() < 1e-13 * R) break;
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

// The deviation of one direction at angle θ, linear between its samples (periodic).
double interpolate(const Trace& t, const std::vector<Eigen::Index>& idx, double theta) {
  const double w = wrap(theta);
  const auto n = idx.size();
  auto angle = [&](std::size_t k) { return wrap(t.angle[idx[k]]); };
  auto upper = std::lower_bound(idx.begin(), idx.end(), w,
                                [&](Eigen::Index p, double v) { return wrap(t.angle[p]) < v; });
  const std::size_t j = static_cast<std::size_t>(upper - idx.begin()) % n;
  const std::size_t i = (j + n - 1) % n;
  double a0 = angle(i), a1 = angle(j), x = w;
  if (a1 <= a0) a1 += kTwoPi;
  if (x < a0) x += kTwoPi;
  const double s = a1 > a0 ? (x - a0) / (a1 - a0) : 0.0;
  return (1 - s) * t.deviation[idx[i]] + s * t.deviation[idx[j]];
}

struct Column {
  std::string key, name, unit;
  double to_unit;  // library value × to_unit = value in `unit`
  Eigen::VectorXd v;
};

// Spike signature: exp(−Δθ/d) after each reversal at `at` (two angles), Δθ measured in the
// direction of travel.
double spike(double theta, double s, const std::array<double, 2>& at, double d) {
  double out = 0;
  for (double r : at) {
    const double dt = wrap(s > 0 ? theta - r : r - theta);
    if (dt < 12 * d) out += std::exp(-dt / d);
  }
  return out;
}

std::vector<Column> columns(const Trace& t, const Options& o, double decay, double delay, bool ccw,
                            bool cw) {
  const Eigen::Index n = t.angle.size();
  const double R = o.radius, v = o.feed / 60.0;
  const char* axes = "XYZ";
  const char A = axes[o.plane.a], B = axes[o.plane.b];
  std::vector<Column> c;
  auto add = [&](std::string key, std::string name, std::string unit, double to_unit) {
    c.push_back(
        {std::move(key), std::move(name), std::move(unit), to_unit, Eigen::VectorXd::Zero(n)});
    return &c.back().v;
  };
  add(fmt::format("centre_offset.{}", A), fmt::format("centre offset along {}", A), "µm", 1e3);
  add(fmt::format("centre_offset.{}", B), fmt::format("centre offset along {}", B), "µm", 1e3);
  add("radius_offset", "radius offset (ballbar length, following lag)", "µm", 1e3);
  add("squareness", fmt::format("squareness of {} and {}", A, B), "µm/m", 1e6);
  add("scale_mismatch", fmt::format("scale mismatch ({} − {})", A, B), "µm/m", 1e6);
  add("lag_mismatch", fmt::format("servo lag mismatch ({} − {})", A, B), "ms", 1e3);
  add(fmt::format("backlash.{}", A), fmt::format("backlash of {}", A), "µm", 1e3);
  add(fmt::format("backlash.{}", B), fmt::format("backlash of {}", B), "µm", 1e3);
  add(fmt::format("straightness.{}", A), fmt::format("straightness of {} (bow along {})", A, B),
      "µm", 1e3);
  add(fmt::format("straightness.{}", B), fmt::format("straightness of {} (bow along {})", B, A),
      "µm", 1e3);
  for (int axis = 0; axis < 2; ++axis)
    for (int dir = 0; dir < 2; ++dir) {
      if ((dir == 0 && !ccw) || (dir == 1 && !cw)) continue;
      const char X = axis == 0 ? A : B;
      add(fmt::format("reversal_spike.{}.{}", X, dir == 0 ? "ccw" : "cw"),
          fmt::format("reversal spike of {}, {}", X, dir == 0 ? "ccw" : "cw"), "µm", 1e3);
    }
  const double pitch[2] = {o.pitch_a, o.pitch_b};
  for (int axis = 0; axis < 2; ++axis)
    if (pitch[axis] > 0) {
      const char X = axis == 0 ? A : B;
      add(fmt::format("cyclic_sin.{}", X), "", "µm", 1e3);
      add(fmt::format("cyclic_cos.{}", X), "", "µm", 1e3);
    }
  for (Eigen::Index k = 0; k < n; ++k) {
    const double th = t.angle[k], cs = std::cos(th), sn = std::sin(th);
    const double s = t.direction[static_cast<std::size_t>(k)] == Direction::Ccw ? 1.0 : -1.0;
    std::size_t j = 0;
    c[j++].v[k] = cs;
    c[j++].v[k] = sn;
    c[j++].v[k] = 1;
    c[j++].v[k] = -R / 2 * std::sin(2 * th);
    c[j++].v[k] = R / 2 * std::cos(2 * th);
    c[j++].v[k] = s * v / 2 * std::sin(2 * th);
    // An axis reverses where its motor's velocity changes sign: `delay` after the commanded
    // reversal in the direction of travel (a following lag's phase).
    c[j++].v[k] = s / 2 * sign(std::sin(th - s * delay)) * cs;
    c[j++].v[k] = -s / 2 * sign(std::cos(th - s * delay)) * sn;
    c[j++].v[k] = cs * cs * sn;
    c[j++].v[k] = sn * sn * cs;
    for (int axis = 0; axis < 2; ++axis) {
      const double base = axis == 0 ? 0.0 : kPi / 2;
      const std::array<double, 2> at{base + s * delay, base + kPi + s * delay};
      for (int dir = 0; dir < 2; ++dir) {
        if ((dir == 0 && !ccw) || (dir == 1 && !cw)) continue;
        if ((dir == 0) == (s > 0))
          c[j].v[k] = spike(th, s, at, decay) * std::abs(axis == 0 ? cs : sn);
        ++j;
      }
    }
    for (int axis = 0; axis < 2; ++axis)
      if (pitch[axis] > 0) {
        const double x = R * (axis == 0 ? cs : sn), w = kTwoPi * x / pitch[axis];
        const double proj = axis == 0 ? cs : sn;
        c[j++].v[k] = std::sin(w) * proj;
        c[j++].v[k] = std::cos(w) * proj;
      }
  }
  return c;
}

struct Fit {
  Eigen::VectorXd beta;                    // per column (NaN where dropped)
  Eigen::MatrixXd cov_unit;                // (JᵀJ)⁻¹ over the kept columns, library units
  std::vector<int> kept;                   // column indices solved for
  std::vector<std::vector<int>> confused;  // groups the data cannot tell apart
  double rss = 0;
};

// Least squares over the columns, with the columns the data cannot tell apart found from the
// scaled normal matrix's near-null directions and all but the first of each group left out.
Fit solve(const std::vector<Column>& cols, const Eigen::VectorXd& y) {
  const Eigen::Index n = y.size();
  Fit f;
  std::vector<int> use;
  for (std::size_t j = 0; j < cols.size(); ++j)
    if (cols[j].v.cwiseAbs().maxCoeff() > 0) use.push_back(static_cast<int>(j));
  auto matrix = [&](const std::vector<int>& which, Eigen::VectorXd& scale) {
    Eigen::MatrixXd J(n, static_cast<Eigen::Index>(which.size()));
    scale.resize(J.cols());
    for (Eigen::Index j = 0; j < J.cols(); ++j) {
      J.col(j) = cols[static_cast<std::size_t>(which[static_cast<std::size_t>(j)])].v;
      scale[j] = J.col(j).norm();
      J.col(j) /= scale[j];
    }
    return J;
  };
  Eigen::VectorXd scale;
  Eigen::MatrixXd J = matrix(use, scale);
  // Groups the data cannot tell apart: the near-null eigenvectors of the scaled normal matrix.
  const Eigen::MatrixXd N = J.transpose() * J;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(N);
  std::vector<bool> drop(use.size(), false);
  const double top = es.eigenvalues().maxCoeff();
  for (Eigen::Index e = 0; e < es.eigenvalues().size(); ++e) {
    if (es.eigenvalues()[e] > 1e-10 * top) continue;
    std::vector<int> group;
    for (Eigen::Index j = 0; j < es.eigenvectors().rows(); ++j)
      if (std::abs(es.eigenvectors()(j, e)) > 0.2) group.push_back(static_cast<int>(j));
    if (group.size() < 2) continue;
    std::vector<int> named;
    for (int j : group) named.push_back(use[static_cast<std::size_t>(j)]);
    f.confused.push_back(named);
    for (std::size_t g = 1; g < group.size(); ++g) drop[static_cast<std::size_t>(group[g])] = true;
  }
  for (std::size_t j = 0; j < use.size(); ++j)
    if (!drop[j]) f.kept.push_back(use[j]);
  J = matrix(f.kept, scale);
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(J);
  const Eigen::VectorXd b = qr.solve(y);
  f.rss = (J * b - y).squaredNorm();
  f.beta = Eigen::VectorXd::Constant(static_cast<Eigen::Index>(cols.size()), NAN);
  const Eigen::MatrixXd inv = (J.transpose() * J).inverse();
  f.cov_unit.resize(J.cols(), J.cols());
  for (Eigen::Index i = 0; i < J.cols(); ++i) {
    f.beta[f.kept[static_cast<std::size_t>(i)]] = b[i] / scale[i];
    for (Eigen::Index k = 0; k < J.cols(); ++k)
      f.cov_unit(i, k) = inv(i, k) / (scale[i] * scale[k]);
  }
  return f;
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
  const auto ccw = of_direction(t, Direction::Ccw), cw = of_direction(t, Direction::Cw);
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
      const double a0 = wrap(t.angle[(*idx)[k]]);
      const double a1 =
          k + 1 < idx->size() ? wrap(t.angle[(*idx)[k + 1]]) : wrap(t.angle[(*idx)[0]]) + kTwoPi;
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
  r.ccw = figures(t, ccw, o.radius);
  r.cw = figures(t, cw, o.radius);
  if (!ccw.empty() && !cw.empty()) {
    double h = 0;
    for (Eigen::Index k : ccw)
      h = std::max(h, std::abs(t.deviation[k] - interpolate(t, cw, t.angle[k])));
    r.H = h;
  }

  // The diagnosis. The spikes' decay and the reversals' delay, when not given, are those that
  // fit best: a coarse grid of both, then a golden-section search of each in turn about the best
  // (decay on a log scale over 0.5° … 30°, delay over 0 … 5°).
  const bool has_ccw = !ccw.empty(), has_cw = !cw.empty();
  auto rss_at = [&](double d, double delay) {
    return solve(columns(t, o, d, delay, has_ccw, has_cw), t.deviation).rss;
  };
  // The least of f over [a, b]: golden section, the bracket's ends included (a step-like RSS,
  // as a backlash step's position between samples gives, or a minimum at an end, is kept).
  auto golden = [](auto f, double a, double b) {
    const double g = (std::sqrt(5.0) - 1) / 2;
    double best_x = a, best_f = f(a);
    if (const double fb = f(b); fb < best_f) {
      best_x = b;
      best_f = fb;
    }
    double x1 = b - g * (b - a), x2 = a + g * (b - a);
    double f1 = f(x1), f2 = f(x2);
    for (int it = 0; it < 30; ++it) {
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
    return fx < best_f ? x : best_x;
  };
  const double lo = std::log(0.5 * kPi / 180), hi = std::log(30 * kPi / 180);
  const double max_delay = 5 * kPi / 180;
  const bool find_decay = o.spike_decay == 0, find_delay = o.reversal_delay < 0;
  constexpr int kScan = 12, kDelays = 10;
  double log_decay = find_decay ? 0.5 * (lo + hi) : std::log(o.spike_decay);
  double delay = find_delay ? 0 : o.reversal_delay;
  if (find_decay || find_delay) {
    double best = INFINITY;
    int bi = 0, bj = 0;
    for (int i = 0; i <= (find_decay ? kScan : 0); ++i)
      for (int j = 0; j <= (find_delay ? kDelays : 0); ++j) {
        const double ld = find_decay ? lo + (hi - lo) * i / kScan : log_decay;
        const double dl = find_delay ? max_delay * j / kDelays : delay;
        const double v = rss_at(std::exp(ld), dl);
        if (v < best) {
          best = v;
          bi = i;
          bj = j;
        }
      }
    if (find_decay) log_decay = lo + (hi - lo) * bi / kScan;
    if (find_delay) delay = max_delay * bj / kDelays;
    for (int round = 0; round < 2; ++round) {
      if (find_decay)
        log_decay = golden([&](double x) { return rss_at(std::exp(x), delay); },
                           std::max(lo, log_decay - (hi - lo) / kScan),
                           std::min(hi, log_decay + (hi - lo) / kScan));
      if (find_delay)
        delay = golden([&](double x) { return rss_at(std::exp(log_decay), x); },
                       std::max(0.0, delay - max_delay / kDelays),
                       std::min(max_delay, delay + max_delay / kDelays));
    }
  }
  const double decay = std::exp(log_decay);
  r.spike_decay = decay;
  r.reversal_delay = delay;
  const auto cols = columns(t, o, decay, delay, has_ccw, has_cw);
  const Fit fit = solve(cols, t.deviation);
  const auto p = static_cast<Eigen::Index>(fit.kept.size());
  const double dof = static_cast<double>(n - p);
  r.sigma = dof > 0 ? std::sqrt(fit.rss / dof) : 0.0;
  r.model = Eigen::VectorXd::Zero(n);
  for (int j : fit.kept) r.model += cols[static_cast<std::size_t>(j)].v * fit.beta[j];
  r.residual = t.deviation - r.model;
  r.unexplained_rms = std::sqrt(r.residual.squaredNorm() / static_cast<double>(n));
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
    if (c.v.cwiseAbs().maxCoeff() == 0) continue;      // no effect on these samples
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
      cause.share = share(c.v * s + cols[static_cast<std::size_t>(Jc)].v * co);
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
      cause.share = share(c.v * fit.beta[J]);
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
