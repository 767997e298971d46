#include "trueaxis/ballgauge/parametric.hpp"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <memory>
#include <set>

#include "../common/eigen_instances.hpp"
#include "common.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::ballgauge {
namespace {

constexpr double kStep = 1e-5;  // central-difference step: mm or rad per (u/1 m)^q
constexpr int kFunctions = 18;  // 3 axes × 6 components
// Singular values of the column-scaled design (Chebyshev basis) below this fraction of the largest
// are undetermined. The pose columns are taken at the measured centres (x − t rather than R·u, the
// same to first order in the errors), so that the map's rigid motion, which the data cannot fix,
// is an exact null direction rather than one near the machine's error gradients; functions that
// move no tip are exact nulls too. Both then lie below 1e-9. The determined directions of Oya,
// Hokari and Tamura's layout lie above 0.05; a stylus offset across the ram (an upright plate
// probed from the side) adds roll and pitch terms seen only through its arm, near 1e-4. Below 1e-5
// a direction would carry 10⁵ times the noise of the determined ones: not determined.
constexpr double kRankThreshold = 1e-5;
// An undetermined direction that moves the model's own stylus (beyond a rigid motion, which no
// length sees) by more than this fraction of the largest singular value makes the model unusable
// for that stylus (identify refuses).
constexpr double kModelStylusLimit = 1e-4;

Eigen::Index parameter_count(int degree) {
  return kFunctions * (degree + 1) + 3;
}

// Coefficients, in powers of (u/1 m), of T_q(s) (Chebyshev, first kind) with s = (u − mid)/half
// (u, mid, half in mm): the well-conditioned basis on the measured span.
std::vector<double> chebyshev_in_metres(int q, double mid, double half) {
  std::vector<double> prev{1}, cur{1};  // T_0; T_1 = s below
  if (q >= 1) cur = {0, 1};
  for (int k = 2; k <= q; ++k) {
    std::vector<double> next(cur.size() + 1, 0.0);
    for (std::size_t j = 0; j < cur.size(); ++j) next[j + 1] += 2 * cur[j];
    for (std::size_t j = 0; j < prev.size(); ++j) next[j] -= prev[j];
    prev = cur;
    cur = next;
  }
  if (q == 0) cur = {1};
  // Substitute s = a·m + b, m = u/1000: Horner on polynomials in m.
  const double a = 1000 / half, b = -mid / half;
  std::vector<double> out{0};
  for (auto it = cur.rbegin(); it != cur.rend(); ++it) {
    std::vector<double> next(out.size() + 1, 0.0);
    for (std::size_t j = 0; j < out.size(); ++j) {
      next[j + 1] += a * out[j];
      next[j] += b * out[j];
    }
    next[0] += *it;
    out = next;
  }
  return out;
}

// Adds v·(basis function p) to the machine's errors (basis: Chebyshev polynomials per axis on
// [mid − half, mid + half], then the three squareness errors).
void add_parameter(sim::Machine& m, int degree, const Eigen::Vector3d& mid,
                   const Eigen::Vector3d& half, Eigen::Index p, double v) {
  const Eigen::Index per = degree + 1, fun = kFunctions * per;
  if (p < fun) {
    const auto f = static_cast<std::size_t>(p / per);
    const auto axis = f / 6;
    const auto c =
        chebyshev_in_metres(static_cast<int>(p % per), mid[static_cast<Eigen::Index>(axis)],
                            half[static_cast<Eigen::Index>(axis)]);
    auto& poly = m.errors[axis][f % 6].polynomial;
    if (poly.size() < c.size()) poly.resize(c.size(), 0.0);
    for (std::size_t j = 0; j < c.size(); ++j) poly[j] += v * c[j];
  } else if (p == fun) {
    m.squareness_c0y += v;
  } else if (p == fun + 1) {
    m.squareness_b0z += v;
  } else {
    m.squareness_a0z += v;
  }
}

sim::Machine blank_machine(const std::string& chain, const Eigen::Vector3d& offset) {
  sim::Machine m;
  m.name = "identified from ball-gauge data";
  m.chain = chain;
  m.offset = offset;
  m.range = {{{-1e6, 1e6}, {-1e6, 1e6}, {-1e6, 1e6}}};
  return m;
}

// d e / d parameters at the commands (3n × parameters; rows 3i..3i+2 = command i), by central
// differences of the exact model about zero errors (exact for the translations; the rotations'
// second-order terms cancel).
Eigen::MatrixXd design_matrix(const std::string& chain, const Eigen::Vector3d& offset, int degree,
                              const Eigen::Vector3d& mid, const Eigen::Vector3d& half,
                              const Eigen::Matrix3Xd& commands) {
  const Eigen::Index P = parameter_count(degree), n = commands.cols();
  Eigen::MatrixXd J(3 * n, P);
  for (Eigen::Index p = 0; p < P; ++p) {
    sim::Machine plus = blank_machine(chain, offset), minus = plus;
    add_parameter(plus, degree, mid, half, p, kStep);
    add_parameter(minus, degree, mid, half, p, -kStep);
    const Eigen::Matrix3Xd d = (plus.errors_at(commands) - minus.errors_at(commands)) / (2 * kStep);
    J.col(p) = Eigen::Map<const Eigen::VectorXd>(d.data(), 3 * n);
  }
  return J;
}

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

// The undetermined directions (`null`, columns in the column-scaled space of the design, the
// parameters first; `scale` the parameters' column scales) are harmless to the model's own
// stylus when they move its tip at the measured commands by a rigid motion at most, which no
// length sees; with one stylus they do by construction. A campaign whose placements use other
// styli (an upright plate probed from the side) can leave a combination of errors that moves none
// of their tips but moves the model's: refused, naming the functions, since the model would
// correct that stylus with errors the data never saw. `largest`: the design's largest singular
// value.
void refuse_if_model_stylus_unseen(const ParametricResult& r, const ParametricOptions& o,
                                   const Eigen::Matrix3Xd& commands, const Eigen::MatrixXd& null,
                                   const Eigen::VectorXd& scale, double largest) {
  if (null.cols() == 0) return;
  if (r.styli.size() == 1 && r.styli.front().offset == o.offset)
    return;  // harmless by construction
  const Eigen::Index P = scale.size(), n = commands.cols();
  const Eigen::MatrixXd Jm =
      design_matrix(o.chain, o.offset, o.degree, r.centre, r.half_span, commands);
  Eigen::MatrixXd D = Jm * (scale.asDiagonal() * null.topRows(P));  // 3n × nulls
  // Less the best rigid motion ω × p + v of the model's tip positions p (centred).
  Eigen::MatrixXd G(3 * n, 6);
  const Eigen::Vector3d mid = commands.rowwise().mean();
  for (Eigen::Index i = 0; i < n; ++i) {
    G.block<3, 3>(3 * i, 0) = -skew(commands.col(i) - mid);
    G.block<3, 3>(3 * i, 3) = Eigen::Matrix3d::Identity();
  }
  D -= G * G.colPivHouseholderQr().solve(D);
  Eigen::Index worst = 0;
  const double moved = D.colwise().norm().maxCoeff(&worst);
  if (!(moved > kModelStylusLimit * largest)) return;
  // The functions that make up that direction (by their share of it in the scaled space).
  const Eigen::Index per = o.degree + 1;
  std::vector<std::pair<double, std::string>> share;
  for (int f = 0; f < kFunctions; ++f)
    share.emplace_back(null.col(worst).segment(f * per, per).norm(),
                       sim::error_name(f / 6, static_cast<sim::Component>(f % 6)));
  const char* squareness[3] = {"EC0Y", "EB0Z", "EA0Z"};
  for (int q = 0; q < 3; ++q)
    share.emplace_back(std::abs(null(kFunctions * per + q, worst)), squareness[q]);
  std::sort(share.begin(), share.end(),
            [](const auto& a, const auto& b) { return a.first > b.first; });
  std::string names;
  for (const auto& [w, name] : share)
    if (w >= 0.3 * share.front().first)
      names += fmt::format("{}{}", names.empty() ? "" : ", ", name);
  throw Error(fmt::format(
      "parametric model: the placements' styli cannot tell {} apart (a combination of them moves "
      "none of their tips), but it moves the tip of the stylus the model is for, ({:g}, {:g}, "
      "{:g}) mm; measure some placements with that stylus too, or probe the upright placements "
      "from both sides",
      names, o.offset.x(), o.offset.y(), o.offset.z()));
}

}  // namespace

