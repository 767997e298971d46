// trueaxis::acceptance — the acceptance and reverification tests of a CMM: the length measuring
// error E0 (and E150 with a stylus offset) and the repeatability range R0 of ISO 10360-2:2009,
// and the probing errors PForm and PSize of ISO 10360-5:2010 on a reference sphere.
//
// The artefacts stand where the user set them up, in the machine's coordinates (mm). A point is
// measured by a Touch: any CMM, the virtual one in process (virtual_touch) or one over I++ DME.
//
// ISO 10360-2: every placement of a calibrated length (a gauge block from its certificate) is
// probed bidirectionally, once on each measuring face from outside, `repetitions` times; the
// measured length is the distance of the two points along the placement's direction, and its
// error E = measured − calibrated length. The placements that lie along one line make one of
// the standard's positions (4 space diagonals and 3 more, 5 lengths each, the longest at least
// 66 % of the travel along the line: on a space diagonal, of the volume's space diagonal). R0 is
// the range of a length's repetitions at a position. Test uncertainty (ISO/TS 23165:2006's
// contributors, k = 2): the length's calibration, its temperature (L·α·u(T)) and expansion
// coefficient (L·u(α)·|T − 20 °C|), the alignment and the fixturing; the CMM's own repeatability is
// not in it (it is what is tested). Decision rule (ISO 14253-1): conformance is proven when every
// |E| ≤ MPE − U, non-conformance when some |E| > MPE + U; between, neither is proven. E_L (E150):
// the same test with the stylus tip offset across the ram (150 mm), in two positions; the
// carriages' rotations then move the tip by their angle times the offset (an Abbe error).
//
// ISO 10360-5: 25 points on the reference sphere in the standard's pattern (the pole, 4 points
// at 22.5° from it, 8 at 45°, 4 at 67.5° and 8 on the equator, each ring turned 22.5° from the
// one before), the least-squares sphere (ISO 10360-6) through them; PForm is the range of the
// radial distances, PSize the least-squares diameter less the calibrated one. Test uncertainty:
// the sphere's own form from its certificate (U(PForm) = F) and its diameter's calibration
// (U(PSize) = 2·u(D)).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "trueaxis/ballgauge/lengths.hpp"
#include "trueaxis/sim/cmm.hpp"
#include "trueaxis/sim/machine.hpp"

