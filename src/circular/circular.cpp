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
#include <optional>

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

// A column of the design: what it is; its values are the design matrix' column of the same index.
struct Column {
  std::string key, name, unit;
  double to_unit;  // library value × to_unit = value in `unit`
};

// The samples a design is built over: angle, its cosine and sine, and the direction's sign
// (+1 ccw, −1 cw), computed once.
struct Samples {
  Eigen::VectorXd th, w, cs, sn, s;  // w: θ wrapped into [0, 2π)
  Eigen::Index size() const { return th.size(); }
  static Samples of(const Trace& t, const std::vector<Eigen::Index>& idx) {
    Samples x;
    const auto n = static_cast<Eigen::Index>(idx.size());
    x.th.resize(n);
    x.w.resize(n);
    x.cs.resize(n);
    x.sn.resize(n);
    x.s.resize(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      const Eigen::Index k = idx[static_cast<std::size_t>(i)];
      x.th[i] = t.angle[k];
      x.w[i] = wrap(x.th[i]);
      ::sincos(x.th[i], &x.sn[i], &x.cs[i]);  // glibc's: both for the price of one
      x.s[i] = t.direction[static_cast<std::size_t>(k)] == Direction::Ccw ? 1.0 : -1.0;
    }
    return x;
  }
};

// The columns that do not depend on the spikes' decay or the reversals' delay, their values
// written into F (n × fixed_count(o)).
Eigen::Index fixed_count(const Options& o) {
  return 8 + (o.pitch_a > 0 ? 2 : 0) + (o.pitch_b > 0 ? 2 : 0);
}
std::vector<Column> fixed_columns(const Samples& x, const Options& o,
                                  Eigen::Ref<Eigen::MatrixXd> F) {
  const Eigen::Index n = x.size();
  const double R = o.radius, v = o.feed / 60.0;
  const char* axes = "XYZ";
  const char A = axes[o.plane.a], B = axes[o.plane.b];
  std::vector<Column> c;
  auto add = [&](std::string key, std::string name, std::string unit, double to_unit) {
    c.push_back({std::move(key), std::move(name), std::move(unit), to_unit});
  };
  add(fmt::format("centre_offset.{}", A), fmt::format("centre offset along {}", A), "µm", 1e3);
  add(fmt::format("centre_offset.{}", B), fmt::format("centre offset along {}", B), "µm", 1e3);
  add("radius_offset", "radius offset (ballbar length, following lag)", "µm", 1e3);
  add("squareness", fmt::format("squareness of {} and {}", A, B), "µm/m", 1e6);
  add("scale_mismatch", fmt::format("scale mismatch ({} − {})", A, B), "µm/m", 1e6);
  add("lag_mismatch", fmt::format("servo lag mismatch ({} − {})", A, B), "ms", 1e3);
  add(fmt::format("straightness.{}", A), fmt::format("straightness of {} (bow along {})", A, B),
      "µm", 1e3);
  add(fmt::format("straightness.{}", B), fmt::format("straightness of {} (bow along {})", B, A),
      "µm", 1e3);
  const double pitch[2] = {o.pitch_a, o.pitch_b};
  for (int axis = 0; axis < 2; ++axis)
    if (pitch[axis] > 0) {
      const char X = axis == 0 ? A : B;
      add(fmt::format("cyclic_sin.{}", X), "", "µm", 1e3);
      add(fmt::format("cyclic_cos.{}", X), "", "µm", 1e3);
    }
  for (Eigen::Index k = 0; k < n; ++k) {
    const double cs = x.cs[k], sn = x.sn[k], s2 = 2 * sn * cs, c2 = cs * cs - sn * sn;
    Eigen::Index j = 0;
    F(k, j++) = cs;
    F(k, j++) = sn;
    F(k, j++) = 1;
    F(k, j++) = -R / 2 * s2;
    F(k, j++) = R / 2 * c2;
    F(k, j++) = x.s[k] * v / 2 * s2;
    F(k, j++) = cs * cs * sn;
    F(k, j++) = sn * sn * cs;
    for (int axis = 0; axis < 2; ++axis)
      if (pitch[axis] > 0) {
        const double proj = axis == 0 ? cs : sn, w = kTwoPi * R * proj / pitch[axis];
        F(k, j++) = std::sin(w) * proj;
        F(k, j++) = std::cos(w) * proj;
      }
  }
  return c;
}

