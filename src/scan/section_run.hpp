// Internal to trueaxis::scan: the error-tolerant flow on one section, as one object. Its free
// moves and touch points are in section_moves.cpp, the design-value scans and the decisions
// between them in controller.cpp, the autonomous scans in autonomous.cpp, what it takes from the
// sections before it and hands on in part_move.cpp.
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "section.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/sim/cmm.hpp"

namespace trueaxis::scan::detail {

// Machine time of one operation, added to a category.
template <class Fn>
auto timed(Machine& m, double& bucket, Fn&& fn) {
  const double t0 = m.time();
  struct Add {
    Machine& m;
    double& b;
    double t0;
    ~Add() { b += m.time() - t0; }
  } add{m, bucket, t0};
  return fn();
}

// Touches and scans start this far beyond the band the surface is searched in (the tolerance
// each way, mm).
constexpr double kBandMargin = 1.5;

// A section gives up a free move (the part is not where it can be reached) after this many
// unexpected touches (UnexpectedTouch).
constexpr int kMostUnexpected = 3;

// One section scanned by the error-tolerant controller (or by autonomous scanning only).
struct SectionRun {
  SectionRun(const detail::SectionContext& c, design::Section section)
      : m(c.machine),
        o(c.options),
        nominal(c.planner),
        events(c.events),
        first_move(c.first_move),
        part_move(c.part_move),
        unreachable(c.unreachable),
        rounds(c.rounds),
        guess(c.guess),
        solid_file(c.solid_file),
        touched(c.touched),
        found(c.found),
        off_design(c.off_design),
        current(std::move(section)) {}
  Machine& m;
  const ControllerOptions& o;
  const Planner& nominal;  // against the design's solid
  std::vector<Event>& events;
  bool& first_move;  // the run's first free move rises along the stylus whatever is around
  std::vector<Correction>& part_move;  // the run's rigid corrections so far (section.hpp)
  std::vector<NotReachable>& unreachable;
  std::vector<TouchRound>& rounds;     // the run's touch rounds that did not tell the part's move
  std::vector<Correction>& guess;      // the part's move as far as the run could guess it
  const std::string& solid_file;       // the part's STEP file ("" without a solid)
  std::vector<SolidTouches>& touched;  // every touch round's points so far in the run
  bool& found;                         // the run has found the part (SectionContext)
  double& off_design;                  // how far off it, at most (SectionContext)
  SectionResult r;
  design::Section current;
  // Against the solid moved by the corrections accepted for this section so far (what the
  // controller knows of where the part really is).
  std::optional<Planner> moved_planner;
  Eigen::Affine3d learnt = Eigen::Affine3d::Identity();
  // The design data changed (a correction, an overwrite) since the run checked that the ball can
  // come down to the section's ends.
  bool moved = false;
  const Planner& planner() const { return moved_planner ? *moved_planner : nominal; }

  // Free moves through waypoints whose legs the planner found clear by its margin: without a
  // stop at each waypoint where the margin leaves room for the corner the machine cuts there,
  // and (with `guard`) at the machine's guarded speed where they come within kGuardBand beyond
  // what the section keeps from the part: not the routes between touch points, which keep
  // beyond the band the surface is searched in. Where the probe stops the move on the part (a part
  // further off its design than that), the ball goes back the way it came to the last
  // waypoint it passed, `seen` takes how far off the part was met, and UnexpectedTouch is
  // thrown on.
  void through(const std::vector<Eigen::Vector3d>& way, bool guard = true);
  // The legs of a free move with their speeds: split where they enter and leave the band in
  // which the move is guarded.
  std::pair<std::vector<Eigen::Vector3d>, std::vector<double>> guarded(
      const std::vector<Eigen::Vector3d>& way, const Eigen::Vector3d& from) const;
  // About how long a free move from `from` through `way` takes (machine s): its legs at their
  // speeds, guarded where guarded, and each leg's speeding up and slowing down.
  double way_time(const std::vector<Eigen::Vector3d>& way, const Eigen::Vector3d& from) const;
  int unexpected = 0;  // unexpected touches in this section so far
  // The speed of guarded legs: the options', else the machine's (none: moves are not slowed).
  std::optional<double> guard_speed() const {
    if (o.guarded_speed > 0) return o.guarded_speed;
    return m.guarded_speed();
  }

