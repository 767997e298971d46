// The references of straightness separation: a separated profile is known up to a line (and,
// with three or more probes and no zero difference or angle channel, a parabola). The ls
// reference subtracts each profile's least-squares line, the min-zone reference the middle line of
// its minimum zone; the parabola gauge takes the guide to have no least-squares quadratic. All in
// one or two vectorised passes per profile over moments on the scale t = (x − x_c)/L.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <future>
#include <limits>
#include <utility>

#include "../geometry/profile_min_zone.hpp"
#include "solution.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/geometry/straightness.hpp"

namespace trueaxis::separation {
namespace detail {
namespace {

// Σθ and Σ(x − x_c) over a pitch profile, in one vectorised pass.
struct PitchSums {
  double st = 0, sx = 0;
};
PitchSums pitch_sums(const Eigen::VectorXd& xt, const Eigen::VectorXd& theta, const Scale& s) {
  double st = 0, sx = 0;
  const double *xp = xt.data(), *tp = theta.data();
#pragma omp simd reduction(+ : st, sx)
  for (Eigen::Index i = 0; i < theta.size(); ++i) {
    st += tp[i];
    sx += xp[i] - s.xc;
  }
  return {st, sx};
}

// y ← y + a·t² less the least-squares line of that sum (found from the moments: the line of y
// plus a times the line of t²), in one pass that also returns the range of the result: the
// least-squares straightness of the profile as referenced.
double add_parabola_less_line(const Eigen::VectorXd& x, Eigen::VectorXd& y, const Moments& m,
                              double a, const Scale& s) {
  const double n = m.t[0], sy = m.ty[0] + a * m.t[2], sty = m.ty[1] + a * m.t[3];
  const double stt = m.t[2] - m.t[1] * m.t[1] / n;
  if (!(stt > 0)) throw Error("least-squares line: all x are equal");
  const double slope = (sty - m.t[1] * sy / n) / stt, icpt = (sy - slope * m.t[1]) / n;
  const double inv = 1 / s.L;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  const double* xp = x.data();
  double* yp = y.data();
#pragma omp simd reduction(min : lo) reduction(max : hi)
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    const double t = (xp[i] - s.xc) * inv;
    const double v = yp[i] + (a * t - slope) * t - icpt;
    yp[i] = v;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  return hi - lo;
}

}  // namespace

// The scale of grid x: its mid-range and half range (from its ends when it is known to increase).
Scale scale_of(Eigen::Ref<const Eigen::VectorXd> x, bool increasing) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  const double* xp = x.data();
  if (increasing && x.size()) {
    lo = xp[0];
    hi = xp[x.size() - 1];
  } else {  // one vectorised pass
#pragma omp simd reduction(min : lo) reduction(max : hi)
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      lo = std::min(lo, xp[i]);
      hi = std::max(hi, xp[i]);
    }
  }
  return {0.5 * (lo + hi), std::max(1e-12, 0.5 * (hi - lo))};
}

// Coefficients e of the functional φ_K = e_0 + e_1·t_K + e_2·t_K² with φᵀg = the coefficient of t²
// in the LS fit of g by {1, t, t²} (t = (x − x_c)/L): e = G⁻¹·(0, 0, 1), G = TᵀT from the moments
// of t.
Eigen::Vector3d quad_coefficients_from(const Moments& m) {
  Eigen::Matrix3d G;
  G << m.t[0], m.t[1], m.t[2], m.t[1], m.t[2], m.t[3], m.t[2], m.t[3], m.t[4];
  return G.ldlt().solve(Eigen::Vector3d(0, 0, 1));
}

Moments moments_of(Eigen::Ref<const Eigen::VectorXd> x, Eigen::Ref<const Eigen::VectorXd> y,
                   const Scale& s) {
  Moments m;
  const double inv = 1 / s.L;
  double t1 = 0, t2s = 0, t3 = 0, t4 = 0, y0 = 0, y1 = 0, y2 = 0;
  const double *xp = x.data(), *yp = y.data();
#pragma omp simd reduction(+ : t1, t2s, t3, t4, y0, y1, y2)
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    const double t = (xp[i] - s.xc) * inv, t2 = t * t, v = yp[i];
    t1 += t;
    t2s += t2;
    t3 += t2 * t;
    t4 += t2 * t2;
    y0 += v;
    y1 += t * v;
    y2 += t2 * v;
  }
  m.t[0] = static_cast<double>(x.size());
  m.t[1] = t1;
  m.t[2] = t2s;
  m.t[3] = t3;
  m.t[4] = t4;
  m.ty[0] = y0;
  m.ty[1] = y1;
  m.ty[2] = y2;
  return m;
}

