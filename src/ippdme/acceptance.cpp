// The CMM acceptance tests over I++ DME: PtMeas on the artefacts with planned moves
// (ippdme/acceptance.hpp).
#include "trueaxis/ippdme/acceptance.hpp"

#include <fmt/format.h>

#include <cmath>
#include <memory>
#include <optional>

#include "trueaxis/error.hpp"
#include "trueaxis/sim/cmm.hpp"

namespace trueaxis::ippdme {
namespace {

struct AcceptancePlanner {
  AcceptancePlanner(RemoteCmm& c, const AcceptanceProbingOptions& options) : cmm(c), o(options) {}
  RemoteCmm& cmm;
  AcceptanceProbingOptions o;
  double approach = 5;
  std::vector<sim::Box> boxes;
  std::optional<sim::Ball> sphere;
  acceptance::Volume travel;
  double safe_z = 0;
  // The last probing: its box (index, −1: the sphere or none) and direction.
  int last_box = -1, last_group = -1;
  Eigen::Vector3d last_dir = Eigen::Vector3d::Zero();
  bool touched = false;

  // Whether the ball on the segment a–b keeps `clearance` from the boxes of `group` (−2: none)
  // and the sphere, but for box `except` (kSphere: the sphere).
  static constexpr int kSphere = -3;
  bool clear(const Eigen::Vector3d& a, const Eigen::Vector3d& b, int group, int except) const {
    const double r = cmm.tip_radius(), keep = r + o.clearance;
    const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / 0.5)));
    for (int k = 0; k <= n; ++k) {
      const Eigen::Vector3d x = a + (b - a) * (static_cast<double>(k) / n);
      for (std::size_t i = 0; i < boxes.size(); ++i)
        if (boxes[i].group == group && static_cast<int>(i) != except &&
            boxes[i].nearest(x).distance < keep)
          return false;
      if (sphere && except != kSphere && (x - sphere->centre).norm() - sphere->radius < keep)
        return false;
    }
    return true;
  }
  bool clear_path(const std::vector<Eigen::Vector3d>& p, int group, int except) const {
    for (std::size_t i = 0; i + 1 < p.size(); ++i)
      if (!clear(p[i], p[i + 1], group, except)) return false;
    return true;
  }
  // From the safe height down to x: straight, or beside a box (then across under it).
  std::optional<std::vector<Eigen::Vector3d>> down_to(const Eigen::Vector3d& x, int group,
                                                      int box) const {
    auto top = [&](const Eigen::Vector3d& p) { return Eigen::Vector3d(p.x(), p.y(), safe_z); };
    std::vector<Eigen::Vector3d> sides{Eigen::Vector3d::Zero()};
    if (box >= 0)
      for (int c = 0; c < 3; ++c) {
        Eigen::Vector3d h = boxes[static_cast<std::size_t>(box)].axes.col(c);
        h.z() = 0;
        if (h.norm() > 1e-6) {
          sides.push_back(h.normalized());
          sides.push_back(-h.normalized());
        }
      }
    for (const Eigen::Vector3d h : {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY()}) {
      sides.push_back(h);
      sides.push_back(-h);
    }
    const double r = cmm.tip_radius();
    for (const auto& h : sides)
      for (const double w : {0.0, 1.0, 2.0, 4.0}) {
        if ((h.norm() == 0) != (w == 0)) continue;
        const double step = w * (r + o.clearance + 5);
        const Eigen::Vector3d beside = x + step * h;
        std::vector<Eigen::Vector3d> p{top(beside), beside, x};
        if (clear_path(p, group, -1)) return p;
      }
    return std::nullopt;
  }

  Eigen::Vector3d touch(const Eigen::Vector3d& at, const Eigen::Vector3d& direction) {
    const Eigen::Vector3d d = direction.normalized();
    const double r = cmm.tip_radius();
    // The box this face belongs to, and its group (none: the sphere).
    int box = -1;
    const bool on_sphere = sphere && std::abs((at - sphere->centre).norm() - sphere->radius) < 0.01;
    double best = r + approach + 1;
    for (std::size_t i = 0; i < boxes.size() && !on_sphere; ++i)
      if (const double dist = std::abs(boxes[i].nearest(at).distance); dist < best) {
        best = dist;
        box = static_cast<int>(i);
      }
    const int group = box >= 0 ? boxes[static_cast<std::size_t>(box)].group : -2;
    if (on_sphere) box = kSphere;
    const Eigen::Vector3d start = at - (approach + r) * d, out = at - (approach + r + o.escape) * d;
    const Eigen::Vector3d here = cmm.position();
    // Out from the last face along its normal (that face's own box excepted on this leg).
    std::vector<Eigen::Vector3d> path;
    Eigen::Vector3d from = here;
    if (touched) {
      from = here - o.escape * last_dir;
      if (!clear(here, from, last_group, last_box))
        throw Error(fmt::format("no safe way out from the face at ({:.1f}, {:.1f}, {:.1f})",
                                here.x(), here.y(), here.z()));
      path.push_back(from);
    }
    if (!clear(out, start, group, box))
      throw Error(fmt::format(
          "no safe way in to the face at ({:.1f}, {:.1f}, {:.1f}) along ({:.3f}, {:.3f}, {:.3f}): "
          "another artefact within {:g} mm of its approach",
          at.x(), at.y(), at.z(), d.x(), d.y(), d.z(), o.clearance));
    if (touched && group == last_group && clear(from, out, group, -1)) {
      // Straight across, within one position.
      path.push_back(out);
    } else {
      // Up to the safe height (stepping aside if need be), across, and down.
      const auto rise = down_to(from, touched ? last_group : -2, touched ? last_box : -1);
      const auto fall = down_to(out, group, box);
      if (!rise || !fall)
        throw Error(fmt::format(
            "no safe way to the face at ({:.1f}, {:.1f}, {:.1f}) probed along ({:.3f}, {:.3f}, "
            "{:.3f}) with {:g} mm clearance",
            at.x(), at.y(), at.z(), d.x(), d.y(), d.z(), o.clearance));
      for (auto it = rise->rbegin() + 1; it != rise->rend(); ++it) path.push_back(*it);
      for (const auto& p : *fall) path.push_back(p);
    }
    path.push_back(start);
    // The way points kept 0.5 mm inside the travel: a corrected CMM reads its limits as a little
    // beyond them (the probing start itself is where the set-up needs it).
    Eigen::Vector3d at_now = here;
    for (std::size_t i = 0; i < path.size(); ++i) {
      Eigen::Vector3d p = path[i];
      if (i + 1 < path.size())
        p = p.cwiseMax(travel.low + Eigen::Vector3d::Constant(0.5))
                .cwiseMin(travel.high - Eigen::Vector3d::Constant(0.5));
      if ((p - at_now).norm() > 1e-6) {
        cmm.move(p, o.move_speed);
        at_now = p;
      }
    }
    const auto t = cmm.measure(at, -d, approach, o.search, o.speed);
    if (!t)
      throw Error(
          fmt::format("no surface met at ({:.3f}, {:.3f}, {:.3f}) probing along ({:.3f}, "
                      "{:.3f}, {:.3f}) (error 1006): is the artefact where the set-up "
                      "says?",
                      at.x(), at.y(), at.z(), d.x(), d.y(), d.z()));
    touched = true;
    last_box = box;
    last_group = group;
    last_dir = d;
    return t->surface;
  }
};

}  // namespace

