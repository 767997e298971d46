#include "trueaxis/geometry/flatness.hpp"

#include <fmt/format.h>
#include <glpk.h>

#include <Eigen/Dense>
#include <algorithm>
#include <memory>
#include <vector>

#include "../common/eigen_instances.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::geometry {
namespace {

// Centre and scale of the (x, y) data, and a check that it spans a plane.
struct Frame {
  double x0, y0, s;
};

Frame check(const Eigen::VectorXd& x, const Eigen::VectorXd& y, const Eigen::VectorXd& z) {
  if (x.size() != y.size() || x.size() != z.size())
    throw Error("flatness: x, y and z differ in length");
  if (x.size() < 3) throw Error(fmt::format("flatness: need at least 3 points, got {}", x.size()));
  if (!x.allFinite() || !y.allFinite() || !z.allFinite())
    throw Error("flatness: coordinates must be finite");
  Frame f{x.mean(), y.mean(), 0};
  f.s = std::max((x.array() - f.x0).abs().maxCoeff(), (y.array() - f.y0).abs().maxCoeff());
  Eigen::MatrixXd A(x.size(), 2);
  A.col(0) = (x.array() - f.x0) / (f.s > 0 ? f.s : 1);
  A.col(1) = (y.array() - f.y0) / (f.s > 0 ? f.s : 1);
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(A);
  if (!(f.s > 0) || svd.singularValues()[1] <= 1e-9 * svd.singularValues()[0])
    throw Error("flatness: the points lie on one line (or coincide) in x, y: no plane is defined");
  return f;
}

HeightPlane finish(const Frame& f, double a, double b, double c, const Eigen::VectorXd& x,
                   const Eigen::VectorXd& y, const Eigen::VectorXd& z) {
  // From the centred, scaled frame back to z = a + b x + c y.
  HeightPlane p;
  p.b = b / f.s;
  p.c = c / f.s;
  p.a = a - p.b * f.x0 - p.c * f.y0;
  const Eigen::ArrayXd r = z.array() - (a + p.b * (x.array() - f.x0) + p.c * (y.array() - f.y0));
  p.width = r.maxCoeff() - r.minCoeff();
  return p;
}

}  // namespace

HeightPlane ls_plane(const Eigen::VectorXd& x, const Eigen::VectorXd& y, const Eigen::VectorXd& z) {
  const Frame f = check(x, y, z);
  Eigen::MatrixXd A(x.size(), 3);
  A.col(0).setOnes();
  A.col(1) = (x.array() - f.x0) / f.s;
  A.col(2) = (y.array() - f.y0) / f.s;
  const Eigen::Vector3d p = A.colPivHouseholderQr().solve(z);
  return finish(f, p[0], p[1], p[2], x, y, z);
}

