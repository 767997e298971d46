// trueaxis::ippdme — the virtual CMM behind `trueaxis serve`: a servo-controlled carriage, a
// scanning probe and, optionally, the 21 geometric errors of a machine, in front of surfaces the
// probe can meet. No I/O here; the I++ DME engine (engine.hpp) drives it.
//
// Units: mm, s. Positions are I++ machine coordinates of the stylus-tip centre as the scales
// read it (MachineCsy). With geometric errors (a sim::Machine), the axis command is
// c = x − machine.offset and the real ball centre x + machine.error(c): the probe meets the
// surface where the real ball is, and everything reported is read from the scales, so the
// machine's errors are in the measurement as on a real CMM.
//
// Surfaces are given per operation as a function that returns the nearest point of the surface
// to a point (foot, unit normal away from the material, signed distance: > 0 outside), or
// nothing when no surface is near. A touch or scan runs in machine time, one servo tick at a time;
// after every tick the hook (if set) is called and may stop the motion (AbortE): the carriage
// then comes to rest and the operation throws Stopped.
#pragma once

#include <Eigen/Core>
#include <array>
#include <functional>
#include <optional>
#include <vector>

#include "trueaxis/error.hpp"
#include "trueaxis/sim/cmm.hpp"
#include "trueaxis/sim/machine.hpp"

namespace trueaxis::ippdme {

using Nearest = sim::Contour::Nearest;
using Surface = std::function<std::optional<Nearest>(const Eigen::Vector3d&)>;

// Thrown when the tick hook stopped a motion.
class Stopped : public Error {
 public:
  Stopped() : Error("motion stopped") {}
};

struct SimulatedCmmOptions {
  SimulatedCmmOptions() { servo.max_velocity = 500; }
  sim::ServoOptions servo;
  sim::ProbeOptions probe;
  // The machine's geometric errors; its axis ranges (plus its tool offset) are then the travel.
  std::optional<sim::Machine> geometry;
  // Travel of the tip centre without geometric errors (mm, machine coordinates).
  std::array<std::array<double, 2>, 3> travel{{{-500, 500}, {-400, 400}, {-300, 300}}};
  Eigen::Vector3d home = Eigen::Vector3d::Zero();  // where Home() goes (mm)
  double trigger = 0.005;                          // contact: a move stops at this deflection (mm)
  // A single point (PtMeas) is read once the deflection reaches this, as a scanning probe
  // measures points: the deflection's direction, the measured normal, is then well above the
  // probe's noise (mm).
  double point_deflection = 0.2;
  // A scan reports a point only while the deflection is at least this: below, its direction
  // (the measured normal) drowns in the probe's noise, as where the probe nearly lifts off at a
  // sharp corner (mm).
  double min_scan_deflection = 0.1;
  double correction_gain = 60;  // scanning: how fast the deflection is held (1/s)
  double max_deflection = 0.8;  // beyond this the probe is over-pushed (error 2001)
  // How far the stylus gives way past the trigger before the probe is damaged (mm): a GoTo that
  // meets the part brakes at its acceleration and ends in error 1001 ("Illegal touch") when it
  // stops within this, in 2504 ("Collision") beyond.
  double overtravel = 2.0;
  // Throws Error naming the option (the home outside the travel, a trigger outside (0, range)).
  void validate() const;
};

class SimulatedCmm {
 public:
  explicit SimulatedCmm(const SimulatedCmmOptions& options);
  const SimulatedCmmOptions& options() const { return o_; }

  // Called after every servo tick; return false to stop the motion.
  void set_hook(std::function<bool()> hook) { hook_ = std::move(hook); }

  double time() const { return servo_.time(); }
  const Eigen::Vector3d& position() const { return servo_.position(); }
  double tip_radius() const { return probe_.options().tip_radius; }
  // Lower and upper corner of the travel (mm, machine coordinates).
  Eigen::Vector3d travel_low() const;
  Eigen::Vector3d travel_high() const;
  bool within_travel(const Eigen::Vector3d& x, double tolerance = 1e-6) const;