namespace trueaxis::acceptance {

// A calibrated length from its certificate.
struct GaugeBlock {
  std::string id;          // as the certificate names it
  double length = 0;       // mm at 20 °C, > 0
  double u = 0;            // mm, standard uncertainty of the calibration, ≥ 0
  double alpha = 11.5e-6;  // 1/K, expansion coefficient (steel)
  double u_alpha = 1e-6;   // 1/K
};

// A block as set up: its measuring faces' centres at centre ∓ length/2·direction (mm, machine
// coordinates), each probed from outside (face A along +direction, face B along −direction).
struct Placement {
  std::string block;     // GaugeBlock::id
  std::string position;  // the line's name; empty: found from the placements' directions
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::UnitX();  // unit
};

// The reference sphere of ISO 10360-5, from its certificate.
struct ReferenceSphere {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // mm, machine coordinates
  double diameter = 25;                              // mm
  double u_diameter = 0;                             // mm, standard uncertainty
  double form = 0;                                   // mm, its form error
  Eigen::Vector3d pole = Eigen::Vector3d::UnitZ();   // unit: where the pattern starts
};

struct Setup {
  std::vector<GaugeBlock> blocks;
  std::vector<Placement> placements;
  std::optional<ReferenceSphere> sphere;
  double temperature = 20;     // °C, the artefacts'
  double u_temperature = 0.2;  // K
  double u_alignment = 0;      // mm, standard uncertainty of a length from its alignment
  double u_fixturing = 0;      // mm, from how it is supported (bending, clamping)
  // The blocks' cross-section (mm), as a long gauge block's: block_width across the line
  // (horizontal where the line is not vertical) and block_height across both; two placements of
  // a position must not come closer than block_width.
  double block_width = 35;
  double block_height = 9;
  double approach = 5;  // mm: a face is approached from this far out
  int repetitions = 3;
  // Throws Error naming the first problem (a placement of an unknown block, a direction that is
  // not a direction, a non-positive length, ...).
  void validate() const;
  const GaugeBlock& block(const std::string& id) const;  // throws Error when unknown
};

// Where the probe can reach: the machine's travel, as tip-centre positions (mm).
struct Volume {
  Eigen::Vector3d low = Eigen::Vector3d::Zero(), high = Eigen::Vector3d::Zero();
  static Volume of(const sim::Machine& machine);
};

// One of ISO 10360-2's positions: the placements along one line.
struct Position {
  std::string name;
  Eigen::Vector3d direction = Eigen::Vector3d::UnitX();  // unit
  std::vector<std::size_t> placements;                   // into Setup::placements
  bool space_diagonal = false;
};

// The positions of a setup, checked against the standard and the volume: throws Error listing
// every reason it cannot be an ISO 10360-2 test (a placement outside the volume or overlapping
// another of its position (positions are set up one after another), fewer than 7 positions or a
// space diagonal missing, a position without 5 lengths or whose longest is below 66 % of the travel
// along it). `only` (names): just these positions are measured and checked, as for E_L with a
// stylus offset, which ISO 10360-2 measures in two positions; the 7 positions are then not asked
// for, and a name the set-up does not have is refused.
std::vector<Position> positions(const Setup& setup, const Volume& volume,
                                const std::vector<std::string>& only = {});

// The blocks as boxes (length × block_width × block_height) in the machine, each one's group
// its position's index (positions are set up one after another).
std::vector<sim::Box> artefact_boxes(const Setup& setup);
// A block's axes: the line's direction, across it (horizontal unless the line is vertical, then
// along Y), and the third.
Eigen::Matrix3d block_axes(const Eigen::Vector3d& direction);

// The placements by position (their own names, or their directions when unnamed), each marked
// when it is a space diagonal; nothing checked.
std::vector<Position> lines(const Setup& setup);

// A set-up that fits `volume` and the standard: the 4 space diagonals and lines along X, Y and Z
// through its middle, each with 5 blocks side by side (0.7, 0.55, 0.4, 0.25 and 0.1 of the
// travel along it, to 10 mm), and a 25 mm reference sphere low in the volume where it is
// farthest from the blocks; the blocks' temperature known to 0.05 K and their alignment to
// 0.1 µm. Positions are set up one after another.
Setup example_setup(const Volume& volume);

// Measures a point: the surface whose nominal point is `at` (mm, machine coordinates), approached
// along unit `direction` (the surface's outward normal is −direction); returns the measured
// surface point, the tip radius compensated (mm). Throws Error when there is no contact.
using Touch =
    std::function<Eigen::Vector3d(const Eigen::Vector3d& at, const Eigen::Vector3d& direction)>;

// The virtual CMM in process: `machine`'s geometric errors and a touch-trigger probe whose
// pre-travel varies with the probing direction: lobing·cos(3φ)·sin²θ (φ the direction's azimuth,
// θ its angle from the stylus, along −Z; the three lobes of a kinematic probe, its mean taken
// out by qualification), plus Gaussian noise along the probing direction. The artefacts are
// where the setup says, and as long as their certificates say.
struct VirtualProbeOptions {
  double lobing = 0;  // mm
  double noise = 0;   // mm, standard deviation
  std::uint64_t seed = 1;
  void validate() const;  // throws Error
};
Touch virtual_touch(const sim::Machine& machine, const VirtualProbeOptions& options = {});

struct LengthResult {
  std::string position, block;
  int repetition = 1;
  double nominal = 0, measured = 0, error = 0;                               // mm
  Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();  // measured, mm
  double mpe = 0;                                                            // mm, at this length
  double U = 0;  // mm, the test's expanded uncertainty (k = 2) for this length
};

struct RepeatRange {  // R0 of one length at one position
  std::string position, block;
  double nominal = 0, range = 0;  // mm
};

enum class Verdict { Conforms, DoesNotConform, NotProven };
const char* to_string(Verdict v);  // "conforms", "does not conform", "not proven"

struct E0Options {
  ballgauge::Mpe mpe;                // E0,MPE (or E150,MPE)
  std::optional<ballgauge::Mpe> r0;  // R0,MPE when given
  // E_L (ISO 10360-2): the stylus tip's offset from the ram axis (mm, machine axes, across the
  // ram: its Z component 0, length up to 500 mm), e.g. 150 mm along X for E150. The touch must
  // probe with that stylus (for the virtual CMM: the machine's offset plus this, with_stylus);
  // the volume is that stylus's too. Rotations of the carriages then move the tip by their angle
  // times this offset (the Abbe error the test exposes), which E0's stylus hides.
  std::optional<Eigen::Vector3d> stylus_offset;
  // E_L only: the positions measured (names from lines()); empty: the set-up's first two space
  // diagonals.
  std::vector<std::string> positions;
  // Called after every length measured: done, total.
  std::function<void(std::size_t, std::size_t)> progress;
  // Called before each position is measured (the position, its index from 0, how many), e.g.
  // to have an operator set it up on a real CMM; an Error it throws stops the run as a touch's.
  std::function<void(const Position&, std::size_t, std::size_t)> before_position;
};

struct E0Result {
  std::string mpe_text, r0_text;
  std::optional<Eigen::Vector3d> stylus_offset;  // mm, E_L's
  std::vector<Position> positions;
  std::vector<LengthResult> lengths;
  std::vector<RepeatRange> r0;
  double e0_max = 0;  // mm, the largest |E|
  double r0_max = 0;  // mm
  Verdict verdict = Verdict::NotProven;
  std::optional<bool> r0_pass;  // against R0,MPE when given
  std::string rule;             // the decision rule in words
  bool complete = true;         // false: stopped before every length was measured
  std::string stopped;          // why
  std::string summary() const;  // µm
  std::string name() const;     // "E0", or "E150" for a 150 mm stylus offset
};

// The test's name for a stylus offset: "E0" without one, else "E" and its length in mm.
std::string el_name(const std::optional<Eigen::Vector3d>& stylus_offset);

// The virtual CMM's machine probing with a stylus offset across the ram (mm): its offset plus
// `lateral`. Throws Error when `lateral` is not across the ram or longer than 500 mm.
sim::Machine with_stylus(sim::Machine machine, const Eigen::Vector3d& lateral);
void validate_stylus_offset(const Eigen::Vector3d& lateral);  // throws Error

// Runs the test: every placement of every position (E_L: of options.positions), `repetitions`
// times, bidirectionally. A
// touch that throws stops the run: what was measured is kept (complete = false, stopped = the
// reason) and judged as far as it goes.
E0Result run_e0(const Setup& setup, const Volume& volume, const Touch& touch,
                const E0Options& options);
// The figures and verdict from measured lengths (LengthResult rows with a, b, nominal and
// measured set), as run_e0 does after measuring.
void judge_e0(const Setup& setup, const E0Options& options, E0Result& result);

// The 25 unit directions from the sphere's centre (outward) of ISO 10360-5's pattern about `pole`.
std::vector<Eigen::Vector3d> probing_pattern(const Eigen::Vector3d& pole);

struct ProbingOptions {
  std::optional<double> mpe_form, mpe_size;  // mm
};

struct ProbingResult {
  Eigen::Matrix3Xd points;  // measured (mm)
  Eigen::VectorXd radial;   // distance from the LS centre less the LS radius, per point (mm)
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double diameter = 0;        // mm, least squares
  double form = 0, size = 0;  // mm: PForm, PSize
  double U_form = 0, U_size = 0;
  std::optional<double> mpe_form, mpe_size;
  std::optional<Verdict> form_verdict, size_verdict;
  std::string rule;
  std::string summary() const;  // µm
};

// Throws Error when the setup has no reference sphere or a touch fails.
ProbingResult run_probing(const Setup& setup, const Touch& touch, const ProbingOptions& options);

}  // namespace trueaxis::acceptance
