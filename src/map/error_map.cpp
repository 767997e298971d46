#include "trueaxis/map/error_map.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "../io/fast_text.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::map {
namespace {

constexpr const char* kNames = "xyz";

// 1-D weights of the nodes base..base+count−1 for the value at v in cell i (t = local
// coordinate in [0, 1]).
struct Weights {
  Eigen::Index base = 0;
  int count = 0;
  double w[4] = {0, 0, 0, 0};
};

// Coefficients of the three-point slope at node `at` on nodes a, a+1, a+2 (a parabola's
// derivative), added to `out` (indexed from a) times `scale`.
void add_slope(const double* x, Eigen::Index a, Eigen::Index at, double scale, double* out) {
  const double x0 = x[a], x1 = x[a + 1], x2 = x[a + 2];
  const double X = x[at];
  // Lagrange basis derivatives at X.
  out[0] += scale * ((X - x1) + (X - x2)) / ((x0 - x1) * (x0 - x2));
  out[1] += scale * ((X - x0) + (X - x2)) / ((x1 - x0) * (x1 - x2));
  out[2] += scale * ((X - x0) + (X - x1)) / ((x2 - x0) * (x2 - x1));
}

// `slope` holds, per node m, the 3 coefficients of its slope on nodes clamp(m − 1, 0, n − 3)..+2
// (add_slope with scale 1, made once per axis).
Weights cubic_weights(const double* x, const double* slope, Eigen::Index n, Eigen::Index i,
                      double t) {
  Weights W;
  const double h = x[i + 1] - x[i];
  const double h00 = (2 * t - 3) * t * t + 1, h10 = ((t - 2) * t + 1) * t,
               h01 = (3 - 2 * t) * t * t, h11 = (t - 1) * t * t;
  if (n == 2) {  // no curvature information: the Hermite form with chord slopes is linear
    W.base = 0;
    W.count = 2;
    W.w[0] = 1 - t;
    W.w[1] = t;
    return W;
  }
  W.base = std::clamp<Eigen::Index>(i - 1, 0, n - std::min<Eigen::Index>(n, 4));
  W.count = static_cast<int>(std::min<Eigen::Index>(n, 4));
  double* w = W.w;
  w[i - W.base] += h00;
  w[i + 1 - W.base] += h01;
  // Slope at node m from the parabola through m−1, m, m+1 (one-sided at the ends).
  auto add = [&](Eigen::Index m, double scale) {
    const Eigen::Index a = std::clamp<Eigen::Index>(m - 1, 0, n - 3);
    const double* s = slope + 3 * m;
    for (int q = 0; q < 3; ++q) w[a + q - W.base] += scale * s[q];
  };
  add(i, h10 * h);
  add(i + 1, h11 * h);
  return W;
}

}  // namespace

const char* to_string(Interpolation i) {
  return i == Interpolation::Linear ? "linear" : "cubic";
}

Interpolation interpolation_from_string(const std::string& s) {
  if (s == "linear") return Interpolation::Linear;
  if (s == "cubic") return Interpolation::Cubic;
  throw Error(fmt::format("unknown interpolation '{}' (linear or cubic)", s));
}

Eigen::Vector3d ErrorMap::node(Eigen::Index n) const {
  const Eigen::Index i = n % size(0), j = (n / size(0)) % size(1), k = n / (size(0) * size(1));
  return {axes[0][i], axes[1][j], axes[2][k]};
}

std::string ErrorMap::outside_message(const Eigen::Vector3d& p) const {
  const auto& a = axes;
  return fmt::format(
      "({:.3f}, {:.3f}, {:.3f}) mm is outside the map's grid x [{:.3f}, {:.3f}], y [{:.3f}, "
      "{:.3f}], z [{:.3f}, {:.3f}] mm (give --clamp, or clamp=True in Python, to hold the edge "
      "value)",
      p.x(), p.y(), p.z(), a[0][0], a[0][a[0].size() - 1], a[1][0], a[1][a[1].size() - 1], a[2][0],
      a[2][a[2].size() - 1]);
}

bool ErrorMap::contains(const Eigen::Vector3d& p, double tol) const {
  for (int a = 0; a < 3; ++a) {
    const auto& x = axes[static_cast<std::size_t>(a)];
    if (!(p[a] >= x[0] - tol && p[a] <= x[x.size() - 1] + tol)) return false;
  }
  return true;
}

void ErrorMap::validate() const {
  for (int a = 0; a < 3; ++a) {
    const auto& x = axes[static_cast<std::size_t>(a)];
    if (x.size() < 2) throw Error(fmt::format("the grid needs at least two {} nodes", kNames[a]));
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      if (!std::isfinite(x[i]))
        throw Error(fmt::format("grid {} node {} is not finite", kNames[a], i));
      if (i > 0 && !(x[i] > x[i - 1]))
        throw Error(fmt::format("grid {} nodes must increase strictly ({} after {})", kNames[a],
                                x[i], x[i - 1]));
    }
  }
  if (error.cols() != nodes())
    throw Error(
        fmt::format("the map has {} error vectors for {} grid nodes", error.cols(), nodes()));
  if (!error.allFinite()) throw Error("the map's errors must be finite");
  if (uncertainty.size() != 0 && (uncertainty.cols() != nodes() || !uncertainty.allFinite()))
    throw Error("the map's uncertainties must be finite, one per node");
}