HeightPlane min_zone_plane(const Eigen::VectorXd& x, const Eigen::VectorXd& y,
                           const Eigen::VectorXd& z) {
  const Frame f = check(x, y, z);
  // Start from the LS plane so the LP works on small residuals: minimise h subject to
  // -h <= r_i - (da + db·u_i + dc·v_i) <= h, with u, v the centred, scaled coordinates.
  const HeightPlane ls = ls_plane(x, y, z);
  const double a0 = ls.a + ls.b * f.x0 + ls.c * f.y0, b0 = ls.b * f.s, c0 = ls.c * f.s;
  const long n = x.size();
  Eigen::VectorXd u = (x.array() - f.x0) / f.s, v = (y.array() - f.y0) / f.s;
  Eigen::VectorXd r = z.array() - (a0 + b0 * u.array() + c0 * v.array());
  const double rs = std::max(1e-300, r.cwiseAbs().maxCoeff());
  r /= rs;  // O(1) numbers for the simplex

  // Constraint generation: the LP over a working set of points is a relaxation of the full one
  // (its optimum h_S <= h*). Start with the points farthest above and below the LS plane; solve;
  // add the points the plane violates most; repeat (the dual simplex restarts from the previous
  // basis). When no point lies outside ±h_S the plane is optimal for all points. A measured
  // surface has few points near its extremes, so a handful of rounds touch a few hundred points
  // instead of loading all 2n constraints.
  std::unique_ptr<glp_prob, void (*)(glp_prob*)> lp(glp_create_prob(), &glp_delete_prob);
  glp_set_obj_dir(lp.get(), GLP_MIN);
  glp_add_cols(lp.get(), 4);  // da, db, dc, h
  for (int j = 1; j <= 3; ++j) glp_set_col_bnds(lp.get(), j, GLP_FR, 0, 0);
  glp_set_col_bnds(lp.get(), 4, GLP_LO, 0, 0);
  glp_set_obj_coef(lp.get(), 4, 1.0);
  std::vector<char> in(static_cast<std::size_t>(n), 0);
  auto add = [&](long i) {
    if (in[static_cast<std::size_t>(i)]) return false;
    in[static_cast<std::size_t>(i)] = 1;
    // Rows: da + db u + dc v + h >= r_i and da + db u + dc v - h <= r_i.
    const int r1 = glp_add_rows(lp.get(), 2), r2 = r1 + 1;
    glp_set_row_bnds(lp.get(), r1, GLP_LO, r[i], 0);
    glp_set_row_bnds(lp.get(), r2, GLP_UP, 0, r[i]);
    const int ind[5] = {0, 1, 2, 3, 4};
    const double up[5] = {0, 1, u[i], v[i], 1}, lo[5] = {0, 1, u[i], v[i], -1};
    glp_set_mat_row(lp.get(), r1, 4, ind, up);
    glp_set_mat_row(lp.get(), r2, 4, ind, lo);
    return true;
  };
  // The `batch` most positive and most negative entries of d among all points.
  const long batch = std::min<long>(n, 32);
  std::vector<long> order(static_cast<std::size_t>(n));
  auto extremes = [&](const Eigen::VectorXd& d, auto&& take) {
    for (long i = 0; i < n; ++i) order[static_cast<std::size_t>(i)] = i;
    std::nth_element(order.begin(), order.begin() + (batch - 1), order.end(),
                     [&](long a, long b) { return d[a] > d[b]; });
    for (long k = 0; k < batch; ++k) take(order[static_cast<std::size_t>(k)]);
    std::nth_element(order.begin(), order.begin() + (batch - 1), order.end(),
                     [&](long a, long b) { return d[a] < d[b]; });
    for (long k = 0; k < batch; ++k) take(order[static_cast<std::size_t>(k)]);
  };
  extremes(r, add);
  glp_smcp parm;
  glp_init_smcp(&parm);
  parm.msg_lev = GLP_MSG_OFF;
  parm.meth = GLP_DUALP;
  constexpr double kTol = 1e-12;  // on the O(1) scaled residuals
  double da = 0, db = 0, dc = 0;
  for (;;) {
    const int rc = glp_simplex(lp.get(), &parm);
    if (rc != 0 || glp_get_status(lp.get()) != GLP_OPT)
      throw Error(fmt::format("minimum-zone flatness: the LP solver failed (code {})", rc));
    da = glp_get_col_prim(lp.get(), 1);
    db = glp_get_col_prim(lp.get(), 2);
    dc = glp_get_col_prim(lp.get(), 3);
    const double h = glp_get_col_prim(lp.get(), 4);
    // Signed violation: how far each point lies outside the zone ±h (≤ 0 inside).
    const Eigen::VectorXd d = r.array() - (da + db * u.array() + dc * v.array());
    const Eigen::VectorXd out = d.cwiseAbs().array() - h;
    if (out.maxCoeff() <= kTol) break;
    bool added = false;
    extremes(d, [&](long i) {
      if (out[i] > kTol) added |= add(i);
    });
    if (!added) break;  // every violator is in the LP already: within the solver's tolerance
  }
  da *= rs;
  db *= rs;
  dc *= rs;
  return finish(f, a0 + da, b0 + db, c0 + dc, x, y, z);
}

}  // namespace trueaxis::geometry
