#include "trueaxis/ballgauge/ballgauge.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <set>

#include "../common/eigen_instances.hpp"
#include "common.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/geometry/fit.hpp"

namespace trueaxis::ballgauge {
namespace detail {

// Sphere fit of probed tip centres, with the centre's uncertainty from the residuals:
// cov = s²·(JᵀJ)⁻¹, s² = Σr² / (n − 4).
Centre fit_ball(const Eigen::Matrix3Xd& points, double tol, bool drop) {
  Eigen::Matrix3Xd p = points;
  std::vector<Eigen::Index> original(static_cast<std::size_t>(p.cols()));
  for (std::size_t i = 0; i < original.size(); ++i) original[i] = static_cast<Eigen::Index>(i);
  std::vector<std::string> dropped;
  auto without = [](const Eigen::Matrix3Xd& q, Eigen::Index i) {
    Eigen::Matrix3Xd r(3, q.cols() - 1);
    r << q.leftCols(i), q.rightCols(q.cols() - i - 1);
    return r;
  };
  auto max_residual = [](const geometry::Fit& f) { return f.residuals.cwiseAbs().maxCoeff(); };
  // A fit that may fail (a set dragged far off by a wrong touch): nullopt then.
  auto try_fit = [](const Eigen::Matrix3Xd& q) -> std::optional<geometry::Fit> {
    try {
      return geometry::fit(geometry::Element::Sphere, q);
    } catch (const Error&) {
      return std::nullopt;
    }
  };
  std::optional<geometry::Fit> f = try_fit(p);
  // One wrong touch at a time: the point without which the rest fit within the tolerance.
  while (p.cols() > 5 && (!f || max_residual(*f) > tol)) {
    Eigen::Index worst = -1;
    std::optional<geometry::Fit> best;
    for (Eigen::Index i = 0; i < p.cols(); ++i) {
      auto g = try_fit(without(p, i));
      if (g && (!best || max_residual(*g) < max_residual(*best))) {
        best = std::move(g);
        worst = i;
      }
    }
    if (!best || !(max_residual(*best) <= tol)) break;  // not one wrong touch: the fit shows it
    const double off = std::abs((p.col(worst) - best->point).norm() - best->diameter / 2);
    const std::string what = fmt::format(
        "point {} is {:.4g} mm off the sphere through the other {} points (they fit within "
        "{:.2g} µm): a wrong touch",
        original[static_cast<std::size_t>(worst)] + 1, off, p.cols() - 1,
        max_residual(*best) * 1e3);
    if (!drop) throw Error(what + "; remove it, or drop such points with --drop-outliers");
    dropped.push_back(what + ", left out");
    original.erase(original.begin() + worst);
    p = without(p, worst);
    f = std::move(best);
  }
  if (!f) f = geometry::fit(geometry::Element::Sphere, p);  // throws with the reason
  Centre c;
  c.dropped = std::move(dropped);
  c.x = f->point;
  c.diameter = f->diameter;
  // The centre's standard uncertainty from the fit itself (Jacobian at the solution, residual
  // variance over n − 4), when the points are redundant.
  if (f->has_uncertainty) c.u = f->u_point;
  return c;
}

// Closed-form least-squares rigid registration X ≈ R·U + t (Kabsch, via SVD).
void kabsch(const std::vector<Eigen::Vector3d>& U, const std::vector<Eigen::Vector3d>& X,
            Eigen::Matrix3d& R, Eigen::Vector3d& t) {
  Eigen::Vector3d mu = Eigen::Vector3d::Zero(), mx = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < U.size(); ++i) {
    mu += U[i];
    mx += X[i];
  }
  mu /= static_cast<double>(U.size());
  mx /= static_cast<double>(U.size());
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < U.size(); ++i) H += (U[i] - mu) * (X[i] - mx).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1 : 1;
  R = svd.matrixV() * D * svd.matrixU().transpose();
  t = mx - R * mu;
}

