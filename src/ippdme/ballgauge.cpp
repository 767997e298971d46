#include "trueaxis/ippdme/ballgauge.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>

#include "trueaxis/error.hpp"

namespace trueaxis::ippdme {
namespace {

// Distance from p to the segment [a, b].
double segment_distance(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                        const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double L2 = ab.squaredNorm();
  const double t = L2 > 0 ? std::clamp((p - a).dot(ab) / L2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

// Detours, shortest first: the two ends of a blocked move shifted alike, up and sideways.
std::vector<Eigen::Vector3d> detours() {
  std::vector<Eigen::Vector3d> out;
  for (double up : {0.0, 5.0, 10.0, 20.0, 40.0, 80.0})
    for (double side : {0.0, 10.0, 20.0, 40.0, 80.0})
      for (int k = 0; k < (side > 0 ? 8 : 1); ++k) {
        const double az = k * M_PI / 4;
        const Eigen::Vector3d o(side * std::cos(az), side * std::sin(az), up);
        if (o.norm() > 0) out.push_back(o);
      }
  std::stable_sort(out.begin(), out.end(), [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return a.norm() < b.norm();
  });
  return out;
}

struct Prober {
  RemoteCmm& cmm;
  double r;
  std::vector<sim::Ball> obstacles;
  BallProbingOptions o;
  std::optional<Eigen::Vector3d> at;  // where the tip is (after the first call)

  bool clear(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const {
    const double margin = r + o.clearance / 2;
    return std::all_of(obstacles.begin(), obstacles.end(), [&](const sim::Ball& s) {
      return segment_distance(s.centre, a, b) >= s.radius + margin;
    });
  }

  // Moves the tip to `to` without coming near a ball.
  void go(const Eigen::Vector3d& to, const std::string& what) {
    const Eigen::Vector3d from = at ? *at : cmm.position();
    std::vector<Eigen::Vector3d> via;
    if (!clear(from, to)) {
      static const std::vector<Eigen::Vector3d> shifts = detours();
      const auto s = std::find_if(shifts.begin(), shifts.end(), [&](const Eigen::Vector3d& d) {
        return clear(from, from + d) && clear(from + d, to + d) && clear(to + d, to);
      });
      if (s == shifts.end())
        throw Error(fmt::format(
            "ball gauge over I++ DME: no way found around the balls from ({:.3f}, {:.3f}, "
            "{:.3f}) to the start of a probing of {}",
            from.x(), from.y(), from.z(), what));
      via = {from + *s, to + *s};
    }
    via.push_back(to);
    for (const auto& p : via) {
      cmm.move(p, o.move_speed);
      at = p;
    }
  }

  Eigen::Vector3d operator()(const Eigen::Vector3d& centre, double reach,
                             const Eigen::Vector3d& direction, const std::string& what) {
    const Eigen::Vector3d d = direction.normalized();
    const Eigen::Vector3d start = centre + (reach + o.clearance) * d;
    go(start, what);
    const auto t = cmm.touch({}, start, -d, o.clearance + o.search, o.speed, 0);
    if (!t)
      throw Error(fmt::format(
          "ball gauge over I++ DME: {}: no surface within {:g} mm of where the ball should be "
          "(direction {:.3f}, {:.3f}, {:.3f}); is the gauge where its pose says?",
          what, o.search, d.x(), d.y(), d.z()));
    // Back out along the probing direction, away from the ball.
    cmm.move(start, o.move_speed);
    at = start;
    return t->surface + r * t->normal;
  }
};

}  // namespace

void BallProbingOptions::validate() const {
  if (!(clearance > 0) || !std::isfinite(clearance))
    throw Error("ball probing: the clearance must be a positive number of mm");
  if (!(search > 0) || !std::isfinite(search))
    throw Error("ball probing: the search distance must be a positive number of mm");
  if (!(speed > 0) || !(move_speed > 0) || !std::isfinite(speed) || !std::isfinite(move_speed))
    throw Error("ball probing: speeds must be positive (mm/s)");
}

sim::BallProbe ball_probe(RemoteCmm& cmm, std::vector<sim::Ball> obstacles,
                          const BallProbingOptions& options) {
  options.validate();
  auto p = std::make_shared<Prober>(
      Prober{cmm, cmm.tip_radius(), std::move(obstacles), options, std::nullopt});
  return [p](const Eigen::Vector3d& centre, double reach, const Eigen::Vector3d& direction,
             const std::string& what) { return (*p)(centre, reach, direction, what); };
}

}  // namespace trueaxis::ippdme
