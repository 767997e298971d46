// trueaxis::sim — the rigid-body virtual 3-axis machine (ISO 230-1 naming).
//
// Model. Each linear axis k ∈ {X, Y, Z} moves its carriage by its coordinate u_k (mm). The
// carriage's actual motion relative to its nominal one is a small rigid transformation with six
// error functions of u_k: translations E_Xk, E_Yk, E_Zk (positioning along k, straightness across
// it) and rotations E_Ak, E_Bk, E_Ck (about X, Y, Z: roll, pitch or yaw depending on k). Three
// constant squareness errors tilt the nominal axis directions (ISO 230-1 / Schwenke et al. 2008):
//
//     d_X = e_x,   d_Y = Rz(E_C0Y)·e_y,   d_Z = Rx(E_A0Z)·Ry(E_B0Z)·e_z.
//
// Each axis is the exact rigid transformation A_k(u) p = u·d_k + δ_k(u) + R_k(u)·p, where
// δ_k = (E_Xk, E_Yk, E_Zk) in the machine frame and R_k is the exact rotation whose rotation vector
// is (E_Ak, E_Bk, E_Ck) (no small-angle linearisation in the simulator). The kinematic chain
// lists the axes from the workpiece to the tool with 'F' marking the machine frame, e.g.
// "FYXZ" (bridge CMM: the bridge Y carries X, X carries the ram Z, the stylus hangs on Z),
// "FXYZ" (all three axes on the tool side), "XFYZ" (the table moves in X). The tool point is
//
//     actual(c) = A_1(u_1) A_2(u_2) A_3(u_3) · offset      (axes in chain order, F dropped),
//
// where `offset` is the stylus or tool offset from the last carriage's reference point, and
// nominal(c) = c + offset. Error functions of axes before 'F' (workpiece side) are stated for
// the relative motion of tool against workpiece, so F changes no number, only the reading.
// Rotations act about the machine origin shifted by the upstream motions, so Abbe offsets grow
// with the downstream coordinates and with the stylus offset.
//
// Units in the library: mm for positions and linear errors, rad for angular errors. Files use
// µm and µrad (see io/machine.hpp).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "trueaxis/separation/separation.hpp"
#include "trueaxis/sim/straightness.hpp"

namespace trueaxis::sim {

// One error function e(u) of an axis coordinate u (mm): the sum of a polynomial in u/1000 mm
// (coefficient k multiplies (u/1 m)^k), sinusoids a·sin(2π·u/period + phase) and a table
// linearly interpolated between its nodes. Values in mm (linear) or rad (angular).
struct ErrorFunction {
  struct Sine {
    double amplitude = 0;  // value unit
    double period = 1;     // mm, > 0
    double phase = 0;      // rad
  };
  std::vector<double> polynomial;
  std::vector<Sine> sines;
  std::vector<double> table_u, table_value;  // nodes (mm, strictly increasing) and values

  bool empty() const { return polynomial.empty() && sines.empty() && table_u.empty(); }
  // Precondition: the table (if any) covers u. Machine::validate checks this for the axis range.
  double operator()(double u) const;
  // Throws Error naming `what` if the function is malformed (non-finite numbers, period <= 0,
  // table not strictly increasing or with fewer than two nodes, or not covering [lo, hi]).
  void validate(const std::string& what, double lo, double hi) const;
};

enum class Component { X = 0, Y = 1, Z = 2, A = 3, B = 4, C = 5 };

// ISO 230-1 name of an axis' error component: "EXX" (positioning of X), "EYX", "EZX"
// (straightness of X), "EAX", "EBX", "ECX" (rotations of X), ... `axis` 0..2 = X, Y, Z.
std::string error_name(int axis, Component c);

struct Machine {
  std::string name;
  std::string chain = "FYXZ";  // axis letters X, Y, Z once each and 'F' once, workpiece → tool
  std::array<std::array<double, 2>, 3> range{{{0, 800}, {0, 600}, {0, 500}}};  // mm, per axis
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();    // stylus/tool offset (mm)
  std::array<std::array<ErrorFunction, 6>, 3> errors;  // [axis][Component]
  double squareness_c0y = 0;                           // E_C0Y, rad: Y about Z
  double squareness_b0z = 0;                           // E_B0Z, rad: Z about Y
  double squareness_a0z = 0;                           // E_A0Z, rad: Z about X

  // Throws Error naming the first problem (chain, ranges, error functions).
  void validate() const;

  // Axis order of the chain (workpiece → tool), e.g. {1, 0, 2} for "FYXZ".
  std::array<int, 3> order() const;
  // True if every coordinate of `command` lies within its axis range (with `tolerance` mm).
  bool contains(const Eigen::Vector3d& command, double tolerance = 1e-9) const;

  // The actual pose of the tool frame at `command` (mm): actual position of a point p of the
  // tool frame is pose * p. Exact rotations. No range check (callers decide).
  Eigen::Isometry3d pose(const Eigen::Vector3d& command) const;
  // Actual tool point at `command`, and its error actual − nominal (mm).
  Eigen::Vector3d actual(const Eigen::Vector3d& command) const { return pose(command) * offset; }
  Eigen::Vector3d error(const Eigen::Vector3d& command) const {
    return actual(command) - command - offset;
  }
  // Errors at many commands (3 × n, mm), in parallel for large n.
  Eigen::Matrix3Xd errors_at(const Eigen::Matrix3Xd& commands) const;

