// trueaxis::scan — motion planning against the part's solid: free moves of the stylus that never
// pass through the part, and the stretches of a scanning path the stylus can reach in a given
// orientation.
//
// What a CMM program does: a free move goes straight when the ball, the stylus and the probe body
// keep a margin from the part all the way; otherwise either the stylus retracts along its own axis
// to a clearance level above everything under the move, crosses there, and comes back down along
// its axis, or it goes round the part at the move's level through intermediate points, whichever
// the caller finds costs less (a retract over a tall part costs more than a way round it). A
// stretch of a path is reachable when, with the ball on the path, nothing but the faces the ball
// measures comes within a margin of the ball, and nothing at all within a margin of the stylus or
// the body (a vertical stylus cannot reach under the part).
//
// Units: mm. Frame: the part's design frame (the solid is the design's, not the real part: the
// margins absorb what the part may be off). Stylus positions are ball centres; `axis` is the unit
// vector from the ball towards the head.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "trueaxis/design/design.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/scan/machine.hpp"
#include "trueaxis/solid/mesh.hpp"

namespace trueaxis::scan {

// A move the planner finds no free way for: the machine has not moved, the section cannot be
// scanned, the run can go on.
class NoWay : public Error {
 public:
  using Error::Error;
};

class Planner {
 public:
  // `part` may be null (design data without a solid): then route() always goes over the top, at
  // `fallback_top` along the axis plus the clearance, and clear() finds every move clear (the
  // caller keeps clear of the sections it knows).
  Planner(std::shared_ptr<const solid::Mesh> part, double tip_radius, const Stylus& stylus,
          double margin, double clearance, double fallback_top);

  // The least clearance of the ball, stylus and body (and the table under the part) with the
  // ball centre at c: how far any of them is from the part (mm; negative: inside). Faces with
  // skip[face] set do not count for the ball.
  double clearance(const Eigen::Vector3d& c, const Eigen::Vector3d& axis,
                   const std::vector<char>& skip = {}) const;
  // The same from the part alone, the table left out (a part off its design stands on the
  // table as the design does).
  double part_clearance(const Eigen::Vector3d& c, const Eigen::Vector3d& axis) const;
  // Whether the straight move from a to b keeps every element `margin` from the part (checked
  // by conservative advancement: a step never longer than the clearance less the margin).
  bool clear(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& axis,
             double margin) const;
  // What a way costs (the points to move to from a, b last): the caller's estimate of its time,
  // or by default its length (mm). A way of length L costs at least `least_per_mm`·L (with the
  // default cost, 1): ways round the part too long to cost less than over the top are not
  // looked at.
  using WayCost = std::function<double(const std::vector<Eigen::Vector3d>&)>;
  // The length of a way from a through its points (mm): the default cost.
  static double length(const Eigen::Vector3d& a, const std::vector<Eigen::Vector3d>& way);
  // The way from a to b as the points to move to (b last). `rise` forces the retract along the
  // axis first (the start of a run: a machine is not trusted to stand anywhere in particular).
  // A start nearer the part than the margin (the ball just left a surface) first backs away from
  // the part, up the clearance's slope, until the margin is reached. Where the straight move is
  // not clear, the way over the top competes with ways round the part at the move's own level
  // (out across the move, along it, and in: a CMM program's intermediate points), and the one
  // that costs least is taken. Throws NoWay saying which leg the part blocks.
  std::vector<Eigen::Vector3d> route(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                     const Eigen::Vector3d& axis, bool rise = false,
                                     const WayCost& cost = {}, double least_per_mm = 1) const;

  // Arcs of a scanning path (mm along it) the stylus cannot reach in orientation `axis`, each
  // with the reason, every `step` mm; the ball may touch the faces crossing the path's plane.
  // The part is taken off its design by the margin in eight directions in the plane, and across
  // the plane as far as a move on the table (x and y, not z) takes it, every 0.2 mm.
  struct Blocked {
    double from = 0, to = 0;
    std::string why;
  };
  std::vector<Blocked> unreachable(const design::ScanPath& path, const Eigen::Vector3d& axis,
                                   double step = 0.5) const;
  // Whether the ball can come down along the axis from above the part to c, keeping the margin.
  bool from_above(const Eigen::Vector3d& c, const Eigen::Vector3d& axis) const;

  // The same planner for the part moved by x -> t·x (what a geometric correction learnt of it).
  // The identity map moves nothing (the same mesh is shared).
  Planner moved(const Eigen::Affine3d& t) const;
  // The same planner keeping `margin` instead (mm > 0): room for a part found further off its
  // design than the margin it was made with allowed for.
  Planner with_margin(double margin) const {
    Planner p = *this;
    p.margin_ = margin;
    return p;
  }
  // Where this planner stands the design's solid: the product of the moves made so far.
  const Eigen::Affine3d& placement() const { return placement_; }

  // The faces of the part that cross a plane (the ones a ball scanning in it may touch).
  std::vector<char> faces_crossing(const design::Plane& plane) const;
  const std::shared_ptr<const solid::Mesh>& part() const { return part_; }
  double margin() const { return margin_; }

 private:
  std::shared_ptr<const solid::Mesh> part_;
  double r_, margin_, clearance_, fallback_top_;
  Stylus stylus_;
  double table_z_ = -INFINITY;
  Eigen::Affine3d placement_ = Eigen::Affine3d::Identity();
  // Clearance of each element (0 ball, 1 stylus, 2 body) over the ball centres from lo to hi
  // along the axis (lo == hi: one place); a clearance beyond `look` mm (by default the margin
  // and a lookout of 20 mm) counts as that far.
  double element(int k, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                 const Eigen::Vector3d& axis, const std::vector<char>& skip, double look = -1,
                 bool table = true) const;
  // The least clearance of the ball, stylus and body (no face skipped) over a move from a to b
  // along the unit axis u itself.
  double swept_along_axis(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                          const Eigen::Vector3d& u) const;
  // The way from start (a after backing away) up along the axis, across above the part and down.
  std::vector<Eigen::Vector3d> over_the_top(const Eigen::Vector3d& a, const Eigen::Vector3d& start,
                                            const Eigen::Vector3d& b,
                                            const Eigen::Vector3d& u) const;
  // Ways from a to b round the part at the move's level, clear by the margin, none longer than
  // `longest` (mm): the shortest of each offset across the move.
  std::vector<std::vector<Eigen::Vector3d>> round_about(const Eigen::Vector3d& a,
                                                        const Eigen::Vector3d& b,
                                                        const Eigen::Vector3d& u,
                                                        double longest) const;
};

}  // namespace trueaxis::scan
