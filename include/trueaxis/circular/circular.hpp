// trueaxis::circular — the circular test of two machine axes with a telescoping ballbar (ISO
// 230-4:2005, Test code for machine tools, Part 4: circular tests for numerically controlled
// machine tools): the test's figures, and the trace explained by its causes.
//
// Plane and angles: the test runs in the plane of two axes, a (first) and b (second): XY, YZ or
// ZX. The angle θ is the commanded one, from +a towards +b; ccw runs with θ increasing, cw with θ
// decreasing. A sample's deviation is the ballbar's reading less its calibrated length: the
// radial deviation δr(θ) of the tool from the pivot at the circle's centre (mm in the library;
// µm in files). Positive outward.
//
// Figures (ISO 230-4, clause 3):
// - circular deviation G per direction: the radial band of the path about its least-squares
//   circle (the circle's centre fitted, then the range of the radial distances from it);
// - radial deviation F per direction: the smallest and largest δr about the nominal circle;
// - circular hysteresis H: the largest radial difference between the two directions' paths at one
//   angle (the cw path interpolated at the ccw path's angles).
//
// Diagnosis: δr is the radial component of the tool's position error e = (e_a, e_b),
// δr = e_a·cosθ + e_b·sinθ, to first order in e/R. Each cause gives e a known form, so δr is a sum
// of the causes' signatures, linear in their sizes, which a least-squares fit of both directions
// at once separates (s = +1 for ccw, −1 for cw; v the feed in mm/s; R the radius):
// - centre offset (c_a, c_b), the path's centre from the pivot:     c_a·cosθ + c_b·sinθ
// - radius offset r0 (ballbar length, following lag at this feed):  r0
// - squareness S (rad; > 0 when the actual +a, +b directions make more than 90°; e_a = −S·b):
//                                                                   −(S·R/2)·sin 2θ
// - scale mismatch M = scale error of a − scale error of b:         (M·R/2)·cos 2θ
// - lag mismatch Δτ = following lag of a − of b (s; e = −τ·velocity): s·(v·Δτ/2)·sin 2θ.
//   A first-order position loop also shrinks each axis' amplitude and turns its phase by second
//   order terms, which read as a scale mismatch of −(3/2)·ω²·(τa² − τb²) (ω = v/R): 20 µm/m for
//   25 and 33 ms at 1000 mm/min on R 100 mm. The data do not give τa + τb, so it is not removed.
// - backlash B per axis (> 0 when the axis stops short of the command, by B/2 each way):
//   a: (s/2)·sign(sin θ'a)·cos θ·B_a,   b: −(s/2)·sign(cos θ'b)·sin θ·B_b, with θ'x = θ − s·δx:
//   each axis reverses its own delay δx after the commanded reversal (its following lag's phase)
// - reversal spike per axis and direction (> 0 outward: the table left behind), decaying over
//   an angle d after each reversal of the axis (a at θ = 0°, 180°; b at 90°, 270°; each δx
//   later):
//   a: A·exp(−Δθ/d)·|cos θ|,   b: A·exp(−Δθ/d)·|sin θ|
// - straightness per axis, a bow of the other coordinate over ±R: e_b = k_a·(a/R)², e_a =
//   k_b·(b/R)²:                                                     k_a·cos²θ·sin θ, k_b·sin²θ·cos
//   θ
// - cyclic error per axis of a given pitch P: e_a = C_s·sin(2πa/P) + C_c·cos(2πa/P) (amplitude
//   √(C_s² + C_c²)), the same for b.
// What remains is the unexplained part, stated by its RMS. Sizes whose signatures the data cannot
// tell apart (|correlation| of their estimates ≥ 0.995, or no effect on these samples) are named,
// not given as numbers.
#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>
#include <vector>

