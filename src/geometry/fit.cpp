#include "trueaxis/geometry/fit.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <random>

#include "../common/eigen_instances.hpp"
#include "fit_checks.hpp"
#include "fit_polish.hpp"
#include "sphere_kernels.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::geometry {
namespace {

using detail::axis_residual;
using detail::AxisState;
using detail::basis;
using detail::check;
using detail::check_points;
using detail::Circle2;
using detail::Pca;
using detail::pca;
using detail::polish_axis;
using detail::polish_sphere;
using detail::Scanned;

// A size whose standard uncertainty exceeds this fraction of it is refused, above the second
// one it is reported with a warning.
constexpr double kSizeNotDetermined = 0.25;
constexpr double kSizePoorlyDetermined = 0.01;
constexpr double kIllConditioned = 1e10;

// Levenberg–Marquardt on a state re-parametrised at every step: `eval(state, r, J)` fills the
// residuals (and the Jacobian with respect to a local correction dx, if J is not null);
// `update(state, dx)` returns the corrected state. Stops when a step no longer lowers the cost
// beyond round-off.
struct Refined {
  int steps = 0;           // accepted steps
  bool converged = false;  // false: stopped by the iteration cap, still descending
};

constexpr int kMaxIterations = 500;
constexpr double kEpsilon = std::numeric_limits<double>::epsilon();
// Cylinders and cones: above twice this many points, the start values compete on a subsample of
// about this size (see fit()).
constexpr Eigen::Index kStartPoints = 10000;

// Gauss–Newton on the normal equations (spheres, and axis fits on large clouds): used while JᵀJ's
// condition number is below this (1e6 for J), for at most kFastSteps steps, until a step is
// below kFastTolerance of the extent, from where the extended-precision polish converges
// quadratically.
constexpr double kNormalConditionLimit = 1e12;
constexpr int kFastSteps = 30;
constexpr double kFastTolerance = 1e-9;
// Uncertainties from the Cholesky factor of JᵀJ below this scaled condition number of JᵀJ
// (their relative rounding is then below ~1e-8), else from the QR of J.
constexpr double kCholeskyUncertaintyLimit = 1e8;

template <class State, class Eval, class Update>
Refined refine(State& st, Eval&& eval, Update&& update, double step_tol, double roundoff) {
  Eigen::VectorXd r, rt;
  Eigen::MatrixXd J;
  eval(st, r, &J);
  const Eigen::Index m = J.rows(), k = J.cols();
  double cost = r.squaredNorm(), lambda = 0, previous = 0;
  Refined out;
  // The damped problem min ‖[J; √λ·D]·dx + [r; 0]‖ is solved through J = Q·R: it is then
  // min ‖[R; √λ·D]·dx + [Qᵀr; 0]‖, a 2k × k problem (column-pivoted, so a rank-deficient J gives
  // a basic solution as before). J is factorised in place once per accepted step; a rejected
  // step only changes λ, so only the small problem is solved again.
  Eigen::MatrixXd R(k, k);
  Eigen::VectorXd qtr(k), colnorm(k);
  auto factorise = [&] {
    for (Eigen::Index j = 0; j < k; ++j) colnorm[j] = std::max(J.col(j).norm(), 1e-300);
    Eigen::HouseholderQR<Eigen::Ref<Eigen::MatrixXd>> qr(J);  // overwrites J
    R = qr.matrixQR().topRows(k).template triangularView<Eigen::Upper>();
    Eigen::VectorXd t = -r;
    t.applyOnTheLeft(qr.householderQ().transpose());
    qtr = t.head(k);
  };
  factorise();
  Eigen::MatrixXd A(2 * k, k);
  Eigen::VectorXd b(2 * k);
  for (int it = 0; it < kMaxIterations; ++it) {
    A.topRows(k) = R;
    A.bottomRows(k).setZero();
    if (lambda > 0)
      for (Eigen::Index j = 0; j < k; ++j) A(k + j, j) = std::sqrt(lambda) * colnorm[j];
    b.head(k) = qtr;
    b.tail(k).setZero();
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
    const Eigen::VectorXd dx = qr.solve(b);
    // The step's size against what the data resolve: the tolerance is never below what
    // round-off in the residuals lets the solution resolve (their error over the smallest
    // singular value of the Jacobian).
    const double step = dx.template lpNorm<Eigen::Infinity>();
    auto tolerance = [&] {
      const Eigen::JacobiSVD<Eigen::MatrixXd> svd(
          qr.matrixR().topLeftCorner(k, k).template triangularView<Eigen::Upper>());
      const double smallest = svd.singularValues()[k - 1];
      const double floor =
          smallest > 0 ? roundoff * std::sqrt(static_cast<double>(m)) / smallest : 0;
      return std::max(step_tol, floor);
    };
    // An undamped step the data cannot resolve: below the tolerance, or promising a decrease of
    // the cost (‖J·dx‖², the linear model's) below the cost's own rounding. If it does not lower
    // the cost, the minimum is reached to round-off: no shortening, no damping.
    const bool resolved =
        lambda > 0 ||
        ((R * dx).squaredNorm() > 16 * kEpsilon * std::sqrt(static_cast<double>(m)) * cost &&
         step > tolerance());
    // Along the step, shorten it while the cost rises: in a curved valley (a small patch of a
    // wide cone) the full step overshoots where a fraction of it still descends.
    State trial = update(st, dx);
    eval(trial, rt, nullptr);
    double ct = rt.squaredNorm(), fraction = 1;
    for (; resolved && !(std::isfinite(ct) && ct <= cost) && fraction > 1e-3;) {
      fraction /= 2;
      trial = update(st, fraction * dx);
      eval(trial, rt, nullptr);
      ct = rt.squaredNorm();
    }
    if (std::isfinite(ct) && ct <= cost) {
      // Stop where the Gauss–Newton step (zero at a stationary point, whatever fraction of it
      // was taken) is at the tolerance and so is what is left to go: in a flat valley (a
      // cone's apex against its angle, a short patch) the iteration converges linearly, the
      // steps shrinking by a ratio ρ close to 1 and leaving step·ρ/(1 − ρ) still to go.
      const double ratio = previous > 0 ? step / previous : 1;
      const double left = ratio < 1 ? step * ratio / (1 - ratio) : HUGE_VAL;
      const double tol = tolerance();
      const bool done = step <= tol && (left <= tol || ct == cost);
      st = trial;
      cost = ct;
      previous = step;
      ++out.steps;
      lambda = lambda > 1e-12 ? lambda / 10 : 0;
      if (done) {
        out.converged = true;
        break;
      }
      eval(st, r, &J);
      factorise();
    } else if (!resolved) {
      out.converged = true;
      break;
    } else {
      lambda = lambda > 0 ? lambda * 10 : 1e-8;
      if (lambda > 1e12) {  // no descent left: at the minimum to round-off
        out.converged = true;
        break;
      }
    }
  }
  return out;
}

[[noreturn]] void not_converged(Element e) {
  throw Error(fmt::format(
      "{} fit: no least-squares solution found in {} iterations: the points fix the {} too "
      "weakly (too little of its surface for their scatter); measure more of it",
      to_string(e), kMaxIterations, to_string(e)));
}

// ---- circle in a plane (2-D) ------------------------------------------------------------------

Circle2 circle2_algebraic(const Eigen::Matrix2Xd& q) {
  const Eigen::Index n = q.cols();
  Eigen::MatrixXd A(n, 3);
  Eigen::VectorXd b(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    A.row(i) << 2 * q(0, i), 2 * q(1, i), 1;
    b[i] = q.col(i).squaredNorm();
  }
  const Eigen::Vector3d s = A.colPivHouseholderQr().solve(b);
  return {s.head<2>(), std::sqrt(std::max(0.0, s[2] + s.head<2>().squaredNorm()))};
}

// `q`: centred coordinates (mm).
Circle2 circle2_fit(const Eigen::Matrix2Xd& q, int* iterations) {
  Circle2 c = circle2_algebraic(q);
  auto eval = [&](const Circle2& s, Eigen::VectorXd& r, Eigen::MatrixXd* J) {
    r.resize(q.cols());
    if (J) J->resize(q.cols(), 3);
    for (Eigen::Index i = 0; i < q.cols(); ++i) {
      const Eigen::Vector2d d = q.col(i) - s.c;
      const double rho = d.norm();
      r[i] = rho - s.r;
      if (J) J->row(i) << -d.x() / rho, -d.y() / rho, -1;
    }
  };
  auto update = [](const Circle2& s, const Eigen::VectorXd& dx) {
    return Circle2{s.c + dx.head<2>(), s.r + dx[2]};
  };
  // Residuals carry the round-off of the centred coordinates.
  const double roundoff = 4 * std::numeric_limits<double>::epsilon() * q.cwiseAbs().maxCoeff();
  const Refined it = refine(c, eval, update, 1e-13 * std::max(1.0, c.r), roundoff);
  if (!it.converged) not_converged(Element::Circle);
  if (iterations) *iterations = it.steps;
  detail::polish_circle(q, c.c, c.r);
  return c;
}

// ---- sphere -----------------------------------------------------------------------------------

struct SphereState {
  Eigen::Vector3d c;
  double r;
};

// ---- cylinder and cone: an axis through x0 along unit a ---------------------------------------

// Local coordinates of the points in the frame with origin x0 and z along a.
Eigen::Matrix3Xd local(const Eigen::Matrix3Xd& p, const AxisState& s, Eigen::Matrix3d& R) {
  R = basis(s.a);
  return R.transpose() * (p.colwise() - s.x0);
}

AxisState move_axis(const AxisState& s, const Eigen::VectorXd& dx) {
  const Eigen::Matrix3d R = basis(s.a);
  AxisState t = s;
  t.x0 = s.x0 + R * Eigen::Vector3d(dx[0], dx[1], 0);
  t.a = (R * Eigen::Vector3d(dx[2], dx[3], 1)).normalized();
  t.r = s.r + dx[4];
  if (dx.size() > 5) t.psi = s.psi + dx[5];
  return t;
}

void axis_eval(const Eigen::Matrix3Xd& p, const AxisState& s, bool cone, Eigen::VectorXd& r,
               Eigen::MatrixXd* J) {
  Eigen::Matrix3d R;
  const Eigen::Matrix3Xd q = local(p, s, R);
  const double C = std::cos(s.psi), S = std::sin(s.psi), T = std::tan(s.psi);
  const int k = cone ? 6 : 5;
  r.resize(p.cols());
  if (J) J->resize(p.cols(), k);
  double d[6];
  for (Eigen::Index i = 0; i < p.cols(); ++i) {
    r[i] = axis_residual(q(0, i), q(1, i), q(2, i), s.r, C, S, T, cone, J ? d : nullptr);
    if (J)
      for (int j = 0; j < k; ++j) (*J)(i, j) = d[j];
  }
}

// JᵀJ, Jᵀr (k = 5 for a cylinder, 6 for a cone) and Σr² of the axis residuals at s, in one pass
// without forming J or a rotated copy of the points.
double axis_normal(const Eigen::Matrix3Xd& p, const AxisState& s, bool cone, Eigen::MatrixXd& JtJ,
                   Eigen::VectorXd& Jtr) {
  const Eigen::Matrix3d R = basis(s.a);
  const double C = std::cos(s.psi), S = std::sin(s.psi), T = std::tan(s.psi);
  Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero(), d;
  d.setZero();
  double cost = 0;
  for (Eigen::Index i = 0; i < p.cols(); ++i) {
    const Eigen::Vector3d q = R.transpose() * (p.col(i) - s.x0);
    const double res = axis_residual(q[0], q[1], q[2], s.r, C, S, T, cone, d.data());
    A.noalias() += d * d.transpose();
    b += res * d;
    cost += res * res;
  }
  const int k = cone ? 6 : 5;
  JtJ = A.topLeftCorner(k, k);
  Jtr = b.head(k);
  return cost;
}

// The condition number of a normal matrix with its diagonal scaled to 1 (that of JᵀJ for the
// Jacobian's columns scaled to unit length), infinite where it is not positive definite.
double scaled_condition(const Eigen::MatrixXd& A) {
  const Eigen::VectorXd s = A.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(s.asDiagonal() * A * s.asDiagonal(),
                                                          Eigen::EigenvaluesOnly);
  const Eigen::VectorXd& ev = es.eigenvalues();
  return ev[0] > 0 ? ev[ev.size() - 1] / ev[0] : std::numeric_limits<double>::infinity();
}

// Start values for an axis along w: the algebraic circle of the points projected on the plane
// normal to w (cylinder), or the algebraic cone x² + y² = 2cx·x + 2cy·y + k0 + k1·z + k2·z².
bool axis_start(const Eigen::Matrix3Xd& p, const Eigen::Vector3d& centroid,
                const Eigen::Vector3d& w, bool cone, AxisState& s) {
  const Eigen::Matrix3d R = basis(w);
  const Eigen::Matrix3Xd q = R.transpose() * (p.colwise() - centroid);
  s.a = w;
  if (!cone) {
    const Circle2 c = circle2_algebraic(q.topRows<2>());
    if (!(c.r > 0) || !std::isfinite(c.r)) return false;
    s.x0 = centroid + R * Eigen::Vector3d(c.c.x(), c.c.y(), 0);
    s.r = c.r;
    return true;
  }
  const Eigen::Index n = q.cols();
  Eigen::MatrixXd A(n, 5);
  Eigen::VectorXd b(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    A.row(i) << 2 * q(0, i), 2 * q(1, i), 1, q(2, i), q(2, i) * q(2, i);
    b[i] = q.col(i).head<2>().squaredNorm();
  }
  const Eigen::VectorXd k = A.colPivHouseholderQr().solve(b);
  const double r0sq = k[2] + k[0] * k[0] + k[1] * k[1];
  if (!(r0sq > 0) || !std::isfinite(r0sq)) return false;
  s.x0 = centroid + R * Eigen::Vector3d(k[0], k[1], 0);
  s.r = std::sqrt(r0sq);
  s.psi = std::atan(k[3] / (2 * s.r));
  return std::isfinite(s.psi);
}

// The axis direction of the algebraic quadric through the points (the singular vector of the
// smallest singular value of [x² y² z² 2xy 2xz 2yz x y z 1], in centred and scaled coordinates):
// the eigenvector of its quadratic part whose eigenvalue stands apart from the other two (a
// cone's (1, 1, −tan²ψ), a cylinder's (1, 1, 0)). Catches axes that no principal direction of
// the cloud is near, as on a small patch of a wide cone. False when the points do not fix it.
bool quadric_axis(const Eigen::Matrix3Xd& p, const Eigen::Vector3d& centroid, Eigen::Vector3d& w) {
  const Eigen::Index n = p.cols();
  if (n < 10) return false;
  const Eigen::Matrix3Xd q = p.colwise() - centroid;
  const double scale = q.colwise().norm().maxCoeff();
  if (!(scale > 0)) return false;
  Eigen::MatrixXd D(n, 10);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d v = q.col(i) / scale;
    D.row(i) << v.x() * v.x(), v.y() * v.y(), v.z() * v.z(), 2 * v.x() * v.y(), 2 * v.x() * v.z(),
        2 * v.y() * v.z(), v.x(), v.y(), v.z(), 1;
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(D, Eigen::ComputeThinV);
  const Eigen::VectorXd c = svd.matrixV().col(9);
  Eigen::Matrix3d A;
  A << c[0], c[3], c[4], c[3], c[1], c[5], c[4], c[5], c[2];
  // The library's one instance of the solver (eigen_instances.hpp): a 3 × 3 instance of its own
  // cost ~6 s of compilation per compiler.
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Eigen::MatrixXd{A});
  const Eigen::Vector3d e = es.eigenvalues();  // ascending
  w = es.eigenvectors().col(e[1] - e[0] < e[2] - e[1] ? 2 : 0);
  return w.allFinite() && w.norm() > 0.5;
}

}  // namespace

