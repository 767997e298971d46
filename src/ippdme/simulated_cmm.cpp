// The virtual CMM behind `trueaxis serve`: moves, touches and scans in machine time.
#include "trueaxis/ippdme/simulated_cmm.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace trueaxis::ippdme {
namespace {

constexpr long kMaxTicks = 50'000'000;  // 14 hours of machine time at 1 kHz: a runaway guard
constexpr double kRadPerDeg = M_PI / 180;

}  // namespace

void SimulatedCmmOptions::validate() const {
  servo.validate();
  probe.validate();
  if (geometry) geometry->validate();
  for (int k = 0; k < 3; ++k)
    if (!(travel[k][0] < travel[k][1]))
      throw Error(fmt::format("virtual CMM: the {} travel is empty", "XYZ"[k]));
  if (!(trigger > 0 && trigger < probe.range))
    throw Error(fmt::format("virtual CMM: trigger deflection {:g} mm must be in (0, {:g})", trigger,
                            probe.range));
  if (!(overtravel > 0 && overtravel <= 20))
    throw Error(fmt::format("virtual CMM: overtravel {:g} mm must be in (0, 20]", overtravel));
  if (!(point_deflection >= trigger && point_deflection < max_deflection))
    throw Error(fmt::format(
        "virtual CMM: the point deflection {:g} mm must lie between trigger and over-push",
        point_deflection));
  if (!(min_scan_deflection >= trigger && min_scan_deflection < max_deflection))
    throw Error(fmt::format(
        "virtual CMM: the least scan deflection {:g} mm must lie between trigger and over-push",
        min_scan_deflection));
  if (!(max_deflection > trigger && max_deflection <= probe.range))
    throw Error("virtual CMM: the over-push deflection must lie between trigger and range");
  if (!(correction_gain > 0 && correction_gain < 0.5 * servo.rate_hz))
    throw Error("virtual CMM: the scanning correction gain must be in (0, rate/2)");
}

SimulatedCmm::SimulatedCmm(const SimulatedCmmOptions& options)
    : o_(options), servo_(options.servo, options.home), probe_(options.probe) {
  o_.validate();
  if (!within_travel(o_.home))
    throw Error(fmt::format("virtual CMM: home ({:g}, {:g}, {:g}) is outside the travel",
                            o_.home.x(), o_.home.y(), o_.home.z()));
}

Eigen::Vector3d SimulatedCmm::travel_low() const {
  if (o_.geometry) {
    const auto& g = *o_.geometry;
    return Eigen::Vector3d(g.range[0][0], g.range[1][0], g.range[2][0]) + g.offset;
  }
  return {o_.travel[0][0], o_.travel[1][0], o_.travel[2][0]};
}

Eigen::Vector3d SimulatedCmm::travel_high() const {
  if (o_.geometry) {
    const auto& g = *o_.geometry;
    return Eigen::Vector3d(g.range[0][1], g.range[1][1], g.range[2][1]) + g.offset;
  }
  return {o_.travel[0][1], o_.travel[1][1], o_.travel[2][1]};
}

bool SimulatedCmm::within_travel(const Eigen::Vector3d& x, double tolerance) const {
  const Eigen::Vector3d lo = travel_low(), hi = travel_high();
  for (int k = 0; k < 3; ++k)
    if (!(x[k] >= lo[k] - tolerance && x[k] <= hi[k] + tolerance)) return false;
  return true;
}

Eigen::Vector3d SimulatedCmm::real_centre() const {
  const Eigen::Vector3d& x = servo_.position();
  if (!o_.geometry) return x;
  return x + o_.geometry->error(x - o_.geometry->offset);
}

sim::ProbeReading SimulatedCmm::read(const Surface& surface) {
  const Eigen::Vector3d c = real_centre();
  if (const auto n = surface ? surface(c) : std::nullopt) return probe_.read(*n);
  sim::ProbeReading free;
  free.surface.point = c;
  free.surface.normal = Eigen::Vector3d::UnitZ();
  free.surface.distance = 1e300;
  return free;
}

void SimulatedCmm::tick(const Eigen::Vector3d& target, const Eigen::Vector3d& feed) {
  servo_.step(target, feed);
  if (hook_ && !hook_()) {
    settle();
    throw Stopped();
  }
}