  // A free move the planner finds: straight when clear of the part, else retract along the
  // stylus to the clearance level, across, and down, or round the part at the move's level,
  // whichever way_time() finds shorter. Where the planner finds no way (the ball
  // stands under an overhang, where a scan ended), it first moves out sideways, across the
  // stylus, to where it does (the nearest of 8 directions and 4 distances, in order).
  // `keep`: the margin to keep instead, when larger than the planner's.
  void safe_move(const Eigen::Vector3d& to, double keep = 0);

  // A free move in the section's plane from one touch start to the next (each at `reach` from
  // the design, the edge of the band the real surface is searched in), around the outside of
  // the design kRouteMargin beyond that: along the design's offset, cutting straight wherever
  // the chord keeps clear of the design.
  // The ball stands on the last touch's approach line, between the surface and `back_to` (that
  // touch's start); `from` and `to` are the samples nearest the two touches, `next_start` the
  // next touch's start.
  void route(const design::Samples& smp, const sim::Contour& design, double reach,
             Eigen::Index from, Eigen::Index to, const Eigen::Vector3d& back_to,
             const Eigen::Vector3d& next_start);

  // How design-value and autonomous scans approach, push and record.
  ScanSettings settings() const {
    ScanSettings st;
    st.pushing = o.path.pushing;
    st.active = o.active;
    st.record_spacing = o.record_spacing;
    // Start the approach beyond the band the real surface may lie in (the tolerance and 1.5 mm
    // more), so that the free move there cannot meet a part that is off its design.
    st.approach_clearance = o.tolerance + kBandMargin + approach_extra + found_extra;
    st.approach_limit = o.tolerance + 1.0;
    return st;
  }
  // Adds an event at the machine's present time.
  void log(double arc, double dl, const std::string& mode, const std::string& ev,
           const std::string& decision) {
    events.push_back({m.time(), current.name, arc, dl, mode, ev, decision});
    if (ev == "trajectory_error" || ev == "touch") seen = std::max(seen, std::abs(dl));
  }
  // How far off its design (where the corrections put it) this section's surface was found so
  // far: the largest trajectory error and touch deviation since the last accepted correction,
  // or what that correction left at its touch points (mm).
  double seen = 0;

  // Where along the section's contour (mm, [from, to] pieces in order) the stylus keeps
  // `margin` from the design's solid where the corrections put it, the ball on the path.
  std::vector<std::pair<double, double>> room_with(double margin) const;

  // Reports [from, to] (mm along the section) as not scanned, and why.
  void cut_off(double from, double to, const std::string& why);

  // Before a design-value scan: the ball must come down from above to where the scan starts
  // and ends (the reachability of the run's stretches was decided for the design data as they
  // were; a correction may have moved an end under the part, or down to the table). A closed
  // contour is started again where it can, an open stretch trimmed to where it can, the rest
  // reported as not reachable. False (the section not reachable) when nothing is left.
  bool reach_ends();

  // Design-value scan; true when it ran through within the tolerance.
  bool design_scan(Sample& stop, std::string& why);

  // Touch points along the design normals; returns the feet and touched points.
  std::pair<Eigen::Matrix3Xd, Eigen::Matrix3Xd> touch();
  // How many touch points the section's round makes: the options' count, fewer on a stretch too
  // short to hold that many a ball's diameter apart (kTouchSpacing). Below kFewestTouches no
  // correction can be fitted, and no round is made.
  int touch_count() const;

  // The 2-D test: geometric correction and autonomous scanning work in a plane section. A
  // space curve that lies in a plane becomes that plane section; any other ends the section.
  bool two_dimensional(double arc, double dl);

  // The stretch [from, to] (mm along the section, initially all of it) an autonomous scan keeps
  // to. The stylus's room was decided for the design with the planner's margin; a surface found
  // further off its design than that (less 1 mm) may stand nearer the stylus or the probe body
  // than the margin wherever the ball follows it. The scan then keeps to where the stylus has
  // that much room, and 1 mm more, from the design's solid (an open stretch: the longest such
  // piece, the rest reported not reachable), or is not made (false: a closed contour the stylus
  // could not follow all round, or nothing long enough left).
  bool autonomous_range(double& from, double& to);

