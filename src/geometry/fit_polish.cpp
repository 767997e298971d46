#include "fit_polish.hpp"

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace trueaxis::geometry::detail {

// An orthonormal, right-handed basis whose third column is `w` (unit).
Eigen::Matrix3d basis(const Eigen::Vector3d& w) {
  const Eigen::Vector3d helper =
      std::abs(w.x()) < 0.6 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d u = helper.cross(w).normalized();
  Eigen::Matrix3d b;
  b.col(0) = u;
  b.col(1) = w.cross(u);
  b.col(2) = w;
  return b;
}

namespace {

// ---- polishing in extended precision -----------------------------------------------------------
//
// Gauss–Newton leaves out the residuals' curvature. Where the residuals are large (NIST's
// circles with millimetres of form error) it overshoots and crawls; on a short patch or a wide
// cone the cost has a flat direction (the axis tilting against the apex moving) where double
// precision no longer sees the gradient. Either way the double-precision solution can stop
// ~1e-9 of the part's size short of the minimum. From there, a few Newton steps in 80-bit
// arithmetic (the Hessian with the residuals' curvature, by central differences of the exact
// gradient) reach the minimum to round-off of the result.

using Ld = long double;
using Vec3L = Eigen::Matrix<Ld, 3, 1>;
using Mat3L = Eigen::Matrix<Ld, 3, 3>;
using VecXL = Eigen::Matrix<Ld, Eigen::Dynamic, 1>;
using MatXL = Eigen::Matrix<Ld, Eigen::Dynamic, Eigen::Dynamic>;

constexpr Ld kReuseHessian = 1e6L;

// Newton's method in 80-bit arithmetic from a state near the minimum: `grad(state, g)` returns
// ½Σr² and its gradient g with respect to a local correction, `hessian(state, H)` fills its
// Hessian (with the residuals' curvature), `move(state, dx)` applies a correction. Steps that lower
// the cost, or that leave it the same to round-off and lower the gradient, are taken; at most 12.
// `settled` (if given) says whether the last Newton step was below `settle`: the state is a
// minimum to that tolerance. Steps below kReuseHessian `stop`s keep the Hessian for the next one.
template <class State, class Grad, class Hessian, class Move>
State newton_polish(State s, Grad&& grad, Hessian&& hessian, Move&& move, Ld stop, Ld settle = 0,
                    bool* settled = nullptr) {
  VecXL g, gt;
  Ld cost = grad(s, g);
  const Eigen::Index k = g.size();
  if (settled) *settled = false;
  Eigen::LDLT<MatXL> ldlt;
  bool reuse = false;  // keep the last Hessian (see below)
  for (int it = 0; it < 12; ++it) {
    if (!reuse) {
      MatXL H(k, k);
      hessian(s, H);
      H = ((H + H.transpose()) / 2).eval();
      ldlt.compute(H);
      if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) break;  // not near a minimum
    }
    VecXL dx = -ldlt.solve(g);
    if (!dx.allFinite()) break;
    if (settled) *settled = dx.cwiseAbs().maxCoeff() <= settle;
    if (dx.cwiseAbs().maxCoeff() <= stop) break;  // nothing left to take
    bool better = false;
    for (int half = 0; half < 8 && !better; ++half, dx /= 2) {
      const State t = move(s, dx);
      const Ld ct = grad(t, gt);
      // Near the minimum the cost stops resolving the step before the gradient does.
      if (ct < cost || (ct <= cost * (1 + 1e-15L) && gt.norm() < g.norm())) {
        s = t;
        cost = ct;
        g = gt;
        better = true;
      }
    }
    if (!better || dx.cwiseAbs().maxCoeff() * 2 <= stop) break;
    // After a full step this close to the minimum the Hessian changes by a relative ~|dx|/size,
    // so the next step with the old one is off by that fraction of an already tiny step: the
    // iteration still ends where the (exact) gradient vanishes, without another Hessian.
    reuse = dx.cwiseAbs().maxCoeff() <= kReuseHessian * stop;
  }
  return s;
}

// The Hessian by central differences of the exact gradient, steps h (one per parameter).
template <class State, class Grad, class Move>
auto central_hessian(Grad& grad, Move& move, const VecXL& h) {
  return [&grad, &move, h](const State& s, MatXL& H) {
    const Eigen::Index k = h.size();
    VecXL gp, gm;
    for (Eigen::Index j = 0; j < k; ++j) {
      VecXL e = VecXL::Zero(k);
      e[j] = h[j];
      grad(move(s, e), gp);
      grad(move(s, -e), gm);
      H.col(j) = (gp - gm) / (2 * h[j]);
    }
  };
}

// A circle (centre c, radius r) or a sphere, in centred coordinates q (2 × n or 3 × n).
template <int D>
struct RoundL {
  Eigen::Matrix<Ld, D, 1> c;
  Ld r;
};

// ½Σ(ρᵢ − r)², ρᵢ = |qᵢ − c|, and its gradient.
template <int D>
Ld round_gradient(const Eigen::Matrix<double, D, Eigen::Dynamic>& q, const RoundL<D>& s, VecXL& g) {
  using VecL = Eigen::Matrix<Ld, D, 1>;
  VecL gc = VecL::Zero();
  Ld cost = 0, gr = 0;
  for (Eigen::Index i = 0; i < q.cols(); ++i) {
    const VecL d = q.col(i).template cast<Ld>() - s.c;
    const Ld rho = d.norm(), res = rho - s.r;
    cost += res * res;
    gc -= (res / rho) * d;  // one x87 division per point, not one per coordinate
    gr -= res;
  }
  g.resize(D + 1);
  g << gc, gr;
  return cost / 2;
}

// Its Hessian in closed form, one pass where central differences take 2·(D + 1): with
// uᵢ = (qᵢ − c)/ρᵢ and resᵢ = ρᵢ − r, H_cc = Σ uᵢuᵢᵀ + resᵢ(I − uᵢuᵢᵀ)/ρᵢ, H_cr = Σ uᵢ, H_rr = n.
// In double precision: the Hessian only scales Newton's step, so its rounding changes the step
// by ~1e-16 of itself, while the gradient (which decides where the step ends) stays 80-bit.
template <int D>
void round_hessian(const Eigen::Matrix<double, D, Eigen::Dynamic>& q, const RoundL<D>& s,
                   MatXL& H) {
  using Vec = Eigen::Matrix<double, D, 1>;
  using Mat = Eigen::Matrix<double, D, D>;
  const Vec c = s.c.template cast<double>();
  const double r = static_cast<double>(s.r);
  Mat Hcc = Mat::Zero();
  Vec Hcr = Vec::Zero();
  for (Eigen::Index i = 0; i < q.cols(); ++i) {
    const Vec d = q.col(i) - c;
    const double rho = d.norm();
    const Vec u = d / rho;
    const double w = (rho - r) / rho;
    Hcc.noalias() += (1 - w) * (u * u.transpose());
    Hcc.diagonal().array() += w;
    Hcr += u;
  }
  H.resize(D + 1, D + 1);
  H.template topLeftCorner<D, D>() = Hcc.template cast<Ld>();
  H.template topRightCorner<D, 1>() = Hcr.template cast<Ld>();
  H.template bottomLeftCorner<1, D>() = Hcr.transpose().template cast<Ld>();
  H(D, D) = static_cast<Ld>(q.cols());
}

// Polishes a circle fit (D = 2) in place; spheres use polish_sphere below, whose passes are
// vectorised.
template <int D>
void polish_round(const Eigen::Matrix<double, D, Eigen::Dynamic>& q,
                  Eigen::Matrix<double, D, 1>& centre, double& radius) {
  const Ld size = std::max<Ld>(1, q.cwiseAbs().maxCoeff());
  const RoundL<D> s = newton_polish(
      RoundL<D>{centre.template cast<Ld>(), radius},
      [&](const RoundL<D>& x, VecXL& g) { return round_gradient<D>(q, x, g); },
      [&](const RoundL<D>& x, MatXL& H) { round_hessian<D>(q, x, H); },
      [](const RoundL<D>& x, const VecXL& dx) {
        return RoundL<D>{x.c + dx.template head<D>(), x.r + dx[D]};
      },
      1e-16L * size);
  centre = s.c.template cast<double>();
  radius = static_cast<double>(s.r);
}

}  // namespace