// Clusters of coordinate values (sorted) within `tol`; returns cluster means and, per value, its
// cluster index.
std::vector<double> clusters(const std::vector<double>& v, double tol, std::vector<int>& which) {
  std::vector<std::size_t> order(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return v[a] < v[b]; });
  std::vector<double> means;
  std::vector<int> count;
  which.assign(v.size(), -1);
  for (std::size_t k = 0; k < order.size(); ++k) {
    const double x = v[order[k]];
    if (means.empty() || x - v[order[k - 1]] > tol) {
      means.push_back(0);
      count.push_back(0);
    }
    means.back() += x;
    ++count.back();
    which[order[k]] = static_cast<int>(means.size() - 1);
  }
  for (std::size_t c = 0; c < means.size(); ++c) means[c] /= count[c];
  return means;
}

}  // namespace detail

namespace {

using detail::Centre;
using detail::clusters;
using detail::fit_ball;
using detail::kabsch;

// Oya, Hokari and Tamura's 3-2-1 alignment (eqs. 11–12), stated in the gauge's own frame so
// that it holds however the gauge stands on the machine (balls 0, 1, 2 here are the gauge's
// three frame balls, Gauge::frame_balls): ball 0 is fixed, ball 1 is free only
// along the line 0→1 and ball 2 only in the plane of balls 0, 1, 2. Returns the columns
// c1, c2, c3 = gauge U, V, W in the machine frame, from the measured centres of balls 0, 1, 2:
// c1 along x1 − x0, c2 in the measured plane of the three balls, perpendicular to c1 and towards
// ball 2, c3 = c1 × c2. Ball 1's error x1 − x0 − a·c1 then lies along c1 and ball 2's has no
// component along c3, whatever the orientation. (Oya, Hokari and Tamura write the conditions in
// machine components, ball 1 "with no y, z error", which is the same alignment to first order when
// the gauge's U and V lie along machine x and y, and no alignment at all otherwise: with ball 1
// along machine y its x error was taken from √(1 − l₂² − l₃²), turning a 10⁻⁵ scale error into
// a 4.5 mrad tilt.) Refuses, naming the reason, balls 0 and 1 measured at one place, three balls
// measured on one line, or measured distances between them that differ from the gauge's by more
// than `tolerance` mm (balls numbered differently from the gauge file, or a wrong gauge).
Eigen::Matrix3d rotation_321(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1,
                             const Eigen::Vector3d& x2, const Eigen::Vector3d& u1,
                             const Eigen::Vector3d& u2, const std::array<int, 3>& balls,
                             double tolerance) {
  const Eigen::Vector3d d1 = x1 - x0, d2 = x2 - x0;
  const double n1 = d1.norm();
  if (!(n1 > 1e-9 * std::max(1.0, u1.norm())))
    throw Error(fmt::format("3-2-1 alignment: balls {} and {} are measured at the same place",
                            balls[0], balls[1]));
  const struct {
    int a, b;
    double measured, nominal;
  } distances[] = {{balls[0], balls[1], n1, u1.norm()},
                   {balls[0], balls[2], d2.norm(), u2.norm()},
                   {balls[1], balls[2], (x2 - x1).norm(), (u2 - u1).norm()}};
  for (const auto& d : distances)
    if (!(std::abs(d.measured - d.nominal) <= tolerance))
      throw Error(fmt::format(
          "3-2-1 alignment: balls {} and {} are measured {:.4f} mm apart, the gauge says {:.4f} mm "
          "(more than {} mm off: are the balls numbered as in the gauge file?)",
          d.a, d.b, d.measured, d.nominal, tolerance));
  const Eigen::Vector3d c1 = d1 / n1;
  const Eigen::Vector3d across = d2 - d2.dot(c1) * c1;
  if (!(across.norm() > 1e-6 * d2.norm()))
    throw Error(fmt::format("3-2-1 alignment: balls {}, {} and {} are measured on one line",
                            balls[0], balls[1], balls[2]));
  Eigen::Matrix3d C;
  C.col(0) = c1;
  C.col(1) = across.normalized();
  C.col(2) = c1.cross(C.col(1));
  return C;
}

// Jacobian of f at `in` by central differences (f is smooth: rotations and fits of centres).
Eigen::MatrixXd jacobian(const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& f,
                         const Eigen::VectorXd& in) {
  const Eigen::Index m = f(in).size();
  Eigen::MatrixXd J(m, in.size());
  Eigen::VectorXd x = in;
  for (Eigen::Index k = 0; k < in.size(); ++k) {
    const double h = 1e-6 * std::max(1.0, std::abs(in[k]));
    x[k] = in[k] + h;
    const Eigen::VectorXd fp = f(x);
    x[k] = in[k] - h;
    const Eigen::VectorXd fm = f(x);
    x[k] = in[k];
    J.col(k) = (fp - fm) / (2 * h);
  }
  return J;
}

// The map as a grid when its nominal positions form a full lattice. A plate's map, whose points
// share one coordinate (one cluster on that axis), becomes a grid on its plane: that axis gets
// two nodes, the plane ± `band`, carrying the same errors (held constant across the band).
std::optional<map::ErrorMap> as_grid(const std::vector<MapPoint>& pts, double tol, double band) {
  std::vector<int> w[3];
  std::vector<double> axes[3];
  int plane = -1;
  for (int a = 0; a < 3; ++a) {
    std::vector<double> v;
    for (const auto& p : pts) v.push_back(p.nominal[a]);
    axes[a] = clusters(v, tol, w[a]);
    if (axes[a].size() == 1 && plane < 0 && band > 0) {
      plane = a;
      axes[a] = {axes[a][0] - band, axes[a][0] + band};
    } else if (axes[a].size() < 2) {
      return std::nullopt;
    }
  }
  map::ErrorMap m;
  for (int a = 0; a < 3; ++a)
    m.axes[static_cast<std::size_t>(a)] = Eigen::Map<const Eigen::VectorXd>(
        axes[a].data(), static_cast<Eigen::Index>(axes[a].size()));
  m.plane = plane;
  const Eigen::Index copies = plane < 0 ? 1 : 2;
  if (m.nodes() != copies * static_cast<Eigen::Index>(pts.size())) return std::nullopt;
  m.error = Eigen::Matrix3Xd::Constant(3, m.nodes(), NAN);
  m.uncertainty.resize(3, m.nodes());
  bool stated = true;
  for (std::size_t i = 0; i < pts.size(); ++i)
    for (Eigen::Index c = 0; c < copies; ++c) {
      Eigen::Index ijk[3] = {w[0][i], w[1][i], w[2][i]};
      if (plane >= 0) ijk[plane] = c;
      const Eigen::Index n = m.index(ijk[0], ijk[1], ijk[2]);
      if (!std::isnan(m.error(0, n))) return std::nullopt;  // two points on one node
      m.error.col(n) = pts[i].error;
      m.uncertainty.col(n) = pts[i].uncertainty;
      stated = stated && pts[i].uncertainty.allFinite();
    }
  if (!stated) m.uncertainty.resize(3, 0);  // not stated: the map carries none
  return m;
}

}  // namespace