void ParametricOptions::validate() const {
  if (degree < 1 || degree > 8) throw Error("parametric model: the degree must be 1 to 8");
  if (!offset.allFinite()) throw Error("parametric model: the stylus offset must be finite");
  if (!(position_tolerance > 0) || !std::isfinite(position_tolerance))
    throw Error("parametric model: the position tolerance must be a positive number of mm");
  if (min_points < 4) throw Error("parametric model: a sphere needs at least 4 points");
  if (max_iterations < 1) throw Error("parametric model: at least one iteration");
  blank_machine(chain, offset).validate();  // the chain
}

Eigen::MatrixXd ParametricResult::design(const Eigen::Vector3d& command) const {
  return design_matrix(model.chain, model.offset, degree, centre, half_span, command);
}

ParametricResult identify(const Gauge& gauge, const std::vector<Placement>& placements,
                          const ParametricOptions& o) {
  o.validate();
  const std::vector<Eigen::Vector3d> U = gauge.canonical();
  if (placements.empty()) throw Error("parametric model: no placements");
  // Observations: measured centres with their gauge coordinates, placement and stylus.
  std::vector<Eigen::Vector3d> x, u;
  std::vector<int> which, stylus;
  ParametricResult r;
  for (std::size_t pi = 0; pi < placements.size(); ++pi) {
    const Placement& pl = placements[pi];
    const std::string name = pl.name.empty() ? fmt::format("placement {}", pi) : pl.name;
    const Eigen::Vector3d off = pl.stylus_offset.value_or(o.offset);
    if (!off.allFinite()) throw Error(fmt::format("{}: the stylus offset must be finite", name));
    auto same = [&](const ParametricResult::Stylus& s) { return s.offset == off; };
    auto sty = std::find_if(r.styli.begin(), r.styli.end(), same);
    if (sty == r.styli.end()) sty = r.styli.insert(r.styli.end(), {off, {}});
    sty->placements.push_back(name);
    const int si = static_cast<int>(sty - r.styli.begin());
    if (pl.balls.size() < 3)
      throw Error(fmt::format("{}: {} balls; a placement needs at least 3 for its pose", name,
                              pl.balls.size()));
    std::set<int> seen;
    for (const auto& b : pl.balls) {
      if (b.index < 0 || b.index >= static_cast<int>(U.size()))
        throw Error(fmt::format("{}: no ball {} in the gauge ({} balls)", name, b.index, U.size()));
      if (!seen.insert(b.index).second)
        throw Error(fmt::format("{}: ball {} is measured twice", name, b.index));
      if (b.centre) {
        if (!b.centre->allFinite())
          throw Error(fmt::format("{}, ball {}: a non-finite centre", name, b.index));
        x.push_back(*b.centre);
      } else {
        if (b.points.cols() < o.min_points)
          throw Error(fmt::format("{}, ball {}: {} points; at least {} are needed", name, b.index,
                                  b.points.cols(), o.min_points));
        try {
          x.push_back(detail::fit_ball(b.points, o.outlier_tolerance, o.drop_outliers).x);
        } catch (const Error& e) {
          throw Error(fmt::format("{}, ball {}: {}", name, b.index, e.what()));
        }
      }
      u.push_back(U[static_cast<std::size_t>(b.index)]);
      which.push_back(static_cast<int>(pi));
      stylus.push_back(si);
    }
  }
  const auto n = static_cast<Eigen::Index>(x.size());
  const auto m = static_cast<Eigen::Index>(placements.size());
  Eigen::Matrix3Xd commands(3, n);
  for (Eigen::Index i = 0; i < n; ++i)
    commands.col(i) = x[static_cast<std::size_t>(i)] -
                      r.styli[static_cast<std::size_t>(stylus[static_cast<std::size_t>(i)])].offset;
  // The observations of each stylus (indices into x), to evaluate the model at its offset.
  std::vector<std::vector<Eigen::Index>> group(r.styli.size());
  for (Eigen::Index i = 0; i < n; ++i)
    group[static_cast<std::size_t>(stylus[static_cast<std::size_t>(i)])].push_back(i);
  auto commands_of = [&](std::size_t g) {
    Eigen::Matrix3Xd c(3, static_cast<Eigen::Index>(group[g].size()));
    for (std::size_t j = 0; j < group[g].size(); ++j)
      c.col(static_cast<Eigen::Index>(j)) = commands.col(group[g][j]);
    return c;
  };
  // e(c) of `model` at every observation, each at its own stylus.
  auto errors_at = [&](sim::Machine model) {
    Eigen::Matrix3Xd e(3, n);
    for (std::size_t g = 0; g < group.size(); ++g) {
      model.offset = r.styli[g].offset;
      const Eigen::Matrix3Xd eg = model.errors_at(commands_of(g));
      for (std::size_t j = 0; j < group[g].size(); ++j)
        e.col(group[g][j]) = eg.col(static_cast<Eigen::Index>(j));
    }
    return e;
  };
  r.degree = o.degree;
  r.model = blank_machine(o.chain, o.offset);
  for (int k = 0; k < 3; ++k) {
    std::vector<double> v;
    for (Eigen::Index i = 0; i < n; ++i) v.push_back(commands(k, i));
    std::vector<int> which_cluster;
    const auto d =
        static_cast<int>(detail::clusters(v, o.position_tolerance, which_cluster).size());
    if (d <= o.degree)
      throw Error(fmt::format(
          "parametric model: axis {} is measured at only {} distinct positions; degree {} "
          "needs at least {} (lower the degree or measure more positions)",
          "XYZ"[k], d, o.degree, o.degree + 1));
    r.model.range[static_cast<std::size_t>(k)] = {commands.row(k).minCoeff(),
                                                  commands.row(k).maxCoeff()};
    r.centre[k] = (commands.row(k).minCoeff() + commands.row(k).maxCoeff()) / 2;
    r.half_span[k] = (commands.row(k).maxCoeff() - commands.row(k).minCoeff()) / 2;
  }

  // Initial poses: the rigid fit of the gauge to each placement's measured centres.
  std::vector<Eigen::Matrix3d> R(static_cast<std::size_t>(m));
  std::vector<Eigen::Vector3d> t(static_cast<std::size_t>(m));
  for (Eigen::Index p = 0; p < m; ++p) {
    std::vector<Eigen::Vector3d> up, xp;
    for (Eigen::Index i = 0; i < n; ++i)
      if (which[static_cast<std::size_t>(i)] == p) {
        up.push_back(u[static_cast<std::size_t>(i)]);
        xp.push_back(x[static_cast<std::size_t>(i)]);
      }
    detail::kabsch(up, xp, R[static_cast<std::size_t>(p)], t[static_cast<std::size_t>(p)]);
  }

  const Eigen::Index P = parameter_count(o.degree), N = P + 6 * m;
  Eigen::MatrixXd J(3 * n, P);
  for (std::size_t g = 0; g < group.size(); ++g) {
    const Eigen::MatrixXd Jg =
        design_matrix(o.chain, r.styli[g].offset, o.degree, r.centre, r.half_span, commands_of(g));
    for (std::size_t j = 0; j < group[g].size(); ++j)
      J.middleRows(3 * group[g][j], 3) = Jg.middleRows(3 * static_cast<Eigen::Index>(j), 3);
  }
  // Error functions that do not move this tip at any measured command.
  const Eigen::Index per = o.degree + 1;
  for (int f = 0; f < kFunctions; ++f) {
    const double arm = f % 6 >= 3 ? 1e3 : 1.0;  // mm per rad vs mm per mm
    if (J.middleCols(f * per, per).norm() <= 1e-9 * arm * std::sqrt(static_cast<double>(n)))
      r.unobservable.push_back(sim::error_name(f / 6, static_cast<sim::Component>(f % 6)));
  }
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(P);
  Eigen::MatrixXd A(3 * n, N);
  Eigen::VectorXd res(3 * n), scale(N);
  auto residuals = [&] {
    sim::Machine model = r.model;
    for (Eigen::Index p = 0; p < P; ++p)
      add_parameter(model, o.degree, r.centre, r.half_span, p, theta[p]);
    const Eigen::Matrix3Xd e = errors_at(model);
    for (Eigen::Index i = 0; i < n; ++i) {
      const auto p = static_cast<std::size_t>(which[static_cast<std::size_t>(i)]);
      res.segment<3>(3 * i) = x[static_cast<std::size_t>(i)] -
                              (R[p] * u[static_cast<std::size_t>(i)] + t[p]) + e.col(i);
    }
  };
  Eigen::JacobiSVD<Eigen::MatrixXd> svd;
  residuals();
  for (r.iterations = 1; r.iterations <= o.max_iterations; ++r.iterations) {
    A.setZero();
    A.leftCols(P) = J;
    for (Eigen::Index i = 0; i < n; ++i) {
      const auto p = which[static_cast<std::size_t>(i)];
      // R·u to first order (see kRankThreshold).
      const Eigen::Vector3d v = x[static_cast<std::size_t>(i)] - t[static_cast<std::size_t>(p)];
      A.block<3, 3>(3 * i, P + 6 * p) = skew(v);
      A.block<3, 3>(3 * i, P + 6 * p + 3) = -Eigen::Matrix3d::Identity();
    }
    for (Eigen::Index c = 0; c < N; ++c) {
      const double s = A.col(c).norm();
      scale[c] = s > 0 ? 1 / s : 1.0;
      A.col(c) *= scale[c];
    }
    svd.compute(A, Eigen::ComputeThinU | Eigen::ComputeThinV);
    svd.setThreshold(kRankThreshold);
    const Eigen::VectorXd step = scale.asDiagonal() * svd.solve(-res);
    const Eigen::VectorXd theta_before = theta;
    const auto R_before = R;
    const auto t_before = t;
    theta += step.head(P);
    for (Eigen::Index p = 0; p < m; ++p) {
      const Eigen::Vector3d w = step.segment<3>(P + 6 * p);
      auto& Rp = R[static_cast<std::size_t>(p)];
      Rp = (w.norm() > 0 ? Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix()
                         : Eigen::Matrix3d::Identity()) *
           Rp;
      t[static_cast<std::size_t>(p)] += step.segment<3>(P + 6 * p + 3);
    }
    const double before = res.norm();
    const Eigen::VectorXd res_before = res;
    residuals();
    if (res.norm() > before) {  // the linearisation no longer helps: keep the better point
      theta = theta_before;
      R = R_before;
      t = t_before;
      res = res_before;
      break;
    }
    // Converged when the step no longer changes the residual (the model is linear in the
    // translations and within ~1e-5 relative in the rotations).
    if (std::abs(before - res.norm()) <= 1e-9 * std::max(before, 1e-12)) break;
  }
  r.iterations = std::min(r.iterations, o.max_iterations);
  r.rank = static_cast<int>(svd.rank());
  r.balls = static_cast<int>(n);
  r.placements = static_cast<int>(m);
  r.unknowns = static_cast<int>(N);
  r.parameters = theta;
  for (Eigen::Index p = 0; p < P; ++p)
    add_parameter(r.model, o.degree, r.centre, r.half_span, p, theta[p]);
  r.residual_rms = std::sqrt(res.squaredNorm() / static_cast<double>(3 * n));
  const double dof = static_cast<double>(3 * n - r.rank);
  r.sigma = dof > 0 ? std::sqrt(res.squaredNorm() / dof) : NAN;
  // Covariance (scaled space: V Σ⁻² Vᵀ over the rank), then unscaled; the parameters' block.
  const Eigen::Index k = svd.rank();
  const Eigen::MatrixXd Vk =
      svd.matrixV().leftCols(k) * svd.singularValues().head(k).cwiseInverse().asDiagonal();
  const Eigen::MatrixXd cov = (r.sigma * r.sigma) * (Vk * Vk.transpose());
  r.covariance = scale.head(P).asDiagonal() * cov.topLeftCorner(P, P) * scale.head(P).asDiagonal();
  refuse_if_model_stylus_unseen(r, o, commands, svd.matrixV().rightCols(N - k), scale.head(P),
                                svd.singularValues()[0]);
  r.iso = iso_figures(r);
  return r;
}