const char* to_string(Element e) {
  switch (e) {
    case Element::Line:
      return "line";
    case Element::Plane:
      return "plane";
    case Element::Circle:
      return "circle";
    case Element::Sphere:
      return "sphere";
    case Element::Cylinder:
      return "cylinder";
    case Element::Cone:
      return "cone";
  }
  return "?";
}

Element element_from_string(const std::string& s) {
  for (Element e : {Element::Line, Element::Plane, Element::Circle, Element::Sphere,
                    Element::Cylinder, Element::Cone})
    if (s == to_string(e)) return e;
  throw Error(fmt::format("unknown element '{}' (line, plane, circle, sphere, cylinder, cone)", s));
}

Eigen::VectorXd distances(const Fit& f, const Eigen::Matrix3Xd& p) {
  if (f.element == Element::Sphere)  // without a copy of the points
    return ((p.colwise() - f.point).colwise().norm().array() - f.diameter / 2).matrix().transpose();
  const Eigen::Matrix3Xd d = p.colwise() - f.point;
  switch (f.element) {
    case Element::Line:
      return (d - f.direction * (f.direction.transpose() * d)).colwise().norm().transpose();
    case Element::Plane:
      return (f.direction.transpose() * d).transpose();
    case Element::Circle: {
      // In-plane radial distance of the projected points (NIST's convention for circles).
      const Eigen::Matrix3Xd inplane = d - f.direction * (f.direction.transpose() * d);
      return (inplane.colwise().norm().array() - f.diameter / 2).matrix().transpose();
    }
    case Element::Sphere:
      break;  // above
    case Element::Cylinder: {
      const Eigen::Matrix3Xd radial = d - f.direction * (f.direction.transpose() * d);
      return (radial.colwise().norm().array() - f.diameter / 2).matrix().transpose();
    }
    case Element::Cone: {
      const double psi = f.apex_angle / 2, C = std::cos(psi), T = std::tan(psi);
      const Eigen::RowVectorXd z = f.direction.transpose() * d;
      const Eigen::Matrix3Xd radial = d - f.direction * z;
      const double r0 = f.distance / C;  // radius at `point`
      return ((radial.colwise().norm().array() - r0 - z.array() * T) * C).matrix().transpose();
    }
  }
  return {};
}