std::array<int, 3> Gauge::frame_balls() const {
  if (!frame.empty()) {
    if (frame.size() != 3)
      throw Error(fmt::format("gauge: 'frame' names {} balls; it needs three (origin, axis, plane)",
                              frame.size()));
    return {frame[0], frame[1], frame[2]};
  }
  if (balls.size() < 3)
    throw Error(fmt::format("gauge: needs at least 3 balls, has {}", balls.size()));
  double size = 0;
  for (const auto& b : balls) size = std::max(size, (b - balls[0]).norm());
  const double tol = 1e-6 * std::max(1.0, size);
  const Eigen::Vector3d a = balls[1] - balls[0];
  if (!(a.norm() > tol)) return {0, 1, 2};  // validate() says why
  const Eigen::Vector3d u = a.normalized();
  auto off_line = [&](const Eigen::Vector3d& b) { return (b - balls[0]).cross(u).norm(); };
  if (off_line(balls[2]) > tol) return {0, 1, 2};
  // A row: its far end along 0→1, then the ball farthest from the row's line.
  int axis = 1, plane = -1;
  double far = 0, most = tol;
  for (std::size_t i = 1; i < balls.size(); ++i) {
    const double along = (balls[i] - balls[0]).dot(u), off = off_line(balls[i]);
    if (off <= tol && along > far + tol) {
      far = along;
      axis = static_cast<int>(i);
    }
    if (off > most + tol) {
      most = off;
      plane = static_cast<int>(i);
    }
  }
  if (plane < 0) return {0, 1, 2};  // all on one line: validate() says so
  return {0, axis, plane};
}