namespace trueaxis::circular {

enum class Direction { Ccw, Cw };

// One plane of two axes: XY, YZ or ZX (a, b = 0..2: X, Y, Z).
struct Plane {
  int a = 0, b = 1;
  std::string name() const;  // "XY"
  // Throws Error for anything but XY, YZ, ZX (any case).
  static Plane parse(const std::string& text);
};

struct Trace {
  std::vector<Direction> direction;  // per sample
  Eigen::VectorXd angle;             // rad, commanded, any real value (taken modulo 2π)
  Eigen::VectorXd deviation;         // mm, reading − calibrated length
  // Where sample k came from, for messages ("trace.csv:12:2: "); empty: its 1-based count.
  std::vector<std::string> where;
};

struct Options {
  double radius = 100;  // mm, the ballbar's calibrated length, > 0
  double feed = 1000;   // mm/min, > 0
  Plane plane;
  // Reversal spikes' decay angle (rad); 0: found from the data (the one that fits best over
  // 0.5° … 30°).
  double spike_decay = 0;
  // The reversals' delay (rad): an axis reverses this far after the commanded reversal, in the
  // direction of travel (its following lag's phase, about ω·τ); the same given for both axes;
  // < 0: each axis' own found from the data (the ones that fit best over 0 … 5°).
  double reversal_delay = -1;
  // Cyclic errors' pitch per axis (mm); 0: not fitted.
  double pitch_a = 0, pitch_b = 0;
  // Refusals: fewer samples per direction, or a larger gap in the angles covered.
  long min_samples = 36;
  double max_gap = 15 * 3.14159265358979323846 / 180;  // rad
  void validate() const;                               // throws Error
};

struct DirectionFigures {
  bool present = false;
  long samples = 0;
  double G = 0;                                      // mm
  double F_min = 0, F_max = 0;                       // mm
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();  // mm, LS circle centre from the pivot (a, b)
};

// One cause of the diagnosis with its size in the unit named, its standard uncertainty (absent
// when the fit has no degrees of freedom left or is exact), and its share: the peak-to-valley of
// its own contribution to the trace over the larger of the two G.
struct Cause {
  std::string key;   // "centre_offset.X", "squareness", "backlash.Y", "reversal_spike.X.ccw", ...
  std::string name;  // in words, with the axis
  std::string unit;  // "µm", "µm/m", "ms"
  double value = 0;  // in `unit`
  std::optional<double> u;
  double share = 0;       // 0..
  bool separated = true;  // false: not told apart from `confused_with` by these data
  std::string confused_with;
};

struct Result {
  Plane plane;
  double radius = 0, feed = 0;
  DirectionFigures ccw, cw;
  std::optional<double> H;    // mm, with both directions
  std::vector<Cause> causes;  // in the order of the list in the header, then ranked by share
  double spike_decay = 0;     // rad, as used
  // The decay's standard uncertainty (rad) when it was found from the data: that of the search
  // that found it (over a weighted subset of the samples when there are many), from how the
  // residuals change with it, the sizes refitted at each decay (the delays held).
  // Absent, with the reason in spike_decay_note, when the decay was given or the data do not
  // resolve it (no spike stands out of the noise, or the best fit is at the end of the range).
  std::optional<double> spike_decay_u;
  std::string spike_decay_note;
  std::array<double, 2> reversal_delay{};  // rad per axis a, b, as used
  // What the samples resolve of a delay (rad): the median angle between successive samples of
  // one direction. A delay found from the data is known to about this, no better.
  double reversal_delay_resolution = 0;
  double unexplained_rms = 0;  // mm
  double sigma = 0;            // mm, the residuals' standard deviation used for the u
  // The fitted model and its residual per sample (mm), in the trace's order.
  Eigen::VectorXd model, residual;
  std::vector<std::string> warnings;
  std::string summary() const;  // µm
};

// Throws Error: a trace that cannot be a test (too few samples in a direction, angles that leave
// a gap larger than options.max_gap, non-finite values), naming the sample where it can.
Result evaluate(const Trace& trace, const Options& options);

}  // namespace trueaxis::circular
