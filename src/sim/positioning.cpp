#include "trueaxis/sim/positioning.hpp"

#include <fmt/format.h>

#include <cmath>
#include <random>

#include "trueaxis/error.hpp"

namespace trueaxis::sim {

void PositioningRunOptions::validate(const Machine& m) const {
  if (axis < 0 || axis > 2) throw Error("axis must be 0, 1 or 2 (x, y, z)");
  if (targets.size() < 2) throw Error("a positioning run needs at least two targets");
  const auto& r = m.range[static_cast<std::size_t>(axis)];
  for (std::size_t i = 0; i < targets.size(); ++i) {
    if (!std::isfinite(targets[i])) throw Error("targets must be finite");
    if (i > 0 && !(targets[i] > targets[i - 1])) throw Error("targets must be strictly increasing");
    if (targets[i] < r[0] - 1e-9 || targets[i] > r[1] + 1e-9)
      throw Error(fmt::format("target {:g} mm lies outside the {} axis' range {:g} .. {:g} mm",
                              targets[i], "xyz"[axis], r[0], r[1]));
  }
  if (cycles < 1) throw Error("a positioning run needs at least one cycle");
  if (!(backlash >= 0) || !std::isfinite(backlash)) throw Error("backlash must be finite and >= 0");
  if (!(noise >= 0) || !std::isfinite(noise)) throw Error("noise must be finite and >= 0");
  if (!std::isfinite(drift) || !std::isfinite(growth))
    throw Error("drift and growth must be finite");
  if (std::isnan(temperature_start) != std::isnan(temperature_end))
    throw Error("give both the start and the end temperature, or neither");
  if (!std::isnan(temperature_start) &&
      (!std::isfinite(temperature_start) || !std::isfinite(temperature_end)))
    throw Error("temperatures must be finite");
  if (!std::isfinite(expansion_coefficient)) throw Error("expansion coefficient must be finite");
  for (int k = 0; k < 3; ++k) {
    if (k == axis || std::isnan(at[k])) continue;
    const auto& q = m.range[static_cast<std::size_t>(k)];
    if (!std::isfinite(at[k]) || at[k] < q[0] - 1e-9 || at[k] > q[1] + 1e-9)
      throw Error(
          fmt::format("the run's {} coordinate {:g} mm lies outside its range {:g} .. {:g} mm",
                      "xyz"[k], at[k], q[0], q[1]));
  }
}

PositioningRun simulate_positioning(const Machine& m, const PositioningRunOptions& o) {
  m.validate();
  o.validate(m);
  using positioning::Direction;
  Eigen::Vector3d base;
  for (int k = 0; k < 3; ++k) {
    const auto& q = m.range[static_cast<std::size_t>(k)];
    base[k] = std::isnan(o.at[k]) ? (q[0] + q[1]) / 2 : o.at[k];
  }
  const int ax = o.axis;
  auto error_at = [&](double u) {
    Eigen::Vector3d c = base;
    c[ax] = u;
    return m.error(c)[ax];
  };
  const std::size_t nt = o.targets.size();
  const double p1 = o.targets.front();
  const double e1 = error_at(p1);
  const bool thermal = !std::isnan(o.temperature_start);
  const long total = 2L * static_cast<long>(nt) * o.cycles;
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> N(0.0, 1.0);

  PositioningRun run;
  run.targets = Eigen::Map<const Eigen::VectorXd>(o.targets.data(), static_cast<Eigen::Index>(nt));
  run.geometric.resize(static_cast<Eigen::Index>(nt));
  run.up = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(nt));
  run.down = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(nt));
  for (std::size_t i = 0; i < nt; ++i)
    run.geometric[static_cast<Eigen::Index>(i)] = error_at(o.targets[i]) - e1;

  long k = 0;
  for (int cycle = 1; cycle <= o.cycles; ++cycle) {
    for (int d = 0; d < 2; ++d) {
      const Direction dir = d == 0 ? Direction::Up : Direction::Down;
      for (std::size_t q = 0; q < nt; ++q) {
        const std::size_t i = d == 0 ? q : nt - 1 - q;
        const double p = o.targets[i];
        const double tau = total > 1 ? static_cast<double>(k) / static_cast<double>(total - 1) : 0;
        const double c = o.compensation ? o.compensation(p, dir) : 0.0;
        if (!std::isfinite(c) || std::abs(c) > 1.0)
          throw Error(
              fmt::format("the compensation at {:g} mm is {:g} mm: not a plausible "
                          "correction",
                          p, c));
        double x = error_at(p + c) - e1 + c + (d == 0 ? -o.backlash / 2 : o.backlash / 2) +
                   o.drift * tau + o.growth * tau * (p - p1) / 1000.0;
        const Eigen::Index ii = static_cast<Eigen::Index>(i);
        (d == 0 ? run.up : run.down)[ii] += x / o.cycles;
        positioning::Reading r;
        r.target = p;
        r.cycle = cycle;
        r.direction = dir;
        if (thermal) {
          const double t = o.temperature_start + (o.temperature_end - o.temperature_start) * tau;
          r.material_temperature = t;
          x += o.expansion_coefficient * (t - 20.0) * (p - p1);
        }
        r.deviation = x + o.noise * N(rng);
        run.readings.push_back(r);
        ++k;
      }
    }
  }
  return run;
}

}  // namespace trueaxis::sim

namespace trueaxis::sim {

PositioningLog simulate_positioning_log(const Machine& m, const PositioningRunOptions& o,
                                        const LogSimOptions& lo) {
  if (!(lo.rate > 0) || !(lo.feed > 0) || !(lo.dwell > 0) || !(lo.overrun >= 0) ||
      !(lo.sample_noise >= 0) || !std::isfinite(lo.rate + lo.feed + lo.dwell + lo.overrun))
    throw Error("the log needs a positive rate, feed and dwell and an overrun >= 0");
  PositioningLog out;
  out.run = simulate_positioning(m, o);
  std::mt19937_64 rng(o.seed + 0x9e3779b97f4a7c15ULL);
  std::normal_distribution<double> N(0.0, 1.0);
  const double dt = 1.0 / lo.rate, speed = lo.feed / 60.0;  // s, mm/s
  double t = 0, x = o.targets.front() - lo.overrun;
  auto sample = [&](double value) {
    out.log.time.push_back(t);
    out.log.reading.push_back(value + lo.sample_noise * N(rng));
    t += dt;
  };
  auto move_to = [&](double to) {
    const double dist = std::abs(to - x);
    const auto steps = static_cast<long>(std::ceil(dist / (speed * dt)));
    for (long s = 1; s < steps; ++s)
      sample(x + (to - x) * static_cast<double>(s) / static_cast<double>(steps));
    x = to;
  };
  auto stop_at = [&](double value) {
    const auto samples = static_cast<long>(std::ceil(lo.dwell * lo.rate)) + 1;
    for (long s = 0; s < samples; ++s) sample(value);
  };
  stop_at(x);  // at rest before the first approach
  const std::size_t nt = o.targets.size();
  std::size_t k = 0;
  for (int cycle = 1; cycle <= o.cycles; ++cycle) {
    for (int d = 0; d < 2; ++d) {
      for (std::size_t q = 0; q < nt; ++q) {
        const auto& r = out.run.readings[k++];
        const double actual = r.target + r.deviation;
        move_to(actual);
        stop_at(actual);
      }
      move_to(d == 0 ? o.targets.back() + lo.overrun : o.targets.front() - lo.overrun);
    }
  }
  return out;
}

}  // namespace trueaxis::sim