void Gauge::validate() const {
  if (!(ball_diameter > 0) || !std::isfinite(ball_diameter))
    throw Error("gauge: ball_diameter must be a positive number of mm");
  if (balls.size() < 3)
    throw Error(fmt::format("gauge: needs at least 3 balls, has {}", balls.size()));
  for (std::size_t i = 0; i < balls.size(); ++i)
    if (!balls[i].allFinite())
      throw Error(fmt::format("gauge: ball {} has a non-finite centre", i));
  // Two balls at one place: a gauge file with a ball listed twice.
  {
    std::vector<std::size_t> order(balls.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(),
              [&](std::size_t a, std::size_t b) { return balls[a].x() < balls[b].x(); });
    constexpr double kSame = 1e-6;  // mm
    for (std::size_t a = 0; a < order.size(); ++a)
      for (std::size_t b = a + 1;
           b < order.size() && balls[order[b]].x() - balls[order[a]].x() <= kSame; ++b)
        if ((balls[order[a]] - balls[order[b]]).norm() <= kSame)
          throw Error(fmt::format("gauge: balls {} and {} are at the same place",
                                  std::min(order[a], order[b]), std::max(order[a], order[b])));
  }
  const auto f = frame_balls();
  for (int i : f)
    if (i < 0 || i >= static_cast<int>(balls.size()))
      throw Error(
          fmt::format("gauge: frame ball {} is not in the gauge (0..{})", i, balls.size() - 1));
  if (f[0] == f[1] || f[0] == f[2] || f[1] == f[2])
    throw Error(fmt::format("gauge: the frame balls {}, {}, {} must be three different balls", f[0],
                            f[1], f[2]));
  const Eigen::Vector3d a = balls[static_cast<std::size_t>(f[1])] -
                            balls[static_cast<std::size_t>(f[0])],
                        b = balls[static_cast<std::size_t>(f[2])] -
                            balls[static_cast<std::size_t>(f[0])];
  if (!(a.norm() > 0) || !(a.cross(b).norm() > 1e-9 * a.norm() * std::max(1.0, b.norm())))
    throw Error(fmt::format(
        "gauge: balls {}, {} and {} must span a plane (they define the gauge frame){}", f[0], f[1],
        f[2],
        frame.empty() ? "; all the balls lie on one line (a ball bar or step gauge fixes no plane)"
                      : ""));
}

std::vector<Eigen::Vector3d> Gauge::canonical() const {
  validate();
  const auto f = frame_balls();
  const Eigen::Vector3d o = balls[static_cast<std::size_t>(f[0])];
  const Eigen::Vector3d u = (balls[static_cast<std::size_t>(f[1])] - o).normalized();
  const Eigen::Vector3d w = u.cross(balls[static_cast<std::size_t>(f[2])] - o).normalized();
  Eigen::Matrix3d F;
  F.col(0) = u;
  F.col(1) = w.cross(u);
  F.col(2) = w;
  std::vector<Eigen::Vector3d> out;
  for (const auto& b : balls) out.push_back(F.transpose() * (b - o));
  return out;
}