void SimulatedCmm::settle() {
  const Eigen::Vector3d hold = servo_.position();
  for (long k = 0; k < kMaxTicks && servo_.velocity().norm() > 1e-3; ++k)
    servo_.step(hold, Eigen::Vector3d::Zero());
}

bool SimulatedCmm::move(const Eigen::Vector3d& to, double speed, double accel,
                        const Surface& surface) {
  if (!(speed > 0) || !(accel > 0) || !to.allFinite()) throw Error("move: bad target or speed");
  const Eigen::Vector3d from = servo_.position();
  const double L = (to - from).norm();
  const Eigen::Vector3d dir = L > 0 ? Eigen::Vector3d((to - from) / L) : Eigen::Vector3d::Zero();
  const double a = std::min(accel, o_.servo.max_acceleration), dt = o_.servo.dt();
  speed = std::min(speed, o_.servo.max_velocity);
  // A move that starts in contact (a retract) may keep its deflection; more is a collision.
  const double start = surface ? read(surface).true_deflection.norm() : 0;
  double s = 0, v = 0;
  for (long k = 0; k < kMaxTicks; ++k) {
    const bool at_end = s >= L;
    if (at_end && (servo_.position() - to).norm() < 1e-4 && servo_.velocity().norm() < 1e-3)
      return true;
    v = at_end ? 0 : std::min({speed, v + a * dt, std::sqrt(2 * a * std::max(0.0, L - s))});
    // Below one tick's worth of acceleration from the end, finish at a crawl.
    if (!at_end && v < a * dt) v = std::min(a * dt, L - s > 0 ? (L - s) / dt : 0.0);
    tick(from + dir * std::min(s, L), dir * v);
    s = std::min(L, s + v * dt);
    if (surface && read(surface).true_deflection.norm() > start + o_.trigger) {
      // The probe triggers: the machine brakes at the move's acceleration, the stylus giving
      // way by as far as the carriage runs on.
      const Eigen::Vector3d at = servo_.position();
      double b = s;
      while (v > 0) {
        v = std::max(0.0, v - a * dt);
        b += v * dt;
        tick(from + dir * b, dir * v);
      }
      settle();
      pushed_ = std::max(read(surface).true_deflection.norm() - start,
                         (servo_.position() - at).norm() + o_.trigger);
      return false;
    }
  }
  throw Error("move: the carriage did not settle");
}

std::optional<SimulatedCmm::Contact> SimulatedCmm::touch(const Eigen::Vector3d& direction,
                                                         double distance, double speed,
                                                         const Surface& surface) {
  const Eigen::Vector3d d = direction.normalized(), start = servo_.position();
  const double dt = o_.servo.dt();
  double s = 0;
  std::optional<Contact> out;
  while (s <= distance) {
    tick(start + d * s, d * speed);
    s += speed * dt;
    const auto r = read(surface);
    if (r.contact && (r.overtravel || r.deflection.norm() >= o_.point_deflection)) {
      const double m = r.deflection.norm();
      const Eigen::Vector3d n = m > 0 ? Eigen::Vector3d(r.deflection / m) : Eigen::Vector3d(-d);
      // A touch-trigger probe latches after its pre-travel, which varies with the direction.
      out = Contact{
          servo_.position() + r.deflection + sim::pretravel_lobing(o_.probe.lobing, d) * d, n};
      break;
    }
  }
  settle();
  return out;
}