  // An autonomous scan of the section (an open stretch: from near its start to near its end),
  // which becomes its measurement and, where the ball can follow it, its design data. False when
  // it failed or could not be made.
  bool autonomous();

  // A local deviation (the touch points agree with the design elsewhere, so no correction
  // fits): an autonomous scan from a little before the stop until the part is back on its
  // design, spliced into the design data, instead of following the whole contour (a 2 mm bump
  // on a 557 mm outline: ~60 mm at the autonomous speed instead of all of it). False when the
  // scans do not show the part leaving its design and coming back: the caller then scans the
  // whole contour.
  bool local_autonomous(const Sample& stop);

  // On a trajectory error where the flow would make a touch round (not one made to confirm a
  // guess), when it takes less machine time than that round and the rescan after it (estimated
  // from the speeds, the band searched and the path's design time): the rest of an open
  // stretch scanned autonomously from a smooth place at or a little before the stop, a closed
  // contour all round from near it. The design-value scan's points before that (a stretch's)
  // and the autonomous scan's are the section's measurement; the correction menu fitted to them
  // (as to a touch round's) tells where the part stands, for the sections after it and the next
  // part's design data; where none fits, the measured contour becomes the design data. False
  // (nothing done, or a scan that failed) leaves the flow to its touch round.
  bool rest_autonomous(const Sample& stop);
  // The measured contour of `samples` as the section's design data (logged): "" when it became
  // them, else why not (the ball cannot follow it; the design data stay as they were).
  std::string take_measured(const std::vector<Sample>& samples);
  // An autonomous scan of `length` mm (all round, `closed`) from `start`, approached against
  // `normal`, the ball standing there; nothing when it failed (logged as the scan `what`).
  std::optional<ScanOutcome> follow(const Eigen::Vector3d& start, const Eigen::Vector3d& normal,
                                    bool closed, double length, const std::string& what);
  // The last design-value scan's path, and its samples up to where it stopped.
  std::optional<design::ScanPath> scanned_path;
  std::vector<Sample> partial;

  // Why no scanning path can be made along s (empty if one can).
  std::string unpathable(const design::Section& s) const {
    try {
      design::make_path(s, o.path);
      return {};
    } catch (const Error& e) {
      return e.what();
    }
  }

  // Applies accepted corrections to the section's design data and to where the planner stands
  // the solid.
  void correct_by(const Eigen::Affine3d& step) {
    // The design's solid follows the corrected curve (the nominal planner already stands it at
    // the section's placement).
    detail::move_section(current, step);
    took(step);
  }
  // The design data are where `step` puts the part (moved with it, or cut from the solid moved
  // with it): the planner stands the solid there too.
  void took(const Eigen::Affine3d& step) {
    found = true;  // the part is where these corrections put it
    as_designed = false;
    // A guess of the part's move this section's touch points corrected is part of what they
    // found (learnt holds it already).
    unguessed.reset();
    approach_extra = 0;
    found_extra = 0;
    learnt = step * learnt;
    moved = true;
    moved_planner.emplace(nominal.moved(learnt));
  }

  // The section's design data where the corrections `cs` (in order) put the part, and their map:
  // moved with them when they keep its plane; cut from the part's solid moved with them when
  // they are a move of the solid (fit_solid_move) that does not keep it (detail::on_moved_solid:
  // a move across the plane changes the section's shape). Nothing when neither can be done.
  std::optional<std::pair<design::Section, Eigen::Affine3d>> placed_by(
      const std::vector<Correction>& cs) const;
  // Before the first scan: where the part stands, as the corrections an earlier section found.
  void carry_part_move();