namespace {

// The reported quantities as one vector: point (3), direction (3), diameter, distance, apex.
using Reported = Eigen::Matrix<double, 9, 1>;

Reported reported(const Eigen::Vector3d& point, const Eigen::Vector3d& direction,
                  double diameter = 0, double distance = 0, double apex = 0) {
  Reported v;
  v << point, direction, diameter, distance, apex;
  return v;
}

// The least-squares problem at the solution (residuals r, Jacobian J with respect to a local
// correction dx) and the map dx -> reported quantities: standard uncertainties
// u = sqrt(diag(G C Gᵀ)) with C = s²(JᵀJ)⁻¹, s² = |r|²/(m − k), G by central differences;
// and the condition number of J with unit columns.
//
// This form takes the triangle R of J = Q·R (or any R with RᵀR = JᵀJ), the squared residual norm
// and the number of residuals m: the SVD of J·S⁻¹ is that of R·S⁻¹ (the same singular values and
// V) and the column norms of J are those of R.
template <class Report>
void propagate_r(const Eigen::MatrixXd& R, double ssr, Eigen::Index m, Report&& report, Fit& f) {
  const Eigen::Index k = R.cols();
  Eigen::VectorXd scale = R.colwise().norm().transpose();
  for (Eigen::Index j = 0; j < k; ++j)
    if (!(scale[j] > 0)) scale[j] = 1;
  const Eigen::MatrixXd Rs = R * scale.cwiseInverse().asDiagonal();
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Rs, Eigen::ComputeThinV);
  const Eigen::VectorXd& sv = svd.singularValues();
  f.condition_number = sv[k - 1] > 0 ? sv[0] / sv[k - 1] : std::numeric_limits<double>::infinity();
  f.dof = m - k;
  if (m <= k || !(sv[k - 1] > 0)) return;
  const double s2 = ssr / static_cast<double>(m - k);
  const Eigen::MatrixXd W =
      scale.cwiseInverse().asDiagonal() * svd.matrixV() * sv.cwiseInverse().asDiagonal();
  const Eigen::MatrixXd C = s2 * W * W.transpose();
  Eigen::Matrix<double, 9, Eigen::Dynamic> G(9, k);
  for (Eigen::Index j = 0; j < k; ++j) {
    const double h = 1e-6 * std::max(1.0, std::sqrt(C(j, j)) * 1e3);
    Eigen::VectorXd dx = Eigen::VectorXd::Zero(k);
    dx[j] = h;
    const Reported plus = report(dx);
    dx[j] = -h;
    G.col(j) = (plus - report(dx)) / (2 * h);
  }
  const Reported u = (G * C * G.transpose()).diagonal().cwiseMax(0).cwiseSqrt();
  if (!u.allFinite()) return;
  f.u_point = u.head<3>();
  f.u_direction = u.segment<3>(3);
  f.u_diameter = u[6];
  f.u_distance = u[7];
  f.u_apex_angle = u[8];
  f.has_uncertainty = true;
}

