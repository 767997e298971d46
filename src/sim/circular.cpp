#include "trueaxis/sim/circular.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "trueaxis/error.hpp"

namespace trueaxis::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

// One axis' drive: the motor under its position loop, the table behind its backlash and
// reversal spikes, the screw's cyclic error.
struct Drive {
  ServoAxis p;
  double motor = 0, last_cmd = 0, direction = 0;  // direction of the motor's last motion
  double last_velocity = 0;
  double reversed_at = -1e300;  // travelled angle at the last reversal (rad)

  void start(double cmd) { motor = last_cmd = cmd; }
  // The motor after dt with the command moving linearly from last_cmd to cmd (exact for a
  // first-order loop). The motor's direction is its velocity's sign at the tick's end: the
  // loop's K·(cmd − motor), or without a loop the command's own velocity `cmd_velocity`; a
  // reversal is placed where the velocity, linear over the tick, passes zero.
  void step(double cmd, double cmd_velocity, double dt, double travelled_before, double travelled) {
    if (p.gain > 0) {
      const double v = (cmd - last_cmd) / dt, e = std::exp(-p.gain * dt);
      motor = cmd - v / p.gain + (motor - last_cmd + v / p.gain) * e;
    } else {
      motor = cmd;
    }
    last_cmd = cmd;
    const double velocity = p.gain > 0 ? p.gain * (cmd - motor) : cmd_velocity;
    if (velocity != 0) {
      const double d = velocity > 0 ? 1.0 : -1.0;
      if (direction != 0 && d != direction) {
        const double f = last_velocity / (last_velocity - velocity);
        reversed_at = travelled_before + std::clamp(f, 0.0, 1.0) * (travelled - travelled_before);
      }
      direction = d;
    }
    last_velocity = velocity;
  }
  // Where the table is, `travelled` rad into the run.
  double table(double travelled) const {
    double x = motor - p.backlash / 2 * direction;
    if (p.spike != 0 && travelled >= reversed_at)
      x -= p.spike * direction * std::exp(-(travelled - reversed_at) / p.spike_decay);
    if (p.cyclic != 0) x += p.cyclic * std::sin(2 * kPi * motor / p.pitch);
    return x;
  }
};

// The circle's centre: as given, or mid-range on every axis left NaN.
Eigen::Vector3d centre_of(const Machine& machine, const CircularOptions& o) {
  Eigen::Vector3d c = o.centre;
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(c[k]))
      c[k] = (machine.range[static_cast<std::size_t>(k)][0] +
              machine.range[static_cast<std::size_t>(k)][1]) /
             2;
  return c;
}

}  // namespace

void CircularOptions::validate() const {
  if (!(radius > 0) || !std::isfinite(radius)) throw Error("circular test: radius must be > 0 mm");
  if (!(feed > 0) || !std::isfinite(feed)) throw Error("circular test: feed must be > 0 mm/min");
  if (!(arc > 0 && arc <= 4 * kPi)) throw Error("circular test: the data arc must be in (0, 720]°");
  if (!(overshoot >= 0 && overshoot <= 2 * kPi))
    throw Error("circular test: the overshoot must be in [0, 360]°");
  if (!ccw && !cw) throw Error("circular test: run at least one direction");
  for (const auto& s : servo)
    if (!(s.gain >= 0) || !(s.spike_decay > 0) || !(s.pitch > 0) || !std::isfinite(s.backlash) ||
        !std::isfinite(s.spike) || !std::isfinite(s.cyclic))
      throw Error("circular test: servo gain >= 0, spike decay > 0 and pitch > 0 per axis");
  for (double b : compensation.backlash)
    if (!std::isfinite(b)) throw Error("circular test: a compensated backlash must be finite");
  if ((compensation.cross_input < 0) != (compensation.cross_output < 0) ||
      compensation.cross_input > 2 || compensation.cross_output > 2 ||
      (compensation.cross_input >= 0 && compensation.cross_input == compensation.cross_output) ||
      !std::isfinite(compensation.cross_slope))
    throw Error("circular test: a cross-axis compensation needs two different axes and a slope");
  if (!(noise >= 0) || !(sample_rate > 0) || !(servo_rate >= sample_rate))
    throw Error("circular test: noise >= 0, sample rate > 0, servo rate >= sample rate");
}