// Applies the ls / min-zone reference in place (parabola gauge first, if free).
LsWidths apply_reference(Raw& r, Reference ref) {
  const Scale s = scale_of(r.xg, r.xg_increasing);
  LsWidths widths;
  const std::launch policy = policy_for(r);
  // The workpiece's sums (ls reference), and θ's, meanwhile on another core.
  std::future<std::pair<Moments, PitchSums>> wsums;
  if (ref != Reference::MinZone)
    wsums = std::async(policy, [&] {
      return std::make_pair(moments_of(r.xw, r.w, s), pitch_sums(r.xt, r.theta, s));
    });
  // The parabola gauge: c = φᵀg, the guide's t² coefficient, from the guide's sums (which the
  // ls reference needs anyway).
  Moments mg;
  if (r.parabola_free || ref != Reference::MinZone) mg = moments_of(r.xg, r.g, s);
  double c = 0;
  if (r.parabola_free) {
    const Eigen::Vector3d e = quad_coefficients_from(mg);
    c = e[0] * mg.ty[0] + e[1] * mg.ty[1] + e[2] * mg.ty[2];
  }
  if (ref != Reference::MinZone) {
    // Parabola gauge and line in two passes per profile: one for the sums, one for the update.
    // θ's sums (which do not depend on the parabola) are taken with the workpiece's, and θ is
    // updated after the guide: the two cores then move about the same number of bytes.
    const auto sums = wsums.get();  // (named members: clang 14 lambdas cannot capture bindings)
    const Moments& mw = sums.first;
    const PitchSums& pitch = sums.second;
    auto wupdate = std::async(policy, [&] { return add_parabola_less_line(r.xw, r.w, mw, c, s); });
    widths.g = add_parabola_less_line(r.xg, r.g, mg, -c, s);
    if (r.theta.size()) {
      // θ less the parabola's slope, about its mean.
      const double k = 2 * c / (s.L * s.L);
      const double mean = (pitch.st - k * pitch.sx) / static_cast<double>(r.theta.size());
      const double* xt = r.xt.data();
      double* theta = r.theta.data();
#pragma omp simd
      for (Eigen::Index i = 0; i < r.theta.size(); ++i) theta[i] -= k * (xt[i] - s.xc) + mean;
    }
    widths.w = wupdate.get();
    return widths;
  }
  if (r.parabola_free) {
    auto t2 = [&](double x) {
      const double t = (x - s.xc) / s.L;
      return t * t;
    };
    for (Eigen::Index i = 0; i < r.w.size(); ++i) r.w[i] += c * t2(r.xw[i]);
    for (Eigen::Index i = 0; i < r.g.size(); ++i) r.g[i] -= c * t2(r.xg[i]);
    for (Eigen::Index i = 0; i < r.theta.size(); ++i)
      r.theta[i] -= 2 * c * (r.xt[i] - s.xc) / (s.L * s.L);
  }
  auto wzone = std::async(
      policy, [&] { geometry::subtract_line(r.xw, r.w, geometry::min_zone(r.xw, r.w).middle); });
  geometry::subtract_line(r.xg, r.g, geometry::min_zone(r.xg, r.g).middle);
  wzone.get();
  if (r.theta.size()) r.theta.array() -= r.theta.mean();
  return widths;
}

}  // namespace detail

void express_in_reference(Profile& workpiece, Profile& guide, Profile* pitch, Reference reference,
                          bool parabola_free) {
  if (reference == Reference::Seed)
    throw Error("express_in_reference: the patent reference depends on the readings");
  detail::Raw r;
  r.xw = workpiece.x;
  r.w = workpiece.value;
  r.xg = guide.x;
  r.g = guide.value;
  if (pitch) {
    r.xt = pitch->x;
    r.theta = pitch->value;
  }
  r.parabola_free = parabola_free;
  detail::apply_reference(r, reference);
  workpiece.value = r.w;
  guide.value = r.g;
  if (pitch) pitch->value = r.theta;
}

}  // namespace trueaxis::separation