  // A straight move at `speed` (mm/s) with acceleration `accel` (mm/s²), ending at rest.
  // `surface` (if set) is checked for a collision: the move stops with the stylus against it
  // and the function returns false. True when it arrived.
  bool move(const Eigen::Vector3d& to, double speed, double accel, const Surface& surface = {});
  // How far the stylus was pushed into the surface when the last move stopped on it: the probe
  // triggered and the machine braked at the move's acceleration (mm).
  double last_push() const { return pushed_; }

  // One probing: from the current position along unit `direction` for up to `distance` mm at
  // `speed`, until the deflection reaches the trigger. Latches the ball centre as read and the
  // measured normal (the deflection's direction). Nothing if no contact within the distance.
  struct Contact {
    Eigen::Vector3d centre, normal;
  };
  std::optional<Contact> touch(const Eigen::Vector3d& direction, double distance, double speed,
                               const Surface& surface);

  // A scan from a contact: the tip follows the surface holding `pushing` mm of deflection, its
  // centre kept on a constraint surface, along the line where the two meet (the constraint's
  // normal × the measured normal), at `speed`: first in the sense of `hint`, then continuing
  // the way it goes. After every tick `stop(point, arc)` decides whether the scan is done; a
  // point is recorded every `step` mm of arc from the start (the starting contact itself is the
  // caller's to record) and passed to `emit`. At most `max_length` mm.
  struct Point {
    Eigen::Vector3d centre, normal;  // ball centre as read (mm), measured surface normal
    double q = 0;                    // quality 0 (good) .. 100 (bad)
  };
  struct Constraint {
    // The constraint surface's unit normal at p and the signed distance of p from it (mm).
    std::function<std::pair<Eigen::Vector3d, double>(const Eigen::Vector3d&)> at;
  };
  enum class ScanEnd { Done, Lost, OverPushed, Travel, TooLong };
  ScanEnd follow(const Surface& surface, const Constraint& constraint, const Eigen::Vector3d& hint,
                 double speed, double pushing, double step, double max_length,
                 const std::function<bool(const Point&, double)>& stop,
                 const std::function<void(const Point&)>& emit);

  // Design-value scanning with active following: the tip centre runs along the polyline
  // `path` (mm) at `speed`, moved along the nominal surface normals `normals` (one per path
  // point) as far as it takes to hold `pushing` mm of deflection, as a scanning CMM's normal
  // correction does, slower on the polyline's turns (v²/R ≤ 2000 mm/s²); a point every `step`
  // mm. Ends early (Lost) once the correction exceeds
  // `deviation` mm, or (OverPushed) when the probe is pushed beyond its range.
  ScanEnd along(const std::vector<Eigen::Vector3d>& path,
                const std::vector<Eigen::Vector3d>& normals, const Surface& surface, double speed,
                double pushing, double deviation, double step,
                const std::function<void(const Point&)>& emit);

  // Brings the carriage to rest where it is.
  void settle();

 private:
  double pushed_ = 0;
  SimulatedCmmOptions o_;
  sim::Servo servo_;
  sim::Probe probe_;
  std::function<bool()> hook_;
  void tick(const Eigen::Vector3d& target, const Eigen::Vector3d& feed);
  Eigen::Vector3d real_centre() const;
  sim::ProbeReading read(const Surface& surface);
};

// Surfaces of the nominal world: what a command describes is where the surface is.
Surface plane_surface(const Eigen::Vector3d& point, const Eigen::Vector3d& normal);
// A cone about the axis (point, unit direction) through the circle of `radius` at the point's
// height; `surface_angle` (degrees) turns the outward normal from radial (0: outside of a
// cylinder, 180: inside, 90: a plane facing along the axis).
Surface cone_surface(const Eigen::Vector3d& axis_point, const Eigen::Vector3d& axis, double radius,
                     double surface_angle);

}  // namespace trueaxis::ippdme
