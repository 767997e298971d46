// The part's rigid move in three dimensions, from touch points against its solid, and a section's
// design data cut from the solid so moved. A part moved across a section's plane (a vertical
// plane, the part off on the table) changes that section's shape wherever its faces slope across
// the plane: no correction in the plane fits it, and each section paid its own touch round. The
// solid tells what the touch points cannot: where faces slope, a move across the plane moves
// them in it.
// The fit is point-to-surface registration (Y. Chen and G. Medioni, "Object modelling by
// registration of multiple range images", Image and Vision Computing 10(3), 1992: each point's
// distance along the surface normal), its Gauss–Newton steps solved by a truncated eigen-
// decomposition of the normal equations (P. C. Hansen, "The truncated SVD as a method for
// regularization", BIT 27, 1987), so that what the points do not resolve does not move.
#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "section.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/solid/mesh.hpp"

namespace trueaxis::scan::detail {
namespace {

// Nothing the fit asks of the solid lies farther than this from it (mm): a touch point is within
// the band the surface is searched in, a few mm.
constexpr double kLookout = 20;

// A move (mm) or turn (as the arc it moves the points at their spread) the touch points resolve
// changes their distances from the solid by this much per unit at least, in the root mean square.
// A part moved across a plane through a sphere's or cylinder's axis changes its section there in
// the second order only; with a contour that ends on a slope, 16 touch points on the
// DaimlerChrysler part at x = 0 resolve all six at 0.03 and 3 of 6 at 0.1, and 8 of them resolve a
// turn of 7° at 0.01 that fits them to 0.2 µm and is no move of the part.
constexpr double kSolidTells = 0.03;

// The solid's signed distance (mm): negative inside the material.
double signed_distance(const solid::Mesh& mesh, const Eigen::Vector3d& p) {
  const double d = mesh.distance(p, kLookout);
  return mesh.inside(p) ? -d : d;
}

// Its gradient, the unit normal out of the material at the nearest surface point (central
// differences 0.1 µm apart; the distance is 1-Lipschitz, so the step cannot mislead it).
Eigen::Vector3d outward(const solid::Mesh& mesh, const Eigen::Vector3d& p) {
  constexpr double h = 1e-4;
  Eigen::Vector3d g;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d e = h * Eigen::Vector3d::Unit(k);
    g[k] = (signed_distance(mesh, p + e) - signed_distance(mesh, p - e)) / (2 * h);
  }
  return g.norm() > 0.5 ? Eigen::Vector3d(g.normalized()) : Eigen::Vector3d::Zero();
}

double worst(const solid::Mesh& mesh, const Eigen::Matrix3Xd& pts, const Eigen::Affine3d& move) {
  const Eigen::Affine3d back = move.inverse();
  double w = 0;
  for (Eigen::Index i = 0; i < pts.cols(); ++i)
    w = std::max(w, std::abs(signed_distance(mesh, back * pts.col(i))));
  return w;
}

}  // namespace

std::optional<Correction> fit_solid_move(const solid::Mesh& mesh, const Eigen::Matrix3Xd& points,
                                         double accept, const std::string& found_on) {
  const Eigen::Index n = points.cols();
  if (n < kFewestTouches + 2) return std::nullopt;
  const Eigen::Vector3d c = points.rowwise().mean();
  // Turns are solved for as the arc they move points at the touch points' spread (mm), so that
  // their columns weigh as the moves' do.
  const double spread = std::max(1.0, std::sqrt((points.colwise() - c).squaredNorm() / n));
  const double before = worst(mesh, points, Eigen::Affine3d::Identity());
  Eigen::Affine3d move = Eigen::Affine3d::Identity();
  int resolved = 0;
  for (int it = 0; it < 30; ++it) {
    // x_part = move · x_solid. A step Δ about c, x -> x + δt + δω × (x − c), applied after the
    // move changes a touch point's signed distance by −G·δt − ((p − c) × G)·δω, G the outward
    // normal in the part's frame at the point's place on the solid.
    const Eigen::Affine3d back = move.inverse();
    Eigen::MatrixXd J(n, 6);
    Eigen::VectorXd r(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      const Eigen::Vector3d q = back * points.col(i);
      r[i] = signed_distance(mesh, q);
      const Eigen::Vector3d G = move.linear() * outward(mesh, q);
      J.row(i).head<3>() = -G.transpose();
      J.row(i).tail<3>() = -(points.col(i) - c).cross(G).transpose() / spread;
    }
    // Only what the points resolve moves: the normal equations' eigenvectors whose eigenvalue
    // per point reaches kSolidTells²; the others (a move along a wall, a turn the points do not
    // see) stay where they are.
    const Eigen::Matrix<double, 6, 6> A = J.transpose() * J;
    const Eigen::Matrix<double, 6, 1> b = -J.transpose() * r;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> es(A);
    Eigen::Matrix<double, 6, 1> step = Eigen::Matrix<double, 6, 1>::Zero();
    resolved = 0;
    for (int k = 0; k < 6; ++k) {
      const double lambda = es.eigenvalues()[k];
      if (lambda < kSolidTells * kSolidTells * static_cast<double>(n)) continue;
      ++resolved;
      step += es.eigenvectors().col(k) * (es.eigenvectors().col(k).dot(b) / lambda);
    }
    const Eigen::Vector3d dt = step.head<3>(), dw = step.tail<3>() / spread;
    Eigen::Affine3d delta = Eigen::Affine3d::Identity();
    if (dw.norm() > 0) delta.linear() = Eigen::AngleAxisd(dw.norm(), dw.normalized()).matrix();
    delta.translation() = c + dt - delta.linear() * c;
    move = delta * move;
    if (dt.norm() < 1e-7 && dw.norm() * spread < 1e-7) break;
  }
  // Some redundancy over what was resolved, as the menu asks of a correction in the plane.
  if (resolved == 0 || n < resolved + 3) return std::nullopt;
  const double after = worst(mesh, points, move);
  const Eigen::AngleAxisd turn(move.linear());
  const Eigen::Vector3d w = turn.angle() * turn.axis() * 180 / M_PI;
  // A fixture error is a few millimetres and a fraction of a degree: anything larger is not a
  // move of this part but a fit gone astray.
  if (!(after <= accept) || !(before > accept) || move.translation().norm() > 20 || w.norm() > 5)
    return std::nullopt;
  Correction out;
  out.type = "solid-move";
  out.transform = move;
  out.parameters = {{"dx_mm", move.translation().x()},
                    {"dy_mm", move.translation().y()},
                    {"dz_mm", move.translation().z()},
                    {"turn_x_deg", w.x()},
                    {"turn_y_deg", w.y()},
                    {"turn_z_deg", w.z()}};
  out.residual_before = before;
  out.residual_after = after;
  out.accepted = true;
  out.found_on = found_on;
  return out;
}