  // A short table of the 21 errors: per axis the span (max − min) of its positioning and
  // angular error functions over its range (µm, µrad), its two straightness errors and the
  // three squareness errors as ISO 230-1 defines them at the tool point (reference_lines).
  // Errors named in `not_determined` (ISO names, e.g. "ECX": an identified model's functions the
  // data cannot see) read "n/d" instead of a number.
  std::string summary(const std::vector<std::string>& not_determined = {}) const;
};

// The tool point's trajectories and their ISO 230-1 reference lines: each axis moved over its
// range with the other two at `at` (commands, mm). The reference line of an axis is the
// least-squares line of its trajectory; its straightness, in each of the two directions across
// the axis, is the range of the trajectory's deviations from that line (mm); the squareness
// errors are the angles between reference lines less 90° (rad), in the sign convention of
// Machine::squareness_c0y, _b0z, _a0z, so that a machine whose only errors are squareness
// errors gives them back. Unlike the error functions' own values, these figures do not depend on
// how a straightness slope is split between the functions and the squareness parameters (a
// split that data never fixes, since it is a rigid motion of the whole machine).
struct ReferenceLines {
  std::array<Eigen::Vector3d, 3> direction;  // unit vectors, per axis
  // [axis][0, 1]: across directions in axis order (X: y, z; Y: x, z; Z: x, y), mm.
  std::array<std::array<double, 2>, 3> straightness{};
  double c0y = 0, b0z = 0, a0z = 0;  // rad
};
ReferenceLines reference_lines(const Machine& machine, const Eigen::Vector3d& at,
                               int samples = 101);

// A seeded random machine with realistic magnitudes. Straightness: bow plus cubic plus
// one long-wave sinusoid, about `straightness` PV over 500 mm; angular: drift, bow and a wave of
// about `angular`; positioning: about `positioning` mm per mm from the axis' start plus a small
// bow (and, if `lead_amplitude` > 0, a lead-screw term of period `lead`); squareness: normal with
// standard deviation `squareness`.
struct MachineOptions {
  std::string chain = "FYXZ";
  std::array<std::array<double, 2>, 3> range{{{0, 800}, {0, 600}, {0, 500}}};  // mm
  Eigen::Vector3d offset{0, 0, -100};                                          // mm
  double straightness = 3e-3;                                                  // mm over 500 mm
  double angular = 10e-6;                                                      // rad
  double positioning = 10e-6;                                                  // mm/mm
  double squareness = 20e-6;                                                   // rad
  double lead_amplitude = 0;                                                   // mm
  double lead = 10;                                                            // mm
  std::uint64_t seed = 1;
  void validate() const;  // throws Error
};

Machine random_machine(const MachineOptions& options);

// A virtual displacement-probe run on the machine (the data of separation/separation.hpp from this
// machine). The carriage (the tool point) stops at c_K = start + K·step·d for K = 0..stations−1;
// probe i is mounted on the tool at `offsets[i]` along d and reads along the sensing direction n (n
// ⟂ d) a straightedge lying along the line with its own profile w:
//
//     m_i(K) = w(x_K + s_i) + n·(actual(c_K, s_i) − nominal(c_K, s_i)) + o_i + noise,
//
// which is exactly the separation's model w + g + s_i·θ + o_i with g(K) = n·error(c_K) and θ(K) =
// n·(R_K d), R_K the tool frame's actual rotation. The optional angle channel (an autocollimator or
// level on the carriage) reads θ(K) + o_a + noise. Along-line coordinate: x_K = start·d + K·step.
struct ProbeRunOptions {
  Eigen::Vector3d start = Eigen::Vector3d::Zero();  // command of the first stop (mm)
  Eigen::Vector3d direction{1, 0, 0};               // motion direction (normalised)
  Eigen::Vector3d sensing{0, 0, 1};                 // probe direction (normalised, ⟂ direction)
  long stations = 41;
  double step = 20;                        // mm
  std::vector<double> offsets{0, 20, 40};  // mm, whole steps, offsets[0] == 0
  double profile_amplitude = 2e-3;         // mm, the straightedge's form error
  double offset_amplitude = 20e-3;         // mm, probe zero offsets
  double noise = 0;                        // mm
  bool angle = false;
  double angle_noise = 0;  // rad
  std::uint64_t seed = 1;
  void validate() const;  // throws Error
};

// `truth` is in the shape of the straightness simulator: the straightedge on the probe grid,
// and the carriage's g and θ at the stations (NaN at grid points that are not stations).
StraightnessCampaign simulate_probe_run(const Machine& machine, const ProbeRunOptions& options);

// A virtual laser-interferometer run: the tool (retroreflector) stops at c_m = start + m·step·d,
// m = 0..stations−1, and the interferometer, zeroed at the first stop, reads the displacement
// error along the beam d: r_m = d·(error(c_m) − error(c_0)) + noise (mm). The run must stay in
// the machine's range.
Eigen::VectorXd simulate_laser_run(const Machine& machine, const Eigen::Vector3d& start,
                                   const Eigen::Vector3d& direction, long stations, double step,
                                   double noise, std::uint64_t seed);

}  // namespace trueaxis::sim