void polish_sphere(const detail::Coords& q, const detail::SphereKernels& kernels, double largest,
                   Eigen::Vector3d& centre, double& radius) {
  const RoundL<3> s = newton_polish(
      RoundL<3>{centre.cast<Ld>(), radius},
      [&](const RoundL<3>& x, VecXL& g) {
        g.resize(4);
        return kernels.gradient(q, x.c.data(), x.r, g.data());
      },
      [&](const RoundL<3>& x, MatXL& H) {
        const Eigen::Vector3d c = x.c.cast<double>();
        Eigen::Matrix4d h;  // symmetric: the kernel's row-major layout reads the same
        kernels.hessian(q, c.data(), static_cast<double>(x.r), h.data());
        H = h.cast<Ld>();
      },
      [](const RoundL<3>& x, const VecXL& dx) {
        return RoundL<3>{x.c + dx.head<3>(), x.r + dx[3]};
      },
      1e-16L * std::max(1.0, largest));
  centre = s.c.cast<double>();
  radius = static_cast<double>(s.r);
}

void polish_circle(const Eigen::Matrix2Xd& q, Eigen::Vector2d& centre, double& radius) {
  polish_round<2>(q, centre, radius);
}

namespace {

// ---- polishing an axis fit in extended precision (see newton_polish) ----------------------

struct AxisStateL {
  Vec3L x0;
  Mat3L R;  // frame: third column the axis; the first two move with it without jumps
  Ld r = 0, psi = 0;
};

// ½Σr² (r as axis_eval) and its gradient with respect to the local correction in the state's
// own frame.
Ld axis_gradient(const Eigen::Matrix3Xd& p, const AxisStateL& s, bool cone, VecXL& g) {
  const Ld C = std::cos(s.psi), S = std::sin(s.psi), T = std::tan(s.psi);
  const int k = cone ? 6 : 5;
  g = VecXL::Zero(k);
  Ld cost = 0, d[6];
  for (Eigen::Index i = 0; i < p.cols(); ++i) {
    const Vec3L q = s.R.transpose() * (p.col(i).cast<Ld>() - s.x0);
    const Ld res = axis_residual(q[0], q[1], q[2], s.r, C, S, T, cone, d);
    cost += res * res;
    for (int j = 0; j < k; ++j) g[j] += res * d[j];
  }
  return cost / 2;
}

AxisStateL move_axis_l(const AxisStateL& s, const VecXL& dx, const Vec3L& centroid, bool cone) {
  AxisStateL t = s;
  t.x0 = s.x0 + s.R * Vec3L(dx[0], dx[1], 0);
  const Vec3L a = s.R.col(2), b = (s.R * Vec3L(dx[2], dx[3], 1)).normalized();
  t.R = Eigen::Quaternion<Ld>::FromTwoVectors(a, b).toRotationMatrix() * s.R;
  t.r = s.r + dx[4];
  if (cone) t.psi = s.psi + dx[5];
  const Ld tau = (centroid - t.x0).dot(b);  // back to the foot of the centroid
  t.x0 += tau * b;
  if (cone) t.r += tau * std::tan(t.psi);
  return t;
}

}  // namespace

