// trueaxis::scan — error-tolerant design-value scanning: the controller that keeps a CMM
// scanning when the part is too far from its design (after Mitutoyo's method, JP 6484108 B2).
//
// For each section: scan along the path computed from the design data (fast). While the
// trajectory error ΔL stays within the tolerance, that is all. A trajectory error is |ΔL| beyond
// the tolerance, or (on a machine that reports its probe's range) a deflection near the range,
// where a surface rising faster than the servo follows would push the probe to over-travel; in
// passive scanning also a probe lifting off. On a trajectory error:
//  1. the 2-D test: a section given as a space curve (with surface normals) that does not lie
//     in one plane (a spiral over a sphere) ends in an error exit with the reason; one that
//     does is treated as that (possibly oblique) plane section from here on;
//  2. first time (flag = 0): touch points along the design normals, fit a menu of geometric
//     corrections (translation; rotation; uniform scale; scale and rotation; scale along one
//     direction — each with a translation) and keep the simplest one that brings every touch
//     point closer and leaves none further than `accept` from the corrected design; apply it to
//     this section's design data only, set flag = 1 and rescan;
//  3. no correction fits, or an error again with flag = 1: scan the section autonomously
//     (slowly, following the surface), overwrite its design data with what was measured
//     (tip radius and pushing amount compensated), set flag = 0 and rescan in design mode;
//  4. stop with an error after `max_autonomous` autonomous corrections of one section.
// The corrected design data are returned, so that the next part of a batch scans with them.
// A part is one rigid body: a translation or rotation accepted on a section whose touch points
// tell a move from a scale (a closed contour's surround it; an open stretch's must be spread
// round its curves or corners, see fit_part_move) is where the whole part stands, so it is
// carried to the sections after it whose plane it keeps (parallel sections), before they are
// first scanned (event correction_carried). What is carried is the rigid fit of those touch
// points, turn included where they show one: a move that fits a small contour within `accept`
// may leave out a turn that grows with the distance to the next section. A carried correction
// that is wrong costs a trajectory error there, and that section's own touch points then correct
// it. So that the move reaches the open stretches too (whose touch points often cannot tell it),
// the whole closed contours among consecutive sections in parallel planes with one probe
// orientation are scanned first; Result::sections is in the order scanned.
// Where the touch points could not tell the move, the rigid correction they accepted is tried on
// the next parallel sections as a guess: their design data move by it (not the solid free moves
// are planned against, and the approach starts further out by as much); a scan that runs
// through needs no touch points, and a closed contour whose points all lie within `accept` of
// the moved design makes the guess where the part stands. On a trajectory error the touch
// points are made about the guess (each from a start outside the margin of the part as
// designed); when they fit no correction, the section starts again from its design data.
//
// With the part's solid (the design's STEP file), every free move is planned against it
// (planner.hpp), the run's first move rises along the stylus before it goes anywhere (a machine
// is not trusted to stand anywhere in particular), and each section is scanned in its probe
// orientation only where the stylus reaches: a section the stylus reaches in stretches is
// scanned as those stretches (open sections named "<name>:1", "<name>:2", ...), and the rest is
// reported as not reachable, with why. A collision (or any failure of the machine) stops the
// run; the result keeps what was measured and says where and why it stopped.
//
// Units: mm, s (machine time). Every decision is logged as an Event.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "trueaxis/design/design.hpp"
#include "trueaxis/scan/machine.hpp"