IsoFigures iso_figures(const ParametricResult& r) {
  IsoFigures out;
  // The model's machine restricted to the identified span, built from the parameters so that
  // each one can be moved on its own.
  auto machine = [&](Eigen::Index p, double delta) {
    sim::Machine m = blank_machine(r.model.chain, r.model.offset);
    m.range = r.model.range;
    for (Eigen::Index q = 0; q < r.parameters.size(); ++q)
      add_parameter(m, r.degree, r.centre, r.half_span, q, r.parameters[q] + (q == p ? delta : 0));
    return m;
  };
  auto figures = [&](const sim::ReferenceLines& l) {
    Eigen::VectorXd v(9);
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 2; ++j)
        v[2 * k + j] = l.straightness[static_cast<std::size_t>(k)][static_cast<std::size_t>(j)];
    v[6] = l.c0y;
    v[7] = l.b0z;
    v[8] = l.a0z;
    return v;
  };
  out.lines = sim::reference_lines(machine(-1, 0), r.centre);
  const Eigen::Index P = r.parameters.size();
  if (r.covariance.rows() != P || r.covariance.cols() != P) return out;
  Eigen::MatrixXd G(9, P);
  for (Eigen::Index p = 0; p < P; ++p)
    G.col(p) = (figures(sim::reference_lines(machine(p, kStep), r.centre)) -
                figures(sim::reference_lines(machine(p, -kStep), r.centre))) /
               (2 * kStep);
  const Eigen::VectorXd u = (G * r.covariance * G.transpose()).diagonal().cwiseMax(0).cwiseSqrt();
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 2; ++j)
      out.u_straightness[static_cast<std::size_t>(k)][static_cast<std::size_t>(j)] = u[2 * k + j];
  out.u_c0y = u[6];
  out.u_b0z = u[7];
  out.u_a0z = u[8];
  return out;
}

