#include "trueaxis/map/error_map.hpp"

#include <fmt/format.h>

#include <algorithm>
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#elif defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <cmath>
#include <vector>

#include "../io/fast_text.hpp"
#include "tricubic.hpp"
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
// (add_slope with scale 1, made once per axis). The weights are linear in the Hermite basis
// values (h00, h01, h10, h11) at the point: given those, they are the node weights; given the
// basis polynomials' t^p coefficients, they are the weights' t^p coefficients.
Weights cubic_weights(const double* x, const double* slope, Eigen::Index n, Eigen::Index i,
                      double h00, double h01, double h10, double h11) {
  Weights W;
  const double h = x[i + 1] - x[i];
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

// The weights of a cell at local coordinate t from its polynomials (Horner, 4 nodes at once).
inline void weights_at(const double* poly, double t, double w[4]) {
  for (int q = 0; q < 4; ++q) w[q] = poly[12 + q];
  for (int p = 2; p >= 0; --p)
    for (int q = 0; q < 4; ++q) w[q] = w[q] * t + poly[4 * p + q];
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
  if (plane >= 0 && plane < 3) {
    const auto& x = a[static_cast<std::size_t>(plane)];
    const double at = (x[0] + x[x.size() - 1]) / 2, band = (x[x.size() - 1] - x[0]) / 2;
    if (std::abs(p[plane] - at) > band)
      return fmt::format(
          "({:.3f}, {:.3f}, {:.3f}) mm is {:.3f} mm off the plane {} = {:.3f} mm that the map "
          "holds (a ball plate's map, used within {:g} mm of its plane; give --clamp, or "
          "clamp=True in Python, to use the plane's errors there anyway)",
          p.x(), p.y(), p.z(), std::abs(p[plane] - at), kNames[plane], at, band);
  }
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
  if (plane >= 0) {
    if (plane > 2 || size(plane) != 2)
      throw Error("a plane map needs two nodes (the plane's band) on its normal axis");
    for (Eigen::Index n = 0; n < nodes(); ++n) {
      const Eigen::Index i = n % size(0), j = (n / size(0)) % size(1), k = n / (size(0) * size(1));
      Eigen::Index ijk[3] = {i, j, k};
      if (ijk[plane] != 0) continue;
      ijk[plane] = 1;
      if (error.col(n) != error.col(index(ijk[0], ijk[1], ijk[2])))
        throw Error(
            fmt::format("a plane map holds one error per node of its plane; the two {} "
                        "nodes differ",
                        kNames[plane]));
    }
  }
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
    ax.count = static_cast<int>(std::min<Eigen::Index>(ax.n, 4));
    // The cubic's node slopes depend on the axis only: their coefficients once, not per point.
    if (ax.n >= 3) {
      ax.slope.assign(static_cast<std::size_t>(3 * ax.n), 0.0);
      for (Eigen::Index m = 0; m < ax.n; ++m)
        add_slope(ax.x, std::clamp<Eigen::Index>(m - 1, 0, ax.n - 3), m, 1.0,
                  ax.slope.data() + 3 * m);
    }
    // Per cell, the node weights as polynomials in t: the weights of the Hermite basis
    // polynomials' t^p coefficients (h00 = 1 − 3t² + 2t³, h01 = 3t² − 2t³, h10 = t − 2t² + t³,
    // h11 = −t² + t³). With two nodes the weights are 1 − t and t.
    constexpr double h00[4] = {1, 0, -3, 2}, h01[4] = {0, 0, 3, -2}, h10[4] = {0, 1, -2, 1},
                     h11[4] = {0, 0, -1, 1};
    ax.base.assign(static_cast<std::size_t>(ax.n - 1), 0);
    ax.poly.assign(static_cast<std::size_t>(16 * (ax.n - 1)), 0.0);
    for (Eigen::Index i = 0; i + 1 < ax.n; ++i) {
      double* c = ax.poly.data() + 16 * i;
      if (ax.n == 2) {
        c[0] = 1;  // node 0: 1 − t
        c[4] = -1;
        c[5] = 1;  // node 1: t
        continue;
      }
      for (int pw = 0; pw < 4; ++pw) {
        const Weights W =
            cubic_weights(ax.x, ax.slope.data(), ax.n, i, h00[pw], h01[pw], h10[pw], h11[pw]);
        ax.base[static_cast<std::size_t>(i)] = W.base;
        for (int q = 0; q < 4; ++q) c[4 * pw + q] = W.w[q];
      }
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
  const double* poly[3];
  Eigen::Index base[3];
  for (int a = 0; a < 3; ++a) {
    const Axis& ax = axis_[static_cast<std::size_t>(a)];
    poly[a] = ax.poly.data() + 16 * c[a];
    base[a] = ax.base[static_cast<std::size_t>(c[a])];
  }
  const double* row0 = E + 3 * (base[0] + nx * base[1] + nxy * base[2]);
  static const detail::TricubicSum tricubic = detail::tricubic_sum();
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  if (axis_[0].count == 4 && axis_[1].count == 4 && axis_[2].count == 4) {
    tricubic(row0, 3 * nx, 3 * nxy, poly, t, v.data());
    return v;
  }
  double w[3][4];
  for (int a = 0; a < 3; ++a) weights_at(poly[a], t[a], w[a]);
  for (int k = 0; k < axis_[2].count; ++k)
    for (int j = 0; j < axis_[1].count; ++j) {
      const double wjk = w[1][j] * w[2][k];
      const double* row = row0 + 3 * (nx * j + nxy * k);
      for (int i = 0; i < axis_[0].count; ++i) {
        const double wi = w[0][i] * wjk;
        v[0] += wi * row[3 * i];
        v[1] += wi * row[3 * i + 1];
        v[2] += wi * row[3 * i + 2];
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

// for_columns in blocks: fn(cols, n) with up to B consecutive columns, all checked. (for_columns
// stays its own loop: routing `correct` through blocks of one or four cost it 8 %.)
template <int B, class Fn>
void for_column_blocks(const ErrorMap& map, const Eigen::Ref<const Eigen::Matrix3Xd>& p,
                       const EvalOptions& o, Fn&& fn) {
  const Eigen::Index n = p.cols();
  const int workers = io::detail::workers_for(static_cast<std::size_t>(n) * 8);
  std::vector<Eigen::Index> first_out(static_cast<std::size_t>(workers), -1);
  const bool refuse_outside = o.outside == Outside::Refuse;
  io::detail::parallel_ranges(static_cast<std::size_t>(n), workers,
                              [&](int t, std::size_t b, std::size_t e) {
                                Eigen::Index cols[B];
                                int k = 0;
                                for (std::size_t i = b; i < e; ++i) {
                                  const auto col = static_cast<Eigen::Index>(i);
                                  if (refuse_outside && !map.contains(p.col(col), o.tolerance)) {
                                    fn(cols, k);
                                    first_out[static_cast<std::size_t>(t)] = col;
                                    return;
                                  }
                                  cols[k++] = col;
                                  if (k == B) {
                                    fn(cols, k);
                                    k = 0;
                                  }
                                }
                                fn(cols, k);
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
  // Four points at a time, iteration by iteration: each iterate waits for the one before it,
  // so interleaving independent points lets the processor overlap their evaluations.
  constexpr int kBlock = 4;
  auto flush = [&](Eigen::Index* cols, int n) {
    Eigen::Vector3d c[kBlock], cp[kBlock];
    for (int b = 0; b < n; ++b) c[b] = cp[b] = points.col(cols[b]);
    for (int m = 0; m < o.iterations; ++m)
      for (int b = 0; b < n; ++b) cp[b] = c[b] - f.clamped(cp[b]);
    for (int b = 0; b < n; ++b) points.col(cols[b]) = cp[b];
  };
  for_column_blocks<kBlock>(map, points, o.eval, flush);
}

void correct(const ErrorMap& map, Eigen::Ref<Eigen::Matrix3Xd> points, const EvalOptions& o) {
  const Interpolator f(map, o);
  for_columns(map, points, o, [&](Eigen::Index i) { points.col(i) -= f.clamped(points.col(i)); });
}

}  // namespace trueaxis::map

namespace trueaxis::map::detail {

// The 4 × 4 × 4 node sum of a tricubic evaluation: the 4 nodes along x are 12 adjacent
// doubles, so each of the 16 rows (j, k) is weighted whole, wy[j]·wz[k] times its 12 values
// added to 12 accumulators, and the accumulators are combined along x once. The compilers
// vectorise this loop across rows instead of along them (scalar adds), so the x86-64 versions
// spell the vectors out, with independent accumulators per plane k so that the adds do not
// wait for each other; they differ from the plain loop by round-off only.
namespace {

inline void combine_x(const double* acc, const double* wx, double* v) {
  for (int q = 0; q < 3; ++q)
    v[q] = wx[0] * acc[q] + wx[1] * acc[3 + q] + wx[2] * acc[6 + q] + wx[3] * acc[9 + q];
}

}  // namespace

void tricubic_sum_portable(const double* row0, Eigen::Index dy, Eigen::Index dz,
                           const double* const poly[3], const double t[3], double* v) {
  double wx[4], wy[4], wz[4];
  weights_at(poly[0], t[0], wx);
  weights_at(poly[1], t[1], wy);
  weights_at(poly[2], t[2], wz);
  alignas(32) double acc[12];
#if defined(__SSE2__)
  // Two sets of accumulators (k even, k odd): two independent chains of adds.
  __m128d a[2][6];
  for (auto& g : a)
    for (auto& x : g) x = _mm_setzero_pd();
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 4; ++j) {
      const __m128d w = _mm_set1_pd(wy[j] * wz[k]);
      const double* row = row0 + dy * j + dz * k;
      for (int q = 0; q < 6; ++q)
        a[k & 1][q] = _mm_add_pd(a[k & 1][q], _mm_mul_pd(w, _mm_loadu_pd(row + 2 * q)));
    }
  for (int q = 0; q < 6; ++q) _mm_store_pd(acc + 2 * q, _mm_add_pd(a[0][q], a[1][q]));
#else
  for (double& x : acc) x = 0;
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 4; ++j) {
      const double wjk = wy[j] * wz[k];
      const double* row = row0 + dy * j + dz * k;
      for (int q = 0; q < 12; ++q) acc[q] += wjk * row[q];
    }
#endif
  combine_x(acc, wx, v);
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
namespace {
// The same sum with AVX2 and FMA (four doubles per instruction, multiply and add in one
// rounding), chosen at run time where the processor has them: 48 fused multiply-adds where the
// SSE2 version takes 96 multiplies and 96 adds.
__attribute__((target("avx2,fma"))) void avx2_sum(const double* row0, Eigen::Index dy,
                                                  Eigen::Index dz, const double* const poly[3],
                                                  const double t[3], double* v) {
  // The weights: the four nodes' polynomials of each axis at once, three Horner steps.
  alignas(32) double wx[4], wy[4], wz[4];
  double* w[3] = {wx, wy, wz};
  for (int ax = 0; ax < 3; ++ax) {
    const __m256d ta = _mm256_set1_pd(t[ax]);
    __m256d h = _mm256_loadu_pd(poly[ax] + 12);
    h = _mm256_fmadd_pd(h, ta, _mm256_loadu_pd(poly[ax] + 8));
    h = _mm256_fmadd_pd(h, ta, _mm256_loadu_pd(poly[ax] + 4));
    h = _mm256_fmadd_pd(h, ta, _mm256_loadu_pd(poly[ax]));
    _mm256_store_pd(w[ax], h);
  }
  // One set of accumulators per k: four independent chains of four fused multiply-adds instead
  // of one of sixteen, whose latency (not the arithmetic) would bound the sum.
  __m256d a[4][3];
  for (int k = 0; k < 4; ++k) {
    const double* plane = row0 + dz * k;
    const __m256d w0 = _mm256_set1_pd(wy[0] * wz[k]);
    for (int q = 0; q < 3; ++q) a[k][q] = _mm256_mul_pd(w0, _mm256_loadu_pd(plane + 4 * q));
    for (int j = 1; j < 4; ++j) {
      const __m256d w = _mm256_set1_pd(wy[j] * wz[k]);
      const double* row = plane + dy * j;
      for (int q = 0; q < 3; ++q)
        a[k][q] = _mm256_fmadd_pd(w, _mm256_loadu_pd(row + 4 * q), a[k][q]);
    }
  }
  alignas(32) double acc[12];
  for (int q = 0; q < 3; ++q)
    _mm256_store_pd(acc + 4 * q, _mm256_add_pd(_mm256_add_pd(a[0][q], a[1][q]),
                                               _mm256_add_pd(a[2][q], a[3][q])));
  combine_x(acc, wx, v);
}
}  // namespace
#endif

TricubicSum tricubic_sum_avx2() {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return avx2_sum;
#endif
  return nullptr;
}

TricubicSum tricubic_sum() {
  static const TricubicSum best = [] {
    const TricubicSum f = tricubic_sum_avx2();
    return f ? f : tricubic_sum_portable;
  }();
  return best;
}

}  // namespace trueaxis::map::detail
