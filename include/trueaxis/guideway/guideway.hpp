// trueaxis::guideway — five motion errors of a guideway from laser spots on quadrant detectors
// (after the Chinese patent application "一种数控机床导轨五自由度几何运动误差的测量方法", a
// measuring method for the five geometric motion errors of a CNC machine-tool guideway).
//
// Carriage frame (mm): z along the travel, x horizontal, y vertical. At carriage position s the
// carriage makes a small error motion: translation (δx, δy, δz) of the frame origin and rotation
// (εx, εy, εz) = (pitch, yaw, roll). Laser beams fixed to the bed run parallel to z. A position
// detector (QPD) at carriage point (x_i, y_i, z_i) sees its spot move by the negative of its own
// transverse motion:
//
//     dx_i = −(δx + εy·z_i − εz·y_i),      dy_i = −(δy + εz·x_i − εx·z_i).
//
// An angle detector (a QPD behind a lens of focal length f) reads f·(εy, −εx), independent of
// translation. δz is invisible. The five unknowns, in this order everywhere:
//
//     q = (horizontal δx [mm], vertical δy [mm], pitch εx [rad], yaw εy [rad], roll εz [rad]).
//
// Observability: roll needs detectors at different transverse positions; pitch and yaw need
// position detectors at different axial positions z_i, or an angle detector. What a layout
// cannot see is found from the null space of its design matrix and dropped in the order yaw,
// pitch, roll, vertical, horizontal (so a coplanar layout loses pitch and yaw and keeps the
// straightness of its detectors' cross-section); it is never reported as a number.
#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>
#include <vector>

