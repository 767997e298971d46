#include "trueaxis/sim/ballgauge.hpp"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include "trueaxis/error.hpp"

namespace trueaxis::sim {
namespace {

// Probing directions over the hemisphere of `pole`: the pole, then rings at 40° and 75° from it.
std::vector<Eigen::Vector3d> directions(int n, const Eigen::Vector3d& pole) {
  std::vector<Eigen::Vector3d> d{Eigen::Vector3d::UnitZ()};
  const int rest = n - 1, ring1 = rest / 2, ring2 = rest - ring1;
  for (int ring = 0; ring < 2; ++ring) {
    const int m = ring == 0 ? ring1 : ring2;
    const double polar = (ring == 0 ? 40.0 : 75.0) * M_PI / 180;
    for (int k = 0; k < m; ++k) {
      const double az = 2 * M_PI * (k + 0.5 * ring) / m;
      d.emplace_back(std::sin(polar) * std::cos(az), std::sin(polar) * std::sin(az),
                     std::cos(polar));
    }
  }
  if (pole != Eigen::Vector3d::UnitZ()) {
    const Eigen::Matrix3d R =
        Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), pole).toRotationMatrix();
    for (auto& v : d) v = R * v;
  }
  return d;
}

// The command whose actual tool point is P (fixed point: |∇e| ≪ 1), refused outside the range.
Eigen::Vector3d command_to_reach(const Machine& machine, const Eigen::Vector3d& P,
                                 const std::string& what) {
  Eigen::Vector3d cmd = P - machine.offset;
  for (int it = 0; it < 6; ++it) cmd = P - machine.offset - machine.error(cmd);
  if (!machine.contains(cmd, 1.0))
    throw Error(fmt::format("{} is outside the machine's range", what));
  return cmd;
}

// The balls a pose probes (its list, else all) with their true centres; Error for an index the
// gauge does not have.
std::vector<std::pair<int, Eigen::Vector3d>> placed_balls(const ballgauge::Gauge& gauge,
                                                          const GaugePose& pose) {
  std::vector<int> balls = pose.balls;
  if (balls.empty())
    for (int i = 0; i < static_cast<int>(gauge.balls.size()); ++i) balls.push_back(i);
  std::vector<std::pair<int, Eigen::Vector3d>> out;
  for (int b : balls) {
    if (b < 0 || b >= static_cast<int>(gauge.balls.size()))
      throw Error(fmt::format("ball gauge: {} has no ball {}", pose.name, b));
    out.emplace_back(b,
                     pose.rotation * gauge.balls[static_cast<std::size_t>(b)] + pose.translation);
  }
  return out;
}

}  // namespace

ballgauge::Gauge frame_gauge(int nx, int ny, int nz, double pitch, double ball_diameter) {
  if (nx < 2 || ny < 2 || nz < 1 || !(pitch > 0))
    throw Error("frame gauge: needs at least 2 x 2 x 1 balls and a positive pitch");
  ballgauge::Gauge g;
  g.ball_diameter = ball_diameter;
  g.balls = {{0, 0, 0}, {pitch, 0, 0}, {0, pitch, 0}};
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        if (k == 0 && ((j == 0 && i <= 1) || (i == 0 && j == 1))) continue;  // balls 0, 1, 2
        g.balls.emplace_back(pitch * i, pitch * j, pitch * k);
      }
  return g;
}

std::vector<GaugePose> stacked_poses(const ballgauge::Gauge& gauge, int sections,
                                     const Eigen::Vector3d& origin,
                                     const Eigen::Matrix3d& rotation) {
  double height = 0;
  for (const auto& b : gauge.balls) height = std::max(height, b.z());
  if (!(height > 0)) throw Error("stacked placements need a gauge with more than one layer");
  std::vector<GaugePose> p;
  for (int k = 0; k < sections; ++k) {
    GaugePose q;
    q.name = fmt::format("placement {}", k + 1);
    q.alignment = k == 0 ? ballgauge::Alignment::ThreeTwoOne : ballgauge::Alignment::Stitch;
    q.rotation = rotation;
    q.translation = origin + rotation * Eigen::Vector3d(0, 0, height * k);
    p.push_back(q);
  }
  return p;
}