Result calibrate(const Gauge& gauge, const std::vector<Placement>& placements, const Options& o) {
  const std::vector<Eigen::Vector3d> U = gauge.canonical();
  if (placements.empty()) throw Error("ball gauge: no placements");
  Result res;
  // Uncertainty with correlations: every mapped error vector is kept as a linear function of all
  // measured centres so far (sens[i]: 3 × inputs, mm per mm); the centres' own uncertainties
  // (u_all) are independent. Tied points carry their dependence on earlier placements.
  Eigen::VectorXd u_all(0);
  std::vector<Eigen::MatrixXd> sens;
  int frame = -1;
  std::optional<Eigen::Vector3d> frame_stylus;  // the stylus of the current frame, when stated
  std::string frame_name;
  for (std::size_t pi = 0; pi < placements.size(); ++pi) {
    const Placement& pl = placements[pi];
    const std::string pname = pl.name.empty() ? fmt::format("placement {}", pi) : pl.name;
    if (pi == 0 && pl.alignment == Alignment::Stitch)
      throw Error(fmt::format(
          "{}: the first placement must define the frame (\"321\" or \"ls\" alignment)", pname));
    // Every aligned placement starts a frame of its own (a plate campaign: each plate placement
    // is aligned by itself); stitched placements join the frame of the last aligned one.
    if (pl.alignment != Alignment::Stitch) {
      ++frame;
      frame_stylus = pl.stylus_offset;
      frame_name = pname;
    } else if (pl.stylus_offset && frame_stylus &&
               (*pl.stylus_offset - *frame_stylus).norm() > 1e-6) {
      // The angular errors move each stylus' tip by its own Abbe arm: two styli map different
      // errors, which no rigid motion ties.
      const Eigen::Vector3d& a = *pl.stylus_offset;
      const Eigen::Vector3d& b = *frame_stylus;
      throw Error(fmt::format(
          "{}: probed with the stylus offset ({:g}, {:g}, {:g}) mm, but its frame ({}) with ({:g}, "
          "{:g}, {:g}) mm; the angular errors move each tip differently, so a stitch needs its "
          "frame's stylus (align it by itself instead: \"321\" or \"ls\")",
          pname, a.x(), a.y(), a.z(), frame_name, b.x(), b.y(), b.z()));
    }
    // Measured centres of this placement's balls.
    std::vector<int> idx;
    std::vector<Centre> cen;
    std::set<int> seen;
    PlacementReport rep;
    rep.name = pname;
    rep.alignment = pl.alignment;
    rep.frame = frame;
    for (const auto& b : pl.balls) {
      if (b.index < 0 || b.index >= static_cast<int>(U.size()))
        throw Error(fmt::format("{}: ball index {} is not in the gauge (0..{})", pname, b.index,
                                U.size() - 1));
      if (!seen.insert(b.index).second)
        throw Error(fmt::format("{}: ball {} is measured twice", pname, b.index));
      Centre c;
      if (b.centre) {
        if (!b.centre->allFinite())
          throw Error(fmt::format("{}: ball {} has a non-finite centre", pname, b.index));
        c.x = *b.centre;
        c.u = b.centre_u;
        c.diameter = NAN;
        rep.given_centres++;
      } else {
        if (b.points.cols() < o.min_points)
          throw Error(fmt::format("{}: ball {} has {} probed points; at least {} are needed", pname,
                                  b.index, b.points.cols(), o.min_points));
        try {
          c = fit_ball(b.points, o.outlier_tolerance, o.drop_outliers);
        } catch (const Error& e) {
          throw Error(fmt::format("{}: ball {}: {}", pname, b.index, e.what()));
        }
        for (const auto& d : c.dropped)
          rep.dropped.push_back(fmt::format("ball {}: {}", b.index, d));
        rep.diameter_error_max =
            std::max(rep.diameter_error_max,
                     std::abs(c.diameter - (gauge.ball_diameter + 2 * pl.tip_radius)));
      }
      idx.push_back(b.index);
      cen.push_back(c);
    }
    rep.balls = static_cast<int>(idx.size());
    const std::size_t nb = idx.size();
    const Eigen::Index K0 = u_all.size(), own = 3 * static_cast<Eigen::Index>(nb);
    Eigen::VectorXd in(own);
    u_all.conservativeResize(K0 + own);
    for (std::size_t k = 0; k < nb; ++k) {
      in.segment<3>(3 * static_cast<Eigen::Index>(k)) = cen[k].x;
      u_all.segment<3>(K0 + 3 * static_cast<Eigen::Index>(k)) = cen[k].u;
    }
    std::vector<int> tied_points;         // map index of each tied input, in input order
    std::vector<std::size_t> tied_balls;  // this placement's balls that tie it (stitch)
    Eigen::Index tied_inputs = 0;         // where their map errors start in `in`
    std::function<Eigen::VectorXd(const Eigen::VectorXd&)> errors;
    std::vector<bool> shared(nb, false);
    if (pl.alignment == Alignment::LeastSquares) {
      if (nb < 3) throw Error(fmt::format("{}: the least-squares alignment needs 3 balls", pname));
      // The frame in which the gauge's measured centres have no rigid-body error: X = R·U + t
      // fitted to all centres (Kabsch), so Σ Δ = 0 and no rotation remains in the LS sense.
      errors = [&](const Eigen::VectorXd& x) {
        std::vector<Eigen::Vector3d> us, xs;
        for (std::size_t k = 0; k < nb; ++k) {
          us.push_back(U[static_cast<std::size_t>(idx[k])]);
          xs.push_back(x.segment<3>(3 * static_cast<Eigen::Index>(k)));
        }
        Eigen::Matrix3d R;
        Eigen::Vector3d t;
        kabsch(us, xs, R, t);
        Eigen::VectorXd d(3 * static_cast<Eigen::Index>(nb));
        for (std::size_t k = 0; k < nb; ++k)
          d.segment<3>(3 * static_cast<Eigen::Index>(k)) = xs[k] - (R * us[k] + t);
        return d;
      };
    } else if (pl.alignment == Alignment::ThreeTwoOne) {
      const auto fb = gauge.frame_balls();
      int k0 = -1, k1 = -1, k2 = -1;
      for (std::size_t k = 0; k < nb; ++k) {
        if (idx[k] == fb[0]) k0 = static_cast<int>(k);
        if (idx[k] == fb[1]) k1 = static_cast<int>(k);
        if (idx[k] == fb[2]) k2 = static_cast<int>(k);
      }
      if (k0 < 0 || k1 < 0 || k2 < 0)
        throw Error(fmt::format(
            "{}: the 3-2-1 alignment needs the gauge's frame balls {}, {} and {} measured", pname,
            fb[0], fb[1], fb[2]));
      errors = [&, k0, k1, k2, fb](const Eigen::VectorXd& x) {
        auto at = [&](int k) { return Eigen::Vector3d(x.segment<3>(3 * k)); };
        const Eigen::Matrix3d C =
            rotation_321(at(k0), at(k1), at(k2), U[static_cast<std::size_t>(fb[1])],
                         U[static_cast<std::size_t>(fb[2])], fb, o.match_tolerance);
        Eigen::VectorXd d(3 * static_cast<Eigen::Index>(nb));
        for (std::size_t k = 0; k < nb; ++k)
          d.segment<3>(3 * static_cast<Eigen::Index>(k)) =
              at(static_cast<int>(k)) - at(k0) - C * U[static_cast<std::size_t>(idx[k])];
        return d;
      };
    } else {
      // Tie to mapped points: the nearest mapped measured centre within the tolerance.
      std::vector<int> tie(nb, -1);
      for (std::size_t k = 0; k < nb; ++k) {
        double best = o.match_tolerance;
        for (std::size_t m = 0; m < res.points.size(); ++m) {
          if (res.points[m].frame != frame) continue;  // another frame's errors: no tie
          const double d = (res.points[m].measured - cen[k].x).norm();
          if (d <= best) {
            best = d;
            tie[k] = static_cast<int>(m);
          }
        }
        shared[k] = tie[k] >= 0;
      }
      std::vector<std::size_t> ks;
      for (std::size_t k = 0; k < nb; ++k)
        if (shared[k]) ks.push_back(k);
      rep.shared = static_cast<int>(ks.size());
      bool spread = ks.size() >= 3;
      if (spread) {
        Eigen::Matrix3Xd S(3, static_cast<Eigen::Index>(ks.size()));
        for (std::size_t j = 0; j < ks.size(); ++j)
          S.col(static_cast<Eigen::Index>(j)) = U[static_cast<std::size_t>(idx[ks[j]])];
        const Eigen::Matrix3Xd c = S.colwise() - S.rowwise().mean();
        const Eigen::Vector3d sv = Eigen::JacobiSVD<Eigen::MatrixXd>(c).singularValues();
        spread = sv[1] > 1e-6 * sv[0];
      }
      if (!spread)
        throw Error(fmt::format(
            "{}: {} of its balls lie within {} mm of points mapped in its frame; stitching needs "
            "at least three that are not collinear (move the gauge so it overlaps the map, or "
            "raise --match-tolerance; a placement that does not overlap is aligned by itself: "
            "\"321\" or \"ls\")",
            pname, ks.size(), o.match_tolerance));
      // Inputs: this placement's centres, then the tied points' error vectors.
      const Eigen::Index base = in.size();
      in.conservativeResize(base + 3 * static_cast<Eigen::Index>(ks.size()));
      for (std::size_t j = 0; j < ks.size(); ++j) {
        const auto& mp = res.points[static_cast<std::size_t>(tie[ks[j]])];
        in.segment<3>(base + 3 * static_cast<Eigen::Index>(j)) = mp.error;
        tied_points.push_back(tie[ks[j]]);
      }
      errors = [&, ks, base](const Eigen::VectorXd& x) {
        std::vector<Eigen::Vector3d> us, xs;
        for (std::size_t j = 0; j < ks.size(); ++j) {
          us.push_back(U[static_cast<std::size_t>(idx[ks[j]])]);
          xs.push_back(x.segment<3>(3 * static_cast<Eigen::Index>(ks[j])) -
                       x.segment<3>(base + 3 * static_cast<Eigen::Index>(j)));
        }
        Eigen::Matrix3d R;
        Eigen::Vector3d t;
        kabsch(us, xs, R, t);
        Eigen::VectorXd d(3 * static_cast<Eigen::Index>(nb));
        for (std::size_t k = 0; k < nb; ++k)
          d.segment<3>(3 * static_cast<Eigen::Index>(k)) =
              x.segment<3>(3 * static_cast<Eigen::Index>(k)) -
              (R * U[static_cast<std::size_t>(idx[k])] + t);
        return d;
      };
      tied_inputs = base;
      tied_balls = ks;
    }
    const Eigen::VectorXd d = errors(in);
    if (!tied_balls.empty()) {
      // Registration residual: the tied balls' new errors against the map's.
      double ss = 0;
      for (std::size_t j = 0; j < tied_balls.size(); ++j)
        ss += (d.segment<3>(3 * static_cast<Eigen::Index>(tied_balls[j])) -
               in.segment<3>(tied_inputs + 3 * static_cast<Eigen::Index>(j)))
                  .squaredNorm();
      rep.registration_rms = std::sqrt(ss / static_cast<double>(tied_balls.size()));
    }
    const Eigen::MatrixXd L = jacobian(errors, in);
    const Eigen::Index K1 = u_all.size();
    for (std::size_t k = 0; k < nb; ++k) {
      if (shared[k]) continue;  // already in the map (it tied this placement)
      const auto row = 3 * static_cast<Eigen::Index>(k);
      Eigen::MatrixXd G = Eigen::MatrixXd::Zero(3, K1);
      G.middleCols(K0, own) = L.block(row, 0, 3, own);
      for (std::size_t j = 0; j < tied_points.size(); ++j) {
        const Eigen::MatrixXd& S = sens[static_cast<std::size_t>(tied_points[j])];
        G.leftCols(S.cols()) += L.block(row, own + 3 * static_cast<Eigen::Index>(j), 3, 3) * S;
      }
      const Eigen::Vector3d u = (G * u_all.asDiagonal()).rowwise().squaredNorm().cwiseSqrt();
      MapPoint mp;
      mp.placement = pname;
      mp.frame = frame;
      mp.ball = idx[k];
      mp.measured = cen[k].x;
      mp.error = d.segment<3>(3 * static_cast<Eigen::Index>(k));
      mp.nominal = mp.measured - mp.error;
      mp.uncertainty = u;
      res.points.push_back(mp);
      sens.push_back(std::move(G));
    }
    res.placements.push_back(rep);
  }
  res.frames = frame + 1;
  if (res.frames == 1) res.grid = as_grid(res.points, o.match_tolerance, o.plane_band);
  return res;
}

