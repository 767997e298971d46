// The I++ DME server's scans: ScanOnLine, ScanOnCircle, ScanOnCurve and ScanUnknownHint, each
// with its arguments checked before anything moves.
#include <fmt/format.h>

#include "engine_state.hpp"

namespace trueaxis::ippdme::detail {

namespace {

// Where an unknown-contour scan's arguments stand, per form (argument count): its direction
// vectors, the points that must lie in the travel, the start and direction points, and the
// cylinder's point and axis (−1: none).
struct ScanLayout {
  std::vector<std::size_t> dirs, points;
  std::size_t start = 0, direction = 0;
  int cylinder = -1;
};
const ScanLayout* scan_layout(const std::string& name, std::size_t count) {
  static const std::map<std::pair<std::string, std::size_t>, ScanLayout> layouts = {
      {{"ScanInPlaneEndIsSphere", 17}, {{3, 14}, {0, 6, 10}, 0, 6}},
      {{"ScanInPlaneEndIsSphere", 21}, {{3, 6, 18}, {0, 9, 13}, 0, 9}},
      {{"ScanInPlaneEndIsPlane", 20}, {{3, 13, 17}, {0, 6}, 0, 6}},
      {{"ScanInPlaneEndIsPlane", 23}, {{3, 6, 16, 20}, {0, 9}, 0, 9}},
      {{"ScanInPlaneEndIsCyl", 21}, {{3, 13, 18}, {0, 6}, 0, 6}},
      {{"ScanInPlaneEndIsCyl", 24}, {{3, 6, 16, 21}, {0, 9}, 0, 9}},
      {{"ScanInCylEndIsSphere", 23}, {{3, 9, 20}, {6, 12, 16}, 6, 12, 0}},
      {{"ScanInCylEndIsSphere", 24}, {{3, 9, 21}, {6, 12, 16}, 6, 12, 0}},
      {{"ScanInCylEndIsPlane", 26}, {{3, 9, 19, 23}, {6, 12}, 6, 12, 0}},
  };
  const auto it = layouts.find({name, count});
  return it == layouts.end() ? nullptr : &it->second;
}

}  // namespace

void Executor::check_arguments() {
  const auto v = numbers(m_);
  auto zero = [&](std::size_t i) { return !(vec(v, i).norm() > 1e-12); };
  auto outside = [&](std::size_t i) { return !s_.cmm.within_travel(s_.to_machine(vec(v, i))); };
  if (name_ == "ScanOnLine") {
    if (zero(6)) throw Fail{1010};
    if (!((vec(v, 3) - vec(v, 0)).norm() > 0)) throw Fail{502};
    if (outside(0) || outside(3)) throw Fail{504};
    return;
  }
  if (name_ == "ScanOnCircle") {
    if (zero(6)) throw Fail{1010};
    const Eigen::Vector3d r = vec(v, 3) - vec(v, 0);
    if (!(r.norm() > 0)) throw Fail{502};
    if (std::abs(r.normalized().dot(vec(v, 6).normalized())) > 1e-3) throw Fail{502};
    if (outside(3)) throw Fail{504};
    return;
  }
  const ScanLayout* l = scan_layout(name_, v.size());
  if (!l) return;
  for (std::size_t d : l->dirs)
    if (zero(d)) throw Fail{1010};
  for (std::size_t p : l->points)
    if (outside(p)) throw Fail{504};
  const Eigen::Vector3d S = vec(v, l->start);
  if (!((vec(v, l->direction) - S).norm() > 0)) throw Fail{502};
  if (l->cylinder >= 0) {
    const auto c = static_cast<std::size_t>(l->cylinder);
    const Eigen::Vector3d a = vec(v, c + 3).normalized(), w = S - vec(v, c);
    if ((w - w.dot(a) * a).norm() < 1e-9) throw Fail{502};
  }
}

void Executor::density_cap(double step, double speed) {
  const double per_tick = speed * s_.cmm.options().servo.dt();
  if (step < per_tick)
    s_.error(c_.tag, 504,
             fmt::format("{}: a point every {:.4g} mm asked for, but at {:g} mm/s the probe moves "
                         "{:.4g} mm per servo tick: one point per tick is recorded",
                         name_, step, speed, per_tick));
}

void Executor::scan_on_line() {
  need_measuring();
  check_arguments();
  const auto v = numbers(m_);
  const Eigen::Vector3d S = s_.to_machine(vec(v, 0)), E = s_.to_machine(vec(v, 3));
  const Eigen::Vector3d n = unit(s_.dir_to_machine(vec(v, 6)));
  const double step = v.at(9), L = (E - S).norm();
  if (!(L > 0) || !(step > 0)) throw Fail{509};
  const Eigen::Vector3d along = (E - S) / L;
  // The surface normal must be square to the line: a normal along it describes no surface.
  if (std::abs(n.dot(along)) > 1e-3) throw Fail{509};
  const Eigen::Vector3d cn = unit(n.cross(along));
  const auto c = probe(S, n, 0.0);
  Surface surface = s_.world();
  if (!surface) surface = plane_surface(S, n);
  const double speed = s_.par("ScanPar", "Speed"), retract = s_.par("ScanPar", "Retract");
  density_cap(step, speed);
  SimulatedCmm::ScanEnd end;
  scan([&](const auto& emit) {
    Unlocked u(lk_);
    emit(SimulatedCmm::Point{c.centre, c.normal, 0});
    SimulatedCmm::Constraint plane{[&](const Eigen::Vector3d& p) {
      return std::pair<Eigen::Vector3d, double>(cn, (p - c.centre).dot(cn));
    }};
    end = s_.cmm.follow(
        surface, plane, along, speed, 0.2, step, 2 * L + 10,
        [&](const SimulatedCmm::Point& p, double) { return (p.centre - c.centre).norm() >= L; },
        emit);
    retract_from(n, retract);
  });
  ended(end);
}

void Executor::scan_on_circle() {
  need_measuring();
  check_arguments();
  const auto v = numbers(m_);
  const Eigen::Vector3d C = s_.to_machine(vec(v, 0)), S = s_.to_machine(vec(v, 3));
  const Eigen::Vector3d ax = unit(s_.dir_to_machine(vec(v, 6)));
  const double delta = v.at(9), sfa = v.at(10), stepw = v.at(11);
  Eigen::Vector3d radial = S - C;
  radial -= radial.dot(ax) * ax;
  const double R = radial.norm();
  if (!(R > 0) || !(stepw > 0) || delta == 0) throw Fail{509};
  radial /= R;
  const Eigen::Vector3d n0 = std::cos(sfa * kDeg) * radial + std::sin(sfa * kDeg) * ax;
  const auto c = probe(S, n0, 0.0);
  Surface surface = s_.world();
  if (!surface) surface = cone_surface(C, ax, R, sfa);
  const bool on_plane = std::abs(std::cos(sfa * kDeg)) < 0.5;
  Eigen::Vector3d rc = c.centre - C;
  const double hc = rc.dot(ax);
  rc -= hc * ax;
  const double rho = rc.norm();
  const Eigen::Vector3d u0 = rc / rho;
  const double speed = s_.par("ScanPar", "Speed"), retract = s_.par("ScanPar", "Retract");
  const Eigen::Vector3d hint = (delta > 0 ? 1.0 : -1.0) * ax.cross(u0);
  density_cap(rho * stepw * kDeg, speed);
  SimulatedCmm::ScanEnd end;
  scan([&](const auto& emit) {
    Unlocked u(lk_);
    emit(SimulatedCmm::Point{c.centre, c.normal, 0});
    SimulatedCmm::Constraint k{[&](const Eigen::Vector3d& p) {
      if (!on_plane) return std::pair<Eigen::Vector3d, double>(ax, (p - C).dot(ax) - hc);
      Eigen::Vector3d w = p - C;
      w -= w.dot(ax) * ax;
      const double r = w.norm();
      return std::pair<Eigen::Vector3d, double>(r > 0 ? Eigen::Vector3d(w / r) : u0, r - rho);
    }};
    double swept = 0;
    Eigen::Vector3d last = u0;
    end = s_.cmm.follow(
        surface, k, hint, speed, 0.2, std::max(1e-3, rho * stepw * kDeg),
        std::abs(delta) * kDeg * (rho + 1) * 2 + 10,
        [&](const SimulatedCmm::Point& p, double) {
          Eigen::Vector3d w = p.centre - C;
          w -= w.dot(ax) * ax;
          if (w.norm() == 0) return false;
          w.normalize();
          swept += std::atan2(last.cross(w).dot(ax), last.dot(w));
          last = w;
          return std::abs(swept) >= std::abs(delta) * kDeg;
        },
        emit);
    retract_from(c.normal, retract);
  });
  ended(end);
}

void Executor::scan_on_curve() {
  need_measuring();
  // Closed(c), Format(X(), Y(), Z(), IJK(), tag[, pi, pj, pk[, si, sj, sk]]), Data(...)
  bool closed = false;
  std::size_t width = 0;
  const Value* data = nullptr;
  for (const auto& a : m_.args) {
    if (a.is_call("Closed")) closed = !a.args.empty() && a.args[0].number() != 0;
    if (a.is_call("Format")) {
      for (const auto& f : a.args) width += f.is_call("IJK") ? 3 : 1;
    }
    if (a.is_call("Data")) data = &a;
  }
  if (!data || width < 7 || data->args.size() % width != 0) throw Fail{502};
  std::vector<Eigen::Vector3d> pts, nrm;
  const auto v = numbers(*data);
  for (std::size_t i = 0; i + width <= v.size(); i += width) {
    if (v[i + 6] < 0) continue;  // a point off the surface
    pts.push_back(s_.to_machine(vec(v, i)));
    nrm.push_back(unit(s_.dir_to_machine(vec(v, i + 3))));
  }
  if (pts.size() < 2) throw Fail{509};
  if (closed && (pts.front() - pts.back()).norm() > 1e-9) {
    pts.push_back(pts.front());
    nrm.push_back(nrm.front());
  }
  const double r = s_.cmm.tip_radius(), push = 0.2;
  std::vector<Eigen::Vector3d> path;
  for (std::size_t i = 0; i < pts.size(); ++i) path.push_back(pts[i] + (r - push) * nrm[i]);
  Surface surface = s_.world();
  if (!surface) {
    Eigen::Matrix3Xd P(3, pts.size()), N(3, pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) {
      P.col(i) = pts[i];
      N.col(i) = nrm[i];
    }
    auto curve = std::make_shared<sim::SpaceCurve>(P, N);
    surface = [curve](const Eigen::Vector3d& q) -> std::optional<Nearest> {
      return curve->nearest(q);
    };
  }
  const double speed = s_.par("ScanPar", "Speed"), retract = s_.par("ScanPar", "Retract");
  const double go_speed = s_.par("GoToPar", "Speed"), go_accel = s_.par("GoToPar", "Accel");
  density_cap(s_.curve_density, speed);
  SimulatedCmm::ScanEnd end;
  scan([&](const auto& emit) {
    Unlocked u(lk_);
    s_.go(path.front() + (s_.par("PtMeasPar", "Approach") + push) * nrm.front(), go_speed,
          go_accel);
    end = s_.cmm.along(path, nrm, surface, speed, push, s_.curve_deviation, s_.curve_density, emit);
    retract_from(nrm.back(), retract);
  });
  ended(end);
}

// ScanInPlaneEndIs{Sphere,Plane,Cyl} and ScanInCylEndIs{Sphere,Plane}.
void Executor::scan_unknown() {
  need_measuring();
  check_arguments();
  auto v = numbers(m_);
  const bool in_cyl = name_.rfind("ScanInCyl", 0) == 0;
  const bool ends_in_sphere = name_.find("EndIsSphere") != std::string::npos;
  // The forms before 1.4.3 (NIST's; their direction point follows the start direction, at
  // argument 6): an in-plane scan's plane is the one through the start point's surface direction
  // and the direction point, and a sphere end counts once. Brought to the 1.4.3 layout here.
  const ScanLayout* l = scan_layout(name_, v.size());
  if (!in_cyl && l && l->direction == 6) {
    const Eigen::Vector3d N = vec(v, 3).cross(vec(v, 6) - vec(v, 0));
    if (!(N.norm() > 1e-9)) throw Fail{502};
    const Eigen::Vector3d u = N.normalized();
    v.insert(v.begin() + 6, {u.x(), u.y(), u.z()});
    if (ends_in_sphere) v.insert(v.begin() + 17, 1.0);
  }
  if (in_cyl && ends_in_sphere && v.size() == 23) v.insert(v.begin() + 20, 1.0);
  const std::size_t o = in_cyl ? 6 : 0;  // the cylinder's axis comes first
  const Eigen::Vector3d S = s_.to_machine(vec(v, o)), Sn = unit(s_.dir_to_machine(vec(v, o + 3)));
  Eigen::Vector3d N = Eigen::Vector3d::Zero(), A0 = Eigen::Vector3d::Zero(), Ad = N;
  if (in_cyl) {
    A0 = s_.to_machine(vec(v, 0));
    Ad = unit(s_.dir_to_machine(vec(v, 3)));
  } else {
    N = unit(s_.dir_to_machine(vec(v, 6)));
  }
  const Eigen::Vector3d D = s_.to_machine(vec(v, 9 + (in_cyl ? 3 : 0)));
  const std::size_t k = in_cyl ? 15 : 12;  // StepW
  double step = v.at(k);
  if (step <= 0) step = s_.unknown_density;
  if (!((D - S).norm() > 0)) throw Fail{509};
  // The stop criterion.
  enum {
    Sphere,
    Plane,
    Cyl
  } kind = name_.find("Sphere") != std::string::npos       ? Sphere
           : name_.find("EndIsPlane") != std::string::npos ? Plane
                                                           : Cyl;
  Eigen::Vector3d E = s_.to_machine(vec(v, k + 1)), En = Eigen::Vector3d::UnitZ();
  double size = 0;
  int n = 1;
  if (kind == Sphere) {
    size = v.at(k + 4) / 2;
    if (v.size() > k + 5 + (in_cyl ? 3 : 0)) n = static_cast<int>(v.at(k + 5));
  } else {
    En = unit(s_.dir_to_machine(vec(v, k + 4)));
    if (kind == Cyl) {
      size = v.at(k + 7) / 2;
      n = static_cast<int>(v.at(k + 8));
    } else {
      n = static_cast<int>(v.at(k + 7));
    }
  }
  n = std::max(n, 1);
  const auto c = probe(S, Sn, 0.0);
  Surface surface = s_.world();
  if (!surface) surface = plane_surface(S, Sn);
  Eigen::Vector3d rc = c.centre - A0;
  rc -= rc.dot(Ad) * Ad;
  const double rho = rc.norm();
  if (in_cyl && !(rho > 0)) throw Fail{509};
  const double speed = s_.par("ScanPar", "Speed"), retract = s_.par("ScanPar", "Retract");
  density_cap(step, speed);
  const double start_gap = (D - S).norm();
  SimulatedCmm::ScanEnd end;
  scan([&](const auto& emit) {
    Unlocked u(lk_);
    emit(SimulatedCmm::Point{c.centre, c.normal, 0});
    SimulatedCmm::Constraint con{[&](const Eigen::Vector3d& p) {
      if (!in_cyl) return std::pair<Eigen::Vector3d, double>(N, (p - c.centre).dot(N));
      Eigen::Vector3d w = p - A0;
      w -= w.dot(Ad) * Ad;
      const double r = w.norm();
      return std::pair<Eigen::Vector3d, double>(r > 0 ? Eigen::Vector3d(w / r) : Ad, r - rho);
    }};
    auto measure = [&](const Eigen::Vector3d& p) {
      if (kind == Sphere) return (p - E).norm() - size;
      if (kind == Plane) return (p - E).dot(En);
      Eigen::Vector3d w = p - E;
      w -= w.dot(En) * En;
      return w.norm() - size;
    };
    // The stop criteria are judged on the scanned points (the surface points reported), as the
    // specification words them: the ball centre less the tip radius along the measured normal.
    const double tip = s_.cmm.tip_radius();
    auto scanned = [&](const Eigen::Vector3d& centre, const Eigen::Vector3d& normal) {
      return measure(centre - tip * normal);
    };
    double prev = scanned(c.centre, c.normal), prev_d = 1e300;
    bool armed = kind == Plane ? false : prev > 0;
    int count = 0;
    const Eigen::Vector3d diag = s_.cmm.travel_high() - s_.cmm.travel_low();
    end = s_.cmm.follow(
        surface, con, D - S, speed, 0.2, step, 4 * diag.norm(),
        [&](const SimulatedCmm::Point& p, double arc) {
          const double d = scanned(p.centre, p.normal);
          bool stop = false;
          if (kind == Plane) {
            armed = armed || arc > start_gap;
            if (armed && (d > 0) != (prev > 0) && ++count >= n) stop = true;
          } else if (kind == Sphere) {
            if (!armed && d > 0) armed = true;
            // Inside the sphere, the n-th local minimum of the distance from its centre.
            if (armed && d < 0 && d > prev_d && prev < 0 && ++count >= n) stop = true;
            prev_d = d;
          } else {
            if (!armed && d > 0) armed = true;
            if (armed && (d > 0) != (prev > 0) && ++count >= n) stop = true;
          }
          prev = d;
          return stop;
        },
        emit);
    retract_from(c.normal, retract);
  });
  ended(end);
}

}  // namespace trueaxis::ippdme::detail