CircularRun simulate_circular(const Machine& machine, const CircularOptions& o) {
  o.validate();
  machine.validate();
  const Eigen::Vector3d centre = centre_of(machine, o);
  const int a = o.plane.a, b = o.plane.b;
  for (int k : {a, b})
    if (centre[k] - o.radius < machine.range[static_cast<std::size_t>(k)][0] - 1e-9 ||
        centre[k] + o.radius > machine.range[static_cast<std::size_t>(k)][1] + 1e-9)
      throw Error(
          fmt::format("circular test: a circle of radius {:g} mm about {:g} leaves the {} "
                      "axis' range",
                      o.radius, centre[k], "XYZ"[k]));
  const double omega = o.feed / 60.0 / o.radius;  // rad/s
  const double dt = 1.0 / o.servo_rate;
  const auto per_sample = static_cast<long>(std::lround(o.servo_rate / o.sample_rate));
  const Eigen::Vector3d pivot = centre + machine.offset + o.pivot_offset;
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> N(0.0, 1.0);
  std::vector<circular::Direction> dir;
  std::vector<double> angle, deviation, time;
  for (const circular::Direction d : {circular::Direction::Ccw, circular::Direction::Cw}) {
    if ((d == circular::Direction::Ccw && !o.ccw) || (d == circular::Direction::Cw && !o.cw))
      continue;
    const double s = d == circular::Direction::Ccw ? 1.0 : -1.0;
    // θ(travelled): ccw from −overshoot/2 up, cw from arc + overshoot/2 down.
    const double total = o.arc + o.overshoot;
    const double start = s > 0 ? -o.overshoot / 2 : o.arc + o.overshoot / 2;
    // The controller's command: the circle, plus what a loaded compensation adds (the backlash
    // half each way of the commanded travel, whose direction `way` holds per axis).
    const ControllerCompensation& comp = o.compensation;
    Eigen::Vector3d way = Eigen::Vector3d::Zero();
    auto command = [&](double travelled) {
      const double th = start + s * travelled;
      Eigen::Vector3d c = centre;
      c[a] += o.radius * std::cos(th);
      c[b] += o.radius * std::sin(th);
      const Eigen::Vector3d nominal = c;
      for (int k = 0; k < 3; ++k) c[k] += comp.backlash[static_cast<std::size_t>(k)] / 2 * way[k];
      if (comp.cross_input >= 0)
        c[comp.cross_output] += comp.cross_slope * nominal[comp.cross_input];
      return c;
    };
    auto velocity = [&](double th) {  // the circle's velocity, mm/s
      Eigen::Vector3d v = Eigen::Vector3d::Zero();
      v[a] = -s * omega * o.radius * std::sin(th);
      v[b] = s * omega * o.radius * std::cos(th);
      return v;
    };
    auto update_way = [&](const Eigen::Vector3d& v) {
      for (int k = 0; k < 3; ++k)
        if (v[k] != 0) way[k] = v[k] > 0 ? 1.0 : -1.0;
    };
    update_way(velocity(start));
    std::array<Drive, 3> drive;
    const Eigen::Vector3d c0 = command(0);
    for (int k = 0; k < 3; ++k) {
      drive[static_cast<std::size_t>(k)].p = o.servo[static_cast<std::size_t>(k)];
      drive[static_cast<std::size_t>(k)].start(c0[k]);
    }
    const auto ticks = static_cast<long>(std::ceil(total / omega / dt));
    double before = 0;
    for (long i = 1; i <= ticks; ++i) {
      const double t = static_cast<double>(i) * dt;
      const double travelled = std::min(omega * t, total);
      const double th = start + s * travelled;
      const Eigen::Vector3d v = velocity(th);
      update_way(v);
      const Eigen::Vector3d c = command(travelled);
      for (int k = 0; k < 3; ++k)
        drive[static_cast<std::size_t>(k)].step(c[k], v[k], dt, before, travelled);
      before = travelled;
      if (i % per_sample != 0) continue;
      const double into = s > 0 ? th : o.arc - th;  // rad into the data arc
      if (into < 0 || into >= o.arc) continue;
      Eigen::Vector3d q;
      for (int k = 0; k < 3; ++k) q[k] = drive[static_cast<std::size_t>(k)].table(travelled);
      const Eigen::Vector3d tool = q + machine.offset + machine.error(q);
      const double reading = (tool - pivot).norm() - o.radius + o.length_error +
                             o.drift * travelled / total + o.noise * N(rng);
      dir.push_back(d);
      angle.push_back(th);
      deviation.push_back(reading);
      time.push_back(t);
    }
  }
  CircularRun run;
  const auto n = static_cast<Eigen::Index>(angle.size());
  run.trace.direction = std::move(dir);
  run.trace.angle = Eigen::Map<Eigen::VectorXd>(angle.data(), n);
  run.trace.deviation = Eigen::Map<Eigen::VectorXd>(deviation.data(), n);
  run.time = Eigen::Map<Eigen::VectorXd>(time.data(), n);
  return run;
}