std::string Result::summary() const {
  double emax = 0, umax = 0;
  bool stated = true;
  for (const auto& p : points) {
    emax = std::max(emax, p.error.norm());
    if (p.uncertainty.allFinite())
      umax = std::max(umax, p.uncertainty.maxCoeff());
    else
      stated = false;
  }
  std::string where;
  if (grid && grid->plane >= 0) {
    const auto& x = grid->axes[static_cast<std::size_t>(grid->plane)];
    const int a = grid->plane == 0 ? 1 : 0, b = grid->plane == 2 ? 1 : 2;
    where = fmt::format(" on a {} x {} grid in the plane {} = {:.3f} mm", grid->size(a),
                        grid->size(b), "xyz"[grid->plane], (x[0] + x[1]) / 2);
  } else if (grid) {
    where = fmt::format(" on a {} x {} x {} grid", grid->size(0), grid->size(1), grid->size(2));
  } else if (frames > 1) {
    where = fmt::format(" in {} separate frames (each aligned placement starts its own)", frames);
  }
  std::string s = fmt::format(
      "ball gauge: {} placements, {} mapped points{}; largest |error| {:.3f} µm, {}\n",
      placements.size(), points.size(), where, emax * 1e3,
      stated ? fmt::format("largest uncertainty {:.3f} µm", umax * 1e3)
             : std::string("uncertainty not stated (centres given without their uncertainty)"));
  for (const auto& r : placements) {
    std::string fitted;
    if (r.given_centres < r.balls)
      fitted = fmt::format(", sphere diameter error max {:.3f} µm", r.diameter_error_max * 1e3);
    if (r.given_centres > 0) fitted += fmt::format(", {} centres given", r.given_centres);
    s += fmt::format("  {:<14} {:<6} {} balls{}{}\n", r.name,
                     r.alignment == Alignment::ThreeTwoOne    ? "321"
                     : r.alignment == Alignment::LeastSquares ? "ls"
                                                              : "stitch",
                     r.balls,
                     r.alignment == Alignment::Stitch
                         ? fmt::format(" ({} shared, registration RMS {:.3f} µm)", r.shared,
                                       r.registration_rms * 1e3)
                         : "",
                     fitted);
  }
  for (const auto& r : placements)
    for (const auto& d : r.dropped) s += fmt::format("  {}: {}\n", r.name, d);
  return s;
}

}  // namespace trueaxis::ballgauge
