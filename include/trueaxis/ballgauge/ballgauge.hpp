// trueaxis::ballgauge — a CMM's error-vector map from 3-D ball gauges (M. Oya, H. Hokari,
// H. Tamura, "A method of improving the accuracy of the three-coordinate measuring machine, 2nd
// report: calibration method using the three-dimensional standard", Trans. JSME (C), 1988).
//
// A gauge carries balls whose centres U_i are known in the gauge frame P1-UVW: origin at its
// frame's first ball (ball 0), U towards the second, W normal to the plane of the three (any frame
// given in gauge.json is brought to this one). The three frame balls are balls 0, 1, 2 for a 3-D
// frame like Oya, Hokari and Tamura's; a ball plate listed row by row has 0, 1, 2 on one row, so
// its frame is ball 0, the far end of that row and the first ball of the row farthest from it (the
// usual 3-2-1 of a plate: for a 5 × 5 plate, balls 0, 4 and 20), or any three balls named. Each
// placement probes some of the balls; a least-squares sphere fit of the probed stylus-tip centres
// gives the measured centre x_i (machine frame, mm). The error vector at a ball is Δ_i = x_i − X_i
// (measured − true, mm); correction is X = x − Δ(x).
//
// The first placement fixes the frame by Oya, Hokari and Tamura's 3-2-1 alignment (eqs. 11–12),
// stated in the gauge's frame so that it holds in any placement (flat, upright, oblique): with
// frame balls 0, 1, 2, X_0 = x_0, ball 1's error lies along the measured line 0→1 and ball 2's in
// the measured plane of balls 0, 1, 2 (Oya, Hokari and Tamura's Δy_1 = Δz_1 = Δz_2 = 0 when the
// gauge's U, V lie along machine x, y); or by a least-squares alignment: the rigid fit of the gauge
// to all its measured centres, so that the placement's errors have no rigid-body part (smaller
// lever arms, smaller uncertainty). Every later placement is stitched (eqs. 13–14): its balls whose
// measured centres lie within the match tolerance of already-mapped measured centres take those
// points' error vectors, so their true positions X_i = x_i − Δ_i are known; the placement's
// rotation and translation follow by closed-form least squares (Kabsch, SVD) over at least three
// non-collinear shared balls, and the error vectors of its other balls follow.
//
// Uncertainty: each centre's standard uncertainty comes from its sphere fit (residual-based).
// Every error vector is kept as a first-order linear function of all measured centres (numerical
// derivatives of each placement's result, chained through the tied points), so the correlations
// that the 3-2-1 frame and each stitch create are carried, and the uncertainty grows with the
// number of stitches, as Oya, Hokari and Tamura note.
#pragma once

#include <Eigen/Core>
#include <array>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "trueaxis/map/error_map.hpp"

