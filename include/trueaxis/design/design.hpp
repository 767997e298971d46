// trueaxis::design — design data for scanning: planar sections of a part, as NURBS curves or
// polylines, read from CAD (STEP, through Open CASCADE Technology) or written by hand, and the
// scanning path computed from them.
//
// Units: mm. Frames: the part's (CAD) coordinates. A section is the intersection of the part
// with a plane; its curve lies in that plane. The material side is stated as seen from the
// plane's normal while walking along the curve's direction: "left" means the material lies to
// the left (so a counter-clockwise outer contour, seen from the normal, has material on its
// left). Surface normals of a section point away from the material.
//
// The scanning path is the stylus-centre path of design-value scanning: the contour offset away
// from the material by the tip radius less the pushing amount (the ball would sink that far into
// a perfect part, so the probe is deflected by the pushing amount), as a chain of parametric
// cubic curve (PCC) segments within a stated chordal tolerance, each with a speed from its
// curvature. NURBS evaluation, offsetting and STEP sectioning are done by Open CASCADE
// Technology (OCCT 7.6), from a part of the library that is loaded on first use
// (libtrueaxis_occt.so): the functions that need it throw Error if it cannot be loaded.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace trueaxis::design {

struct Plane {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit
};

// A non-uniform rational B-spline: `degree` ≥ 1, n = control_points.cols() ≥ degree + 1,
// knots: n + degree + 1 non-decreasing values (the full, "flat" vector, every repeated knot
// written out, as in STEP and most texts), weights: n positive values (all 1 = polynomial).
struct Nurbs {
  int degree = 3;
  Eigen::VectorXd knots;
  Eigen::VectorXd weights;
  Eigen::Matrix3Xd control_points;
};

enum class Side { Left, Right };
const char* to_string(Side s);

// The orientation of the probe on an indexing head (as Renishaw's PH10 family): A tilts the
// stylus from pointing straight down (A = 0°) towards horizontal (A = 90°, at most 105°); B turns
// it about the vertical, B = 0° pointing towards −Y, B = 90° towards +X (±180°). Both in steps of
// 7.5°.
struct ProbeOrientation {
  double a_deg = 0, b_deg = 0;
  bool vertical() const { return a_deg == 0; }
};
constexpr double kHeadStep = 7.5, kHeadMaxA = 105;  // degrees
// The stylus axis: the unit vector from the ball towards the head (machine frame; +Z for A = 0).
Eigen::Vector3d stylus_axis(const ProbeOrientation& o);
// What keeps the head from taking the orientation ("" if it can).
std::string head_refusal(const ProbeOrientation& o);

struct Section {
  std::string name;
  Plane plane;
  bool closed = true;  // the curve returns to its start (first and last points coincide)
  // Exactly one of the two: a NURBS curve, or a polyline (3 × n points, straight between them).
  std::optional<Nurbs> nurbs;
  Eigen::Matrix3Xd polyline;
  Side material = Side::Left;
  // A space curve instead of a plane section (e.g. a spiral over a sphere): the surface normal
  // at each polyline point (3 × n, unit, away from the material). Empty for a plane section.
  // A space curve is a polyline; `plane` and `material` do not apply to it.
  Eigen::Matrix3Xd normals;
  bool space_curve() const { return normals.cols() > 0; }
  // A section cut from CAD: the largest gap between the cut's edges (or between its last edge and
  // its first) that was closed to join them into one curve (mm; 0 when they met exactly).
  double joined_gap = 0;
  // The probe orientation the section is scanned in (default: the stylus vertical).
  ProbeOrientation probe;
  // Where the design's solid stands for this section: x_part = solid_placement · x_solid (mm).
  // The identity for data cut from the solid; a scan that corrects the section's curve by a
  // rigid or affine move (a part off in its fixture) moves it too, so that the next part of a
  // batch is planned against the solid where the corrected curve says the part is.
  Eigen::Affine3d solid_placement = Eigen::Affine3d::Identity();
};

struct Design {
  std::vector<Section> sections;
  // The part's solid: the STEP file the sections were cut from (a path; design.json holds it
  // relative to its own folder). Scanning plans every move against it and the virtual CMM
  // detects collisions with it. Empty for design data written by hand.
  std::string solid;
};

// Planarity tolerance: every control point or polyline vertex within this of its plane (mm).
constexpr double kPlanarTolerance = 1e-3;
// A closed curve's first and last points coincide within this (mm).
constexpr double kClosureTolerance = 1e-3;

// What is wrong with a section, and where: `field` is the JSON path of the offending value
// inside the section as design.json writes it ("plane/normal", "curve/nurbs/knots",
// "curve/polyline", "closed", ...), `index` the element within it (−1: the whole value).
struct Problem {
  std::string field;
  long index = -1;
  std::string what;  // one line, for a metrologist
};