Eigen::Index Interpolator::Axis::cell(double v) const {
  Eigen::Index i;
  if (uniform) {
    i = static_cast<Eigen::Index>((v - x0) * inv_h);
  } else {
    // Guess from the mean spacing (right, or one off, on the near-uniform axes of measured grids
    // such as a ball-gauge map's cluster means); otherwise search.
    i = std::clamp<Eigen::Index>(static_cast<Eigen::Index>((v - x0) * inv_h), 0, n - 2);
    if (v < x[i]) {
      if (i > 0 && v >= x[i - 1])
        --i;
      else
        i = static_cast<Eigen::Index>(std::upper_bound(x, x + n, v) - x) - 1;
    } else if (v >= x[i + 1] && i < n - 2) {
      if (v < x[i + 2])
        ++i;
      else
        i = static_cast<Eigen::Index>(std::upper_bound(x, x + n, v) - x) - 1;
    }
  }
  return std::clamp<Eigen::Index>(i, 0, n - 2);
}

Interpolator::Interpolator(const ErrorMap& map, EvalOptions options)
    : map_(&map), options_(options) {
  map.validate();
  for (int a = 0; a < 3; ++a) {
    const auto& x = map.axes[static_cast<std::size_t>(a)];
    Axis& ax = axis_[static_cast<std::size_t>(a)];
    ax.x = x.data();
    ax.n = x.size();
    ax.x0 = x[0];
    const double h = (x[x.size() - 1] - x[0]) / static_cast<double>(x.size() - 1);
    ax.uniform = true;
    for (Eigen::Index i = 0; i < x.size(); ++i)
      if (std::abs(x[i] - (x[0] + static_cast<double>(i) * h)) >
          1e-12 * std::max(1.0, std::abs(h) * static_cast<double>(x.size())))
        ax.uniform = false;
    ax.inv_h = 1.0 / h;
    // The cubic's node slopes depend on the axis only: their coefficients once, not per point.
    if (ax.n >= 3) {
      ax.slope.assign(static_cast<std::size_t>(3 * ax.n), 0.0);
      for (Eigen::Index m = 0; m < ax.n; ++m)
        add_slope(ax.x, std::clamp<Eigen::Index>(m - 1, 0, ax.n - 3), m, 1.0,
                  ax.slope.data() + 3 * m);
    }
  }
}

Eigen::Vector3d Interpolator::clamped(const Eigen::Vector3d& p) const {
  Eigen::Vector3d q;
  for (int a = 0; a < 3; ++a) {
    const Axis& ax = axis_[static_cast<std::size_t>(a)];
    q[a] = std::clamp(p[a], ax.x[0], ax.x[ax.n - 1]);
  }
  return eval(q);
}

Eigen::Vector3d Interpolator::operator()(const Eigen::Vector3d& p) const {
  if (options_.outside == Outside::Refuse && !map_->contains(p, options_.tolerance))
    throw Error(map_->outside_message(p));
  return clamped(p);
}