ballgauge::Gauge plate_gauge(int rows, int columns, double pitch, double ball_diameter) {
  if (rows < 2 || columns < 2 || !(pitch > 0) || !(ball_diameter > 0))
    throw Error("ball plate: needs at least 2 x 2 balls, a positive pitch and diameter");
  ballgauge::Gauge g;
  g.ball_diameter = ball_diameter;
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < columns; ++i) g.balls.emplace_back(pitch * i, pitch * j, 0.0);
  return g;
}

std::vector<GaugePose> plate_poses(const ballgauge::Gauge& plate, const Machine& machine,
                                   double margin, const Eigen::Matrix3d& rotation,
                                   bool from_the_side) {
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
  for (const auto& b : plate.balls) size = size.cwiseMax(b);
  const Eigen::Vector3d X = Eigen::Vector3d::UnitX(), Y = Eigen::Vector3d::UnitY(),
                        Z = Eigen::Vector3d::UnitZ();
  struct Plane {
    const char* name;
    Eigen::Vector3d u, v;
    double level;  // where along the normal, as a fraction of the room (0.5: centred)
    bool upright;
  };
  const Plane planes[] = {{"XY low", X, Y, 0.1, false},
                          {"XY high", X, Y, 0.9, false},
                          {"XZ", X, Z, 0.5, true},
                          {"YZ", Y, Z, 0.5, true}};
  std::vector<GaugePose> out;
  for (const auto& p : planes) {
    const Eigen::Vector3d n = p.u.cross(p.v);  // XZ: −Y, YZ: +X
    // The styli: the machine's, or the horizontal one from each side of an upright plate (the
    // tip on the plate's side of the ram: offset −|offset|·pole).
    std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> sides;  // pole, offset
    if (p.upright && from_the_side)
      for (double side : {1.0, -1.0})
        sides.emplace_back(side * n, (-machine.offset.norm() * side * n).array() + 0.0);  // no −0
    else
      sides.emplace_back(Eigen::Vector3d::UnitZ(), machine.offset);
    // The true tip positions every one of its styli reaches, `margin` inside the command range.
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(-HUGE_VAL),
                    hi = Eigen::Vector3d::Constant(HUGE_VAL);
    for (const auto& [pole, offset] : sides)
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::max(lo[k], machine.range[static_cast<std::size_t>(k)][0] + offset[k] + margin);
        hi[k] = std::min(hi[k], machine.range[static_cast<std::size_t>(k)][1] + offset[k] - margin);
      }
    const Eigen::Vector3d mid = (lo + hi) / 2, room = hi - lo;
    Eigen::Matrix3d F;
    F << p.u, p.v, n;
    const Eigen::Vector3d extent = (F * size).cwiseAbs();
    for (int a = 0; a < 3; ++a)
      if (!(extent[a] <= room[a]))
        throw Error(fmt::format(
            "ball plate campaign: the {:.0f} x {:.0f} mm plate does not fit the {} placement "
            "({:.0f} mm of room along {})",
            size.x(), size.y(), p.name, std::max(room[a], 0.0), "xyz"[a]));
    Eigen::Vector3d at = mid - F * size / 2;  // centred in its plane
    const int normal = std::abs(n.x()) > 0.5 ? 0 : std::abs(n.y()) > 0.5 ? 1 : 2;
    at[normal] = lo[normal] + p.level * room[normal];
    for (const auto& [pole, offset] : sides) {
      GaugePose q;
      q.name = p.name;
      if (sides.size() > 1) {
        const int k = std::abs(pole.x()) > 0.5 ? 0 : 1;
        q.name += fmt::format(" from {}{}", pole[k] > 0 ? '+' : '-', "XY"[k]);
        q.pole = pole;
        q.stylus_offset = offset;
      }
      q.alignment = ballgauge::Alignment::ThreeTwoOne;
      q.rotation = rotation * F;
      q.translation = at;
      out.push_back(q);
    }
  }
  return out;
}