template <class Report>
void propagate(const Eigen::MatrixXd& J, const Eigen::VectorXd& r, Report&& report, Fit& f) {
  const Eigen::Index m = J.rows(), k = J.cols();
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(J);
  Eigen::MatrixXd R = Eigen::MatrixXd::Zero(k, k);
  R.topRows(std::min(m, k)) = qr.matrixQR().topRows(std::min(m, k)).triangularView<Eigen::Upper>();
  propagate_r(R, r.squaredNorm(), m, std::forward<Report>(report), f);
}

// A plane through c with normal R.col(2), perturbed by dx = (tilt a, tilt b, offset d): its
// normal and the foot of c on it.
void perturbed_plane(const Eigen::Vector3d& c, const Eigen::Matrix3d& R, const double* dx,
                     Eigen::Vector3d& point, Eigen::Vector3d& normal) {
  normal = (R * Eigen::Vector3d(-dx[0], -dx[1], 1)).normalized();
  point = c + (R.col(2) * dx[2]).dot(normal) * normal;
}

// Plane residuals (heights in the frame R about c) and Jacobian for dx = (a, b, d).
void plane_problem(const Eigen::Matrix3Xd& p, const Eigen::Vector3d& c, const Eigen::Matrix3d& R,
                   Eigen::VectorXd& r, Eigen::MatrixXd& J) {
  const Eigen::Matrix3Xd q = R.transpose() * (p.colwise() - c);
  r = q.row(2).transpose();
  J.resize(p.cols(), 3);
  J.col(0) = -q.row(0).transpose();
  J.col(1) = -q.row(1).transpose();
  J.col(2).setConstant(-1);
}

