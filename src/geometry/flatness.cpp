#include "trueaxis/geometry/flatness.hpp"

#include <fmt/format.h>
#include <glpk.h>

#include <Eigen/Dense>
#include <algorithm>
#include <memory>
#include <vector>

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

  std::unique_ptr<glp_prob, void (*)(glp_prob*)> lp(glp_create_prob(), &glp_delete_prob);
  glp_set_obj_dir(lp.get(), GLP_MIN);
  glp_add_cols(lp.get(), 4);  // da, db, dc, h
  for (int j = 1; j <= 3; ++j) glp_set_col_bnds(lp.get(), j, GLP_FR, 0, 0);
  glp_set_col_bnds(lp.get(), 4, GLP_LO, 0, 0);
  glp_set_obj_coef(lp.get(), 4, 1.0);
  glp_add_rows(lp.get(), static_cast<int>(2 * n));
  std::vector<int> ia{0}, ja{0};
  std::vector<double> ar{0};
  for (long i = 0; i < n; ++i) {
    // Row 2i+1: da + db u + dc v + h >= r_i ; row 2i+2: da + db u + dc v - h <= r_i.
    const int r1 = static_cast<int>(2 * i + 1), r2 = r1 + 1;
    glp_set_row_bnds(lp.get(), r1, GLP_LO, r[i], 0);
    glp_set_row_bnds(lp.get(), r2, GLP_UP, 0, r[i]);
    const double c[4] = {1, u[i], v[i], 1};
    for (int j = 0; j < 4; ++j) {
      ia.push_back(r1);
      ja.push_back(j + 1);
      ar.push_back(c[j]);
      ia.push_back(r2);
      ja.push_back(j + 1);
      ar.push_back(j == 3 ? -1.0 : c[j]);
    }
  }
  glp_load_matrix(lp.get(), static_cast<int>(ia.size() - 1), ia.data(), ja.data(), ar.data());
  glp_smcp parm;
  glp_init_smcp(&parm);
  parm.msg_lev = GLP_MSG_OFF;
  parm.meth = GLP_DUALP;
  const int rc = glp_simplex(lp.get(), &parm);
  if (rc != 0 || glp_get_status(lp.get()) != GLP_OPT)
    throw Error(fmt::format("minimum-zone flatness: the LP solver failed (code {})", rc));
  const double da = glp_get_col_prim(lp.get(), 1) * rs, db = glp_get_col_prim(lp.get(), 2) * rs,
               dc = glp_get_col_prim(lp.get(), 3) * rs;
  return finish(f, a0 + da, b0 + db, c0 + dc, x, y, z);
}

}  // namespace trueaxis::geometry
