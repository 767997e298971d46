// trueaxis::sim — a ball gauge probed on the virtual CMM (sim/machine.hpp).
//
// Each placement sets the gauge at a pose (rotation, translation: X_i = R·U_i + t, mm). Every
// ball is probed at `points_per_ball` directions spread over a hemisphere (the pose's pole, from
// above unless stated, then rings), with the pose's stylus; the stylus-tip centre must reach P =
// X_i + (ball radius + tip radius)·d, so the machine is commanded to c with actual(c) = P (solved
// by fixed-point iteration, |∇e| ≪ 1), and the CMM reports its nominal tip position c + offset,
// plus probing noise.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "trueaxis/ballgauge/ballgauge.hpp"
#include "trueaxis/ballgauge/lengths.hpp"
#include "trueaxis/sim/cmm.hpp"
#include "trueaxis/sim/machine.hpp"

namespace trueaxis::sim {

struct GaugePose {
  std::string name;
  ballgauge::Alignment alignment = ballgauge::Alignment::Stitch;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // gauge frame → machine frame
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();   // mm
  std::vector<int> balls;                                  // probed balls (empty: all)
  // The hemisphere each ball is probed on: its pole (unit, machine frame). +Z: from above; an
  // upright plate is probed from the side.
  Eigen::Vector3d pole = Eigen::Vector3d::UnitZ();
  // The stylus it is probed with: its tip's offset from the ram's reference point (mm, as
  // Machine::offset). Unset: the machine's.
  std::optional<Eigen::Vector3d> stylus_offset;
};

struct BallGaugeOptions {
  int points_per_ball = 10;
  double tip_radius = 1.5;  // mm
  double noise = 0;         // mm, per coordinate of every probed point
  std::uint64_t seed = 1;
  void validate() const;  // throws Error
};

struct BallGaugeCampaign {
  std::vector<ballgauge::Placement> placements;
  // Per placement, per probed ball (same order): the true centre X (mm).
  std::vector<std::vector<Eigen::Vector3d>> true_centres;
  // The box of all true centres (mm): where the map lies, e.g. for GaugeBlockOptions::lo, hi.
  void bounds(Eigen::Vector3d& lo, Eigen::Vector3d& hi) const;
};

// A 3-D ball frame like that of Oya, Hokari, Tamura (1988): nx × ny × nz balls at `pitch` (mm);
// balls 0, 1, 2 at (0,0,0), (pitch,0,0), (0,pitch,0), the rest in row order.
ballgauge::Gauge frame_gauge(int nx = 5, int ny = 4, int nz = 2, double pitch = 80,
                             double ball_diameter = 25);
// `sections` placements of that frame stacked along z by (nz − 1)·pitch, each sharing a layer of
// balls with the one below; the first uses the 3-2-1 alignment. `origin` is ball 0's true
// position in the first placement; `rotation` the gauge's (small) misalignment.
std::vector<GaugePose> stacked_poses(const ballgauge::Gauge& gauge, int sections,
                                     const Eigen::Vector3d& origin,
                                     const Eigen::Matrix3d& rotation = Eigen::Matrix3d::Identity());

// A ball plate: rows × columns balls at `pitch` (mm) in the gauge's UV plane, numbered row by
// row from ball 0 (its 3-2-1 frame: ball 0, the end of the first row, the first ball of the last
// row; ballgauge::Gauge::frame_balls).
ballgauge::Gauge plate_gauge(int rows = 5, int columns = 5, double pitch = 133,
                             double ball_diameter = 22);
// A plate campaign on `machine`: the plate flat (XY) near the bottom and near the top of the
// box its stylus reaches, upright along X (XZ) and along Y (YZ), each aligned 3-2-1 by itself;
// `rotation` is each placement's small misalignment. The flat placements are probed from above
// with the machine's stylus. With `from_the_side`, each upright plate is probed as a real one is,
// from the side with the stylus turned horizontal towards it (an articulating head at A = 90°:
// the same length |offset|, its rotation centre at the ram's reference point), from both sides
// (two placements, "XZ from -Y" and "XZ from +Y"): from one side only, a scale error along Z and
// the ram's pitch and yaw growing along Z move the horizontal tip alike, and the vertical stylus
// of the flat placements cannot tell them apart either. Otherwise the upright plates are probed
// from above like the flat ones. Each plate stands in the middle of the box that all its styli
// reach with `margin` (mm) to the command range. Throws Error when the plate does not fit.
std::vector<GaugePose> plate_poses(const ballgauge::Gauge& plate, const Machine& machine,
                                   double margin = 30,
                                   const Eigen::Matrix3d& rotation = Eigen::Matrix3d::Identity(),
                                   bool from_the_side = true);

// A ball-gauge campaign as a user sets one up. Either the frame gauge (frame_gauge) in
// `placements` placements stacked in z (stacked_poses) from `origin`, or, with plate_rows and
// plate_columns, a plate of that many balls at `pitch` in its four (or five) placements in the
// machine's reach (plate_poses; the upright ones probed from the side unless `from_above`). Each
// placement is misaligned by `misalignment` (rad) about a fixed oblique axis, as a gauge set
// down by hand is; the first frame placement (every plate placement) is aligned 3-2-1, or by
// least squares with `least_squares`.
struct BallGaugeSetup {
  int plate_rows = 0, plate_columns = 0;  // 0: the frame gauge
  double pitch = 100;                     // mm, of the plate
  int placements = 3;                     // of the frame
  Eigen::Vector3d origin{150, 120, 60};   // mm, ball 0 of the first frame placement
  double misalignment = 4e-3;             // rad
  bool least_squares = false;
  bool from_above = false;  // probe upright plates from above (a CMM's one stylus)
  void validate() const;    // throws Error
};

struct BallGaugeLayout {
  ballgauge::Gauge gauge;
  std::vector<GaugePose> poses;
  std::string description;  // "a 40-ball frame gauge", "a 5x5 ball plate at 100 mm pitch (...)"
};

// Throws Error for an invalid set-up or a plate that does not fit the machine.
BallGaugeLayout ballgauge_setup(const Machine& machine, const BallGaugeSetup& setup);

// A plate's size as written, "5x5" (ROWSxCOLUMNS, 2 … 100 each), into setup's plate_rows and
// plate_columns; false (setup unchanged) for anything else.
bool parse_plate(const std::string& text, BallGaugeSetup& setup);

// What a campaign was measured against: each probed ball's true centre and the machine's error
// there (actual − nominal at the command that puts the stylus it was probed with on it; mm), in
// the order of the placements and their balls.
struct BallGaugeTruth {
  std::vector<int> placement, ball;  // placement index, ball index in the gauge
  Eigen::Matrix3Xd centre, error;    // mm
};
BallGaugeTruth ballgauge_truth(const Machine& machine, const BallGaugeCampaign& campaign);

// `gauge.balls` are used as given (gauge frame); poses map them into the machine.
BallGaugeCampaign simulate_ballgauge(const Machine& machine, const ballgauge::Gauge& gauge,
                                     const std::vector<GaugePose>& poses,
                                     const BallGaugeOptions& options);

// One probing of a ball: the stylus-tip centre as the CMM reads it (mm, machine frame) when the
// tip touches the ball of true centre `centre` where the unit `direction` leaves it (the tip
// centre then nominally at centre + reach·direction, reach = ball radius + tip radius). `what`
// names the ball for messages. Throws Error when the probing fails.
using BallProbe =
    std::function<Eigen::Vector3d(const Eigen::Vector3d& centre, double reach,
                                  const Eigen::Vector3d& direction, const std::string& what)>;

// The same campaign with any probe (e.g. a CMM over I++ DME): each pose's balls in order, each
// probed at options.points_per_ball directions over the hemisphere of the pose's pole (the pole,
// then rings at 40° and 75° from it, in order round each ring). The probe is the one stylus the
// poses' stylus_offset names (it is copied into the placements, not applied). options.noise and
// seed are not used: the probe's readings are what they are.
BallGaugeCampaign measure_ballgauge(const ballgauge::Gauge& gauge,
                                    const std::vector<GaugePose>& poses,
                                    const BallGaugeOptions& options, const BallProbe& probe);

// Where the gauge's balls stand over all its poses (true centres, machine frame): each ball once,
// those that two poses share (within 1e-6 mm) merged. For a server's world (EngineOptions::balls)
// and for moving around the gauge.
std::vector<Ball> gauge_balls(const ballgauge::Gauge& gauge, const std::vector<GaugePose>& poses);

// Gauge blocks (or any calibrated lengths) measured on the virtual CMM, ISO 10360-2 style: seven
// positions through the centre of the box [lo, hi] (true positions, mm) — along x, y, z and the
// box's four space diagonals — each length measured `repeats` times. A block from A to B = A +
// L·d is probed once on each end face: the stylus tip centre must reach A − r·d (and B + r·d),
// the machine is commanded there as in simulate_ballgauge, and the CMM reports its nominal tip
// position plus probing noise, then adds back the tip radius along d: a = reading + r·d.
struct GaugeBlockOptions {
  Eigen::Vector3d lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Zero();  // mm
  // Lengths (mm); those that do not fit a position (with `margin` to the box) are left out there.
  // Empty: five per position, 30 … 90 % of the room along it (whole mm).
  std::vector<double> lengths;
  int repeats = 3;
  double margin = 5;        // mm from the box faces
  double tip_radius = 1.5;  // mm
  double noise = 0;         // mm, per coordinate of every probed point
  std::uint64_t seed = 1;
  void validate() const;  // throws Error
};

struct GaugeBlockCampaign {
  std::vector<ballgauge::LengthMeasurement> lengths;
  std::vector<std::string> position;            // per length: "x", "y", "z", "+x+y+z", ...
  std::vector<Eigen::Vector3d> true_a, true_b;  // per length: true end points (mm)
};

GaugeBlockCampaign simulate_gauge_blocks(const Machine& machine, const GaugeBlockOptions& options);

// Gauge blocks held out from a campaign (simulate_gauge_blocks' lo, hi): the box of the mapped
// ball centres, within the span of axis commands the campaign covered with the machine's own
// stylus (where a model identified from it holds; placements probed with other styli cover
// other spans). Other options stay as given.
GaugeBlockOptions held_out_blocks(const Machine& machine, const BallGaugeCampaign& campaign,
                                  GaugeBlockOptions options = {});

}  // namespace trueaxis::sim
