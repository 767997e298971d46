// Internal to trueaxis::scan: the error-tolerant flow on one section (controller.cpp), called by
// the run over all sections (run.cpp).
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "trueaxis/scan/controller.hpp"
#include "trueaxis/scan/planner.hpp"
#include "trueaxis/sim/cmm.hpp"

namespace trueaxis::scan::detail {

// One round of touch points on a section's design data: the feet on the design and the surface
// points found along the design normals there (3 x m each, mm, the part's design frame).
struct TouchRound {
  design::Section section;
  Eigen::Matrix3Xd feet, touched;
};

// The surface points one touch round found (3 x m, mm, the part's frame), with the solid the
// planner stood the part's design at when they were made (the solid they are fitted against).
struct SolidTouches {
  const solid::Mesh* solid = nullptr;
  std::string section;
  design::Plane plane;  // the section's
  Eigen::Matrix3Xd points;
};

struct SectionContext {
  Machine& machine;
  const ControllerOptions& options;
  const Planner& planner;
  std::vector<Event>& events;
  bool& first_move;        // the run's first free move rises along the stylus first
  SectionResult& partial;  // receives what was measured when the section throws
  // Where the part stands, as the rigid corrections (translation, rotation) the last corrected
  // section accepted: carried to a section whose plane they keep before it is first scanned, and
  // replaced by that section's when it accepts corrections of its own that are all rigid.
  std::vector<Correction>& part_move;
  // The run's stretches not reachable: a section adds what a correction moved out of reach.
  std::vector<NotReachable>& unreachable;
  // Touch rounds made on design data where the design puts the part, whose sections could not
  // tell the part's move on their own (pooled_part_move): kept until one tells it.
  std::vector<TouchRound>& rounds;
  // The part's move as the last section's touch points suggest it where they could not tell it
  // (a move from a scale): rigid corrections, tried on the next sections in parallel planes
  // before their own touch points are made (SectionRun::guess_part_move).
  std::vector<Correction>& guess;
  // The STEP file of the part's solid ("" without one), and every touch round's points so far
  // (fit_solid_move).
  const std::string& solid_file;
  std::vector<SolidTouches>& touched;
  // The run has found the part where its design data put it (a design-value scan ran through, a
  // correction was accepted, a section was measured): until then nothing bounds how far off its
  // design the part was placed, and free moves are guarded further out.
  bool& found;
  // The most this run found the part off its design data, where its sections' corrections put
  // it, by the probe stopping a free move or by a whole autonomous scan (mm): free moves of later
  // sections are guarded that far out too. A part 5 mm off met on one section is as far off on
  // the next, which autonomous scanning does not correct for.
  double& off_design;
};

// A reachable stretch shorter than this is not scanned (mm): nothing to follow.
inline constexpr double kShortest = 2.0;

// A geometric correction is fitted to this many touch points or more: with fewer, the menu's
// four-parameter candidates (translation, rotation and a scale in the plane) are not over-
// determined and their residuals tell nothing.
inline constexpr int kFewestTouches = 4;
// Touch points of one round stand at least this many ball diameters apart along the contour.
// Nearer ones touch what their neighbours did, within the ball's own contact patch, and add
// little to the fit for about 0.75 s of machine time each (a 4.9 mm stretch took 8 touch points
// 0.64 mm apart, 6.3 s, and none of the fits they gave was accepted).
inline constexpr double kTouchSpacing = 1.0;

// Where the ball can come down along the stylus, from above the part, to the approach distance
// off a stretch's path at both its ends: [a, b] (mm along the section's contour) moved in from
// the given ends, 0.5 mm at a time, until it can. Nothing when less than kShortest is left.
std::optional<std::pair<double, double>> reachable_ends(const design::Section& s, double a,
                                                        double b, const Planner& planner,
                                                        const ControllerOptions& o,
                                                        double approach);
// Where along a closed contour (mm from its start, in 1 mm steps) the ball can come down to it
// to start scanning; nothing when it can nowhere.
std::optional<double> reachable_start(const design::Section& s, const Planner& planner,
                                      const ControllerOptions& o, double approach);
// The closed contour s started `a` mm along it (s itself at 0).
design::Section started_at(const design::Section& s, double a);
// The point of s's samples nearest `arc` mm along it (wrapped round a closed contour, clamped to
// an open one's ends).
Eigen::Vector3d point_at(const design::Section& s, const design::Samples& smp, double arc);
// Where along the contour (mm, its samples' arc) the ball's centre stands `along` mm along the
// path offset from it: the sample nearest the path point's foot on the contour.
double contour_arc(const design::Samples& smp, const design::ScanPath& path, double along);

// The measured section as design data: the samples' surface points as a polyline in the
// section's plane, thinned to the vertices that keep every point within 2 µm of it.
design::Section overwrite(const design::Section& s, const std::vector<Sample>& samples);

// A local deviation measured and spliced into a closed contour's design data.
struct Splice {
  design::Section section;  // the design with the measured stretch in place of [from, to]
  double from = 0, to = 0;  // where the part leaves the design and rejoins it (mm along it)
  double largest = 0;       // the largest deviation from the design in between (mm)
};
// Where an autonomous scan through `at` (mm along the design, where a trajectory error stopped
// the design-value scan) leaves the design by `rejoin` mm or more and comes back within it for
// 2 mm: the design with the measured points in between (thinned as overwrite does). Nothing when
// the scan does not show both ends of the deviation, or for an open or space-curve section.
std::optional<Splice> splice(const design::Section& s, const std::vector<Sample>& samples,
                             double at, double rejoin);

// Touch points tell where the whole part stands (its move, and a turn or a scale) when they
// tell them apart at least this well (PartMove::resolution; a closed contour's are about 0.7):
// a parameter is then known to within ten times what it would be from well-spread points.
inline constexpr double kTellsPart = 0.1;

// A plane section's curve as a contour for distance queries, sampled every `spacing` mm (chords
// within spacing²/8R of the curve: 0.3 µm at R = 1 mm for the default).
sim::Contour contour_of(const design::Section& s, double spacing = 0.05);
// The section's design data moved by x -> step·x: its curve, and where its solid stands.
void move_section(design::Section& s, const Eigen::Affine3d& step);
// Whether t maps the section's plane onto itself (a move in it, a turn about its normal), as a
// correction found on a parallel section does.
bool keeps_plane(const design::Section& s, const Eigen::Affine3d& t);

// The rigid corrections a section's run leaves as where the part stands, for the sections after
// it: all its accepted corrections (those carried to it and its own; `told` gives, by their
// index in `corrections`, what each round of its own touch points told of the part). Nothing
// when one of them is not rigid, none is its own, or an open stretch's touch points do not tell
// a move from a scale (kTellsPart): one straight wall's do not see a move along it, and two
// walls at a corner do not tell a scale from a move, which is wrong for the wall opposite
// (carried there, it put the planned moves 4 mm off the part); a closed contour's surround it.
// Each own correction is handed on as the rigid fit of its touch points where they show a turn
// (one a move fitted to a small contour leaves out, and that grows with the distance to the
// next section): a turn they see (round a circle they see none) and larger than three of its
// standard uncertainties. Otherwise the menu's own correction is handed on.
std::optional<std::vector<Correction>> part_move_of(
    const std::vector<Correction>& corrections,
    const std::vector<std::pair<std::size_t, PartMove>>& told, bool closed,
    const std::string& name);

// The rigid move of the part's solid (x_part = transform · x_solid, about every axis) that puts
// every point (touched surface points, mm, the part's frame) on its surface: Gauss–Newton on the
// points' signed distances from the solid, in which only what the points resolve moves (the
// normal equations' eigenvectors whose eigenvalue per point reaches 0.03²; a move along the
// walls they touched, or a turn they do not see, stays zero). Touch points in one plane may fit
// other moves alike (the mirror image of the move across a plane the part is symmetric about):
// the result is a move that fits, not necessarily the part's. A correction of type
// "solid-move" (parameters dx, dy, dz in mm and the turn as a rotation vector, turn_x..z in °)
// when it leaves every point within `accept` of the moved solid, some were farther before, the
// points are at least three more than what they resolve, and the move is one a fixture error
// makes (within 20 mm and 5°). Nothing otherwise.
std::optional<Correction> fit_solid_move(const solid::Mesh& solid, const Eigen::Matrix3Xd& points,
                                         double accept, const std::string& found_on);

// The part of a rigid move that keeps the plane: its turn about the plane's normal and where it
// takes the plane's origin, in the plane. Touch points in the plane tell that part of a move of
// the solid without the ambiguity of its move across the plane and its tilts (a mirror image).
Eigen::Affine3d in_plane_part(const Eigen::Affine3d& move, const design::Plane& plane);

// Section s's design data where the part's solid (the STEP file `step`, which s.solid_placement
// places for s) moved by `move` meets s's plane, exactly as Open CASCADE cuts it: of the moved
// solid's contours there, the one nearest s's design moved by `move`, started where s's start
// moved to (a closed contour) or cut between where its ends moved to (a stretch). Its
// solid_placement is in_plane_part(move) · s.solid_placement. Nothing when no contour stands for
// it.
std::optional<design::Section> on_moved_solid(const design::Section& s, const std::string& step,
                                              const Eigen::Affine3d& move);

// The part's rigid move (a move in the plane, and a turn about its normal where the touch points
// see one) that the touch rounds of several sections in parallel planes tell together, when none
// tells it alone: two stretches of a contour cut by what the stylus cannot reach, each seeing one
// wall, tell a move from a scale together. Fitted to the touch points' normal distances from each
// section's design (Gauss-Newton, the feet refined on the moved design as the menu does).
// Nothing unless the rounds' planes are parallel, their touch points tell a move from a scale
// (kTellsPart), and the move leaves every one within `accept` of its section's moved design.
// `found_on` names the correction's sections.
std::optional<Correction> pooled_part_move(const std::vector<TouchRound>& rounds, double accept,
                                           const std::string& found_on);

// Where along a section (mm from its start, in order) its k touch points go. Evenly spread (a
// closed contour's at the middles of k equal pieces, an open stretch's from 5 % to 95 % of it),
// unless those do not tell the part's move, turn and scale apart (their resolution, as
// PartMove's, below `least`): a stretch that is one long wall between two short legs gets them
// all on the wall, which does not see a move along it. Then places are exchanged, one at a
// time, for those among every 0.5 mm of the section (1 mm clear of an open stretch's ends, off
// its corners, 1 mm from each other) that raise the resolution most, when that brings it to
// `least`. `usable` (when given) says whether the ball can get to the touch start for a foot on
// the design with its normal there: places it cannot are taken to the nearest one it can, and
// never exchanged for.
struct TouchPlaces {
  std::vector<double> arcs;
  bool even = true;  // the evenly spread places
  double resolution = 0, even_resolution = 0;
  int unreachable = 0;  // even places the ball cannot get to (moved, or left out)
};
using Usable = std::function<bool(const Eigen::Vector3d& foot, const Eigen::Vector3d& normal)>;
TouchPlaces touch_places(const design::Section& s, int k, double least, const Usable& usable = {});

// Scans `section` (its design data are corrected in place) and returns its result. Throws what
// the machine throws (a collision); `partial` then holds what was measured until then.
SectionResult run_section(const SectionContext& context, design::Section& section);

}  // namespace trueaxis::scan::detail