// The columns that do: backlash per axis, then the reversal spikes per axis and direction run
// (the ones run: `ccw`, `cw`), written into V (n × columns). The spike after a reversal at r,
// Δθ = the angle travelled since r, is exp(−Δθ/d) (left out beyond 12·d, below 6·10⁻⁶).
int varying_count(bool ccw, bool cw) {
  return 2 + 2 * ((ccw ? 1 : 0) + (cw ? 1 : 0));
}
void varying_matrix(const Samples& x, double decay, const std::array<double, 2>& delay, bool ccw,
                    bool cw,
                    Eigen::Ref<Eigen::MatrixXd> V) {  // sized n × varying_count(ccw, cw)
  const Eigen::Index n = x.size();
  V.setZero();
  int spike_col[2][2] = {{-1, -1}, {-1, -1}};  // [axis][direction]
  int next = 2;
  for (int axis = 0; axis < 2; ++axis)
    for (int dir = 0; dir < 2; ++dir)
      if ((dir == 0 && ccw) || (dir == 1 && cw)) spike_col[axis][dir] = next++;
  const double ca = std::cos(delay[0]), sa = std::sin(delay[0]), cb = std::cos(delay[1]),
               sb = std::sin(delay[1]), reach = 12 * decay;
  for (Eigen::Index k = 0; k < n; ++k) {
    const double cs = x.cs[k], sn = x.sn[k], s = x.s[k];
    // An axis reverses where its motor's velocity changes sign: its own delay after the
    // commanded reversal in the direction of travel (its following lag's phase). sin(θ − s·δa)
    // for the first axis, cos(θ − s·δb) for the second:
    const double sin_a = sn * ca - s * cs * sa, cos_b = cs * cb + s * sn * sb;
    V(k, 0) = s / 2 * sign(sin_a) * cs;
    V(k, 1) = -s / 2 * sign(cos_b) * sn;
    const int dir = s > 0 ? 0 : 1;
    for (int axis = 0; axis < 2; ++axis) {
      const int j = spike_col[axis][dir];
      if (j < 0) continue;
      const double first = (axis == 0 ? 0.0 : kPi / 2) + s * delay[static_cast<std::size_t>(axis)];
      double sum = 0;
      for (const double r : {first, first + kPi}) {
        double d = s > 0 ? x.w[k] - r : r - x.w[k];  // in (−2π − δ, 2π + δ): two steps at most
        if (d < 0) d += kTwoPi;
        if (d < 0) d += kTwoPi;
        if (d >= kTwoPi) d -= kTwoPi;
        if (d < reach) sum += std::exp(-d / decay);
      }
      V(k, j) = sum * std::abs(axis == 0 ? cs : sn);
    }
  }
}
// What varying_matrix's columns are.
std::vector<Column> varying_columns(const Options& o, bool ccw, bool cw) {
  const char* axes = "XYZ";
  const char AB[2] = {axes[o.plane.a], axes[o.plane.b]};
  std::vector<Column> c;
  for (int axis = 0; axis < 2; ++axis)
    c.push_back(
        {fmt::format("backlash.{}", AB[axis]), fmt::format("backlash of {}", AB[axis]), "µm", 1e3});
  for (int axis = 0; axis < 2; ++axis)
    for (int dir = 0; dir < 2; ++dir) {
      if ((dir == 0 && !ccw) || (dir == 1 && !cw)) continue;
      const char* d = dir == 0 ? "ccw" : "cw";
      c.push_back({fmt::format("reversal_spike.{}.{}", AB[axis], d),
                   fmt::format("reversal spike of {}, {}", AB[axis], d), "µm", 1e3});
    }
  return c;
}