void BallGaugeOptions::validate() const {
  if (points_per_ball < 5) throw Error("ball gauge simulation: at least 5 points per ball");
  if (!(tip_radius >= 0) || !(noise >= 0))
    throw Error("ball gauge simulation: tip radius and noise must be >= 0");
}

BallGaugeCampaign measure_ballgauge(const ballgauge::Gauge& gauge,
                                    const std::vector<GaugePose>& poses, const BallGaugeOptions& o,
                                    const BallProbe& probe) {
  o.validate();
  gauge.validate();
  const double reach = gauge.ball_diameter / 2 + o.tip_radius;
  BallGaugeCampaign c;
  for (const auto& pose : poses) {
    if (!(std::abs(pose.pole.norm() - 1) < 1e-9))
      throw Error(fmt::format("ball gauge: {}: the probing pole must be a unit vector", pose.name));
    const auto dirs = directions(o.points_per_ball, pose.pole);
    ballgauge::Placement pl;
    pl.name = pose.name;
    pl.alignment = pose.alignment;
    pl.tip_radius = o.tip_radius;
    pl.stylus_offset = pose.stylus_offset;
    std::vector<Eigen::Vector3d> truth;
    for (const auto& [b, X] : placed_balls(gauge, pose)) {
      ballgauge::BallPoints bp;
      bp.index = b;
      bp.points.resize(3, static_cast<Eigen::Index>(dirs.size()));
      const std::string what = fmt::format("{} ball {}", pose.name, b);
      for (std::size_t k = 0; k < dirs.size(); ++k)
        bp.points.col(static_cast<Eigen::Index>(k)) = probe(X, reach, dirs[k], what);
      pl.balls.push_back(std::move(bp));
      truth.push_back(X);
    }
    c.placements.push_back(std::move(pl));
    c.true_centres.push_back(std::move(truth));
  }
  return c;
}

BallGaugeCampaign simulate_ballgauge(const Machine& machine, const ballgauge::Gauge& gauge,
                                     const std::vector<GaugePose>& poses,
                                     const BallGaugeOptions& o) {
  o.validate();
  gauge.validate();
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> N(0.0, 1.0);
  BallGaugeCampaign c;
  for (const auto& pose : poses) {
    // The machine with this pose's stylus.
    Machine m = machine;
    if (pose.stylus_offset) m.offset = *pose.stylus_offset;
    auto one = measure_ballgauge(
        gauge, {pose}, o,
        [&](const Eigen::Vector3d& X, double reach, const Eigen::Vector3d& d,
            const std::string& what) {
          const Eigen::Vector3d cmd =
              command_to_reach(m, X + reach * d, fmt::format("ball gauge simulation: {}", what));
          // Drawn z first, as GCC evaluated the three draws of earlier versions: the same seed
          // gives the same campaign as before.
          const double nz = N(rng), ny = N(rng), nx = N(rng);
          return Eigen::Vector3d(cmd + m.offset + o.noise * Eigen::Vector3d(nx, ny, nz));
        });
    c.placements.push_back(std::move(one.placements.front()));
    c.true_centres.push_back(std::move(one.true_centres.front()));
  }
  return c;
}

std::vector<Ball> gauge_balls(const ballgauge::Gauge& gauge, const std::vector<GaugePose>& poses) {
  gauge.validate();
  std::vector<Ball> out;
  for (const auto& pose : poses)
    for (const auto& [b, X] : placed_balls(gauge, pose)) {
      const bool seen = std::any_of(out.begin(), out.end(), [&, &X = X](const Ball& q) {
        return (q.centre - X).norm() <= 1e-6;
      });
      if (!seen) out.push_back({X, gauge.ball_diameter / 2});
    }
  return out;
}

