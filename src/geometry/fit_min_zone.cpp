// Minimum-zone fits: the line, plane or circle whose zone (two parallel lines or planes, or two
// concentric circles) holding every point is narrowest, the minimum-zone criterion of
// ISO 12780-1 (straightness), ISO 12781-1 (flatness) and ISO 12181-1 (roundness). The line and
// plane come from the straightness and flatness zones' exact solvers, the circle from linear
// programs (GLPK) repeated from each new centre.
#include <fmt/format.h>
#include <glpk.h>

#include <Eigen/Dense>
#include <cmath>
#include <memory>

#include "fit_checks.hpp"
#include "fit_polish.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/geometry/fit.hpp"
#include "trueaxis/geometry/flatness.hpp"
#include "trueaxis/geometry/straightness.hpp"

namespace trueaxis::geometry {

using detail::basis;
using detail::Circle2;

namespace {

constexpr int kMinZoneCircleMaxPivots = 5000;

// Minimum-zone circle of 2-D points: minimise R − r subject to r ≤ |q_i − c| ≤ R, linearised
// at the current centre (|q_i − c − dc| ≈ ρ_i − u_i·dc) and solved as an LP; repeated from the
// new centre until the step is below round-off.
Circle2 min_zone_circle(const Eigen::Matrix2Xd& q, Circle2 c, double& width, int& iterations) {
  const Eigen::Index n = q.cols();
  const double scale = std::max(1.0, c.r);
  for (iterations = 1; iterations <= 50; ++iterations) {
    std::unique_ptr<glp_prob, void (*)(glp_prob*)> lp(glp_create_prob(), &glp_delete_prob);
    glp_set_obj_dir(lp.get(), GLP_MIN);
    glp_add_cols(lp.get(), 4);  // dcx, dcy (free), r_in, r_out (free); minimise r_out − r_in
    for (int j = 1; j <= 4; ++j) glp_set_col_bnds(lp.get(), j, GLP_FR, 0, 0);
    glp_set_obj_coef(lp.get(), 3, -1);
    glp_set_obj_coef(lp.get(), 4, 1);
    glp_add_rows(lp.get(), static_cast<int>(2 * n));
    for (Eigen::Index i = 0; i < n; ++i) {
      const Eigen::Vector2d d = q.col(i) - c.c;
      const double rho = d.norm();
      const Eigen::Vector2d u = d / rho;
      // r_in ≤ ρ − u·dc ≤ r_out, scaled to O(1).
      const int r1 = static_cast<int>(2 * i + 1), r2 = r1 + 1;
      const double a[4] = {0, u.x(), u.y(), 1};
      const int i1[4] = {0, 1, 2, 3}, i2[4] = {0, 1, 2, 4};
      glp_set_mat_row(lp.get(), r1, 3, i1, a);  // u·dc + r_in ≤ ρ
      glp_set_row_bnds(lp.get(), r1, GLP_UP, 0, rho / scale);
      glp_set_mat_row(lp.get(), r2, 3, i2, a);  // u·dc + r_out ≥ ρ
      glp_set_row_bnds(lp.get(), r2, GLP_LO, rho / scale, 0);
    }
    glp_smcp parm;
    glp_init_smcp(&parm);
    parm.msg_lev = GLP_MSG_OFF;
    // Four structural columns: an optimum takes a few dozen pivots. The limit only ends a
    // simplex that stalls on a degenerate LP (points that barely bend, not refused by the
    // least-squares check) instead of running for minutes.
    parm.it_lim = kMinZoneCircleMaxPivots;
    const int rc = glp_simplex(lp.get(), &parm);
    if (rc == GLP_EITLIM)
      throw Error(fmt::format(
          "minimum-zone circle: the LP did not reach an optimum within {} pivots; the points "
          "barely determine a circle: fit a line or a plane",
          kMinZoneCircleMaxPivots));
    if (rc != 0 || glp_get_status(lp.get()) != GLP_OPT)
      throw Error(fmt::format("minimum-zone circle: the LP solver failed (code {}, status {})", rc,
                              glp_get_status(lp.get())));
    const Eigen::Vector2d dc(glp_get_col_prim(lp.get(), 1) * scale,
                             glp_get_col_prim(lp.get(), 2) * scale);
    c.c += dc;
    if (dc.norm() <= 1e-13 * scale) break;
  }
  Eigen::ArrayXd rho(n);
  for (Eigen::Index i = 0; i < n; ++i) rho[i] = (q.col(i) - c.c).norm();
  width = rho.maxCoeff() - rho.minCoeff();
  c.r = 0.5 * (rho.maxCoeff() + rho.minCoeff());
  return c;
}

}  // namespace

Fit fit_min_zone(Element element, const Eigen::Matrix3Xd& p) {
  if (element != Element::Line && element != Element::Plane && element != Element::Circle)
    throw Error(fmt::format("minimum-zone fits are available for line, plane and circle, not {}",
                            to_string(element)));
  const detail::Pca s = detail::pca(p, detail::check_points(element, p).centroid);
  detail::check(element, p, s);
  Fit f;
  f.element = element;
  switch (element) {
    case Element::Line: {
      // In the LS plane's frame (u along the line, v across it, in the plane).
      Eigen::Matrix3d R;
      R.col(0) = s.axes.col(0);
      R.col(1) = s.axes.col(1);
      R.col(2) = s.axes.col(0).cross(s.axes.col(1));
      const Eigen::Matrix3Xd q = R.transpose() * (p.colwise() - s.centroid);
      const MinZone mz = min_zone(q.row(0).transpose(), q.row(1).transpose());
      f.direction = (R * Eigen::Vector3d(1, mz.middle.slope, 0)).normalized();
      f.point = s.centroid + R * Eigen::Vector3d(0, mz.middle.intercept, 0);
      f.zone = mz.width;
      const Eigen::Vector3d across = R.col(2).cross(f.direction);
      f.residuals = (across.transpose() * (p.colwise() - f.point)).transpose();
      break;
    }
    case Element::Plane: {
      Eigen::Vector3d normal = s.axes.col(2), point = s.centroid;
      for (f.iterations = 1; f.iterations <= 20; ++f.iterations) {
        const Eigen::Matrix3d R = basis(normal);
        const Eigen::Matrix3Xd q = R.transpose() * (p.colwise() - point);
        const HeightPlane h =
            min_zone_plane(q.row(0).transpose(), q.row(1).transpose(), q.row(2).transpose());
        normal = (R * Eigen::Vector3d(-h.b, -h.c, 1)).normalized();
        point = point + R * Eigen::Vector3d(0, 0, h.a);
        if (std::hypot(h.b, h.c) <= 1e-15) break;
      }
      f.direction = normal;
      f.point = point;
      const Eigen::VectorXd d = (normal.transpose() * (p.colwise() - point)).transpose();
      const double mid = 0.5 * (d.maxCoeff() + d.minCoeff());
      f.point = point + mid * normal;
      f.residuals = d.array() - mid;
      f.zone = d.maxCoeff() - d.minCoeff();
      break;
    }
    case Element::Circle: {
      // Starts from the least-squares circle (in the same plane and frame), which also refuses
      // points that do not determine a circle (too little of an arc for their scatter): the
      // zone's LP would be degenerate.
      const Fit ls = fit(Element::Circle, p);
      const Eigen::Matrix3d R = basis(s.axes.col(2));
      const Eigen::Matrix2Xd q = (R.transpose() * (p.colwise() - s.centroid)).topRows<2>();
      const Circle2 start{(R.transpose() * (ls.point - s.centroid)).head<2>(), ls.diameter / 2};
      int it = 0;
      const Circle2 c = min_zone_circle(q, start, f.zone, it);
      f.iterations = it;
      f.point = s.centroid + R * Eigen::Vector3d(c.c.x(), c.c.y(), 0);
      f.direction = s.axes.col(2);
      f.diameter = 2 * c.r;
      f.residuals = distances(f, p);
      break;
    }
    default:
      break;
  }
  f.rms = std::sqrt(f.residuals.squaredNorm() / static_cast<double>(p.cols()));
  f.max = f.residuals.cwiseAbs().maxCoeff();
  return f;
}

}  // namespace trueaxis::geometry
