// An ISO 10360-2 set-up checked against the standard and the machine's volume (acceptance.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "trueaxis/acceptance/acceptance.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/geometry/distance.hpp"

namespace trueaxis::acceptance {
namespace {

// Directions within 2° are one line's (as ballgauge::LengthOptions takes them).
constexpr double kParallel = 0.99939;  // cos 2°

// The length of the line through p along unit d inside the volume (mm).
double chord(const Volume& v, const Eigen::Vector3d& p, const Eigen::Vector3d& d) {
  double lo = -INFINITY, hi = INFINITY;
  for (int a = 0; a < 3; ++a) {
    if (std::abs(d[a]) < 1e-12) continue;
    double t0 = (v.low[a] - p[a]) / d[a], t1 = (v.high[a] - p[a]) / d[a];
    if (t0 > t1) std::swap(t0, t1);
    lo = std::max(lo, t0);
    hi = std::min(hi, t1);
  }
  return hi > lo ? hi - lo : 0.0;
}

std::string xyz(const Eigen::Vector3d& v) {
  return fmt::format("({:.1f}, {:.1f}, {:.1f})", v.x(), v.y(), v.z());
}

}  // namespace

void Setup::validate() const {
  if (placements.empty() && !sphere)
    throw Error("acceptance set-up: no placements of calibrated lengths and no reference sphere");
  if (!placements.empty() && blocks.empty())
    throw Error("acceptance set-up: placements but no calibrated lengths (blocks)");
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    const auto& b = blocks[i];
    if (b.id.empty()) throw Error(fmt::format("block {}: no id", i + 1));
    if (!(b.length > 0) || !std::isfinite(b.length))
      throw Error(fmt::format("block '{}': the length must be > 0 mm", b.id));
    if (!(b.u >= 0) || !std::isfinite(b.u) || !(b.u_alpha >= 0) || !std::isfinite(b.alpha))
      throw Error(fmt::format("block '{}': uncertainties must be ≥ 0 and finite", b.id));
    for (std::size_t j = 0; j < i; ++j)
      if (blocks[j].id == b.id) throw Error(fmt::format("block '{}' is listed twice", b.id));
  }
  for (std::size_t i = 0; i < placements.size(); ++i) {
    const auto& p = placements[i];
    block(p.block);
    if (!p.centre.allFinite() || !p.direction.allFinite() ||
        std::abs(p.direction.norm() - 1) > 1e-9)
      throw Error(
          fmt::format("placement {} (block '{}'): the centre must be finite and the "
                      "direction a unit vector",
                      i + 1, p.block));
  }
  if (sphere && (!(sphere->diameter > 0) || !(sphere->u_diameter >= 0) || !(sphere->form >= 0) ||
                 !sphere->centre.allFinite() || std::abs(sphere->pole.norm() - 1) > 1e-9))
    throw Error("reference sphere: diameter > 0, u and form ≥ 0, a finite centre and a unit pole");
  if (!(u_temperature >= 0) || !(u_alignment >= 0) || !(u_fixturing >= 0) ||
      !std::isfinite(temperature))
    throw Error(
        "acceptance set-up: the temperature and its u, and the alignment's and fixturing's u, "
        "must be ≥ 0");
  if (!(block_width > 0) || !(block_height > 0) || !(approach > 0))
    throw Error("acceptance set-up: the block's width and height and the approach must be > 0 mm");
  if (repetitions < 1 || repetitions > 100)
    throw Error("acceptance set-up: repetitions must be 1 … 100 (ISO 10360-2: 3)");
}

const GaugeBlock& Setup::block(const std::string& id) const {
  for (const auto& b : blocks)
    if (b.id == id) return b;
  throw Error(fmt::format("no calibrated length '{}' in the set-up's blocks", id));
}

Volume Volume::of(const sim::Machine& m) {
  Volume v;
  for (int a = 0; a < 3; ++a) {
    v.low[a] = m.range[static_cast<std::size_t>(a)][0] + m.offset[a];
    v.high[a] = m.range[static_cast<std::size_t>(a)][1] + m.offset[a];
  }
  return v;
}

namespace {

// The placements by position: their own names, or (unnamed) their directions.
std::vector<Position> group(const Setup& setup) {
  std::vector<Position> out;
  for (std::size_t i = 0; i < setup.placements.size(); ++i) {
    const auto& p = setup.placements[i];
    Position* home = nullptr;
    for (auto& pos : out) {
      const bool same = p.position.empty()
                            ? std::abs(pos.direction.dot(p.direction)) >= kParallel &&
                                  setup.placements[pos.placements.front()].position.empty()
                            : pos.name == p.position;
      if (same) home = &pos;
    }
    if (!home) {
      Position pos;
      pos.name = p.position.empty() ? ballgauge::direction_name(p.direction) : p.position;
      pos.direction = p.direction;
      out.push_back(pos);
      home = &out.back();
    }
    home->placements.push_back(i);
  }
  return out;
}

}  // namespace