namespace trueaxis::ballgauge {

struct Gauge {
  double ball_diameter = 0;            // mm
  std::vector<Eigen::Vector3d> balls;  // centres in the gauge frame (mm)
  // The three balls that define the frame and the 3-2-1 alignment: origin, axis (U towards it),
  // plane (U, V in the plane of the three). Empty: frame_balls() chooses.
  std::vector<int> frame;
  // `frame` when given; otherwise balls 0, 1, 2 when they span a plane; otherwise (a plate listed
  // row by row) ball 0, the ball farthest from it on the line 0→1, and the ball farthest from that
  // line (the lowest-numbered of equals, to 1e-6 of the gauge's size).
  std::array<int, 3> frame_balls() const;
  // Throws Error: fewer than 3 balls, non-finite values, frame balls not three distinct balls of
  // the gauge, or on one line; all balls on one line.
  void validate() const;
  // The centres in Oya, Hokari and Tamura's frame P1-UVW (origin at the first frame ball).
  std::vector<Eigen::Vector3d> canonical() const;
};

// How a placement is placed in the map's frame: Oya, Hokari and Tamura's 3-2-1 alignment or a
// least-squares one (first placement only), or stitched to the map (every later placement).
enum class Alignment { ThreeTwoOne, LeastSquares, Stitch };

struct BallPoints {
  int index = 0;            // ball index in the gauge
  Eigen::Matrix3Xd points;  // probed stylus-tip centres (mm, machine frame)
  // Or the centre itself, as a CMM's software reports a ball it fitted (mm, machine frame; then
  // `points` is empty), with its standard uncertainty per component (mm) when stated: NaN
  // otherwise, and then every uncertainty that depends on it is NaN (not stated), never 0.
  std::optional<Eigen::Vector3d> centre;
  Eigen::Vector3d centre_u = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
};

struct Placement {
  std::string name;
  Alignment alignment = Alignment::Stitch;
  double tip_radius = 0;  // mm
  // The stylus this placement was probed with: its tip's offset from the ram's reference point
  // (mm, machine frame, as sim::Machine::offset), when it is not the campaign's usual one (an
  // upright plate is probed from the side with a horizontal stylus). Unset: the usual stylus
  // (ParametricOptions::offset). The angular errors move a tip by their Abbe arm, so the errors a
  // placement maps are those of its stylus: a stitch must use its frame's stylus.
  std::optional<Eigen::Vector3d> stylus_offset;
  std::vector<BallPoints> balls;
};

struct Options {
  double match_tolerance =
      1.0;              // mm: a ball is shared when its centre is this close to a mapped one
  long min_points = 5;  // probed points per ball (a sphere needs 4; 5 leaves a residual)
  // A probed point farther than this (mm) from the sphere through a ball's other points, while
  // they fit within it, is a wrong touch: refused naming it, or left out with drop_outliers.
  double outlier_tolerance = 0.02;
  bool drop_outliers = false;
  // mm: how far from a plate's plane its map is used (its errors held constant across the band).
  // An angular error of 10 µrad changes the error by 0.05 µm over 5 mm.
  double plane_band = 5.0;
};

struct MapPoint {
  std::string placement;
  int frame = 0;  // which aligned placement's frame (0: the first)
  int ball = 0;
  Eigen::Vector3d measured = Eigen::Vector3d::Zero();  // x (mm)
  Eigen::Vector3d nominal = Eigen::Vector3d::Zero();   // X = true position (mm)
  Eigen::Vector3d error = Eigen::Vector3d::Zero();     // Δ = x − X (mm)
  // Standard uncertainty of Δ (mm); NaN where it depends on a centre given without one.
  Eigen::Vector3d uncertainty = Eigen::Vector3d::Zero();
};

struct PlacementReport {
  std::string name;
  Alignment alignment = Alignment::Stitch;
  int frame = 0;  // the frame it belongs to (each aligned placement starts one)
  int balls = 0, shared = 0;
  double registration_rms = 0;       // mm, shared balls after the fit (stitch)
  double diameter_error_max = 0;     // mm, |fitted diameter − (ball + 2·tip)|, worst fitted ball
  int given_centres = 0;             // balls given as centres (no sphere fit, no diameter check)
  std::vector<std::string> dropped;  // wrong touches left out (drop_outliers), one per point
};

struct Result {
  std::vector<MapPoint> points;  // every mapped ball, first placement first
  std::vector<PlacementReport> placements;
  // Frames: each aligned placement starts one, and maps in its own 3-2-1 or least-squares frame.
  // Errors of different frames differ by a rigid motion that no ball ties down, so they form no
  // common map (a plate campaign's placements join in the 21-error model, parametric.hpp).
  int frames = 1;
  // The map as a grid, when it has one frame and the nominal positions form a full lattice
  // (coordinates clustered within the match tolerance; node coordinates are the clusters' means).
  // A plate's map, all its balls in one plane normal to a machine axis, is a grid on that plane:
  // its axis has two nodes, the plane ± Options::plane_band, with equal errors (ErrorMap::plane).
  std::optional<map::ErrorMap> grid;
  std::string summary() const;  // µm
};

// Throws Error (naming the placement and ball): unknown ball index, a ball measured twice in a
// placement, too few points on a ball, a first placement that is a stitch, a 3-2-1 placement
// without its frame balls, or with them measured on one line or at distances more than the match
// tolerance from the gauge's, or a stitch with fewer than three non-collinear balls shared with
// its frame.
Result calibrate(const Gauge& gauge, const std::vector<Placement>& placements,
                 const Options& options = {});

}  // namespace trueaxis::ballgauge
