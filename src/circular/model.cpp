// The circular test's diagnosis model (see model.hpp): the causes' signatures as columns, and
// the least squares that sizes them.
#include "model.hpp"

#include <fmt/format.h>

#include <cmath>

namespace trueaxis::circular::detail {

double wrap(double angle) {
  const double w = angle - kTwoPi * std::floor(angle / kTwoPi);
  return w < kTwoPi ? w : 0.0;  // an angle just below a multiple of 2π can round up to 2π
}

Samples Samples::of(const Trace& t, const std::vector<Eigen::Index>& idx) {
  Samples x;
  const auto n = static_cast<Eigen::Index>(idx.size());
  for (auto* v : {&x.th, &x.w, &x.cs, &x.sn, &x.s}) v->resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index k = idx[static_cast<std::size_t>(i)];
    x.th[i] = t.angle[k];
    x.w[i] = wrap(x.th[i]);
    ::sincos(x.th[i], &x.sn[i], &x.cs[i]);  // glibc's: both for the price of one
    x.s[i] = t.direction[static_cast<std::size_t>(k)] == Direction::Ccw ? 1.0 : -1.0;
  }
  return x;
}

Samples Samples::subset(const std::vector<Eigen::Index>& idx) const {
  Samples x;
  const auto n = static_cast<Eigen::Index>(idx.size());
  for (auto* v : {&x.th, &x.w, &x.cs, &x.sn, &x.s}) v->resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index k = idx[static_cast<std::size_t>(i)];
    x.th[i] = th[k];
    x.w[i] = w[k];
    x.cs[i] = cs[k];
    x.sn[i] = sn[k];
    x.s[i] = s[k];
  }
  return x;
}

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
// Δθ = the angle travelled since r, is exp(−Δθ/d), summed over the axis' last two reversals.
int varying_count(bool ccw, bool cw) {
  return 2 + 2 * ((ccw ? 1 : 0) + (cw ? 1 : 0));
}
// Column `col` of V: the backlash of `axis`. An axis reverses where its motor's velocity changes
// sign: its own delay after the commanded reversal in the direction of travel (its following
// lag's phase), at sin(θ − s·δ) = 0 for the first axis and cos(θ − s·δ) = 0 for the second.
void backlash_column(const Samples& x, int axis, double delay, Eigen::Ref<Eigen::VectorXd> v) {
  const double c = std::cos(delay), sd = std::sin(delay);
  for (Eigen::Index k = 0; k < x.size(); ++k) {
    const double cs = x.cs[k], sn = x.sn[k], s = x.s[k];
    v[k] = axis == 0 ? s / 2 * sign(sn * c - s * cs * sd) * cs
                     : -s / 2 * sign(cs * c + s * sn * sd) * sn;
  }
}
// The angle travelled since `axis` last reversed (its delay after the commanded reversal in
// the travel's direction), per sample: in [0, π), as an axis reverses twice a turn.
Eigen::ArrayXd since_reversal(const Samples& x, int axis, double delay) {
  Eigen::ArrayXd d = x.s.array() * (x.w.array() - (axis == 0 ? 0.0 : kPi / 2)) - delay;
  return d - kPi * (d / kPi).floor();
}
// The spike columns of `axis` (ccw then cw, those run) into V's columns from `col`: the spikes
// of its latest reversal, d ago, and of the one before, d + π ago (earlier ones are below
// exp(−2π/d): 6·10⁻⁶ at the longest decay searched).
void spike_columns(const Samples& x, int axis, double decay, double delay, bool ccw, bool cw,
                   Eigen::Ref<Eigen::MatrixXd> V, Eigen::Index col) {
  const Eigen::ArrayXd d = since_reversal(x, axis, delay);
  // Array expressions throughout, so Eigen evaluates them (exp included) by SIMD packets.
  const Eigen::ArrayXd spike =
      (-d / decay).exp() * ((1 + std::exp(-kPi / decay)) * (axis == 0 ? x.cs : x.sn).array().abs());
  const auto s = x.s.array();
  if (ccw) V.col(col++) = spike * (0.5 + 0.5 * s);
  if (cw) V.col(col) = spike * (0.5 - 0.5 * s);
}
// The first of `axis`' spike columns in V.
Eigen::Index spike_column(int axis, bool ccw, bool cw) {
  return 2 + axis * ((ccw ? 1 : 0) + (cw ? 1 : 0));
}
void varying_matrix(const Samples& x, double decay, const std::array<double, 2>& delay, bool ccw,
                    bool cw,
                    Eigen::Ref<Eigen::MatrixXd> V) {  // sized n × varying_count(ccw, cw)
  for (int axis = 0; axis < 2; ++axis) {
    backlash_column(x, axis, delay[static_cast<std::size_t>(axis)], V.col(axis));
    spike_columns(x, axis, decay, delay[static_cast<std::size_t>(axis)], ccw, cw, V,
                  spike_column(axis, ccw, cw));
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

// Least squares from the normal equations N = JᵀJ, c = Jᵀy, yy = yᵀy over the columns, scaled to
// unit norm: the columns the data cannot tell apart are found from N's near-null directions and
// all but the first of each group left out; the rest solved by Cholesky. Columns with no effect
// (zero diagonal) are left out. With the columns scaled, N's condition is that of the
// signatures' correlations (|corr| < 0.995 kept apart: a condition below ~10⁴).
Fit solve_normal(const Eigen::MatrixXd& N0, const Eigen::VectorXd& c0, double yy, bool covariance) {
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
  f.beta = Eigen::VectorXd::Constant(p, NAN);
  for (Eigen::Index i = 0; i < q; ++i)
    f.beta[f.kept[static_cast<std::size_t>(i)]] = b[i] / scale[at[static_cast<std::size_t>(i)]];
  if (!covariance) return f;  // the search needs the sizes only
  const Eigen::MatrixXd inv = ldlt.solve(Eigen::MatrixXd::Identity(q, q));
  f.cov_unit.resize(q, q);
  for (Eigen::Index i = 0; i < q; ++i) {
    const double si = scale[at[static_cast<std::size_t>(i)]];
    for (Eigen::Index k = 0; k < q; ++k)
      f.cov_unit(i, k) = inv(i, k) / (si * scale[at[static_cast<std::size_t>(k)]]);
  }
  return f;
}

}  // namespace trueaxis::circular::detail