// Refuses a size the points cannot determine; warns when it is poorly determined.
void judge_size(Fit& f, const char* what, double size) {
  if (!f.has_uncertainty || !(size > 0)) return;
  const double rel = f.u_diameter / size;
  const char* e = to_string(f.element);
  if (rel > kSizeNotDetermined)
    throw Error(fmt::format(
        "{} fit: the {} is not determined by these points ({:.4g} mm with a standard "
        "uncertainty of {:.2g} mm): they cover too little of a {} for their scatter; fit a "
        "simpler element (a plane or a line) or measure more of the surface",
        e, what, size, f.u_diameter, e));
  if (rel > kSizePoorlyDetermined)
    f.warnings.push_back(fmt::format(
        "the {} is poorly determined: {:.4g} mm with a standard uncertainty of {:.2g} mm "
        "({:.1f} %); the points cover little of the {}",
        what, size, f.u_diameter, 100 * rel, e));
}

}  // namespace

Fit fit(Element element, const Eigen::Matrix3Xd& p) {
  const Scanned scanned = check_points(element, p);
  // A sphere uses only the centroid and the spreads, a cylinder or cone the axes as start values.
  const Pca s = pca(
      p, scanned.centroid,
      !(element == Element::Sphere || element == Element::Cylinder || element == Element::Cone));
  check(element, p, s);
  Fit f;
  f.element = element;
  const double extent = std::max(1.0, s.extent);
  const double step_tol = 1e-13 * extent;
  // Residuals carry the round-off of the coordinates they are computed from: centred ones for
  // circles and spheres, the raw ones (less the axis point) for cylinders and cones.
  const double roundoff = 4 * kEpsilon * scanned.largest;
  switch (element) {
    case Element::Line: {
      f.point = s.centroid;
      f.direction = s.axes.col(0);
      // Perpendicular offsets (2 per point) against dx = (x0, y0, a, b) in the line's frame.
      const Eigen::Matrix3d R = basis(f.direction);
      const Eigen::Matrix3Xd q = R.transpose() * (p.colwise() - s.centroid);
      const Eigen::Index n = p.cols();
      Eigen::VectorXd r(2 * n);
      Eigen::MatrixXd J = Eigen::MatrixXd::Zero(2 * n, 4);
      for (Eigen::Index i = 0; i < n; ++i) {
        r[2 * i] = q(0, i);
        r[2 * i + 1] = q(1, i);
        J(2 * i, 0) = J(2 * i + 1, 1) = -1;
        J(2 * i, 2) = J(2 * i + 1, 3) = -q(2, i);
      }
      propagate(
          J, r,
          [&](const Eigen::VectorXd& dx) {
            const Eigen::Vector3d d = (R * Eigen::Vector3d(dx[2], dx[3], 1)).normalized();
            const Eigen::Vector3d x0 = s.centroid + R * Eigen::Vector3d(dx[0], dx[1], 0);
            return reported(x0 + (s.centroid - x0).dot(d) * d, d);
          },
          f);
      break;
    }
    case Element::Plane: {
      f.point = s.centroid;
      f.direction = s.axes.col(2);
      const Eigen::Matrix3d R = basis(f.direction);
      Eigen::VectorXd r;
      Eigen::MatrixXd J;
      plane_problem(p, s.centroid, R, r, J);
      propagate(
          J, r,
          [&](const Eigen::VectorXd& dx) {
            Eigen::Vector3d point, normal;
            perturbed_plane(s.centroid, R, dx.data(), point, normal);
            return reported(point, normal);
          },
          f);
      break;
    }
    case Element::Circle: {
      const Eigen::Matrix3d R = basis(s.axes.col(2));
      const Eigen::Matrix2Xd q = (R.transpose() * (p.colwise() - s.centroid)).topRows<2>();
      const Circle2 c = circle2_fit(q, &f.iterations);
      f.point = s.centroid + R * Eigen::Vector3d(c.c.x(), c.c.y(), 0);
      f.direction = s.axes.col(2);
      f.diameter = 2 * c.r;
      // The plane (a, b, d) and the circle in it (cx, cy, r), as one block-diagonal problem.
      const Eigen::Index n = p.cols();
      Eigen::VectorXd rp, r(2 * n);
      Eigen::MatrixXd Jp, J = Eigen::MatrixXd::Zero(2 * n, 6);
      plane_problem(p, s.centroid, R, rp, Jp);
      r.head(n) = rp;
      J.topLeftCorner(n, 3) = Jp;
      for (Eigen::Index i = 0; i < n; ++i) {
        const Eigen::Vector2d d = q.col(i) - c.c;
        const double rho = d.norm();
        r[n + i] = rho - c.r;
        J.row(n + i).tail<3>() << -d.x() / rho, -d.y() / rho, -1;
      }
      propagate(
          J, r,
          [&](const Eigen::VectorXd& dx) {
            Eigen::Vector3d point, normal;
            perturbed_plane(s.centroid, R, dx.data(), point, normal);
            const Eigen::Vector3d centre =
                s.centroid + R * Eigen::Vector3d(c.c.x() + dx[3], c.c.y() + dx[4], dx[2]);
            return reported(centre, normal, 2 * (c.r + dx[5]));
          },
          f);
      judge_size(f, "diameter", f.diameter);
      break;
    }
    case Element::Sphere: {
      const Eigen::Index n = p.cols();
      // Centred for conditioning, and stored by coordinate (x, y and z each contiguous) for the
      // vectorised passes below. The same pass sums the algebraic start's moments: with
      // centred points (Σq = 0) the normal equations of |q − c|² = r² (linear in c and
      // r² − |c|²) split into (Σ q·qᵀ)·c = ½·Σ q·|q|², r² = |c|² + Σ|q|²/n, and Σ q·qᵀ is the
      // scatter matrix the principal axes came from.
      Eigen::MatrixX3d Q(n, 3);
      Eigen::Vector3d v = Eigen::Vector3d::Zero();
      double qq = 0, largest = 0;
      for (Eigen::Index i = 0; i < n; ++i) {
        const Eigen::Vector3d x = p.col(i) - s.centroid;
        Q.row(i) = x.transpose();
        const double x2 = x.squaredNorm();
        v += x2 * x;
        qq += x2;
        largest = std::max(largest, x.cwiseAbs().maxCoeff());
      }
      const detail::Coords qc{Q.col(0).data(), Q.col(1).data(), Q.col(2).data(), n};
      const detail::SphereKernels& kernels = detail::sphere_kernels();
      const Eigen::Matrix3d M = s.axes * s.spread.cwiseAbs2().asDiagonal() * s.axes.transpose();
      const Eigen::Vector3d c0 = M.ldlt().solve(v / 2);
      SphereState st{c0, std::sqrt(c0.squaredNorm() + qq / static_cast<double>(n))};
      auto eval = [&](const SphereState& x, Eigen::VectorXd& r, Eigen::MatrixXd* J) {
        r.resize(n);
        if (J) J->resize(n, 4);
        for (Eigen::Index i = 0; i < n; ++i) {
          const Eigen::Vector3d d = Q.row(i).transpose() - x.c;
          const double rho = d.norm();
          r[i] = rho - x.r;
          if (J) J->row(i) << -d.x() / rho, -d.y() / rho, -d.z() / rho, -1;
        }
      };
      auto update = [](const SphereState& x, const Eigen::VectorXd& dx) {
        return SphereState{x.c + dx.head<3>(), x.r + dx[3]};
      };
      // JᵀJ, Jᵀr and Σr² in one pass, without forming J.
      using Mat4 = Eigen::Matrix4d;
      using Vec4 = Eigen::Vector4d;
      auto normal = [&](const SphereState& x, Mat4& JtJ, Vec4& Jtr) {
        return kernels.normal(qc, x.c.data(), x.r, JtJ.data(), Jtr.data());  // JᵀJ symmetric
      };
      // Gauss–Newton on the normal equations while they are well conditioned (a sphere, or a
      // cap that is not too shallow) and the steps shrink: the extended-precision polish below then
      // settles the last digits. A cap too shallow for that, or a start that does not
      // converge, goes through Levenberg–Marquardt on the QR of J as before.
      auto well_conditioned = [&](const Mat4& A) {
        // The library's one instance of the solver (eigen_instances.hpp), as above.
        const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Eigen::MatrixXd{A},
                                                                Eigen::EigenvaluesOnly);
        const Vec4& ev = es.eigenvalues();
        return ev[0] > 0 && ev[3] < kNormalConditionLimit * ev[0];
      };
      Mat4 JtJ;
      Vec4 Jtr;
      double cost = normal(st, JtJ, Jtr);
      bool fast = false;
      int steps = 0;
      for (; steps < kFastSteps; ++steps) {
        if (!well_conditioned(JtJ)) break;
        const Vec4 dx = -JtJ.ldlt().solve(Jtr);
        // Close enough for the 80-bit Newton polish, which converges quadratically from here
        // (and where the double-precision cost may no longer tell such a step from none).
        if (dx.cwiseAbs().maxCoeff() <= kFastTolerance * extent) {
          fast = true;
          break;
        }
        const SphereState trial = update(st, dx);
        Mat4 JtJ2;
        Vec4 Jtr2;
        const double ct = normal(trial, JtJ2, Jtr2);
        if (!(std::isfinite(ct) && ct <= cost)) break;  // no plain descent: leave it to LM
        st = trial;
        cost = ct;
        JtJ = JtJ2;
        Jtr = Jtr2;
      }
      if (fast) {
        f.iterations = steps;
      } else {
        const Refined it = refine(st, eval, update, step_tol, 4 * kEpsilon * extent);
        if (!it.converged) not_converged(element);
        f.iterations = steps + it.steps;
      }
      polish_sphere(qc, kernels, largest, st.c, st.r);
      f.point = s.centroid + st.c;
      f.diameter = 2 * std::abs(st.r);
      auto report = [&](const Eigen::VectorXd& dx) {
        const SphereState t = update(st, dx);
        return reported(s.centroid + t.c, Eigen::Vector3d::Zero(), 2 * std::abs(t.r));
      };
      // The uncertainty from the normal equations' Cholesky factor where they are well
      // conditioned (R with RᵀR = JᵀJ), else from the QR of J.
      cost = normal(st, JtJ, Jtr);
      const Eigen::LLT<Mat4> llt(JtJ);
      if (well_conditioned(JtJ) && llt.info() == Eigen::Success) {
        propagate_r(Eigen::MatrixXd(llt.matrixU()), cost, n, report, f);
      } else {
        Eigen::VectorXd r;
        Eigen::MatrixXd J;
        eval(st, r, &J);
        propagate(J, r, report, f);
      }
      judge_size(f, "diameter", f.diameter);
      break;
    }
    case Element::Cylinder:
    case Element::Cone: {
      const bool cone = element == Element::Cone;
      double best = std::numeric_limits<double>::infinity();
      AxisState found;
      auto eval = [&](const AxisState& x, Eigen::VectorXd& r, Eigen::MatrixXd* J) {
        axis_eval(p, x, cone, r, J);
      };
      // Start from each principal direction of the cloud, and from the quadric's axis.
      Eigen::Matrix<double, 3, 4> starts;
      starts.leftCols<3>() = s.axes;
      // Re-centre the axis point on the foot of the centroid after every step, so that the
      // axis turns about the data and not about a point the data have left behind.
      auto update = [&](const AxisState& x, const Eigen::VectorXd& dx) {
        AxisState t = move_axis(x, dx);
        const double tau = (s.centroid - t.x0).dot(t.a);
        t.x0 += tau * t.a;
        if (cone) t.r += tau * std::tan(t.psi);
        return t;
      };
      bool converged = false;
      // On a large cloud the starts compete on a subsample of about kStartPoints points, and
      // only the winner is refined on all of them: the basin is the same, and the losing starts
      // (which may wander for many steps) are not paid for a hundredfold. One point at a random
      // place in each run of `stride` (fixed seed, so the fit is repeatable): it covers the
      // cloud like every stride-th point would, without aliasing with a scan's regular order.
      const Eigen::Index stride = p.cols() / kStartPoints;
      Eigen::Matrix3Xd sub;
      if (stride > 1) {
        std::mt19937_64 rng(0x5eed);
        std::uniform_int_distribution<Eigen::Index> offset(0, stride - 1);
        sub.resize(3, p.cols() / stride);
        for (Eigen::Index j = 0; j < sub.cols(); ++j) sub.col(j) = p.col(j * stride + offset(rng));
      }
      const Eigen::Matrix3Xd& ps = stride > 1 ? sub : p;
      auto eval_starts = [&](const AxisState& x, Eigen::VectorXd& r, Eigen::MatrixXd* J) {
        axis_eval(ps, x, cone, r, J);
      };
      Eigen::Vector3d wq;
      const int n_starts = quadric_axis(ps, s.centroid, wq) ? 4 : 3;
      if (n_starts == 4) starts.col(3) = wq.normalized();
      for (int k = 0; k < n_starts; ++k) {
        AxisState st;
        if (!axis_start(ps, s.centroid, starts.col(k), cone, st)) continue;
        const Refined it = refine(st, eval_starts, update, step_tol, roundoff);
        Eigen::VectorXd r;
        eval_starts(st, r, nullptr);
        const double cost = r.squaredNorm();
        // A later start wins only by lowering the cost beyond round-off: starts that end in the
        // same minimum keep the first (the iteration count reported is then that start's).
        if (std::isfinite(cost) && (!std::isfinite(best) || cost < best * (1 - 1e-12))) {
          best = cost;
          found = st;
          converged = it.converged;
          f.iterations = it.steps;
        }
      }
      if (stride > 1 && std::isfinite(best)) {
        // On all the points, from the subsample's minimum (close to theirs): Gauss–Newton on
        // the normal equations, one pass per step without forming J, while they are well
        // conditioned and the cost falls, until the step is small enough for the extended-
        // precision polish below; otherwise Levenberg–Marquardt on the QR of J.
        Eigen::MatrixXd JtJ;
        Eigen::VectorXd Jtr;
        double cost = axis_normal(p, found, cone, JtJ, Jtr);
        bool fast = false;
        for (int step = 0; step < kFastSteps; ++step) {
          if (!(scaled_condition(JtJ) < kNormalConditionLimit)) break;
          const Eigen::VectorXd dx = -JtJ.ldlt().solve(Jtr);
          // Tilts and ψ are radians: a tilt moves the ends of the cloud by about extent·tilt.
          const double size =
              std::max({std::abs(dx[0]), std::abs(dx[1]), std::abs(dx[4]), extent * std::abs(dx[2]),
                        extent * std::abs(dx[3]), cone ? extent * std::abs(dx[5]) : 0.0});
          if (!(size > kFastTolerance * extent)) {
            fast = size <= kFastTolerance * extent;  // false for a NaN step
            break;
          }
          const AxisState trial = update(found, dx);
          Eigen::MatrixXd JtJ2;
          Eigen::VectorXd Jtr2;
          const double ct = axis_normal(p, trial, cone, JtJ2, Jtr2);
          if (!(std::isfinite(ct) && ct <= cost)) break;  // no plain descent: leave it to LM
          found = trial;
          cost = ct;
          JtJ = std::move(JtJ2);
          Jtr = std::move(Jtr2);
          ++f.iterations;
        }
        if (fast) {
          converged = true;
        } else {
          const Refined it = refine(found, eval, update, step_tol, roundoff);
          converged = it.converged;
          f.iterations += it.steps;
        }
      }
      if (!std::isfinite(best))
        throw Error(fmt::format("{} fit: no start value converged (are the points on a {}?)",
                                to_string(element), to_string(element)));
      // Where Gauss–Newton crept to the iteration cap, Newton's steps may still settle on the
      // minimum; if they do not, whatever the lowest cost is, it is not a minimum.
      bool settled = false;
      found = polish_axis(p, s.centroid, found, cone, extent, &settled);
      if (!converged && !settled) not_converged(element);
      // Report the axis point nearest the centroid; a cone opens towards +direction.
      const double sign = found.psi < 0 ? -1 : 1;
      auto report = [&](const AxisState& x) {
        const double t = (s.centroid - x.x0).dot(x.a);
        const Eigen::Vector3d point = x.x0 + t * x.a;
        if (!cone) return reported(point, x.a, 2 * std::abs(x.r));
        const double psi = sign * x.psi, radius = x.r + t * std::tan(x.psi);
        return reported(point, sign * x.a, 0, radius * std::cos(psi), 2 * psi);
      };
      const Reported v = report(found);
      f.point = v.head<3>();
      f.direction = v.segment<3>(3);
      f.diameter = v[6];
      f.distance = v[7];
      f.apex_angle = v[8];
      // The uncertainty from the normal equations' Cholesky factor where they are well
      // conditioned enough for it (R with RᵀR = JᵀJ, so its rounding is that of JᵀJ), else
      // from the QR of J.
      auto moved = [&](const Eigen::VectorXd& dx) { return report(move_axis(found, dx)); };
      Eigen::MatrixXd JtJ;
      Eigen::VectorXd Jtr;
      const double cost = axis_normal(p, found, cone, JtJ, Jtr);
      const Eigen::LLT<Eigen::MatrixXd> llt(JtJ);
      if (scaled_condition(JtJ) < kCholeskyUncertaintyLimit && llt.info() == Eigen::Success) {
        propagate_r(Eigen::MatrixXd(llt.matrixU()), cost, p.cols(), moved, f);
      } else {
        Eigen::VectorXd r;
        Eigen::MatrixXd J;
        eval(found, r, &J);
        propagate(J, r, moved, f);
      }
      if (!cone) judge_size(f, "diameter", f.diameter);
      if (cone && f.has_uncertainty && f.u_apex_angle > f.apex_angle)
        f.warnings.push_back(fmt::format(
            "the apex angle {:.3g} deg is smaller than its standard uncertainty ({:.2g} deg): "
            "these points do not tell this cone from a cylinder",
            f.apex_angle * 180 / M_PI, f.u_apex_angle * 180 / M_PI));
      break;
    }
  }
  if (element == Element::Plane || element == Element::Circle) {
    // Points that share one coordinate exactly (a 2-D set written as x, y, z with z fixed) lie
    // in that coordinate plane: the element lies there exactly, not to the round-off of the
    // centroid and the rotation into the fitted plane (7e-15 of z = −867.2 otherwise).
    for (int k = 0; k < 3; ++k) {
      const double v = p(k, 0);
      if (!(p.row(k).array() == v).all()) continue;
      f.point[k] = v;
      const double sign = f.direction[k] < 0 ? -1.0 : 1.0;
      f.direction = sign * Eigen::Vector3d::Unit(k);
      break;
    }
  }
  if (f.condition_number > kIllConditioned)
    f.warnings.push_back(fmt::format(
        "the fit is numerically ill-conditioned (condition number {:.2g}): the points barely "
        "determine some of the {}'s parameters",
        f.condition_number, to_string(element)));
  f.residuals = distances(f, p);
  f.rms = std::sqrt(f.residuals.squaredNorm() / static_cast<double>(p.cols()));
  f.max = f.residuals.cwiseAbs().maxCoeff();
  return f;
}

}  // namespace trueaxis::geometry