struct Fit {
  Eigen::VectorXd beta;                    // per column (NaN where dropped)
  Eigen::MatrixXd cov_unit;                // (JᵀJ)⁻¹ over the kept columns, library units
  std::vector<int> kept;                   // column indices solved for
  std::vector<std::vector<int>> confused;  // groups the data cannot tell apart
  double rss = 0;                          // yᵀy − βᵀJᵀy (the normal equations' own)
};

// Least squares from the normal equations N = JᵀJ, c = Jᵀy, yy = yᵀy over the columns, scaled to
// unit norm: the columns the data cannot tell apart are found from N's near-null directions and
// all but the first of each group left out; the rest solved by Cholesky. Columns with no effect
// (zero diagonal) are left out. With the columns scaled, N's condition is that of the
// signatures' correlations (|corr| < 0.995 kept apart: a condition below ~10⁴).
Fit solve_normal(const Eigen::MatrixXd& N0, const Eigen::VectorXd& c0, double yy,
                 bool covariance = true) {
  const auto p = N0.rows();
  Fit f;
  std::vector<int> use;
  for (Eigen::Index j = 0; j < p; ++j)
    if (N0(j, j) > 0) use.push_back(static_cast<int>(j));
  const auto m = static_cast<Eigen::Index>(use.size());
  Eigen::VectorXd scale(m);
  for (Eigen::Index i = 0; i < m; ++i)
    scale[i] = std::sqrt(N0(use[static_cast<std::size_t>(i)], use[static_cast<std::size_t>(i)]));
  Eigen::MatrixXd N(m, m);
  for (Eigen::Index i = 0; i < m; ++i)
    for (Eigen::Index k = 0; k < m; ++k)
      N(i, k) = N0(use[static_cast<std::size_t>(i)], use[static_cast<std::size_t>(k)]) /
                (scale[i] * scale[k]);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(N);
  std::vector<bool> drop(use.size(), false);
  const double top = es.eigenvalues().maxCoeff();
  for (Eigen::Index e = 0; e < m; ++e) {
    if (es.eigenvalues()[e] > 1e-10 * top) continue;
    std::vector<int> group;
    for (Eigen::Index j = 0; j < m; ++j)
      if (std::abs(es.eigenvectors()(j, e)) > 0.2) group.push_back(static_cast<int>(j));
    if (group.size() < 2) continue;
    std::vector<int> named;
    for (int j : group) named.push_back(use[static_cast<std::size_t>(j)]);
    f.confused.push_back(named);
    for (std::size_t g = 1; g < group.size(); ++g) drop[static_cast<std::size_t>(group[g])] = true;
  }
  std::vector<Eigen::Index> at;  // positions in `use` kept
  for (std::size_t j = 0; j < use.size(); ++j)
    if (!drop[j]) {
      f.kept.push_back(use[j]);
      at.push_back(static_cast<Eigen::Index>(j));
    }
  const auto q = static_cast<Eigen::Index>(at.size());
  Eigen::MatrixXd K(q, q);
  Eigen::VectorXd c(q);
  for (Eigen::Index i = 0; i < q; ++i) {
    c[i] = c0[use[static_cast<std::size_t>(at[static_cast<std::size_t>(i)])]] /
           scale[at[static_cast<std::size_t>(i)]];
    for (Eigen::Index k = 0; k < q; ++k)
      K(i, k) = N(at[static_cast<std::size_t>(i)], at[static_cast<std::size_t>(k)]);
  }
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(K);
  const Eigen::VectorXd b = ldlt.solve(c);
  f.rss = std::max(yy - b.dot(c), 0.0);
  if (!covariance) return f;  // the search needs the RSS only
  const Eigen::MatrixXd inv = ldlt.solve(Eigen::MatrixXd::Identity(q, q));
  f.beta = Eigen::VectorXd::Constant(p, NAN);
  f.cov_unit.resize(q, q);
  for (Eigen::Index i = 0; i < q; ++i) {
    const double si = scale[at[static_cast<std::size_t>(i)]];
    f.beta[f.kept[static_cast<std::size_t>(i)]] = b[i] / si;
    for (Eigen::Index k = 0; k < q; ++k)
      f.cov_unit(i, k) = inv(i, k) / (si * scale[at[static_cast<std::size_t>(k)]]);
  }
  return f;
}