SimulatedCmm::ScanEnd SimulatedCmm::follow(const Surface& surface, const Constraint& constraint,
                                           const Eigen::Vector3d& hint, double speed,
                                           double pushing, double step, double max_length,
                                           const std::function<bool(const Point&, double)>& stop,
                                           const std::function<void(const Point&)>& emit) {
  const double dt = o_.servo.dt(), gain = o_.correction_gain;
  const double accel = std::min(2000.0, o_.servo.max_acceleration);
  auto r = read(surface);
  Eigen::Vector3d nhat = r.contact && r.deflection.norm() > 0
                             ? Eigen::Vector3d(r.deflection.normalized())
                             : Eigen::Vector3d(0, 0, 1);
  Eigen::Vector3d last = servo_.position() + r.deflection;
  // The contact the scan starts from is the caller's first point: the next is `step` on.
  double arc = 0, next = step, lost = 0, v = 0;
  Eigen::Vector3d prev = hint;
  ScanEnd end = ScanEnd::TooLong;
  for (long k = 0; k < kMaxTicks; ++k) {
    if (r.contact && r.deflection.norm() > 0) nhat = r.deflection.normalized();
    const Eigen::Vector3d p = servo_.position();
    const auto [cn, cd] = constraint.at(p);
    Eigen::Vector3d t = cn.cross(nhat);
    if (t.norm() < 1e-6) {
      // The surface is tangent to the constraint: go the hinted way within the surface.
      t = (k == 0 ? hint : prev);
      t -= t.dot(nhat) * nhat;
      if (t.norm() < 1e-9) {
        end = ScanEnd::Lost;
        break;
      }
    }
    t.normalize();
    if (t.dot(k == 0 ? hint : prev) < 0) t = -t;
    prev = t;
    const double e = r.contact ? r.deflection.norm() - pushing : -pushing;
    v = std::min(speed, v + accel * dt);
    const Eigen::Vector3d vel = v * t + gain * e * nhat - gain * cd * cn;
    tick(p, vel);
    r = read(surface);
    if (!within_travel(servo_.position())) {
      end = ScanEnd::Travel;
      break;
    }
    if (r.overtravel || r.deflection.norm() > o_.max_deflection) {
      end = ScanEnd::OverPushed;
      break;
    }
    if (!r.contact) {
      lost += v * dt;
      if (lost > 5) {
        end = ScanEnd::Lost;
        break;
      }
      continue;
    }
    lost = 0;
    const Point pt{servo_.position() + r.deflection, r.deflection.normalized(), 0};
    arc += (pt.centre - last).norm();
    last = pt.centre;
    if (arc >= next && r.deflection.norm() >= o_.min_scan_deflection) {
      emit(pt);
      next += step;
    }
    if (stop(pt, arc)) {
      end = ScanEnd::Done;
      break;
    }
    if (arc > max_length) break;
  }
  settle();
  return end;
}