void AcceptanceProbingOptions::validate() const {
  if (!(clearance > 0) || !(escape > clearance) || !(search > 0) || !(speed > 0) ||
      !(move_speed > 0))
    throw Error(
        "acceptance probing: clearance, search and speeds must be > 0, the escape above the "
        "clearance");
}

acceptance::Touch acceptance_touch(RemoteCmm& cmm, const acceptance::Setup& setup,
                                   const acceptance::Volume& travel,
                                   const AcceptanceProbingOptions& options) {
  options.validate();
  auto p = std::make_shared<AcceptancePlanner>(cmm, options);
  p->approach = setup.approach;
  p->travel = travel;
  if (!setup.placements.empty()) p->boxes = acceptance::artefact_boxes(setup);
  if (setup.sphere) p->sphere = sim::Ball{setup.sphere->centre, setup.sphere->diameter / 2};
  double top = p->sphere ? p->sphere->centre.z() + p->sphere->radius : -INFINITY;
  for (const auto& b : p->boxes) top = std::max(top, b.top());
  // Below the top of the travel by more than a corrected CMM's reading differs from its scales.
  p->safe_z = std::min(top + cmm.tip_radius() + options.clearance, travel.high.z() - 0.5);
  if (p->safe_z < top + cmm.tip_radius())
    throw Error(
        fmt::format("the artefacts reach z = {:.1f} mm, too high for the travel ({:.1f} "
                    "mm) to pass above them",
                    top, travel.high.z()));
  return [p](const Eigen::Vector3d& at, const Eigen::Vector3d& direction) {
    return p->touch(at, direction);
  };
}

}  // namespace trueaxis::ippdme