void BallGaugeCampaign::bounds(Eigen::Vector3d& lo, Eigen::Vector3d& hi) const {
  lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  hi = -lo;
  for (const auto& placement : true_centres)
    for (const auto& t : placement) {
      lo = lo.cwiseMin(t);
      hi = hi.cwiseMax(t);
    }
}

void GaugeBlockOptions::validate() const {
  if (!lo.allFinite() || !hi.allFinite() || !((hi - lo).minCoeff() > 0))
    throw Error("gauge block simulation: the box needs lo < hi in x, y and z");
  if (repeats < 1) throw Error("gauge block simulation: at least one repeat");
  if (!(margin >= 0) || !(tip_radius >= 0) || !(noise >= 0))
    throw Error("gauge block simulation: margin, tip radius and noise must be >= 0");
  for (double L : lengths)
    if (!(L > 0) || !std::isfinite(L))
      throw Error("gauge block simulation: lengths must be positive numbers of mm");
}

GaugeBlockCampaign simulate_gauge_blocks(const Machine& machine, const GaugeBlockOptions& o) {
  o.validate();
  const Eigen::Vector3d centre = (o.lo + o.hi) / 2, half = (o.hi - o.lo) / 2;
  struct Position {
    std::string name;
    Eigen::Vector3d d;
  };
  std::vector<Position> positions{{"x", Eigen::Vector3d::UnitX()},
                                  {"y", Eigen::Vector3d::UnitY()},
                                  {"z", Eigen::Vector3d::UnitZ()}};
  for (int s = 0; s < 4; ++s) {
    const double sx = (s & 1) ? -1 : 1, sy = (s & 2) ? -1 : 1;
    positions.push_back({fmt::format("{}x{}y+z", sx > 0 ? '+' : '-', sy > 0 ? '+' : '-'),
                         Eigen::Vector3d(sx * half.x(), sy * half.y(), half.z()).normalized()});
  }
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> N(0.0, 1.0);
  GaugeBlockCampaign c;
  for (const auto& pos : positions) {
    // Room along d through the centre, keeping the margin to every face it approaches.
    double room = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k)
      if (std::abs(pos.d[k]) > 1e-12)
        room = std::min(room, 2 * (half[k] - o.margin) / std::abs(pos.d[k]));
    std::vector<double> lengths = o.lengths;
    if (lengths.empty())
      for (double f : {0.3, 0.45, 0.6, 0.75, 0.9}) lengths.push_back(std::floor(f * room));
    for (double L : lengths) {
      if (!(L <= room) || !(L > 0)) continue;
      const Eigen::Vector3d A = centre - L / 2 * pos.d, B = centre + L / 2 * pos.d;
      for (int rep = 0; rep < o.repeats; ++rep) {
        auto probe = [&](const Eigen::Vector3d& tip, const Eigen::Vector3d& back) {
          const Eigen::Vector3d cmd = command_to_reach(
              machine, tip, fmt::format("gauge block simulation: {} mm along {}", L, pos.name));
          return Eigen::Vector3d(cmd + machine.offset +
                                 o.noise * Eigen::Vector3d(N(rng), N(rng), N(rng)) + back);
        };
        ballgauge::LengthMeasurement m;
        m.nominal = L;
        m.a = probe(A - o.tip_radius * pos.d, o.tip_radius * pos.d);
        m.b = probe(B + o.tip_radius * pos.d, -o.tip_radius * pos.d);
        c.lengths.push_back(m);
        c.position.push_back(pos.name);
        c.true_a.push_back(A);
        c.true_b.push_back(B);
      }
    }
  }
  if (c.lengths.empty())
    throw Error("gauge block simulation: no length fits the box (with its margin)");
  return c;
}