  // Where nothing was carried: the design data (not the solid free moves are planned against)
  // moved by the run's guess of the part's move, the design-value scan's approach starting
  // further out by as much, when it then starts outside the planner's margin from the part where
  // the design puts it. A guess that holds saves the section its touch round. On a trajectory
  // error the touch points are made about the guessed design, each from a start outside that
  // margin from the part where the design puts it (touch), and every free move still keeps to
  // that part: a correction they fit, or their agreeing with the guess, makes it this section's
  // (confirm_guess); otherwise the guess is dropped (drop_guess) and the section starts again
  // from its design data, as it would have without it.
  void guess_part_move();
  // The guess does not hold: the section's design data as they were.
  void drop_guess(const Sample& stop);
  // After a dropped guess whose touch points fit no correction to the design data either: false
  // (the section not reachable) when they found the part further off its design (`curve`, the
  // section's contour) than the margin the free moves keep.
  bool beyond_margin(const Sample& stop, const sim::Contour& curve,
                     const Eigen::Matrix3Xd& touched);
  // The correction menu on a round of touch points (feet on the design data, got the surface
  // points found), each candidate logged; an accepted one applied to the section. `nominal`:
  // the round was made on design data as the design stands the part (touched_on). True when a
  // correction was applied; `local` set when the touch points agree with the design.
  // `what`: what the points are, as the log names them.
  bool fit_touches(const Sample& stop, const Eigen::Matrix3Xd& feet, const Eigen::Matrix3Xd& got,
                   bool nominal, const design::Section& touched_on, bool& local,
                   const std::string& what = "touch points");
  // After a design-value scan about the guessed design ran through: its points confirm the
  // guess where they all lie within the menu's acceptance of it and tell a move from a scale (a
  // closed contour's do): then it is where the part stands, handed on as a correction found.
  void confirm_by_points();
  bool guess_confirmed = false;
  void confirm_guess() {
    unguessed.reset();
    approach_extra = 0;
    moved_planner.emplace(nominal.moved(learnt));
  }
  std::optional<design::Section> unguessed;  // the design data before the guess
  // How much further out a design-value scan starts its approach (mm): by the guess's move, so
  // that it starts outside the band the part may be in both where the design puts it and where
  // the guess does.
  double approach_extra = 0;
  // How much further out scans and touches start since an unexpected touch found the part
  // further off its design than they allow for (mm); until a correction is applied.
  double found_extra = 0;

  // The part's move as each round of this section's own touch points told it, by the index in
  // r.corrections of the correction that round accepted.
  std::vector<std::pair<std::size_t, PartMove>> told;

  // This section's touch rounds made on its design data as the design stands the part (no
  // correction carried or applied, nothing measured put in them), with those data.
  std::vector<TouchRound> own_rounds;
  bool as_designed = true;

  // After the section: where it found the part is where the part stands for the sections after
  // it (detail::part_move_of). Where its touch points do not tell that on their own, with those
  // of earlier sections in parallel planes that did not either (detail::pooled_part_move).
  void hand_on_part_move();
  // What hand_on_part_move does in the section's plane; true when it handed a move or a guess on.
  bool hand_on_in_plane();
  // Where nothing in the plane was handed on after a touch round of this section: the part's
  // solid fitted to every touch round of the run made about the same solid (fit_solid_move),
  // the guess for the sections after it in the planes of those rounds (in_touched_plane).
  void guess_solid_move();
  bool made_round = false;  // this section made a touch round
  // The part's solid fitted to every touch round of the run made about the section's solid
  // (`points` of them); nothing when no move fits them all.
  std::optional<Correction> pooled_solid_move(Eigen::Index& points) const;
  // After the menu on a round of touch points (pooled in `touched` already) found no move or
  // turn in the plane: a move of the solid that fits them and the run's earlier ones is more
  // likely than a scale of the part (a part moved across the plane changes the section's shape,
  // and a scale along some direction may fit that locally). When one does: that move (with the
  // number of touch points it fits in `points`) and the section's design data cut from the
  // solid moved so.
  std::optional<std::pair<Correction, design::Section>> solid_instead(
      const std::vector<Correction>& tried, Eigen::Index& points) const;
  // Whether the section lies in the plane of a touch round made about its solid (where a move of
  // the solid fitted to touch points in that plane is tried, and nowhere else).
  bool in_touched_plane() const;
  static bool solid_guess(const std::vector<Correction>& cs) {
    return !cs.empty() && cs.front().type == "solid-move";
  }

  // The section's flow: design-value scans, and on a trajectory error touch points and a
  // correction, or an autonomous scan (of the whole contour, or locally round the stop), then a
  // rescan; until a scan runs through, the section is found not reachable, or a limit is met.
  void run();
};

}  // namespace trueaxis::scan::detail