// The residual sum of squares at (decay, delay), for the search: the normal equations of
// Z = [fixed columns | varying columns | y], the fixed part's products computed once and the
// varying columns' products (one matrix product) per call, over at most `cap` samples evenly
// taken from the trace (every k-th in its order). The decay and delay are found from them; the
// sizes are then fitted over every sample.
class Search {
 public:
  Search(const Trace& t, const Options& o, bool ccw, bool cw, std::size_t cap)
      : ccw_(ccw), cw_(cw) {
    const auto n = static_cast<std::size_t>(t.angle.size());
    const std::size_t step = (n + cap - 1) / cap;
    std::vector<Eigen::Index> idx;
    for (std::size_t k = 0; k < n; k += step) idx.push_back(static_cast<Eigen::Index>(k));
    x_ = Samples::of(t, idx);
    pf_ = fixed_count(o);
    pv_ = varying_count(ccw, cw);
    Z_.resize(x_.size(), pf_ + pv_ + 1);
    fixed_columns(x_, o, Z_.leftCols(pf_));
    const auto F = Z_.leftCols(pf_);
    for (Eigen::Index i = 0; i < x_.size(); ++i)
      Z_(i, pf_ + pv_) = t.deviation[idx[static_cast<std::size_t>(i)]];
    const Eigen::MatrixXd Fz = F.transpose() * Z_.rightCols(1);
    FF_ = F.transpose() * F;
    Fy_ = Fz.col(0);
    yy_ = Z_.rightCols(1).squaredNorm();
  }
  double rss(double decay, const std::array<double, 2>& delay) {
    varying_matrix(x_, decay, delay, ccw_, cw_, Z_.middleCols(pf_, pv_));
    const Eigen::MatrixXd P = Z_.transpose() * Z_.middleCols(pf_, pv_);  // (p + 1) × pv
    const Eigen::Index p = pf_ + pv_;
    Eigen::MatrixXd N(p, p);
    N.topLeftCorner(pf_, pf_) = FF_;
    N.rightCols(pv_) = P.topRows(p);
    N.bottomLeftCorner(pv_, pf_) = P.topRows(pf_).transpose();
    Eigen::VectorXd c(p);
    c.head(pf_) = Fy_;
    c.tail(pv_) = P.row(p).transpose();
    return solve_normal(N, c, yy_, false).rss;
  }
  // The mean angle between the samples searched over (rad): finer delays cannot be told apart.
  double spacing() const {
    return 4 * kPi / static_cast<double>(std::max<Eigen::Index>(x_.size(), 1));
  }