void BallGaugeSetup::validate() const {
  const bool plate = plate_rows != 0 || plate_columns != 0;
  if (plate && (plate_rows < 2 || plate_columns < 2 || plate_rows > 100 || plate_columns > 100))
    throw Error("ball-gauge set-up: a plate has 2 to 100 rows and columns");
  if (plate && !(pitch > 0 && std::isfinite(pitch)))
    throw Error("ball-gauge set-up: the plate's pitch must be a positive number of mm");
  if (!plate && (placements < 1 || placements > 20))
    throw Error("ball-gauge set-up: the frame takes 1 to 20 placements");
  if (!origin.allFinite()) throw Error("ball-gauge set-up: the origin must be finite");
  if (!(std::abs(misalignment) < 0.1))
    throw Error("ball-gauge set-up: the misalignment must be below 0.1 rad (a gauge set by hand)");
}

bool parse_plate(const std::string& text, BallGaugeSetup& setup) {
  int rows = 0, columns = 0;
  char x = 0, rest = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", &rows, &x, &columns, &rest) != 3 ||
      (x != 'x' && x != 'X') || rows < 2 || columns < 2 || rows > 100 || columns > 100)
    return false;
  setup.plate_rows = rows;
  setup.plate_columns = columns;
  return true;
}

BallGaugeLayout ballgauge_setup(const Machine& machine, const BallGaugeSetup& s) {
  s.validate();
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(s.misalignment, Eigen::Vector3d(0.2, -0.1, 1).normalized())
          .toRotationMatrix();
  BallGaugeLayout out;
  if (s.plate_rows == 0) {
    out.gauge = frame_gauge();
    out.poses = stacked_poses(out.gauge, s.placements, s.origin, R);
    if (s.least_squares) out.poses.front().alignment = ballgauge::Alignment::LeastSquares;
    out.description = fmt::format("a {}-ball frame gauge", out.gauge.balls.size());
  } else {
    out.gauge = plate_gauge(s.plate_rows, s.plate_columns, s.pitch);
    out.poses = plate_poses(out.gauge, machine, 30, R, !s.from_above);
    if (s.least_squares)
      for (auto& q : out.poses) q.alignment = ballgauge::Alignment::LeastSquares;
    out.description = fmt::format(
        "a {}x{} ball plate at {:g} mm pitch (flat low and high, upright along X and along Y{}, "
        "each aligned by itself)",
        s.plate_rows, s.plate_columns, s.pitch,
        s.from_above ? "" : " probed from the side with the stylus turned horizontal");
  }
  return out;
}

BallGaugeTruth ballgauge_truth(const Machine& machine, const BallGaugeCampaign& c) {
  BallGaugeTruth t;
  std::size_t n = 0;
  for (const auto& p : c.placements) n += p.balls.size();
  t.centre.resize(3, static_cast<Eigen::Index>(n));
  t.error.resize(3, static_cast<Eigen::Index>(n));
  Eigen::Index k = 0;
  for (std::size_t p = 0; p < c.placements.size(); ++p) {
    // The machine's error at the tip of the stylus this placement was probed with.
    Machine ms = machine;
    if (c.placements[p].stylus_offset) ms.offset = *c.placements[p].stylus_offset;
    for (std::size_t b = 0; b < c.placements[p].balls.size(); ++b, ++k) {
      const Eigen::Vector3d X = c.true_centres[p][b];
      t.placement.push_back(static_cast<int>(p));
      t.ball.push_back(c.placements[p].balls[b].index);
      t.centre.col(k) = X;
      t.error.col(k) = ms.error(X - ms.offset);
    }
  }
  return t;
}

GaugeBlockOptions held_out_blocks(const Machine& machine, const BallGaugeCampaign& c,
                                  GaugeBlockOptions o) {
  c.bounds(o.lo, o.hi);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(HUGE_VAL), hi = -lo;
  for (std::size_t p = 0; p < c.placements.size(); ++p)
    for (const auto& X : c.true_centres[p]) {
      const Eigen::Vector3d cmd = X - c.placements[p].stylus_offset.value_or(machine.offset);
      lo = lo.cwiseMin(cmd);
      hi = hi.cwiseMax(cmd);
    }
  o.lo = o.lo.cwiseMax(lo + machine.offset);
  o.hi = o.hi.cwiseMin(hi + machine.offset);
  return o;
}

}  // namespace trueaxis::sim