std::string ParametricResult::summary() const {
  std::string s = fmt::format(
      "parametric model ({} chain, polynomials of degree {}): {} balls in {} placements\n"
      "  {} unknowns ({} error coefficients + 6 per placement), rank {}: {} directions are not "
      "determined by the data (the map's rigid-body motion{})\n"
      "  residual RMS {:.3f} µm per centre component (sigma {:.3f} µm), {} Gauss-Newton "
      "iterations\n",
      model.chain, degree, balls, placements, unknowns, unknowns - 6 * placements, rank,
      unknowns - rank,
      unobservable.empty() ? ""
      : styli.size() > 1   ? " and functions that move none of these tips"
                           : " and functions that do not move this tip",
      residual_rms * 1e3, sigma * 1e3, iterations);
  if (styli.size() > 1) {
    std::string list;
    for (const auto& st : styli) {
      std::string names;
      for (const auto& p : st.placements)
        names += fmt::format("{}{}", names.empty() ? "" : ", ", p);
      // (+ 0.0: no "-0" for a zero component)
      list += fmt::format("{}({:g}, {:g}, {:g}) mm in {}", list.empty() ? "" : "; ",
                          st.offset.x() + 0.0, st.offset.y() + 0.0, st.offset.z() + 0.0, names);
    }
    s += fmt::format("  {} styli: {}; the model corrects for ({:g}, {:g}, {:g}) mm\n", styli.size(),
                     list, model.offset.x(), model.offset.y(), model.offset.z());
  }
  if (!unobservable.empty()) {
    std::string names;
    for (const auto& u : unobservable) names += (names.empty() ? "" : ", ") + u;
    s += fmt::format("  not seen by {}: {}\n", styli.size() > 1 ? "these styli" : "this stylus",
                     names);
  }
  s += model.summary(unobservable);
  // Expanded uncertainties (k = 2) of the ISO figures, and those the data cannot resolve.
  const auto& L = iso.lines;
  std::string st, unresolved;
  for (int k = 0; k < 3; ++k) {
    const int a = (k + 1) % 3, b = (k + 2) % 3;
    const int across[2] = {std::min(a, b), std::max(a, b)};
    st += fmt::format("{}{} {:.2f} {:.2f}", k ? ", " : "", "XYZ"[k],
                      2e3 * iso.u_straightness[static_cast<std::size_t>(k)][0],
                      2e3 * iso.u_straightness[static_cast<std::size_t>(k)][1]);
    for (int j = 0; j < 2; ++j) {
      const double v = L.straightness[static_cast<std::size_t>(k)][static_cast<std::size_t>(j)],
                   U = 2 *
                       iso.u_straightness[static_cast<std::size_t>(k)][static_cast<std::size_t>(j)];
      const std::string name = sim::error_name(k, static_cast<sim::Component>(across[j]));
      if (U >= v && std::find(unobservable.begin(), unobservable.end(), name) == unobservable.end())
        unresolved +=
            fmt::format("{}{} (U {:.2f} µm)", unresolved.empty() ? "" : ", ", name, U * 1e3);
    }
  }
  s += fmt::format(
      "  U (k = 2): straightness {} µm; squareness EC0Y {:.1f}, EB0Z {:.1f}, EA0Z {:.1f} µrad\n",
      st, 2e6 * iso.u_c0y, 2e6 * iso.u_b0z, 2e6 * iso.u_a0z);
  if (!unresolved.empty())
    s += fmt::format("  not resolved (U reaches the value): {}\n", unresolved);
  return s;
}