 private:
  bool ccw_, cw_;
  Samples x_;
  Eigen::Index pf_ = 0, pv_ = 0;
  Eigen::MatrixXd Z_, FF_;
  Eigen::VectorXd Fy_;
  double yy_ = 0;
};

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

  // The diagnosis. The spikes' decay and the reversals' delay, when not given, are those that
  // fit best: a coarse grid of both (over at most kGridSamples samples), then a golden-section
  // search of each in turn about the best (over at most kSearchSamples; decay on a log scale
  // over 0.5° … 30°, delay over 0 … 5°).
  constexpr std::size_t kGridSamples = 1024, kSearchSamples = 4096;
  const bool has_ccw = !ccw.empty(), has_cw = !cw.empty();
  std::optional<Search> coarse, fine;
  using Delays = std::array<double, 2>;
  auto coarse_rss = [&](double d, const Delays& delay) {
    if (!coarse) coarse.emplace(t, o, has_ccw, has_cw, kGridSamples);
    return coarse->rss(d, delay);
  };
  auto rss_at = [&](double d, const Delays& delay) {
    if (!fine) fine.emplace(t, o, has_ccw, has_cw, kSearchSamples);
    return fine->rss(d, delay);
  };
  // The least of f over [a, b]: golden section, the bracket's ends included (a step-like RSS,
  // as a backlash step's position between samples gives, or a minimum at an end, is kept).
  auto golden = [](auto f, double a, double b, double tol) {
    const double g = (std::sqrt(5.0) - 1) / 2;
    double best_x = a, best_f = f(a);
    if (const double fb = f(b); fb < best_f) {
      best_x = b;
      best_f = fb;
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
    return fx < best_f ? x : best_x;
  };
  const double lo = std::log(0.5 * kPi / 180), hi = std::log(30 * kPi / 180);
  const double max_delay = 5 * kPi / 180;
  const bool find_decay = o.spike_decay == 0, find_delay = o.reversal_delay < 0;
  constexpr int kScan = 12, kDelays = 5;
  double log_decay = find_decay ? 0.5 * (lo + hi) : std::log(o.spike_decay);
  Delays delay{find_delay ? 0 : o.reversal_delay, find_delay ? 0 : o.reversal_delay};
  if (find_decay || find_delay) {
    // The grid with one delay for both axes; then each axis' own.
    double best = INFINITY;
    int bi = 0, bj = 0;
    for (int i = 0; i <= (find_decay ? kScan : 0); ++i)
      for (int j = 0; j <= (find_delay ? kDelays : 0); ++j) {
        const double ld = find_decay ? lo + (hi - lo) * i / kScan : log_decay;
        const double dl = find_delay ? max_delay * j / kDelays : delay[0];
        const double v = coarse_rss(std::exp(ld), {dl, dl});
        if (v < best) {
          best = v;
          bi = i;
          bj = j;
        }
      }
    if (find_decay) log_decay = lo + (hi - lo) * bi / kScan;
    if (find_delay) delay[0] = delay[1] = max_delay * bj / kDelays;
    // Two rounds: the first over the grid's samples, the second over the finer set.
    for (int round = 0; round < 2; ++round) {
      auto f = [&](double d, const Delays& dl) {
        return round == 0 ? coarse_rss(d, dl) : rss_at(d, dl);
      };
      if (find_decay)
        log_decay = golden([&](double x) { return f(std::exp(x), delay); },
                           std::max(lo, log_decay - (hi - lo) / kScan),
                           std::min(hi, log_decay + (hi - lo) / kScan), 1e-5);
      if (find_delay) {
        f(std::exp(log_decay), delay);  // the searched samples' spacing sets the tolerance
        const double spacing = (round == 0 ? coarse : fine)->spacing();
        for (std::size_t axis = 0; axis < 2; ++axis)
          delay[axis] = golden(
              [&](double x) {
                Delays d = delay;
                d[axis] = x;
                return f(std::exp(log_decay), d);
              },
              std::max(0.0, delay[axis] - max_delay / kDelays),
              std::min(max_delay, delay[axis] + max_delay / kDelays), spacing / 8);
      }
    }
  }
  const double decay = std::exp(log_decay);
  r.spike_decay = decay;
  r.reversal_delay = delay;
  const Eigen::Index pf = fixed_count(o), pv = varying_count(has_ccw, has_cw);
  Eigen::MatrixXd design(n, pf + pv);
  auto cols = fixed_columns(x, o, design.leftCols(pf));
  for (auto& c : varying_columns(o, has_ccw, has_cw)) cols.push_back(std::move(c));
  varying_matrix(x, decay, delay, has_ccw, has_cw, design.rightCols(pv));
  // JᵀJ by a symmetric rank update (half the work of the full product).
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(pf + pv, pf + pv);
  normal.selfadjointView<Eigen::Lower>().rankUpdate(design.transpose());
  normal = normal.selfadjointView<Eigen::Lower>();
  Fit fit = solve_normal(normal, design.transpose() * t.deviation, t.deviation.squaredNorm());
  const auto p = static_cast<Eigen::Index>(fit.kept.size());
  const double dof = static_cast<double>(n - p);
  r.model = design * fit.beta.unaryExpr([](double b) { return std::isnan(b) ? 0.0 : b; });
  r.residual = t.deviation - r.model;
  fit.rss = r.residual.squaredNorm();  // from the residual itself: no cancellation
  r.sigma = dof > 0 ? std::sqrt(fit.rss / dof) : 0.0;
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
