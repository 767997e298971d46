// The geometric-correction menu: in-plane transformations of a section's design data fitted to
// touched points by Gauss–Newton on their normal distances.
#include <fmt/format.h>

#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>

#include "section.hpp"
#include "trueaxis/scan/controller.hpp"
#include "trueaxis/sim/cmm.hpp"

namespace trueaxis::scan {
namespace {

// The section plane's frame, centred on the section's centroid.
struct Frame {
  Eigen::Vector3d o, e1, e2, n;
  Eigen::Vector2d to2(const Eigen::Vector3d& x) const { return {(x - o).dot(e1), (x - o).dot(e2)}; }
  Eigen::Vector3d to3(const Eigen::Vector2d& x, const Eigen::Vector3d& like) const {
    return o + e1 * x.x() + e2 * x.y() + n * (like - o).dot(n);
  }
};

Frame frame_of(const design::Section& s, const Eigen::Matrix3Xd& samples) {
  Frame f;
  f.n = s.plane.normal.normalized();
  const Eigen::Vector3d a =
      std::abs(f.n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  f.e1 = (a - a.dot(f.n) * f.n).normalized();
  f.e2 = f.n.cross(f.e1);
  f.o = samples.rowwise().mean();
  return f;
}

enum class Kind { Translation, Rotation, Scale, ScaleRotation, Directional };
const char* name(Kind k) {
  switch (k) {
    case Kind::Translation:
      return "translation";
    case Kind::Rotation:
      return "rotation";
    case Kind::Scale:
      return "scale";
    case Kind::ScaleRotation:
      return "scale+rotation";
    case Kind::Directional:
      return "directional-scale";
  }
  return "";
}

// x -> A x + t in the plane frame.
struct Affine2 {
  Eigen::Matrix2d A = Eigen::Matrix2d::Identity();
  Eigen::Vector2d t = Eigen::Vector2d::Zero();
};

Affine2 model(Kind k, const Eigen::VectorXd& q) {
  Affine2 m;
  auto rot = [](double a) {
    Eigen::Matrix2d r;
    r << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
    return r;
  };
  switch (k) {
    case Kind::Translation:
      m.t = q.head<2>();
      break;
    case Kind::Rotation:
      m.A = rot(q[2]);
      m.t = q.head<2>();
      break;
    case Kind::Scale:
      m.A *= 1 + q[2];
      m.t = q.head<2>();
      break;
    case Kind::ScaleRotation:
      m.A = (1 + q[2]) * rot(q[3]);
      m.t = q.head<2>();
      break;
    case Kind::Directional: {
      const Eigen::Vector2d u(std::cos(q[3]), std::sin(q[3]));
      m.A += q[2] * u * u.transpose();
      m.t = q.head<2>();
      break;
    }
  }
  return m;
}

int params(Kind k) {
  return k == Kind::Translation ? 2 : (k == Kind::Rotation || k == Kind::Scale) ? 3 : 4;
}

// Normal distances of the touched points from the transformed design at their feet.
Eigen::VectorXd residuals(Kind k, const Eigen::VectorXd& q, const std::vector<Eigen::Vector2d>& p,
                          const std::vector<Eigen::Vector2d>& m,
                          const std::vector<Eigen::Vector2d>& touched) {
  const Affine2 a = model(k, q);
  const Eigen::Matrix2d nt = a.A.inverse().transpose();
  Eigen::VectorXd r(static_cast<Eigen::Index>(p.size()));
  for (std::size_t i = 0; i < p.size(); ++i)
    r[static_cast<Eigen::Index>(i)] =
        (touched[i] - (a.A * p[i] + a.t)).dot((nt * m[i]).normalized());
  return r;
}

Eigen::VectorXd gauss_newton(Kind k, Eigen::VectorXd q, const std::vector<Eigen::Vector2d>& p,
                             const std::vector<Eigen::Vector2d>& m,
                             const std::vector<Eigen::Vector2d>& touched) {
  // The contour's size about the frame's origin (its centroid), at least 1 mm.
  double size = 0;
  for (const auto& x : p) size += x.squaredNorm();
  size = std::max(1.0, std::sqrt(size / static_cast<double>(std::max<std::size_t>(1, p.size()))));
  for (int it = 0; it < 30; ++it) {
    const Eigen::VectorXd r = residuals(k, q, p, m, touched);
    Eigen::MatrixXd J(r.size(), q.size());
    for (Eigen::Index j = 0; j < q.size(); ++j) {
      Eigen::VectorXd h = q;
      const double step = 1e-7;
      h[j] += step;
      const Eigen::VectorXd rp = residuals(k, h, p, m, touched);
      h[j] -= 2 * step;
      J.col(j) = (rp - residuals(k, h, p, m, touched)) / (2 * step);
    }
    // The least-norm step, singular values below 1e-6 of the largest left out, on columns in
    // comparable units: a translation moves a point by 1 mm per mm, a turn or a scale by the
    // contour's size per radian or unit. Touch points on one straight wall do not see a move
    // along it: its column is the numerical derivative's round-off, left out, and a rotation
    // fits the tilt and the move across the wall and leaves the move along it at 0 (a pivoted QR
    // took that round-off for a column and moved the design by 10⁶ mm).
    Eigen::VectorXd unit = Eigen::VectorXd::Ones(q.size());
    unit.tail(q.size() - 2).setConstant(size);
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(J * unit.cwiseInverse().asDiagonal(),
                                          Eigen::ComputeThinU | Eigen::ComputeThinV);
    svd.setThreshold(1e-6);
    const Eigen::VectorXd dq = unit.cwiseInverse().asDiagonal() * svd.solve(-r);
    if (!dq.allFinite()) break;
    q += dq;
    if (dq.norm() < 1e-12) break;
  }
  return q;
}

design::Section apply(const design::Section& s, const Frame& f, const Affine2& a) {
  design::Section out = s;
  auto map = [&](Eigen::Matrix3Xd& pts) {
    for (Eigen::Index i = 0; i < pts.cols(); ++i) {
      const Eigen::Vector2d x = f.to2(pts.col(i));
      pts.col(i) = f.to3(a.A * x + a.t, pts.col(i));
    }
  };
  if (out.nurbs)
    map(out.nurbs->control_points);
  else
    map(out.polyline);
  return out;
}

// The least scatter a touch point is taken to have (mm): a CMM's resolution.
constexpr double kResolution = 1e-4;

// Signed distances of the touched points from a section's curve, sampled every 0.05 mm (chords
// within 0.05²/8R of the curve: 0.3 µm at R = 1 mm).
constexpr double kSampling = 0.05;
// A section's curve as a contour for distance queries.
sim::Contour curve_of(const design::Section& s) {
  return detail::contour_of(s, kSampling);
}

// Signed distances of the touched points from a curve.
Eigen::VectorXd distances(const sim::Contour& c, const Eigen::Matrix3Xd& touched) {
  Eigen::VectorXd d(touched.cols());
  for (Eigen::Index i = 0; i < touched.cols(); ++i) d[i] = c.nearest(touched.col(i)).distance;
  return d;
}

// The touch points in the section's plane frame, with their feet on the design.
struct Touches {
  sim::Contour curve;
  Frame f;
  std::vector<Eigen::Vector2d> p0, m0, t;  // feet, design normals there, touched points
  Eigen::VectorXd before;                  // signed distances of the touched points (mm)
  double extent = 0;                       // the contour's size in its plane (mm)
  const Eigen::Matrix3Xd& touched;
};

Touches prepare(const design::Section& section, const Eigen::Matrix3Xd& feet,
                const Eigen::Matrix3Xd& touched) {
  sim::Contour curve = curve_of(section);
  const Frame f = frame_of(section, curve.points());
  Touches in{std::move(curve), f, {}, {}, {}, {}, 0, touched};
  for (Eigen::Index i = 0; i < feet.cols(); ++i) {
    const auto nr = in.curve.nearest(feet.col(i));
    in.p0.push_back(f.to2(nr.point));
    in.m0.push_back(Eigen::Vector2d(nr.normal.dot(f.e1), nr.normal.dot(f.e2)).normalized());
    in.t.push_back(f.to2(touched.col(i)));
  }
  in.before = distances(in.curve, touched);
  const Eigen::Matrix3Xd& q = in.curve.points();
  in.extent = (q.rowwise().maxCoeff() - q.rowwise().minCoeff()).norm();
  return in;
}

// A model's parameters q (plane frame f) as a correction: the map in 3-D (in the plane A about
// the frame's origin, then t; along the normal nothing) and its parameters as reported.
Correction describe(Kind k, const Eigen::VectorXd& q, const Frame& f) {
  const Affine2 a = model(k, q);
  Correction c;
  c.type = name(k);
  Eigen::Matrix<double, 3, 2> E;
  E << f.e1, f.e2;
  const Eigen::Matrix3d lin = E * a.A * E.transpose() + f.n * f.n.transpose();
  c.transform.linear() = lin;
  c.transform.translation() = f.o + E * a.t - lin * f.o;
  const Eigen::Vector3d t3 = f.e1 * a.t.x() + f.e2 * a.t.y();
  if (k == Kind::Rotation || k == Kind::ScaleRotation)
    c.parameters.push_back({"rotation_deg", q[k == Kind::Rotation ? 2 : 3] * 180 / M_PI});
  if (k == Kind::Scale || k == Kind::ScaleRotation || k == Kind::Directional)
    c.parameters.push_back({"scale", 1 + q[2]});
  if (k == Kind::Directional) {
    const Eigen::Vector3d u = f.e1 * std::cos(q[3]) + f.e2 * std::sin(q[3]);
    c.parameters.push_back({"direction_x", u.x()});
    c.parameters.push_back({"direction_y", u.y()});
    c.parameters.push_back({"direction_z", u.z()});
  }
  c.parameters.push_back({"dx_mm", t3.x()});
  c.parameters.push_back({"dy_mm", t3.y()});
  c.parameters.push_back({"dz_mm", t3.z()});
  if (k != Kind::Translation) {
    c.parameters.push_back({"centre_x_mm", f.o.x()});
    c.parameters.push_back({"centre_y_mm", f.o.y()});
    c.parameters.push_back({"centre_z_mm", f.o.z()});
  }
  return c;
}

// One step of fitting on the exact curves: each touched point's nearest point on its section's
// design moved by the model as its new foot (mapped back to the design), with the design normal
// there. `rounds`: the sections with their touched points, in the order of p and m. Returns how
// far the feet moved (mm).
using Rounds = std::vector<std::pair<const design::Section*, const Eigen::Matrix3Xd*>>;
double refoot(Kind k, const Eigen::VectorXd& q, const Frame& f, const Rounds& rounds,
              std::vector<Eigen::Vector2d>& p, std::vector<Eigen::Vector2d>& m) {
  const Affine2 a = model(k, q);
  const Eigen::Matrix2d back = a.A.inverse();
  double shift = 0;
  std::size_t i = 0;
  for (const auto& [section, touched] : rounds) {
    const sim::Contour moved = curve_of(apply(*section, f, a));
    for (Eigen::Index j = 0; j < touched->cols(); ++j, ++i) {
      const auto nr = moved.nearest(touched->col(j));
      const Eigen::Vector2d foot = back * (f.to2(nr.point) - a.t);
      shift = std::max(shift, (foot - p[i]).norm());
      p[i] = foot;
      m[i] = (a.A.transpose() * Eigen::Vector2d(nr.normal.dot(f.e1), nr.normal.dot(f.e2)))
                 .normalized();
    }
  }
  return shift;
}

// One model of the menu fitted to the touch points. `closer` is set when it leaves every touch
// point within `accept` and none further than before; `corrected` receives the section with it
// applied when the fit did not diverge.
Correction fit_one(Kind k, const design::Section& section, const Touches& in, double accept,
                   bool& closer, design::Section* corrected, Eigen::VectorXd* left = nullptr) {
  const Frame& f = in.f;
  std::vector<Eigen::Vector2d> p = in.p0, m = in.m0;
  const std::vector<Eigen::Vector2d>& t = in.t;
  Eigen::VectorXd best;
  double best_cost = 1e300;
  for (int start = 0; start < (k == Kind::Directional ? 4 : 1); ++start) {
    Eigen::VectorXd q = Eigen::VectorXd::Zero(params(k));
    if (k == Kind::Directional) q[3] = start * M_PI / 4;
    q = gauss_newton(k, q, p, m, t);
    const double cost = residuals(k, q, p, m, t).squaredNorm();
    if (q.allFinite() && cost < best_cost) {
      best_cost = cost;
      best = q;
    }
  }
  if (best.size() == 0) best = Eigen::VectorXd::Constant(params(k), NAN);
  // A fit that ran away is reported as such, and its design data are never built (a scale of
  // 1e-3 or 1e3 would make a curve nothing can sample).
  auto runaway = [&](const Eigen::VectorXd& q) -> std::string {
    if (!q.allFinite()) return "the fit did not converge";
    const Affine2 a = model(k, q);
    const Eigen::JacobiSVD<Eigen::Matrix2d> svd(a.A, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const auto sv = svd.singularValues();
    if (!(sv.minCoeff() >= 0.5 && sv.maxCoeff() <= 2) || a.A.determinant() <= 0)
      return fmt::format("a scale of {:.4g} to {:.4g}: no fixture or size error is that large",
                         sv.minCoeff(), sv.maxCoeff());
    const Eigen::Matrix2d R = svd.matrixU() * svd.matrixV().transpose();
    // The turn as fitted, not only as the map shows it: a fit that wound round a circle's
    // centre (where no turn is seen) by -742° shows a map turned by -22°.
    double turn = std::abs(std::atan2(R(1, 0), R(0, 0))) * 180 / M_PI;
    if (k == Kind::Rotation || k == Kind::ScaleRotation)
      turn = std::max(turn, std::abs(q[k == Kind::Rotation ? 2 : 3]) * 180 / M_PI);
    if (turn > 45) return fmt::format("a turn of {:.4g}°: more than 45°", turn);
    double moved = 0;
    for (const auto& x : in.p0) moved = std::max(moved, (a.A * x + a.t - x).norm());
    if (moved > std::max(10.0, in.extent))
      return fmt::format(
          "design points moved by up to {:.4g} mm, more than the contour's "
          "{:.4g} mm size",
          moved, in.extent);
    return "";
  };
  std::string why = runaway(best);
  // Refine on the exact curve: take each touched point's nearest point on the corrected design
  // as its new foot (mapped back to the design), and fit again, until the feet settle.
  for (int it = 0; it < 8 && why.empty(); ++it) {
    const double shift = refoot(k, best, f, {{&section, &in.touched}}, p, m);
    best = gauss_newton(k, best, p, m, t);
    why = runaway(best);
    if (shift < 1e-7) break;
  }
  const Affine2 a = model(k, best);
  Eigen::VectorXd after = Eigen::VectorXd::Constant(in.touched.cols(), NAN);
  if (why.empty()) {
    design::Section cand = apply(section, f, a);
    after = distances(curve_of(cand), in.touched);
    if (corrected) *corrected = std::move(cand);
  }
  Correction c = describe(k, best, f);
  c.diverged = why;
  c.residual_before = in.before.cwiseAbs().maxCoeff();
  c.residual_after = why.empty() ? after.cwiseAbs().maxCoeff() : NAN;
  if (left) *left = after;
  closer = why.empty() && c.residual_after <= accept;
  for (Eigen::Index i = 0; closer && i < after.size(); ++i)
    closer = std::abs(after[i]) <= std::max(std::abs(in.before[i]), accept);
  return c;
}

// The normal distances' Jacobian of touch points at p (plane frame, mm) with design normals m, in
// a move (x, y) and the maps picked, each about the points' centroid: a turn, a uniform scale.
// Their columns are in mm per radian or unit, or (`in_mm`) in mm, times the points' rms distance
// from the centroid, comparable with the move's. Empty when there are fewer points than columns,
// or all at one place.
Eigen::MatrixXd jacobian(const std::vector<Eigen::Vector2d>& p,
                         const std::vector<Eigen::Vector2d>& m, bool turn, bool scale, bool in_mm) {
  const auto n = static_cast<Eigen::Index>(p.size());
  const int cols = 2 + turn + scale;
  if (n < cols) return {};
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  for (const auto& x : p) c += x / static_cast<double>(n);
  double size = 0;
  for (const auto& x : p) size += (x - c).squaredNorm() / static_cast<double>(n);
  size = std::sqrt(size);
  if (!(size > 0)) return {};
  const double unit = in_mm ? size : 1.0;
  Eigen::MatrixXd J(n, cols);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector2d v = p[static_cast<std::size_t>(i)] - c;
    const Eigen::Vector2d& u = m[static_cast<std::size_t>(i)];
    J(i, 0) = u.x();
    J(i, 1) = u.y();
    int k = 2;
    if (turn) J(i, k++) = (v.x() * u.y() - v.y() * u.x()) / unit;
    if (scale) J(i, k) = v.dot(u) / unit;
  }
  return J;
}

// Its singular values, largest first (columns in mm).
Eigen::VectorXd singular_values(const std::vector<Eigen::Vector2d>& p,
                                const std::vector<Eigen::Vector2d>& m, bool turn, bool scale) {
  const Eigen::MatrixXd J = jacobian(p, m, turn, scale, true);
  if (J.size() == 0) return {};
  return Eigen::JacobiSVD<Eigen::MatrixXd>(J).singularValues();
}

// How well they tell those apart: the smallest singular value over the largest; 0 when a
// combination is not seen at all.
double resolution(const std::vector<Eigen::Vector2d>& p, const std::vector<Eigen::Vector2d>& m,
                  bool turn, bool scale) {
  const Eigen::VectorXd sv = singular_values(p, m, turn, scale);
  return sv.size() && sv[0] > 0 ? sv[sv.size() - 1] / sv[0] : 0.0;
}

// What the prepared touch points tell of the part's move (fit_part_move). `chosen` and `left`:
// the menu's accepted correction and its residuals at the touch points, when it has one (a
// rotation is then the rigid fit, not fitted again).
PartMove part_move(const design::Section& section, const Touches& in, double accept,
                   const Correction* chosen, const Eigen::VectorXd* left_by_chosen) {
  PartMove out;
  out.resolution = resolution(in.p0, in.m0, false, true);
  out.turn_resolution = resolution(in.p0, in.m0, true, false);
  auto none = [&](const char* why) {
    out.rigid.type = name(Kind::Rotation);
    out.rigid.diverged = why;
    out.rigid.residual_before = in.before.size() ? in.before.cwiseAbs().maxCoeff() : NAN;
    out.rigid.residual_after = NAN;
    return out;
  };
  // Round a circle: nothing to fit a turn to.
  if (out.turn_resolution < 1e-6) return none("the touch points see no turn");
  const auto n = static_cast<Eigen::Index>(in.p0.size());
  if (n < params(Kind::Rotation) + 2) return none("too few touch points for a turn and a move");
  Eigen::VectorXd left;
  bool closer = false;
  if (chosen && left_by_chosen && chosen->accepted && chosen->type == name(Kind::Rotation)) {
    out.rigid = *chosen;
    left = *left_by_chosen;
    closer = true;
  } else {
    out.rigid = fit_one(Kind::Rotation, section, in, accept, closer, nullptr, &left);
  }
  out.rigid.accepted = closer;
  // The turn's standard uncertainty from the fit's scatter (each residual at least 0.1 µm, a
  // CMM's resolution, so that noise-free points do not make round-off a turn), linearised at the
  // feet: s² (JᵀJ)⁻¹ with J in the move (x, y) and the turn (mm per rad; the turn's variance is
  // the same about any centre).
  if (closer && left.allFinite()) {
    const Eigen::MatrixXd J = jacobian(in.p0, in.m0, true, false, false);
    const double s2 =
        std::max(left.squaredNorm() / static_cast<double>(n - 3), kResolution * kResolution);
    const Eigen::Matrix3d JtJ = J.transpose() * J;
    const Eigen::FullPivLU<Eigen::Matrix3d> lu(JtJ);
    if (lu.isInvertible()) out.turn_u = std::sqrt(s2 * lu.inverse()(2, 2)) * 180 / M_PI;
  }
  return out;
}

}  // namespace

std::vector<Correction> fit_corrections(const design::Section& section,
                                        const Eigen::Matrix3Xd& feet,
                                        const Eigen::Matrix3Xd& touched, double accept,
                                        design::Section* corrected, PartMove* move) {
  const Touches in = prepare(section, feet, touched);
  const double worst_before = in.before.cwiseAbs().maxCoeff();
  std::vector<Correction> out;
  if (worst_before <= accept) {
    // The touch points already agree with the design: the deviation that stopped the scan is
    // local, and no geometric correction of the whole section is indicated.
    Correction c;
    c.type = "none";
    c.residual_before = c.residual_after = worst_before;
    out.push_back(c);
    return out;
  }
  Eigen::VectorXd left;
  for (Kind k :
       {Kind::Translation, Kind::Rotation, Kind::Scale, Kind::ScaleRotation, Kind::Directional}) {
    if (static_cast<int>(in.p0.size()) < params(k) + 2) continue;  // keep some redundancy
    bool closer = false;
    design::Section cand;
    out.push_back(fit_one(k, section, in, accept, closer, &cand, &left));
    if (closer) {
      out.back().accepted = true;
      if (corrected) *corrected = std::move(cand);
      break;
    }
  }
  if (move && !out.empty() && out.back().accepted)
    *move = part_move(section, in, accept, &out.back(), &left);
  return out;
}

PartMove fit_part_move(const design::Section& section, const Eigen::Matrix3Xd& feet,
                       const Eigen::Matrix3Xd& touched, double accept) {
  return part_move(section, prepare(section, feet, touched), accept, nullptr, nullptr);
}

namespace detail {

sim::Contour contour_of(const design::Section& s, double spacing) {
  const auto smp = design::sample(s, spacing);
  return sim::Contour(smp.points, s.plane.normal.normalized(), s.closed,
                      s.material == design::Side::Left);
}

void move_section(design::Section& s, const Eigen::Affine3d& step) {
  Eigen::Matrix3Xd& pts = s.nurbs ? s.nurbs->control_points : s.polyline;
  for (Eigen::Index i = 0; i < pts.cols(); ++i) pts.col(i) = step * pts.col(i);
  s.solid_placement = step * s.solid_placement;
}

bool keeps_plane(const design::Section& s, const Eigen::Affine3d& t) {
  const Eigen::Vector3d n = s.plane.normal.normalized(), at = s.plane.origin;
  return (t.linear() * n - n).norm() < 1e-9 && std::abs((t * at - at).dot(n)) < 1e-9;
}

std::optional<std::vector<Correction>> part_move_of(
    const std::vector<Correction>& corrections,
    const std::vector<std::pair<std::size_t, PartMove>>& told, bool closed,
    const std::string& name) {
  std::vector<Correction> rigid;
  bool own = false;
  for (std::size_t i = 0; i < corrections.size(); ++i) {
    const Correction& c = corrections[i];
    if (!c.accepted) continue;
    Correction moved = c;
    if (c.found_on.empty()) {
      const auto t =
          std::find_if(told.begin(), told.end(), [&](const auto& x) { return x.first == i; });
      if (t == told.end()) return std::nullopt;
      const PartMove& pm = t->second;
      if (!closed && pm.resolution < kTellsPart) return std::nullopt;
      const auto turn = std::find_if(pm.rigid.parameters.begin(), pm.rigid.parameters.end(),
                                     [](const auto& q) { return q.first == "rotation_deg"; });
      if (pm.rigid.accepted && pm.turn_resolution >= kTellsPart &&
          turn != pm.rigid.parameters.end() && std::abs(turn->second) > 3 * pm.turn_u)
        moved = pm.rigid;
      moved.found_on = name;
      own = true;
    }
    const Eigen::Matrix3d R = moved.transform.linear();
    if ((R.transpose() * R - Eigen::Matrix3d::Identity()).norm() > 1e-9 || R.determinant() < 0)
      return std::nullopt;
    rigid.push_back(moved);
  }
  if (!own) return std::nullopt;
  return rigid;
}

std::optional<Correction> pooled_part_move(const std::vector<TouchRound>& rounds, double accept,
                                           const std::string& found_on) {
  if (rounds.empty()) return std::nullopt;
  const Eigen::Vector3d n = rounds.front().section.plane.normal.normalized();
  Eigen::Index count = 0;
  for (const auto& r : rounds) {
    if (r.section.space_curve() ||
        std::abs(r.section.plane.normal.normalized().dot(n)) < 1 - 1e-9 ||
        r.feet.cols() != r.touched.cols())
      return std::nullopt;
    count += r.feet.cols();
  }
  if (count < params(Kind::Rotation) + 2) return std::nullopt;  // as the menu: some redundancy
  // One frame for all: the plane's, centred on all the feet.
  Eigen::Matrix3Xd feet(3, count);
  Eigen::Index at = 0;
  for (const auto& r : rounds) {
    feet.middleCols(at, r.feet.cols()) = r.feet;
    at += r.feet.cols();
  }
  const Frame f = frame_of(rounds.front().section, feet);
  std::vector<Eigen::Vector2d> p, m, t;
  double before = 0;
  for (const auto& r : rounds) {
    const sim::Contour curve = curve_of(r.section);
    for (Eigen::Index j = 0; j < r.feet.cols(); ++j) {
      const auto nr = curve.nearest(r.feet.col(j));
      p.push_back(f.to2(nr.point));
      m.push_back(Eigen::Vector2d(nr.normal.dot(f.e1), nr.normal.dot(f.e2)).normalized());
      t.push_back(f.to2(r.touched.col(j)));
      before = std::max(before, std::abs(curve.nearest(r.touched.col(j)).distance));
    }
  }
  if (resolution(p, m, false, true) < kTellsPart) return std::nullopt;
  // A turn only where the touch points see one (round a circle they do not).
  const Kind k = resolution(p, m, true, false) >= kTellsPart ? Kind::Rotation : Kind::Translation;
  Eigen::VectorXd q = gauss_newton(k, Eigen::VectorXd::Zero(params(k)), p, m, t);
  // On the exact curves, as fit_one, until the feet settle.
  Rounds on;
  for (const auto& r : rounds) on.emplace_back(&r.section, &r.touched);
  for (int it = 0; it < 8 && q.allFinite(); ++it) {
    const double shift = refoot(k, q, f, on, p, m);
    q = gauss_newton(k, q, p, m, t);
    if (shift < 1e-7) break;
  }
  if (!q.allFinite()) return std::nullopt;
  const Affine2 a = model(k, q);
  // A fit that ran away (a turn beyond 45°, a move beyond 10 mm) tells nothing.
  if (k == Kind::Rotation && std::abs(q[2]) > M_PI / 4) return std::nullopt;
  if (a.t.norm() > 10) return std::nullopt;
  double after = 0;
  for (const auto& r : rounds)
    after = std::max(after,
                     distances(curve_of(apply(r.section, f, a)), r.touched).cwiseAbs().maxCoeff());
  if (!(after <= accept)) return std::nullopt;
  Correction c = describe(k, q, f);
  c.residual_before = before;
  c.residual_after = after;
  c.accepted = true;
  c.found_on = found_on;
  return c;
}

TouchPlaces touch_places(const design::Section& s, int k, double least, const Usable& usable) {
  TouchPlaces out;
  const double L = design::length(s);
  for (int i = 0; i < k; ++i)
    out.arcs.push_back(s.closed ? (i + 0.5) * L / k : (0.05 + 0.9 * i / std::max(1, k - 1)) * L);
  if (k < 4 || s.space_curve()) return out;
  const design::Samples smp = design::sample(s, 0.5);
  const Eigen::Index n = smp.points.cols();
  if (n < k) return out;
  const Frame f = frame_of(s, smp.points);
  auto nearest = [&](double arc) {
    Eigen::Index j = 0;
    (smp.arc.array() - arc).abs().minCoeff(&j);
    return j;
  };
  // The resolution, and what the exchange raises: the sum of log(σ² + ε) over the singular
  // values (a D-optimal design, regularised so that a place that sees a combination no other
  // does counts before the set sees them all: one touch on a short leg of a U does not yet tell
  // a move along the long wall from a scale, two do).
  auto score_of = [&](const std::vector<Eigen::Index>& at, double* res) {
    std::vector<Eigen::Vector2d> p, m;
    for (const Eigen::Index j : at) {
      p.push_back(f.to2(smp.points.col(j)));
      const Eigen::Vector3d nn = smp.normals.col(j);
      m.push_back(Eigen::Vector2d(nn.dot(f.e1), nn.dot(f.e2)).normalized());
    }
    const Eigen::VectorXd sv = singular_values(p, m, true, true);
    if (sv.size() == 0) return -std::numeric_limits<double>::infinity();
    if (res) *res = sv[0] > 0 ? sv[sv.size() - 1] / sv[0] : 0.0;
    const double eps = 1e-6 * static_cast<double>(at.size());
    return static_cast<double>((sv.array().square() + eps).log().sum());
  };
  // Whether the ball can get to a sample's touch start (asked once per sample).
  std::vector<signed char> ok(static_cast<std::size_t>(n), -1);
  auto usable_at = [&](Eigen::Index j) {
    if (!usable) return true;
    signed char& o = ok[static_cast<std::size_t>(j)];
    if (o < 0) o = usable(smp.points.col(j), smp.normals.col(j)) ? 1 : 0;
    return o == 1;
  };
  std::vector<Eigen::Index> chosen;
  auto apart = [&](Eigen::Index j, std::size_t skip) {
    for (std::size_t q = 0; q < chosen.size(); ++q) {
      if (q == skip) continue;
      double d = std::abs(smp.arc[j] - smp.arc[chosen[q]]);
      if (s.closed) d = std::min(d, L - d);
      if (d < 1) return false;
    }
    return true;
  };
  // Each even place the ball cannot get to is taken to the nearest sample it can (1 mm from the
  // others, and from an open stretch's ends), or left out when there is none.
  bool shifted = false;
  for (const double a : out.arcs) {
    const Eigen::Index j = nearest(a);
    if (usable_at(j)) {
      chosen.push_back(j);
      continue;
    }
    shifted = true;
    ++out.unreachable;
    for (Eigen::Index d = 1; d < n; ++d) {
      Eigen::Index found = -1;
      for (const Eigen::Index c : {j - d, j + d}) {
        const Eigen::Index w = s.closed ? ((c % n) + n) % n : c;
        if (w < 0 || w >= n || (!s.closed && (smp.arc[w] < 1 || smp.arc[w] > L - 1))) continue;
        if (usable_at(w) && apart(w, chosen.size())) {
          found = w;
          break;
        }
      }
      if (found >= 0) {
        chosen.push_back(found);
        break;
      }
    }
  }
  auto as_chosen = [&] {
    out.even = false;
    out.arcs.clear();
    for (const Eigen::Index j : chosen) out.arcs.push_back(smp.arc[j]);
    std::sort(out.arcs.begin(), out.arcs.end());
    return out;
  };
  double best = score_of(chosen, &out.resolution);
  out.even_resolution = out.resolution;
  if (out.resolution >= least) return shifted ? as_chosen() : out;
  const std::vector<Eigen::Index> first = chosen;
  // Candidates: every sample 1 mm clear of an open stretch's ends and off the corners (the
  // normal turns by less than 0.2 rad to the samples either side).
  std::vector<Eigen::Index> cand;
  for (Eigen::Index j = 0; j < n; ++j) {
    if (!s.closed && (smp.arc[j] < 1 || smp.arc[j] > L - 1)) continue;
    const Eigen::Index a = s.closed ? (j + n - 1) % n : std::max<Eigen::Index>(0, j - 1);
    const Eigen::Index b = s.closed ? (j + 1) % n : std::min(n - 1, j + 1);
    if (smp.normals.col(a).dot(smp.normals.col(j)) < std::cos(0.2) ||
        smp.normals.col(b).dot(smp.normals.col(j)) < std::cos(0.2))
      continue;
    cand.push_back(j);
  }
  // Exchange one place at a time for the candidate that raises the score most, until no
  // exchange does (Fedorov's exchange).
  for (int pass = 0; pass < 4; ++pass) {
    bool better = false;
    for (std::size_t i = 0; i < chosen.size(); ++i) {
      const Eigen::Index was = chosen[i];
      Eigen::Index keep = was;
      for (const Eigen::Index j : cand) {
        if (!apart(j, i) || !usable_at(j)) continue;
        chosen[i] = j;
        const double r = score_of(chosen, nullptr);
        if (r > best + 1e-9) {
          best = r;
          keep = j;
          better = true;
        }
      }
      chosen[i] = keep;
    }
    if (!better) break;
  }
  double res = 0;
  score_of(chosen, &res);
  if (res < least) {
    chosen = first;
    return shifted ? as_chosen() : out;
  }
  out.resolution = res;
  return as_chosen();
}

}  // namespace detail

std::string Correction::parameters_text() const {
  // Each parameter in words, to what touch points on a CMM resolve: translations to 1 µm,
  // rotations to 1e-4° (0.4"), scale to 1 ppm, directions to 1e-4 ("dy -1.100 mm", not
  // "dy_mm=-1.09999").
  std::string out;
  for (const auto& parameter : parameters) {
    const std::string& name = parameter.first;  // not a structured binding: the lambda uses it
    const double v = parameter.second;
    if (name.rfind("centre", 0) == 0) continue;
    const auto ends = [&name](const std::string& tail) {
      return name.size() > tail.size() &&
             name.compare(name.size() - tail.size(), tail.size(), tail) == 0;
    };
    std::string word = name;
    for (const std::string tail : {"_mm", "_deg"})
      if (ends(tail)) word = name.substr(0, name.size() - tail.size());
    for (char& c : word)
      if (c == '_') c = ' ';
    out += out.empty() ? "" : " ";
    if (ends("_mm"))
      out += fmt::format("{} {:.3f} mm", word, v);
    else if (ends("_deg"))
      out += fmt::format("{} {:.4f}°", word, v);
    else
      out += fmt::format("{} {:.{}f}", word, v, name == "scale" ? 6 : 4);
  }
  return out;
}

}  // namespace trueaxis::scan