CircularTruth circular_truth(const Machine& machine, const CircularOptions& o) {
  const Eigen::Vector3d c = centre_of(machine, o);
  const int a = o.plane.a, b = o.plane.b;
  // Each axis' actual direction over the test's span: least-squares slopes of the tool's
  // in-plane position as the axis moves from −R to +R about the centre (the other axis there).
  constexpr int kPoints = 41;
  auto slopes = [&](int axis) {
    Eigen::Vector2d sum_u = Eigen::Vector2d::Zero();
    double suu = 0;
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    std::array<Eigen::Vector2d, kPoints> p;
    std::array<double, kPoints> u{};
    for (int i = 0; i < kPoints; ++i) {
      u[static_cast<std::size_t>(i)] = o.radius * (2.0 * i / (kPoints - 1) - 1);
      Eigen::Vector3d q = c;
      q[axis] += u[static_cast<std::size_t>(i)];
      const Eigen::Vector3d actual = q + machine.error(q);
      p[static_cast<std::size_t>(i)] = Eigen::Vector2d(actual[a], actual[b]);
      mean += p[static_cast<std::size_t>(i)] / kPoints;
    }
    for (int i = 0; i < kPoints; ++i) {
      const auto I = static_cast<std::size_t>(i);
      sum_u += u[I] * (p[I] - mean);
      suu += u[I] * u[I];
    }
    return Eigen::Vector2d(sum_u / suu);  // d(a, b)/du
  };
  const Eigen::Vector2d da = slopes(a), db = slopes(b);
  CircularTruth t;
  t.squareness = std::acos(da.dot(db) / (da.norm() * db.norm())) - kPi / 2;
  t.scale_mismatch = (da.x() - 1) - (db.y() - 1);
  const auto& sa = o.servo[static_cast<std::size_t>(a)];
  const auto& sb = o.servo[static_cast<std::size_t>(b)];
  t.lag_mismatch = (sa.gain > 0 ? 1 / sa.gain : 0.0) - (sb.gain > 0 ? 1 / sb.gain : 0.0);
  // The path's centre is the tool at the circle's centre: its error there, less the pivot's
  // offset.
  const Eigen::Vector3d e = machine.error(c);
  t.centre_offset = Eigen::Vector2d(e[a] - o.pivot_offset[a], e[b] - o.pivot_offset[b]);
  t.backlash = {sa.backlash - o.compensation.backlash[static_cast<std::size_t>(a)],
                sb.backlash - o.compensation.backlash[static_cast<std::size_t>(b)]};
  // A cross table adding slope·b to a's command leaves e_a = −(S − slope)·b.
  // Either way round (b corrected over a turns +a towards +b) it takes the slope off S.
  const auto& cc = o.compensation;
  if ((cc.cross_output == a && cc.cross_input == b) ||
      (cc.cross_output == b && cc.cross_input == a))
    t.squareness -= cc.cross_slope;
  t.spike = {sa.spike, sb.spike};
  return t;
}

}  // namespace trueaxis::sim