Correction parametric_correction(const ParametricResult& result) {
  auto r = std::make_shared<const ParametricResult>(result);
  Correction c;
  c.name = "parametric";
  c.apply = [r](Eigen::Ref<Eigen::Matrix3Xd> p) {
    for (Eigen::Index i = 0; i < p.cols(); ++i) {
      const Eigen::Vector3d cmd = p.col(i) - r->model.offset;
      if (!r->model.contains(cmd, 1e-6))
        throw Error(fmt::format(
            "point {} ({:.3f}, {:.3f}, {:.3f}) is outside the identified span x {:.3f}..{:.3f}, "
            "y {:.3f}..{:.3f}, z {:.3f}..{:.3f} mm (commands)",
            i + 1, p(0, i), p(1, i), p(2, i), r->model.range[0][0], r->model.range[0][1],
            r->model.range[1][0], r->model.range[1][1], r->model.range[2][0],
            r->model.range[2][1]));
    }
    const Eigen::Matrix3Xd cmds = p.colwise() - r->model.offset;
    p += r->model.errors_at(cmds);
  };
  c.length_uncertainties = [r](const Eigen::Matrix3Xd& a, const Eigen::Matrix3Xd& b) {
    // The design matrix of all ends at once, in blocks that bound its memory (6·block × P).
    constexpr Eigen::Index kBlock = 2048;
    const Eigen::Index n = a.cols();
    Eigen::VectorXd u(n);
    for (Eigen::Index s = 0; s < n; s += kBlock) {
      const Eigen::Index m = std::min(kBlock, n - s);
      Eigen::Matrix3Xd ends(3, 2 * m);
      ends.leftCols(m) = a.middleCols(s, m).colwise() - r->model.offset;
      ends.rightCols(m) = b.middleCols(s, m).colwise() - r->model.offset;
      const Eigen::MatrixXd J =
          design_matrix(r->model.chain, r->model.offset, r->degree, r->centre, r->half_span, ends);
      for (Eigen::Index i = 0; i < m; ++i) {
        const Eigen::Vector3d d = (b.col(s + i) - a.col(s + i)).normalized();
        const Eigen::RowVectorXd g =
            d.transpose() * (J.middleRows(3 * (m + i), 3) - J.middleRows(3 * i, 3));
        u[s + i] = std::sqrt(std::max(0.0, (g * r->covariance * g.transpose())(0, 0)));
      }
    }
    return u;
  };
  c.length_uncertainty = [r](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    const Eigen::Vector3d d = (b - a).normalized();
    const Eigen::RowVectorXd g =
        d.transpose() * (r->design(b - r->model.offset) - r->design(a - r->model.offset));
    return std::sqrt(std::max(0.0, (g * r->covariance * g.transpose())(0, 0)));
  };
  return c;
}

}  // namespace trueaxis::ballgauge