std::vector<sim::Box> artefact_boxes(const Setup& setup) {
  setup.validate();
  std::vector<sim::Box> out;
  const auto positions = group(setup);
  for (std::size_t g = 0; g < positions.size(); ++g)
    for (const auto i : positions[g].placements) {
      const auto& p = setup.placements[i];
      sim::Box b;
      b.centre = p.centre;
      b.axes = block_axes(p.direction);
      b.half =
          Eigen::Vector3d(setup.block(p.block).length, setup.block_width, setup.block_height) / 2;
      b.group = static_cast<int>(g);
      out.push_back(b);
    }
  return out;
}

Eigen::Matrix3d block_axes(const Eigen::Vector3d& direction) {
  const Eigen::Vector3d d = direction.normalized();
  Eigen::Vector3d across = d.cross(Eigen::Vector3d::UnitZ());
  if (across.norm() < 1e-6) across = Eigen::Vector3d::UnitX().cross(d);
  across.normalize();
  Eigen::Matrix3d a;
  a << d, across, d.cross(across);
  return a;
}

std::vector<Position> lines(const Setup& setup) {
  std::vector<Position> out = group(setup);
  const double third = std::sin(20 * 3.14159265358979323846 / 180);
  for (auto& pos : out) pos.space_diagonal = (pos.direction.array().abs() > third).all();
  return out;
}

std::vector<Position> positions(const Setup& setup, const Volume& volume,
                                const std::vector<std::string>& only) {
  setup.validate();
  std::vector<std::string> why;
  std::vector<Position> out = lines(setup);
  if (!only.empty()) {
    std::vector<Position> chosen;
    for (const auto& name : only) {
      const auto it =
          std::find_if(out.begin(), out.end(), [&](const Position& p) { return p.name == name; });
      if (it != out.end()) {
        chosen.push_back(*it);
        continue;
      }
      std::string known;
      for (const auto& p : out) known += (known.empty() ? "'" : ", '") + p.name + "'";
      why.push_back(fmt::format("no position '{}' in the set-up (it has {})", name, known));
    }
    out = std::move(chosen);
  }
  // Every face of the positions measured, approached from `approach` mm out, inside the volume.
  std::vector<std::size_t> measured;
  for (const auto& pos : out)
    measured.insert(measured.end(), pos.placements.begin(), pos.placements.end());
  std::sort(measured.begin(), measured.end());
  for (const std::size_t i : measured) {
    const auto& p = setup.placements[i];
    const double half = setup.block(p.block).length / 2 + setup.approach;
    for (const double s : {-1.0, 1.0}) {
      const Eigen::Vector3d at = p.centre + s * half * p.direction;
      if ((at.array() < volume.low.array() - 1e-9).any() ||
          (at.array() > volume.high.array() + 1e-9).any())
        why.push_back(fmt::format(
            "placement {} (block '{}'): face {} approached from {} mm out is at {}, outside the "
            "volume {} … {}",
            i + 1, p.block, s < 0 ? "A" : "B", setup.approach, xyz(at), xyz(volume.low),
            xyz(volume.high)));
    }
  }
  // No two blocks of one line in one place (the positions are set up one after another): their
  // axes closer than a block's width.
  for (const auto& pos : out)
    for (std::size_t m = 0; m < pos.placements.size(); ++m) {
      const std::size_t i = pos.placements[m];
      const auto& p = setup.placements[i];
      if (std::abs(pos.direction.dot(p.direction)) < kParallel)
        why.push_back(fmt::format("placement {} (block '{}') is in position '{}' but not along it",
                                  i + 1, p.block, pos.name));
      for (std::size_t k = 0; k < m; ++k) {
        const std::size_t j = pos.placements[k];
        const auto& q = setup.placements[j];
        const double hp = setup.block(p.block).length / 2, hq = setup.block(q.block).length / 2;
        const double d = std::sqrt(
            geometry::segment_distance2(p.centre - hp * p.direction, p.centre + hp * p.direction,
                                        q.centre - hq * q.direction, q.centre + hq * q.direction));
        if (d < setup.block_width)
          why.push_back(fmt::format(
              "placements {} and {} (blocks '{}' and '{}') overlap: their axes come {:.1f} mm "
              "apart, closer than a block's width ({:g} mm)",
              j + 1, i + 1, q.block, p.block, d, setup.block_width));
      }
    }
  // ISO 10360-2:2009, 6.3: 7 positions, the 4 space diagonals among them, 5 lengths in each,
  // the longest at least 66 % of the space diagonal.
  bool diagonal[4] = {false, false, false, false};
  for (auto& pos : out) {
    Eigen::Vector3d d = pos.direction;
    if (pos.space_diagonal) {
      if (d.z() < 0) d = -d;
      diagonal[(d.x() > 0 ? 0 : 1) + (d.y() > 0 ? 0 : 2)] = true;
    }
    std::vector<double> lengths;
    for (const auto i : pos.placements) {
      const double l = setup.block(setup.placements[i].block).length;
      if (std::find(lengths.begin(), lengths.end(), l) == lengths.end()) lengths.push_back(l);
    }
    if (lengths.size() < 5)
      why.push_back(fmt::format("position '{}' has {} different lengths; ISO 10360-2 needs 5",
                                pos.name, lengths.size()));
  }
  const int diagonals =
      static_cast<int>(std::count(std::begin(diagonal), std::end(diagonal), true));
  if (only.empty() && out.size() < 7)
    why.push_back(fmt::format(
        "{} positions; ISO 10360-2 needs 7 (the 4 space diagonals and 3 more)", out.size()));
  if (only.empty() && diagonals < 4)
    why.push_back(fmt::format("{} of the 4 space diagonals of the volume are among the positions",
                              diagonals));
  // The longest length of a position at least 66 % of the travel along its line (on a space
  // diagonal: of the volume's space diagonal).
  for (const auto& pos : out) {
    double longest = 0;
    for (const auto i : pos.placements)
      longest = std::max(longest, setup.block(setup.placements[i].block).length);
    const double travel =
        chord(volume, setup.placements[pos.placements.front()].centre, pos.direction);
    if (longest < 0.66 * travel)
      why.push_back(fmt::format(
          "position '{}': the longest length, {:g} mm, is below 66 % of the travel along its line "
          "({:.0f} mm: at least {:.0f} mm)",
          pos.name, longest, travel, 0.66 * travel));
  }
  if (!why.empty()) {
    std::string text = "not an ISO 10360-2 test as set up:";
    for (const auto& w : why) text += "\n  - " + w;
    throw Error(text);
  }
  return out;
}