Eigen::Affine3d in_plane_part(const Eigen::Affine3d& move, const design::Plane& plane) {
  const Eigen::Vector3d n = plane.normal.normalized(), o = plane.origin;
  auto project = [&](const Eigen::Vector3d& x) { return Eigen::Vector3d(x - (x - o).dot(n) * n); };
  // The turn about the plane's normal: the angle the move turns an in-plane direction by, seen
  // in the plane; the move: where the plane's origin goes, in the plane.
  const Eigen::Vector3d e1 = n.unitOrthogonal(), e2 = n.cross(e1);
  const Eigen::Vector3d d = move.linear() * e1;
  const double angle = std::atan2(d.dot(e2), d.dot(e1));
  Eigen::Affine3d out = Eigen::Affine3d::Identity();
  out.linear() = Eigen::AngleAxisd(angle, n).matrix();
  out.translation() = project(move * o) - out.linear() * o;
  return out;
}

std::optional<design::Section> on_moved_solid(const design::Section& s, const std::string& step,
                                              const Eigen::Affine3d& move) {
  if (s.space_curve() || step.empty()) return std::nullopt;
  design::Plane plane = s.plane;
  plane.normal.normalize();
  const Eigen::Affine3d placement = move * s.solid_placement;
  const design::Design cut = design::moved_sections(step, placement, plane);
  // The design's own samples, moved: the contour of the moved solid nearest them stands for the
  // section (as the simulated part picks its own).
  const auto smp = design::sample(s, 1.0);
  const Eigen::Index m = smp.points.cols();
  if (m < 2) return std::nullopt;
  auto in_plane = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector3d x = move * p;
    return Eigen::Vector3d(x - (x - plane.origin).dot(plane.normal) * plane.normal);
  };
  double best = INFINITY;
  const design::Section* chosen = nullptr;
  for (const auto& c : cut.sections) {
    if (c.material != s.material) continue;
    const sim::Contour cc = contour_of(c);
    double sum = 0;
    for (Eigen::Index i = 0; i < m; ++i)
      sum += std::abs(cc.nearest(in_plane(smp.points.col(i))).distance);
    if (sum < best) {
      best = sum;
      chosen = &c;
    }
  }
  if (!chosen) return std::nullopt;
  design::Section out;
  if (s.closed) {
    if (!chosen->closed) return std::nullopt;
    const double a = contour_of(*chosen).nearest(in_plane(smp.points.col(0))).arc;
    out = started_at(*chosen, a);
  } else {
    // The stretch between where its ends moved to, in the contour's own direction (the cut
    // orders every contour by its material side, as it did the design's).
    const sim::Contour cc = contour_of(*chosen);
    const double L = design::length(*chosen);
    const double a = cc.nearest(in_plane(smp.points.col(0))).arc;
    const double mid = cc.nearest(in_plane(smp.points.col(m / 2))).arc;
    double b = cc.nearest(in_plane(smp.points.col(m - 1))).arc;
    auto ahead = [&](double from, double to) {
      return chosen->closed ? std::fmod(to - from + 2 * L, L) : to - from;
    };
    if (!(ahead(a, mid) > 0 && ahead(a, mid) < ahead(a, b))) return std::nullopt;
    b = a + ahead(a, b);
    if (b - a < kShortest) return std::nullopt;
    out = design::piece(*chosen, a, b, s.name);
  }
  out.name = s.name;
  out.probe = s.probe;
  // The solid stands where the move's unambiguous part puts it (touch points in the plane tell
  // the move across it and the tilts only up to a mirror image).
  out.solid_placement = in_plane_part(move, plane) * s.solid_placement;
  return out;
}

}  // namespace trueaxis::scan::detail
