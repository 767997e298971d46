// The virtual CMM's free moves: through waypoints, a speed per leg, turning without a stop
// where the corner allows, and stopped by the probe where the stylus meets the part.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "trueaxis/error.hpp"
#include "trueaxis/scan/machine.hpp"
#include "virtual_cmm_detail.hpp"

namespace trueaxis::scan {
using namespace vcmm;

void Machine::move_legs(const std::vector<Eigen::Vector3d>& way,
                        const std::vector<double>& speeds) {
  if (speeds.size() != way.size()) throw Error("move: one speed per waypoint");
  for (std::size_t i = 0; i < way.size(); ++i) {
    try {
      move(way[i], speeds[i]);
    } catch (const UnexpectedTouch& e) {
      throw UnexpectedTouch(e.what(), e.at, i);
    }
  }
}

std::optional<double> VirtualCmm::guarded_speed() const {
  // Braking from v at the path's acceleration a after the servo's lag τ takes v·τ + v²/(2a):
  // half the overtravel.
  const double a = o_.path_acceleration,
               tau = servo_.options().lag + 1 / servo_.options().position_gain,
               room = 0.5 * o_.overtravel;
  return a * (-tau + std::sqrt(tau * tau + 2 * room / a));
}

void VirtualCmm::move(const Eigen::Vector3d& to, double speed) {
  move_through({to}, speed);
}

void VirtualCmm::move_through(const std::vector<Eigen::Vector3d>& way, double speed) {
  move_legs(way, std::vector<double>(way.size(), speed));
}

double VirtualCmm::pushed_in() const {
  double deepest = penetration();
  if (!solid_) return deepest;
  const Eigen::Vector3d c = free_ball_centre(), ball = c + deflection_ + corner_;
  const double r = probe_.options().tip_radius, rs = o_.stylus.shaft(r);
  const Eigen::Vector3d& u = axis_;
  deepest = std::max(deepest, r - solid_->distance(ball, r + 1, touchable_));
  deepest = std::max(
      deepest, rs - dent_ -
                   solid_->distance(ball + r * u,
                                    ball + (o_.stylus.length + o_.stylus.body_radius) * u, rs + 1));
  return deepest;
}

std::string VirtualCmm::brake(const Eigen::Vector3d& hit, const Eigen::Vector3d& target,
                              const Eigen::Vector3d& dir, double speed, double start,
                              const char* doing) {
  // The probe triggered: the machine brakes along its way at the path's acceleration, the
  // stylus giving way against the part, and comes to rest.
  const double a = o_.path_acceleration, dt = servo_.options().dt();
  const int what = triggered_;
  double v = speed, s = 0;
  // The stylus gives way by as far as the carriage runs on after the trigger, at least.
  const Eigen::Vector3d at = servo_.position();
  const double first = std::max(0.0, pushed_in() - start);
  double deepest = first;
  auto push = [&] {
    deepest = std::max({deepest, pushed_in() - start, first + (servo_.position() - at).norm()});
  };
  while (v > 0) {
    v = std::max(0.0, v - a * dt);
    s += v * dt;
    servo_.step(target + s * dir, v * dir);
    penetration(&deflection_);
    check_solid();  // the probe's body still collides
    push();
  }
  settle();
  triggered_ = -1;
  push();
  const char* element = what == 1 ? "stylus" : "ball";
  const char* met = on_table_ ? "the table" : "the part";
  if (deepest > o_.overtravel)
    throw Error(fmt::format(
        "collision: the {} met {} at ({:.2f}, {:.2f}, {:.2f}) mm {} at {:.0f} mm/s, too fast "
        "to stop within the probe's {:g} mm overtravel (pushed in {:.2f} mm)",
        element, met, hit.x(), hit.y(), hit.z(), doing, speed, o_.overtravel, deepest));
  return fmt::format(
      "the probe triggered {}: the {} met {} with the ball centre at ({:.2f}, {:.2f}, {:.2f}) "
      "mm, and the machine stopped",
      doing, element, met, hit.x(), hit.y(), hit.z());
}

void VirtualCmm::stop_on_contact(const Eigen::Vector3d& hit, const Eigen::Vector3d& target,
                                 const Eigen::Vector3d& dir, double speed, double start,
                                 std::size_t passed) {
  throw UnexpectedTouch(brake(hit, target, dir, speed, start, "on a free move"), hit, passed);
}

void VirtualCmm::move_legs(const std::vector<Eigen::Vector3d>& way,
                           const std::vector<double>& speeds) {
  if (way.empty() || speeds.size() != way.size() ||
      std::any_of(speeds.begin(), speeds.end(), [](double v) { return !(v > 0); }) ||
      std::any_of(way.begin(), way.end(), [](const auto& p) { return !p.allFinite(); }))
    throw Error("move: bad target or speed");
  const Eigen::Vector3d from = servo_.position();
  // The ball may leave a surface it touches (a retract) but enter none: it may be as deep in a
  // face as it starts, and kCollision more; the stem too (a move off an unexpected touch).
  struct Allowance {
    double& slot;
    double saved;
    ~Allowance() { slot = saved; }
  } keep{ball_allowance_, ball_allowance_}, keep_stem{stem_allowance_, stem_allowance_};
  const Guard guard(guarded_, triggered_);
  if (solid_) {
    const double r = probe_.options().tip_radius, rs = o_.stylus.shaft(r);
    const Eigen::Vector3d c = free_ball_centre();
    // The table too: a move off the table the ball was stopped on.
    ball_allowance_ =
        std::max({ball_allowance_, r - solid_->distance(c, r, touchable_) + kCollision,
                  r - (c.z() - table_z_) + kCollision});
    const Eigen::Vector3d& u = axis_;
    stem_allowance_ = std::max(
        0.0, rs - dent_ -
                 solid_->distance(c + r * u, c + (o_.stylus.length + o_.stylus.body_radius) * u,
                                  rs + 1) +
                 kCollision);
    guard_clear_ = {-1, -1, -1};
  }
  // A free move must not push the ball into the part's sections either: more than the deflection
  // it started with (a retract starts in contact) and kCollision triggers the probe.
  const double start = penetration(), start_in = pushed_in();
  // The legs (waypoints where the last one is left out), the arc length at each waypoint, and
  // the speed allowed there: 0 at the end, and at a turn of θ that of the arc of radius R that
  // cuts the corner by kCornerCut, R = kCornerCut / (1/cos(θ/2) − 1), and fits on half of each
  // leg, R·tan(θ/2) — at the path's acceleration as normal acceleration.
  const double a = o_.path_acceleration, dt = servo_.options().dt();
  std::vector<Eigen::Vector3d> pts{from};
  std::vector<double> cap{0.0};       // the speed of the leg to each point
  std::vector<std::size_t> index{0};  // how many waypoints are reached at each point
  for (std::size_t i = 0; i < way.size(); ++i) {
    if ((way[i] - pts.back()).norm() > 1e-9) {
      pts.push_back(way[i]);
      cap.push_back(speeds[i]);
      index.push_back(i + 1);
    } else {
      index.back() = i + 1;
    }
  }
  const std::size_t legs = pts.size() - 1;
  std::vector<double> arc(pts.size(), 0.0), turn_speed(pts.size(), 0.0);
  std::vector<Eigen::Vector3d> dir(std::max<std::size_t>(legs, 1), Eigen::Vector3d::Zero());
  for (std::size_t i = 0; i < legs; ++i) {
    const double l = (pts[i + 1] - pts[i]).norm();
    arc[i + 1] = arc[i] + l;
    dir[i] = (pts[i + 1] - pts[i]) / l;
  }
  for (std::size_t i = 1; i < legs; ++i) {
    const double theta = std::acos(std::clamp(dir[i - 1].dot(dir[i]), -1.0, 1.0));
    if (theta < 1e-9) {
      turn_speed[i] = INFINITY;
      continue;
    }
    if (theta > 3.0) continue;  // a reversal: stop there
    const double half = 0.5 * theta;
    const double shortest = std::min(arc[i] - arc[i - 1], arc[i + 1] - arc[i]);
    const double R =
        std::min(kCornerCut / (1 / std::cos(half) - 1), 0.5 * shortest / std::tan(half));
    // The carriage lags its command by about the drive's time constant and 1/kp: a turn at v
    // changes the velocity by 2v·sin(θ/2), and the carriage runs on about that times the lag
    // beyond the corner; that too within kCornerCut.
    const double tau = servo_.options().lag + 1 / servo_.options().position_gain;
    turn_speed[i] = std::min(std::sqrt(a * R), kCornerCut / (2 * std::sin(half) * tau));
  }
  // No faster at a waypoint than either leg at it.
  for (std::size_t i = 1; i < legs; ++i)
    turn_speed[i] = std::min({turn_speed[i], cap[i], cap[i + 1]});
  // The speed allowed at each waypoint also lets the carriage brake to the next one's.
  for (std::size_t i = legs; i-- > 1;)
    turn_speed[i] = std::min(turn_speed[i], std::sqrt(turn_speed[i + 1] * turn_speed[i + 1] +
                                                      2 * a * (arc[i + 1] - arc[i])));
  const double L = arc.back();
  const Eigen::Vector3d to = pts.back();
  double s = 0, v = 0;
  std::size_t leg = 0;
  for (long k = 0; k < kMaxTicks; ++k) {
    const bool at_end = s >= L;
    if (at_end && (servo_.position() - to).norm() < 1e-4 && servo_.velocity().norm() < 1) return;
    while (leg + 1 < legs && s >= arc[leg + 1]) ++leg;
    if (at_end) {
      v = 0;
    } else {
      // Slow enough to brake to the speed allowed at the next waypoint.
      const double next = turn_speed[leg + 1];
      v = std::min({cap[leg + 1], v + a * dt,
                    std::sqrt(next * next + 2 * a * std::max(0.0, arc[leg + 1] - s))});
    }
    const Eigen::Vector3d target =
        legs ? Eigen::Vector3d(pts[leg] + dir[leg] * (std::min(s, L) - arc[leg])) : to;
    servo_.step(target, dir[leg] * v);
    s = std::min(L, s + v * dt);
    // The stylus leaves a surface deflected by it (a retract), then free.
    const double depth = penetration(&deflection_);
    corner_.setZero();
    if (depth <= probe_.options().range) check_solid();
    if (triggered_ >= 0 || depth > start + kCollision) {
      // The probe triggers on the contact; the machine brakes.
      if (triggered_ < 0) triggered_ = 0;
      stop_on_contact(free_ball_centre(), target, legs ? dir[leg] : Eigen::Vector3d::Zero(),
                      servo_.velocity().norm(), start_in, index[legs ? leg : 0]);
    }
  }
  throw Error("move: the carriage did not settle");
}

}  // namespace trueaxis::scan