// Checks a section: a normal of non-zero length (a space curve: a polyline with one non-zero
// normal per point, no plane check), a NURBS that OCCT can represent (degree 1..25,
// n + degree + 1 non-decreasing knots with interior multiplicity ≤ degree, positive weights,
// at least degree + 1 control points) or a polyline of ≥ 2 points with no two consecutive ones
// equal, all points in the plane (kPlanarTolerance), all values finite and within 1e6 mm, and a
// curve marked closed that closes (kClosureTolerance). Returns the first problem found.
std::optional<Problem> check(const Section& s);

// The 2-D test of scanning: does a space curve lie in one plane (points within
// kPlanarTolerance, surface normals in the plane within 1e-3 rad), so that it is a plane
// section after all (an oblique one, perhaps)? Returns it as one (the least-squares plane
// through its points, the material side from its normals), or nothing with `why` saying how
// far it leaves its best-fit plane. A plane section is returned as it is.
std::optional<Section> as_plane_section(const Section& s, std::string* why = nullptr);

// Arc length of a section's curve (mm): exact for a polyline, by OCCT's Gauss integration for a
// NURBS.
double length(const Section& s);

// The stretch of a plane section's curve from arc length `from` to `to` (mm, from < to; on a
// closed curve `to` may pass its end, the stretch then running on from its start), as an open
// section of the same plane, material side and probe, named `name`. Throws Error for a space
// curve or arcs outside the curve.
Section piece(const Section& s, double from, double to, const std::string& name);

// Points along the curve at (about) `spacing` mm, with their unit surface normals (in the plane,
// away from the material; a space curve's own normals, interpolated): 3 × m each. Closed curves do
// not repeat the start point. A polyline's vertices are always samples (each segment divided evenly
// at no more than `spacing`).
struct Samples {
  Eigen::Matrix3Xd points, normals;
  Eigen::VectorXd arc;  // arc length of each point from the curve's start (mm)
};
Samples sample(const Section& s, double spacing);
// The same as a polyline that is the curve within `chord_tolerance` (mm, > 0): every corner (a
// polyline's vertices, a NURBS's knots) among the points, the others at most `spacing` apart and
// added where a chord would leave the curve by more than the tolerance. `arc` is then the
// length along the polyline.
Samples sample(const Section& s, double spacing, double chord_tolerance);

// The sections of the part of a STEP file moved by x -> t·x, cut by `plane` (as cut_step makes
// them, named "", ".1", ...): the exact contours of a part that is off its design. Throws Error
// when the file cannot be read or the plane gives no contour.
Design moved_sections(const std::string& step, const Eigen::Affine3d& t, const Plane& plane);

// Sections of a STEP (AP203/AP214) part, cut by planes. The part is the union of every solid in
// the file (solids that share volume are named in `notes`). Each closed contour of a cut becomes a
// section named after its request ("<name>", or "<name>.<k>" when the plane cuts several contours,
// longest first), its curve one NURBS (lines and arcs converted exactly), oriented
// counter-clockwise seen from the plane's normal. The material side comes from the contours'
// nesting in the plane: a contour inside an even number of others bounds material on its inside,
// inside an odd number a hole. The cut's edges are joined across gaps up to the tolerance the
// file states for its geometry (ISO 10303-41 uncertainty_measure_with_unit, in mm), bounded by
// StepCutOptions; each section records the largest gap closed (Section::joined_gap).
struct StepSectionRequest {
  std::string name;  // the section's name (its contours get ".1", ".2" when there are several)
  Plane plane;
};

struct StepCutOptions {
  // The join tolerance is the file's own, but at least min_join (the round-off of exact CAD
  // arithmetic; also used when the file states none) and at most max_join (mm).
  double min_join = 1e-4, max_join = 0.1;
  void validate() const;  // throws Error naming the option: 1e-7 ≤ min_join ≤ max_join ≤ 1 mm
};

// A plane that gave no section, and why, in words: it misses the part (with the part's extent
// along its normal), lies on a flat face, only grazes the part, or its cut does not close (where,
// and by how much).
struct StepPlaneFailure {
  std::string name;
  Plane plane;
  std::string reason;
};

struct StepCut {
  Design design;                           // the sections of every plane that gave some
  std::vector<StepPlaneFailure> failures;  // the planes that gave none, in request order
  double join_tolerance = 0;               // mm: the gaps joined across
  std::optional<double> file_tolerance;    // mm: the file's stated tolerance (none: not stated)
  int solids = 0;                          // solids in the file
  std::vector<std::string> notes;          // facts about the part a user should know
  bool ok() const { return failures.empty(); }
};