Eigen::Vector3d Interpolator::eval(const Eigen::Vector3d& p) const {
  const double* E = map_->error.data();
  const Eigen::Index nx = axis_[0].n, nxy = nx * axis_[1].n;
  Eigen::Index c[3];
  double t[3];
  for (int a = 0; a < 3; ++a) {
    const Axis& ax = axis_[static_cast<std::size_t>(a)];
    if (ax.uniform) {  // direct lookup: no search, no division
      const double s = (p[a] - ax.x0) * ax.inv_h;
      c[a] = std::min(static_cast<Eigen::Index>(s), ax.n - 2);
      t[a] = s - static_cast<double>(c[a]);
    } else {
      c[a] = ax.cell(p[a]);
      t[a] = (p[a] - ax.x[c[a]]) / (ax.x[c[a] + 1] - ax.x[c[a]]);
    }
  }
  if (options_.interpolation == Interpolation::Linear) {
    const double* b = E + 3 * (c[0] + nx * c[1] + nxy * c[2]);
    const Eigen::Index dx = 3, dy = 3 * nx, dz = 3 * nxy;
    Eigen::Vector3d v;
    for (int q = 0; q < 3; ++q) {
      const double c00 = b[q] + t[0] * (b[q + dx] - b[q]);
      const double c10 = b[q + dy] + t[0] * (b[q + dy + dx] - b[q + dy]);
      const double c01 = b[q + dz] + t[0] * (b[q + dz + dx] - b[q + dz]);
      const double c11 = b[q + dz + dy] + t[0] * (b[q + dz + dy + dx] - b[q + dz + dy]);
      const double c0 = c00 + t[1] * (c10 - c00), c1 = c01 + t[1] * (c11 - c01);
      v[q] = c0 + t[2] * (c1 - c0);
    }
    return v;
  }
  Weights W[3];
  for (int a = 0; a < 3; ++a) {
    const Axis& ax = axis_[static_cast<std::size_t>(a)];
    W[a] = cubic_weights(ax.x, ax.slope.data(), ax.n, c[a], t[a]);
  }
  if (W[0].count == 4) {
    // The 4 nodes along x are 12 adjacent doubles: weight whole rows (a plain, vectorisable
    // axpy), then combine along x once.
    double acc[12] = {};
    for (int k = 0; k < W[2].count; ++k)
      for (int j = 0; j < W[1].count; ++j) {
        const double wjk = W[1].w[j] * W[2].w[k];
        const double* row = E + 3 * (W[0].base + nx * (W[1].base + j) + nxy * (W[2].base + k));
        for (int q = 0; q < 12; ++q) acc[q] += wjk * row[q];
      }
    Eigen::Vector3d v = Eigen::Vector3d::Zero();
    for (int i = 0; i < 4; ++i)
      for (int q = 0; q < 3; ++q) v[q] += W[0].w[i] * acc[3 * i + q];
    return v;
  }
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  for (int k = 0; k < W[2].count; ++k)
    for (int j = 0; j < W[1].count; ++j) {
      const double wjk = W[1].w[j] * W[2].w[k];
      const double* row = E + 3 * (W[0].base + nx * (W[1].base + j) + nxy * (W[2].base + k));
      for (int i = 0; i < W[0].count; ++i) {
        const double w = W[0].w[i] * wjk;
        v[0] += w * row[3 * i];
        v[1] += w * row[3 * i + 1];
        v[2] += w * row[3 * i + 2];
      }
    }
  return v;
}

namespace {

[[noreturn]] void refuse(const ErrorMap& map, const Eigen::Ref<const Eigen::Matrix3Xd>& p,
                         Eigen::Index i) {
  throw Error(fmt::format("point {} {}", i + 1, map.outside_message(p.col(i))));
}

// Runs fn(i) over the columns in parallel, checking first (in the same pass) that column i lies
// in the grid unless clamping was asked for. The lowest refused column is reported; columns
// before it (and in other ranges) may already have been processed in place.
template <class Fn>
void for_columns(const ErrorMap& map, const Eigen::Ref<const Eigen::Matrix3Xd>& p,
                 const EvalOptions& o, Fn&& fn) {
  const Eigen::Index n = p.cols();
  const int workers = io::detail::workers_for(static_cast<std::size_t>(n) * 8);
  std::vector<Eigen::Index> first_out(static_cast<std::size_t>(workers), -1);
  const bool refuse_outside = o.outside == Outside::Refuse;
  io::detail::parallel_ranges(static_cast<std::size_t>(n), workers,
                              [&](int t, std::size_t b, std::size_t e) {
                                for (std::size_t i = b; i < e; ++i) {
                                  const auto col = static_cast<Eigen::Index>(i);
                                  if (refuse_outside && !map.contains(p.col(col), o.tolerance)) {
                                    first_out[static_cast<std::size_t>(t)] = col;
                                    return;
                                  }
                                  fn(col);
                                }
                              });
  for (Eigen::Index i : first_out)
    if (i >= 0) refuse(map, p, i);
}

}  // namespace

Eigen::Matrix3Xd evaluate(const ErrorMap& map, const Eigen::Matrix3Xd& points,
                          const EvalOptions& options) {
  const Interpolator f(map, options);
  Eigen::Matrix3Xd out(3, points.cols());
  for_columns(map, points, options, [&](Eigen::Index i) { out.col(i) = f.clamped(points.col(i)); });
  return out;
}

void compensate(const ErrorMap& map, Eigen::Ref<Eigen::Matrix3Xd> points,
                const CompensateOptions& o) {
  if (o.iterations < 1) throw Error("compensation needs at least one iteration");
  const Interpolator f(map, o.eval);
  for_columns(map, points, o.eval, [&](Eigen::Index i) {
    const Eigen::Vector3d c = points.col(i);
    Eigen::Vector3d cp = c;
    for (int m = 0; m < o.iterations; ++m) cp = c - f.clamped(cp);
    points.col(i) = cp;
  });
}

void correct(const ErrorMap& map, Eigen::Ref<Eigen::Matrix3Xd> points, const EvalOptions& o) {
  const Interpolator f(map, o);
  for_columns(map, points, o, [&](Eigen::Index i) { points.col(i) -= f.clamped(points.col(i)); });
}

}  // namespace trueaxis::map