Setup example_setup(const Volume& volume) {
  Setup s;
  s.u_temperature = 0.05;  // K: a room at 20 ± 0.5 °C, the blocks' thermometer calibrated
  s.u_alignment = 0.1e-3;  // mm
  const Eigen::Vector3d size = volume.high - volume.low, middle = (volume.low + volume.high) / 2;
  struct Line {
    const char *id, *name;
    Eigen::Vector3d d;
  };
  const Line lines[7] = {
      {"D1", "space diagonal 1 (+X+Y+Z)", Eigen::Vector3d(size.x(), size.y(), size.z())},
      {"D2", "space diagonal 2 (−X+Y+Z)", Eigen::Vector3d(-size.x(), size.y(), size.z())},
      {"D3", "space diagonal 3 (+X−Y+Z)", Eigen::Vector3d(size.x(), -size.y(), size.z())},
      {"D4", "space diagonal 4 (−X−Y+Z)", Eigen::Vector3d(-size.x(), -size.y(), size.z())},
      {"X", "along X", Eigen::Vector3d::UnitX()},
      {"Y", "along Y", Eigen::Vector3d::UnitY()},
      {"Z", "along Z", Eigen::Vector3d::UnitZ()}};
  const double fraction[5] = {0.7, 0.55, 0.4, 0.25, 0.1};  // of the travel along the line
  const int side[5] = {0, 1, -1, 2, -2};                   // lateral places, longest in the middle
  for (const auto& line : lines) {
    const Eigen::Vector3d d = line.d.normalized();
    // Side by side across the line: horizontally where the line is not vertical.
    const Eigen::Vector3d across = block_axes(d).col(1);
    const double travel = chord(volume, middle, d);
    for (int k = 0; k < 5; ++k) {
      const double length = std::floor(fraction[k] * travel / 10) * 10;
      GaugeBlock b;
      b.id = fmt::format("{}-{:g}", line.id, length);
      b.length = length;
      b.u = (0.05 + 0.5e-3 * length) * 1e-3;  // a grade-K certificate's order: 0.05 µm + 0.5 µm/m
      s.blocks.push_back(b);
      Placement p;
      p.block = b.id;
      p.position = line.name;
      p.direction = d;
      p.centre = middle + side[k] * 1.5 * s.block_width * across;
      s.placements.push_back(p);
    }
  }
  // The sphere low in the volume, where it is farthest from every block's place.
  ReferenceSphere sphere;
  const auto boxes = artefact_boxes(s);
  double farthest = -1;
  for (const double fx : {0.15, 0.3, 0.5, 0.7, 0.85})
    for (const double fy : {0.15, 0.3, 0.5, 0.7, 0.85}) {
      const Eigen::Vector3d c = volume.low + Eigen::Vector3d(fx, fy, 0.2).cwiseProduct(size);
      double nearest = INFINITY;
      for (const auto& b : boxes) nearest = std::min(nearest, b.nearest(c).distance);
      if (nearest > farthest) {
        farthest = nearest;
        sphere.centre = c;
      }
    }
  sphere.diameter = 25.0003;
  sphere.u_diameter = 0.1e-3;
  sphere.form = 0.05e-3;
  s.sphere = sphere;
  return s;
}

}  // namespace trueaxis::acceptance