// Throws Error naming the file for unreadable files and files with no solid; every plane's own
// failure is returned in `failures`, the other planes' sections still made.
StepCut cut_step(const std::string& path, const std::vector<StepSectionRequest>& planes,
                 const StepCutOptions& options = {});
// The same, throwing Error ("<file>: section '<name>': <reason>") at the first failed plane.
Design from_step(const std::string& path, const std::vector<StepSectionRequest>& planes);
// Gives each section the probe orientation of its plane in `by_plane` (keyed by the requested
// name: a plane's contours "NAME.1", "NAME.2" take NAME's); the others keep theirs.
void assign_probes(Design& design, const std::map<std::string, ProbeOrientation>& by_plane);

// ---------------------------------------------------------------------------------------------
// Scanning path: parametric cubic curve segments.

struct PathOptions {
  double tip_radius = 1.0;          // stylus ball radius (mm), > 0
  double pushing = 0.3;             // pushing amount Ep: probe deflection held on the path (mm)
  double chordal_tolerance = 1e-3;  // max distance of the PCC from the exact offset curve (mm)
  double max_speed = 100;           // scanning speed on straight or gently curved parts (mm/s)
  double min_speed = 5;             // never slower than this (mm/s)
  double max_normal_acceleration = 1000;  // v²/R limit that sets the speed on curves and at
                                          // sharp corners (mm/s²)
  // Throws Error naming the option if a value is out of range (pushing must be below the tip
  // radius; speeds positive, min ≤ max; tolerance 1e-7..1 mm).
  void validate() const;
};

// One cubic segment p(u) = a + b u + c u² + d u³, u ∈ [0, 1], of the stylus-centre path.
struct PccSegment {
  Eigen::Matrix<double, 3, 4> coeff;  // columns a, b, c, d (mm)
  double length = 0;                  // arc length (mm)
  // Scanning speed on this segment (mm/s): v²·curvature within the normal-acceleration limit;
  // on the arc round a convex corner, that of the widest arc through the same tangents that cuts
  // the corner by at most a third of the pushing amount and fits on the spans beside it.
  double speed = 0;
  double curvature = 0;  // largest curvature of the offset curve on it (1/mm)
  // The speed allowed where the segment starts, at a sharp corner of the path (the ball passing
  // from one wall to the other in a concave corner): the speed of the arc that cuts the corner
  // by a third of the pushing amount, at the normal-acceleration limit (mm/s; +inf: no corner).
  double corner_speed = INFINITY;
  Eigen::Vector3d point(double u) const {
    return coeff.col(0) + u * (coeff.col(1) + u * (coeff.col(2) + u * coeff.col(3)));
  }
  Eigen::Vector3d tangent(double u) const {  // dp/du (not unit)
    return coeff.col(1) + u * (2 * coeff.col(2) + 3 * u * coeff.col(3));
  }
};

// A point of a path at arc length s: position, unit tangent, and unit normal in the plane away
// from the material.
struct PathPoint {
  Eigen::Vector3d p, tangent, normal;
  double speed = 0;  // of the segment (mm/s)
};

struct ScanPath {
  std::string section;
  Plane plane;
  bool closed = true;
  Side material = Side::Left;  // as the section's: seen from the plane normal, along the path
  double offset = 0;           // tip radius − pushing (mm)
  std::vector<PccSegment> segments;
  // A space curve's path: the surface normal at each segment's start and at the last one's
  // end (segments.size() + 1); empty for a plane section. `plane` and `material` then do not
  // apply, and the normal along a segment is interpolated between its ends.
  std::vector<Eigen::Vector3d> space_normals;
  bool space() const { return !space_normals.empty(); }
  // Largest distance of the PCC from the exact offset curve, measured at 16 points per segment
  // after the fit (mm): the achieved chordal error.
  double chordal_error = 0;
  double length() const;
  // Design time along the path at each segment's speed (s), without acceleration phases.
  double nominal_time() const;
  // The point at arc length s (clamped to [0, length()]): the segment's parameter found from its
  // arc length.
  PathPoint at(double s) const;

 private:
  mutable std::vector<double> cumulative_;  // segment start arcs, built on first use
  mutable std::size_t last_ = 0;
};

// The stylus-centre path of design-value scanning for one section. Throws Error if the offset
// cannot be made (e.g. a tip too large for a concave corner or a narrow slot of the section).
// A space curve's path is each point moved along its surface normal, straight between them
// (the design's own polyline, so no chordal error), each segment's speed from the turning of
// the path at its ends.
ScanPath make_path(const Section& s, const PathOptions& options = {});

}  // namespace trueaxis::design