SimulatedCmm::ScanEnd SimulatedCmm::along(const std::vector<Eigen::Vector3d>& path,
                                          const std::vector<Eigen::Vector3d>& normals,
                                          const Surface& surface, double speed, double pushing,
                                          double deviation, double step,
                                          const std::function<void(const Point&)>& emit) {
  const double dt = o_.servo.dt(), a = std::min(2000.0, o_.servo.max_acceleration);
  std::vector<double> begin(path.size(), 0.0);
  for (std::size_t i = 1; i < path.size(); ++i)
    begin[i] = begin[i - 1] + (path[i] - path[i - 1]).norm();
  const double L = begin.back();
  // The path point at arc s, its tangent and the nominal normal there.
  auto at = [&](double s, Eigen::Vector3d* tangent, Eigen::Vector3d* normal) {
    const auto it = std::upper_bound(begin.begin(), begin.end(), s);
    std::size_t i =
        std::min<std::size_t>(std::max<std::ptrdiff_t>(it - begin.begin(), 1), path.size() - 1);
    const double len = begin[i] - begin[i - 1];
    const double u = len > 0 ? std::clamp((s - begin[i - 1]) / len, 0.0, 1.0) : 0.0;
    *tangent = len > 0 ? Eigen::Vector3d((path[i] - path[i - 1]) / len) : Eigen::Vector3d::Zero();
    const Eigen::Vector3d n = (1 - u) * normals[i - 1] + u * normals[i];
    *normal = n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : normals[i];
    return Eigen::Vector3d(path[i - 1] + u * (path[i] - path[i - 1]));
  };
  // The speed allowed at each vertex: v²/R within kNormalAcceleration on the polyline's turns
  // (R from the turning angle over the adjacent segments), then lowered so that the carriage
  // can brake in time for the slower vertices ahead and stop at the end.
  constexpr double kNormalAcceleration = 2000, kMinSpeed = 1;  // mm/s², mm/s
  std::vector<double> limit(path.size(), speed);
  limit.back() = 0;
  for (std::size_t i = 1; i + 1 < path.size(); ++i) {
    const Eigen::Vector3d u = path[i] - path[i - 1], w = path[i + 1] - path[i];
    const double lu = u.norm(), lw = w.norm();
    if (!(lu > 0 && lw > 0)) continue;
    const double turn = std::acos(std::clamp(u.dot(w) / (lu * lw), -1.0, 1.0));
    if (turn > 1e-9)
      limit[i] =
          std::clamp(std::sqrt(kNormalAcceleration * 0.5 * (lu + lw) / turn), kMinSpeed, speed);
  }
  for (std::size_t i = path.size() - 1; i-- > 0;)
    limit[i] = std::min(limit[i],
                        std::sqrt(limit[i + 1] * limit[i + 1] + 2 * a * (begin[i + 1] - begin[i])));
  auto allowed = [&](double s) {
    const auto it = std::upper_bound(begin.begin(), begin.end(), s);
    const std::size_t j = std::min<std::size_t>(it - begin.begin(), path.size() - 1);
    return std::sqrt(limit[j] * limit[j] + 2 * a * std::max(0.0, begin[j] - s));
  };
  double s = 0, v = 0, next = 0;
  Eigen::Vector3d t, n;
  // The approach: from where the tip is, along the first normal until pushed by `pushing`.
  const Eigen::Vector3d p0 = at(0, &t, &n);
  double c = (servo_.position() - p0).dot(n);  // the normal correction (mm)
  const double approach_speed = std::min(speed, 10.0);
  for (long k = 0;; ++k) {
    c -= approach_speed * dt;
    tick(p0 + c * n, -approach_speed * n);
    const auto r = read(surface);
    if (r.overtravel || r.deflection.norm() > o_.max_deflection) {
      settle();
      return ScanEnd::OverPushed;
    }
    if (r.contact && r.deflection.dot(n) >= pushing) break;
    if (c < -deviation || k >= kMaxTicks) {
      settle();
      return ScanEnd::Lost;
    }
  }
  for (long k = 0; k < kMaxTicks; ++k) {
    v = std::min({speed, v + a * dt, allowed(s)});
    const Eigen::Vector3d target = at(s, &t, &n) + c * n;
    tick(target, t * v);
    s = std::min(L, s + v * dt);
    const auto r = read(surface);
    if (r.overtravel || r.deflection.norm() > o_.max_deflection) {
      settle();
      return ScanEnd::OverPushed;
    }
    // Hold the deflection at `pushing` along the nominal normal (none: move in to find it).
    c += o_.correction_gain * (r.contact ? r.deflection.dot(n) - pushing : -pushing) * dt;
    if (std::abs(c) > deviation) {
      settle();
      return ScanEnd::Lost;
    }
    if (r.contact && s >= next && r.deflection.norm() >= o_.min_scan_deflection) {
      emit(Point{servo_.position() + r.deflection, r.deflection.normalized(), 0});
      next += step;
    }
    if (s >= L && (v < 1e-9 || L == 0)) break;
  }
  settle();
  return ScanEnd::Done;
}

Surface plane_surface(const Eigen::Vector3d& point, const Eigen::Vector3d& normal) {
  const Eigen::Vector3d n = normal.normalized();
  return [point, n](const Eigen::Vector3d& q) -> std::optional<Nearest> {
    Nearest out;
    out.distance = (q - point).dot(n);
    out.point = q - out.distance * n;
    out.normal = n;
    return out;
  };
}

Surface cone_surface(const Eigen::Vector3d& axis_point, const Eigen::Vector3d& axis, double radius,
                     double surface_angle) {
  const Eigen::Vector3d ax = axis.normalized();
  const double c = std::cos(surface_angle * kRadPerDeg), s = std::sin(surface_angle * kRadPerDeg);
  return [=](const Eigen::Vector3d& q) -> std::optional<Nearest> {
    const Eigen::Vector3d v = q - axis_point;
    const double h = v.dot(ax);
    const Eigen::Vector3d w = v - h * ax;
    const double rho = w.norm();
    if (rho < 1e-9) return std::nullopt;  // on the axis: no direction to the surface
    const Eigen::Vector3d u = w / rho;
    Nearest out;
    out.normal = c * u + s * ax;
    out.distance = (rho - radius) * c + h * s;
    out.point = q - out.distance * out.normal;
    return out;
  };
}

}  // namespace trueaxis::ippdme