namespace trueaxis::scan {

enum class Strategy { ErrorTolerant, Design, Autonomous };
const char* to_string(Strategy s);
Strategy strategy_from_string(const std::string& s);  // throws Error

struct ControllerOptions {
  Strategy strategy = Strategy::ErrorTolerant;
  design::PathOptions path;    // tip radius, pushing, tolerance and speeds of the path
  double tolerance = 1.5;      // |ΔL| allowed during design-value scanning (mm)
  int max_autonomous = 3;      // autonomous corrections per section before giving up
  bool active = true;          // active (pushing held) or passive design-value scanning
  int touch_points = 8;        // points touched for a geometric correction
  double touch_trigger = 0.3;  // deflection that records a touch (mm)
  double touch_speed = 10;     // mm/s
  double move_speed = 200;     // free moves (mm/s)
  // Free moves between sections and to a scan's start go up (machine +z) to this far above
  // the design data's highest point, across, and down; between touch points of a section they
  // follow the design outside the search band. (mm)
  double clearance = 20;
  double autonomous_speed = 12;  // mm/s
  double accept = 0.05;          // a correction must leave every touch point within this (mm)
  double record_spacing = 0.2;   // mm between recorded surface points
  Stylus stylus;                 // what carries the ball (for planning against the solid)
  // Free moves keep the ball, stylus and probe body this far from the design's solid (mm); 0:
  // the tolerance + 1 mm, room for a part that is off its design by about the tolerance (touch
  // and scan starts lie 1.5 mm beyond it).
  double margin = 0;
  // Free moves near the part (within 2 mm beyond what they keep from it) at most this fast, so
  // that the probe, meeting a part further off than that, stops the machine within its
  // overtravel (mm/s). 0: the machine's own (Machine::guarded_speed; the virtual CMM's); a
  // machine that gives none (an I++ DME server) is then not slowed.
  double guarded_speed = 0;
  // Throws Error naming the option when out of range.
  void validate() const;
};

struct Event {
  double t = 0;  // machine time (s)
  std::string section;
  double arc = 0, delta_l = 0;  // where on the path, and the trajectory error there (mm)
  std::string mode;             // design, touch, autonomous, correction, section
  // trajectory_error, touch, correction_applied, correction_rejected, correction_carried,
  // autonomous_scan, design_overwritten, design_spliced (a local deviation's measured stretch
  // put in the design data), rescan, section_done, error_exit, loop_limit,
  // two_dimensional (a space curve found to lie in a plane), not_reachable, design_moved (a
  // section not measured given the part's move found on others, for the next part), restart (a
  // closed contour started elsewhere), part_move_found (the part's move from the touch points of
  // several stretches together), part_move_guessed (the part's solid moved to fit the touch
  // points so far, tried on the sections after), rest_autonomous (the rest of a stretch scanned
  // autonomously instead of a touch round and a rescan), approach_missed (an autonomous scan's
  // approach met no surface: tried further along), unexpected_touch (the probe stopped a free
  // move on the part)
  std::string event;
  std::string decision;  // in words
};

struct Correction {
  std::string type;  // translation, rotation, scale, scale+rotation, directional-scale
  std::vector<std::pair<std::string, double>> parameters;  // named values (mm, °, factor)
  double residual_before = 0, residual_after = 0;  // max |distance| of the touch points (mm)
  bool accepted = false;
  // Why the fit is not a correction at all (empty when it is one): it diverged to a map no
  // fixture error explains (a scale outside 0.5 to 2, a turn over 45°, a move larger than the
  // contour). residual_after is NaN then, and `parameters` are where the fit stopped.
  std::string diverged;
  // The correction as a map of the design data: x -> transform · x (mm, part frame).
  Eigen::Affine3d transform = Eigen::Affine3d::Identity();
  // The section whose touch points found it, when it was carried over from there ("" when this
  // section's own touch points found it); the residuals are then those of that section.
  std::string found_on;
  // Its parameters in words, to what touch points on a CMM resolve (translations to 1 µm,
  // rotations to 1e-4°, scale to 1 ppm, directions to 1e-4), the centre of rotation and scale
  // left out: "dx 1.800 mm dy -1.100 mm dz 0.000 mm".
  std::string parameters_text() const;
};

// Machine time by activity (s). `moves` are the free moves between operations (safe-height
// moves, the route between touch points); the approach and retract within an operation count
// to that operation.
struct MachineTime {
  double total = 0, design = 0, touch = 0, autonomous = 0, moves = 0;  // s
};

// The trajectory error along one design-value scan of a section, every 0.5 mm of path (and where
// it stopped).
struct Trace {
  std::string label;                 // "design", "rescan 1", ...
  std::vector<double> arc, delta_l;  // mm
  bool completed = false;
};

struct SectionResult {
  std::string name;
  std::string source;  // the design section a stretch was cut from ("" for a whole section)
  bool ok = false;
  std::string reason;  // why it ended in an error ("" when ok)
  MachineTime time;
  std::vector<Correction> corrections;
  int autonomous_count = 0, trajectory_errors = 0;
  std::vector<Sample> points;  // the final scan's surface points
  std::vector<Trace> traces;   // ΔL of every design-value scan of the section, in order
  // The stylus reaches none of it in its probe orientation (or the head cannot take that
  // orientation): refused before any move, `reason` says why.
  bool not_reachable = false;
  // "ok", "not_reachable" or "error" (as scan.json writes it).
  const char* status() const { return ok ? "ok" : not_reachable ? "not_reachable" : "error"; }
};

// A stretch of a section's contour the stylus cannot reach in the section's probe orientation.
struct NotReachable {
  std::string section;
  double from = 0, to = 0;  // arc along the section's contour from its start (mm)
  Eigen::Vector3d start = Eigen::Vector3d::Zero(), end = Eigen::Vector3d::Zero();  // on it (mm)
  std::string why;
};

struct Result {
  std::vector<SectionResult> sections;
  std::vector<NotReachable> unreachable;
  std::vector<Event> events;
  MachineTime time;
  design::Design design;  // the design data after the corrections: input for the next part
  // What each entry of `sections` set out to scan: the design's section, or the reachable
  // stretch of it, before the run corrected it (one to one with `sections`).
  design::Design planned;
  std::string stopped;  // why the run stopped before its end ("" when it did not)
  bool ok() const;      // every section scanned (stretches not reachable aside)
  std::string summary() const;
};

// A place to start a run from: above the design's first section, clear of the part by the
// clearance (the stylus vertical).
Eigen::Vector3d start_position(const design::Design& design, const ControllerOptions& options);

// Scans every section of `design` on `machine`. `progress(index, count, name)` is called as each
// section (or reachable stretch) starts (may be empty).
using Progress = std::function<void(std::size_t, std::size_t, const std::string&)>;
Result scan(Machine& machine, const design::Design& design, const ControllerOptions& options,
            const Progress& progress = {});

// What touch points tell of where the whole part stands, to carry it to other sections.
struct PartMove {
  // The rigid fit (a turn about the contour's centroid and a move in its plane) of the touch
  // points, whichever model the menu chose for the section: a move that fits a small contour
  // within `accept` may leave out a turn that grows with the distance to the next section (a
  // 0.3° turn left out on a 64 mm slot put a contour 130 mm away 0.65 mm off). `accepted` when
  // it leaves every touch point within `accept`; to be used only where turn_resolution says the
  // touch points see a turn.
  Correction rigid;
  // How well the feet tell a move in the plane from a uniform scale: the smallest singular value
  // of the normal distances' Jacobian in (x, y, scale), the scale's column in mm (times the
  // feet's rms distance from their centroid), over the largest. 0 when some combination is not
  // seen at all: touches on one straight wall do not see a move along it, nor those on two
  // walls at a corner a scale from a move. A whole closed contour's are about 0.7.
  double resolution = 0;
  // The same for a move and a turn: 0 for touches round a circle, which no turn about its
  // centre moves (there `rigid` has the fit's round-off for a turn, and is not to be used).
  double turn_resolution = 0;
  // The standard uncertainty of rigid's turn (°) from the scatter of the touch points about it;
  // NaN when the fit is not accepted or the turn not seen. A turn within three of them is
  // nothing the touch points show.
  double turn_u = NAN;
};
PartMove fit_part_move(const design::Section& section, const Eigen::Matrix3Xd& feet,
                       const Eigen::Matrix3Xd& touched, double accept);

// The geometric-correction menu on its own. `touched` (3 × m, mm) are surface points found by
// touching along the design normals at `feet` (3 × m, points of the design curve). Returns every
// model tried, in menu order, with `accepted` set on the one chosen (at most one); `corrected`
// receives the section with that correction applied (its curve transformed, the plane kept).
// When the touch points already lie within `accept` of the design, nothing is fitted: the result
// is one entry of type "none" (the deviation is local). `move` (if given), when a correction is
// accepted, receives what the same touch points tell of the whole part (as fit_part_move,
// without preparing them again, nor fitting a turn again when the menu chose one).
std::vector<Correction> fit_corrections(const design::Section& section,
                                        const Eigen::Matrix3Xd& feet,
                                        const Eigen::Matrix3Xd& touched, double accept,
                                        design::Section* corrected, PartMove* move = nullptr);

}  // namespace trueaxis::scan