namespace trueaxis::guideway {

inline constexpr int kErrors = 5;
// Names used in files and reports, in the order of q.
inline constexpr const char* kErrorNames[kErrors] = {"horizontal", "vertical", "pitch", "yaw",
                                                     "roll"};

// A carriage on a machine axis (X, Y or Z: 0, 1, 2) has its frame oriented so: travel X gives
// carriage (x, y, z) = machine (Y, Z, X); travel Y, (−X, Z, Y); travel Z, (X, Y, Z). All three
// are right-handed. The rotation whose columns are the carriage axes in machine coordinates:
Eigen::Matrix3d carriage_axes(int axis);

// ISO 230-1's name of each of the five errors of a carriage on machine axis `axis` (0..2), e.g.
// for X: EYX, EZX, EBX, ECX, EAX, and the sign (±1) that turns the carriage-frame value into the
// machine-frame one the name means (travel Y: EXY = −horizontal).
struct IsoName {
  std::string name;
  double sign = 1;
};
std::array<IsoName, kErrors> iso_names(int axis);

enum class Kind { Position, Angle };

struct Detector {
  std::string name;
  Kind kind = Kind::Position;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // mm, carriage frame (position detectors)
  double focal_length = 0;                             // mm, > 0 (angle detectors)
};

struct Layout {
  std::vector<Detector> detectors;
  // Throws Error: no detectors, empty or duplicated names, non-finite positions, angle detectors
  // without a positive focal length, or position detectors that all lie on one line (the
  // patent application's triangle abc is degenerate; with two or fewer position detectors, at least
  // one angle detector must complete the layout).
  void validate() const;
  // The design matrix A (2m × 5): readings (dx_1, dy_1, dx_2, dy_2, ...; mm) = A·q.
  Eigen::MatrixXd design() const;
};

// Quadrant-detector signal conversion. Photocurrents I1..I4 of the quadrants counter-clockwise
// from (+x, +y) give the normalised differences
//
//     sx = ((I1 + I4) − (I2 + I3)) / ΣI,      sy = ((I1 + I2) − (I3 + I4)) / ΣI,
//
// converted to a spot displacement by a linear gain (valid near the centre) or by a calibration
// table (the response of a Gaussian spot follows an error function and flattens off-centre).
struct Qpd {
  double gain = 0;                     // mm per unit signal (used when there is no table)
  Eigen::VectorXd table_signal;        // strictly increasing, within (−1, 1)
  Eigen::VectorXd table_displacement;  // mm at those signals, strictly increasing
  double min_sum = 0;                  // ΣI below this: spot lost (current units)
  double max_signal = 0.9;             // |s| above this: outside the linear range (gain only)
  bool empty() const { return gain == 0 && table_signal.size() == 0; }
  void validate() const;  // throws Error
  // The displacement (mm) for one normalised signal; throws Error (with the reason) outside the
  // table or beyond max_signal.
  double displacement(double signal) const;
  // (dx, dy) in mm from the four currents; throws Error for a lost spot or an out-of-range one.
  Eigen::Vector2d spot(double i1, double i2, double i3, double i4) const;
};

// The normalised difference sx of a Gaussian spot (1/e² intensity radius w, mm) centred at x (mm)
// on an infinite quadrant detector with no gap: erf(√2·x / w).
double gaussian_signal(double x, double w);

struct LayoutAnalysis {
  std::array<bool, kErrors> observable{};
  // Singular values and condition number of the design with the angle columns scaled by the
  // layout's size (so mm and rad columns compare), over all five unknowns (condition infinite
  // when rank-deficient) and over the observable ones (what the solve uses).
  Eigen::VectorXd singular_values;
  double condition_number = 0, observable_condition_number = 0;
  std::string message;  // what is unobservable and why; empty if all five are observable
};

LayoutAnalysis analyze_layout(const Layout& layout);

struct Options {
  // Standard deviation of one spot reading (mm). 0: estimated from the residuals when the layout
  // has redundant readings, otherwise no uncertainty.
  double sigma = 0;
  // Refuse layouts whose observable part has a larger condition number.
  double max_condition = 1e8;
};

struct Result {
  Eigen::VectorXd s;                           // mm, carriage positions
  std::array<Eigen::VectorXd, kErrors> value;  // mm or rad per position; empty if unobservable
  std::array<double, kErrors> uncertainty{};   // standard uncertainty per position (mm or rad)
  Eigen::VectorXd residual;                    // mm, RMS of the readings' residuals per position
  LayoutAnalysis layout;
  double sigma = 0;  // mm, the reading noise used (given or estimated; 0 if none)
  bool sigma_estimated = false;
  // Why no uncertainty is stated (sigma 0), in words: no redundant readings, or readings that
  // agree to round-off ("noise-free input: ..."); empty when one is.
  std::string no_uncertainty;
  // Horizontal and vertical straightness against their least-squares lines over s (mm), when
  // observable and at least two positions.
  Eigen::VectorXd horizontal_straightness, vertical_straightness;
  // Peak-to-valley and RMS per error (of the straightness for δx, δy; of the raw values for the
  // angles), 0 if unobservable.
  std::array<double, kErrors> pv{}, rms{};
  // Expanded uncertainty (95 % coverage) of the PV of error j: 2·z·u with z = Φ⁻¹(1 − 0.025/n)
  // over the n positions (every position is solved alike, so u is the same at each; a PV is off
  // by at most twice the largest position error). Absent when no uncertainty is stated or j is
  // not observable.
  std::optional<double> pv_U(std::size_t j) const;
  // Whether the data resolve the PV of error j (pv_U below it); absent with pv_U.
  std::optional<bool> resolved(std::size_t j) const;
  // µm, µrad; a PV the data do not resolve reads "not resolved (U = …)", figures are rounded to
  // what their uncertainty supports.
  std::string summary() const;
  // The machine axis the carriage rides (0..2), when known: the errors are then named as ISO
  // 230-1 names them (iso_names). -1: a stand-alone carriage, its errors named in its own frame.
  // `value` stays in the carriage frame either way.
  int axis = -1;
  // The name error j is shown by: "EYX (horizontal)" on a machine axis, "horizontal" otherwise;
  // and the sign that turns value[j] into what that name means.
  std::string name(std::size_t j) const;
  double sign(std::size_t j) const;
};

// Solves every position: `spots` is positions × 2m (columns dx_1, dy_1, dx_2, dy_2, ... in the
// order of the layout's detectors; mm). The least-squares operator is factored once and applied
// to all positions. Throws Error for bad shapes, non-finite readings, an invalid layout, or one
// whose observable part is worse conditioned than `options.max_condition`.
Result solve(const Layout& layout, const Eigen::VectorXd& s, const Eigen::MatrixXd& spots,
             const Options& options = {});

}  // namespace trueaxis::guideway