AxisState polish_axis(const Eigen::Matrix3Xd& p, const Eigen::Vector3d& centroid,
                      const AxisState& s0, bool cone, double extent, bool* settled) {
  const Vec3L c = centroid.cast<Ld>();
  VecXL h(cone ? 6 : 5);  // ~1e-7 of the size (mm) or of a radian
  h << 1e-7L * extent, 1e-7L * extent, 1e-7L, 1e-7L, 1e-7L * extent;
  if (cone) h[5] = 1e-7L;
  auto grad = [&](const AxisStateL& x, VecXL& g) { return axis_gradient(p, x, cone, g); };
  auto move = [&](const AxisStateL& x, const VecXL& dx) { return move_axis_l(x, dx, c, cone); };
  auto central = central_hessian<AxisStateL>(grad, move, h);
  // The Hessian is JᵀJ + Σ resᵢ·∇²resᵢ. The second term is left out (Gauss–Newton, one pass in
  // double) when it cannot matter: it is about max|res|/size of JᵀJ's scale, and it must stay a
  // small fraction of JᵀJ's smallest eigenvalue too, so that each Newton step still gains
  // ~3 digits. Otherwise (large form error, a flat valley) it comes from central differences of
  // the exact gradient, 2k gradient passes in 80-bit arithmetic.
  constexpr double kLeftOutCurvature = 1e-3;
  const int k = cone ? 6 : 5;
  auto hessian = [&](const AxisStateL& x, MatXL& H) {
    const Eigen::Matrix3d R = x.R.cast<double>();
    const Eigen::Vector3d x0 = x.x0.cast<double>();
    const double psi = static_cast<double>(x.psi), r0 = static_cast<double>(x.r);
    const double C = std::cos(psi), S = std::sin(psi), T = std::tan(psi);
    Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> d = Eigen::Matrix<double, 6, 1>::Zero();
    double worst = 0;
    for (Eigen::Index i = 0; i < p.cols(); ++i) {
      const Eigen::Vector3d q = R.transpose() * (p.col(i) - x0);
      const double res = axis_residual(q[0], q[1], q[2], r0, C, S, T, cone, d.data());
      A.noalias() += d * d.transpose();
      worst = std::max(worst, std::abs(res));
    }
    const Eigen::VectorXd scale = A.diagonal().head(k).cwiseSqrt().cwiseMax(1e-300);
    const Eigen::MatrixXd As = scale.cwiseInverse().asDiagonal() * A.topLeftCorner(k, k) *
                               scale.cwiseInverse().asDiagonal();
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(As, Eigen::EigenvaluesOnly);
    const double lo = es.eigenvalues()[0], hi = es.eigenvalues()[k - 1];
    if (lo > 0 && worst / extent * (hi / lo) <= kLeftOutCurvature)
      H = A.topLeftCorner(k, k).cast<Ld>();
    else
      central(x, H);
  };
  const AxisStateL s =
      newton_polish(AxisStateL{s0.x0.cast<Ld>(), basis(s0.a).cast<Ld>(), s0.r, s0.psi}, grad,
                    hessian, move, 1e-16L * extent, 1e-10L * extent, settled);
  AxisState out = s0;
  out.x0 = s.x0.cast<double>();
  out.a = s.R.col(2).cast<double>().normalized();
  out.r = static_cast<double>(s.r);
  out.psi = static_cast<double>(s.psi);
  return out;
}

}  // namespace trueaxis::geometry::detail
