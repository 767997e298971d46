// trueaxis::scan — what the scanning controller needs from a CMM, and a virtual CMM that
// provides it (a servo-level simulation).
//
// The interface is the small set of operations a CMM controller offers (and I++ DME carries:
// GoTo, PtMeas, ScanOnCurve, ScanUnknownHint): move, touch a point along a direction, scan along
// a stylus-centre path (design-value scanning), and scan an unknown contour in a plane
// (autonomous scanning). Every operation runs in machine time and reports what it measured.
//
// Units: mm, s. Frame: the machine's, which is the part's design frame. Points returned are
// workpiece surface points: the ball centre compensated by the tip radius along the measured
// normal (the deflection direction), so the pushing amount is compensated too.
#pragma once

#include <Eigen/Core>
#include <array>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "trueaxis/design/design.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/sim/cmm.hpp"
#include "trueaxis/sim/machine.hpp"
#include "trueaxis/sim/part.hpp"
#include "trueaxis/solid/mesh.hpp"

namespace trueaxis::scan {

// One recorded point of a scan.
struct Sample {
  double t = 0;                                       // machine time (s)
  double arc = 0;                                     // along the path or scan (mm)
  Eigen::Vector3d surface = Eigen::Vector3d::Zero();  // workpiece surface point (mm)
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();   // measured surface normal (unit)
  // Trajectory error: how far the ball centre runs from where it would on the design, along the
  // path normal (mm): (ball centre − path point)·normal − Ep, 0 on a perfect part.
  double delta_l = 0;
  double deflection = 0;  // the probe's deflection as read (mm, its magnitude; 0 off the surface)
  bool contact = false, overtravel = false;
};

// What a running scan tells its monitor each servo tick; the monitor returns false to stop.
using Monitor = std::function<bool(const Sample&)>;

struct ScanOutcome {
  std::vector<Sample> samples;  // recorded at about `record_spacing` mm
  bool completed = false;       // ran to the end (else stopped by the monitor or a fault)
  Sample stop;                  // the last tick's state (where it stopped)
  std::string fault;            // why the machine stopped by itself ("" if it did not)
  bool missed_surface = false;  // an autonomous scan's approach found no surface in its search
};

// A free move stopped by the probe: the ball, or the stem above it, met the part where the move
// expected none, and the machine braked within the probe's overtravel. The machine stands
// where it stopped, the stylus still against the part. Over I++ DME: error 1001, "Illegal
// touch", on a GoTo.
class UnexpectedTouch : public Error {
 public:
  UnexpectedTouch(const std::string& what, const Eigen::Vector3d& ball, std::size_t passed)
      : Error(what), at(ball), passed(passed) {}
  Eigen::Vector3d at;      // the ball centre (scale reading) where the probe triggered (mm)
  std::size_t passed = 0;  // how many of the move's waypoints it had reached
};

struct Touch {
  Eigen::Vector3d surface, normal;  // tip-compensated surface point and measured normal
  double t = 0;
};

struct ScanSettings {
  double pushing = 0.3;             // Ep held by active scanning (mm)
  bool active = true;               // active (pushing held along the normal) or passive
  double record_spacing = 0.2;      // mm between recorded samples
  double approach_clearance = 1.0;  // start the approach this far outside the path (mm)
  double approach_limit = 3.0;      // give up if no surface this far inside the path (mm)
};

// The stylus that carries the ball and the probe above it: a straight stem from the ball along the
// stylus axis (towards the head) to the probe's body, a cylinder with a round nose (mm). Both are
// checked as capsules: the stem from the ball to the nose's tip, the body from there.
struct Stylus {
  double length = 50;        // ball centre to the tip of the probe body's nose
  double shaft_radius = 0;   // the stem; 0: half the tip radius (a Ø1 mm stem on a Ø2 mm ball)
  double body_radius = 6.5;  // the probe body (Ø13 mm)
  double body_length = 40;   // from the nose's tip (at least the body's radius)
  // The stem's radius for a ball of this radius.
  double shaft(double tip_radius) const {
    return shaft_radius > 0 ? shaft_radius : 0.5 * tip_radius;
  }
  // Throws Error naming the value: a stem thinner than the ball, a length of at least twice the
  // ball's radius, positive sizes within 1000 mm.
  void validate(double tip_radius) const;
};

class Machine {
 public:
  virtual ~Machine() = default;
  // Turns the stylus so that its axis (the unit vector from the ball towards the head) is
  // `axis`; the operations after it use that orientation. Throws Error if this machine cannot.
  virtual void orient(const Eigen::Vector3d& axis) { axis_ = axis.normalized(); }
  const Eigen::Vector3d& stylus_axis() const { return axis_; }
  virtual double time() const = 0;  // machine seconds so far
  // The deflection beyond which the probe stops the machine (its measuring range, mm), when the
  // scans report the deflection (Sample::deflection) so that the controller can stop before it;
  // empty when the CMM guards its probe itself (an I++ DME server reports error 2001).
  virtual std::optional<double> probe_range() const { return std::nullopt; }
  virtual Eigen::Vector3d position() const = 0;
  // Free move of the (undeflected) stylus centre to `to` at `speed` mm/s, in a straight line.
  // Throws UnexpectedTouch if the probe stops it on the part, and Error if it runs the stylus
  // into the part (a collision: too fast to stop within the probe's overtravel, or the probe's
  // body).
  virtual void move(const Eigen::Vector3d& to, double speed) = 0;
  // The fastest free move the machine stops within half the probe's overtravel when the ball
  // meets the part (mm/s): a move near the part at most this fast ends in UnexpectedTouch, not a
  // collision, where the part is further off its design than the move allowed for. Empty when
  // the machine does not say (then nothing is slowed for it).
  virtual std::optional<double> guarded_speed() const { return std::nullopt; }
  // Free move through the waypoints in turn, straight from each to the next, at up to `speed`.
  // A machine that can (the virtual CMM) does not stop at a waypoint: it turns there at the
  // speed of an arc that cuts the corner by at most kCornerCut and fits on half of each leg, so
  // every point of the motion stays within kCornerCut (and the servo's following error) of the
  // legs. By default, one move() per waypoint.
  static constexpr double kCornerCut = 0.2;  // mm
  virtual void move_through(const std::vector<Eigen::Vector3d>& way, double speed) {
    move_legs(way, std::vector<double>(way.size(), speed));
  }
  // The same with a speed per leg: speeds[i] on the way to way[i] (mm/s, as many as waypoints).
  // UnexpectedTouch::passed counts the waypoints reached.
  virtual void move_legs(const std::vector<Eigen::Vector3d>& way,
                         const std::vector<double>& speeds);
  // From `start` (stylus centre), approach along unit `direction` at `speed` until the deflection
  // reaches `trigger`; then retract 1 mm along the approach (no further than `start`). Nothing if
  // no contact within `distance` mm.
  virtual std::optional<Touch> touch(const design::Plane& plane, const Eigen::Vector3d& start,
                                     const Eigen::Vector3d& direction, double distance,
                                     double speed, double trigger) = 0;
  // Design-value scanning along a stylus-centre path (its segments' speeds).
  virtual ScanOutcome scan_path(const design::ScanPath& path, const ScanSettings& settings,
                                const Monitor& monitor) = 0;
  // Autonomous scanning in a plane: from `start` (stylus centre, free) approach along
  // `approach` to the surface, then follow it with the deflection held at settings.pushing, the
  // material on `material` side of the direction of travel, at `speed`, until back at the first
  // contact (closed) or after `length` mm (open).
  virtual ScanOutcome scan_unknown(const design::Plane& plane, const Eigen::Vector3d& start,
                                   const Eigen::Vector3d& approach, design::Side material,
                                   bool closed, double length, double speed,
                                   const ScanSettings& settings) = 0;

 protected:
  Eigen::Vector3d axis_ = Eigen::Vector3d::UnitZ();
};

// The virtual CMM: a servo-controlled carriage and a scanning probe in front of a simulated
// part. With the part's solid (its design's STEP file, or VirtualCmmOptions::solid), every servo
// tick checks the ball, the stylus and the probe body against the real part (the solid moved
// with the part's deviations) and the table under it: the ball may touch the faces that cross
// the plane it measures in, and nothing else; the stylus and the body touch nothing. A collision
// stops the machine and throws Error saying what hit where. The part's section whose design plane
// contains an operation's plane is the surface the probe meets (each section's true contour, built
// once). A space-curve path meets the part's space-curve section of the same name (sim::SpaceCurve:
// its tangent planes along the curve).
//
// Optionally the CMM has the 21 geometric errors of a sim::Machine: the servo runs on the
// scale readings, and the ball centre really is where the erroneous axes put it. With the
// part's design origin at `part_origin` in machine coordinates, the scale position p (part
// frame) is the machine command c = p + part_origin − machine.offset, and the free ball centre
// is p + machine.error(c). The probe meets the part at the real ball centre, while every
// reported point is built from the scale readings, so the machine's errors are in the
// measurement as on a real CMM.
struct VirtualCmmOptions {
  sim::ServoOptions servo;
  sim::ProbeOptions probe;
  double path_acceleration = 2000;  // ramps of the path speed at a scan's start and end (mm/s²)
  double correction_gain = 60;      // active scanning: normal correction rate (1/s)
  double positioning_speed = 100;   // free moves within an operation (mm/s)
  double approach_speed = 10;       // approaching the surface before a scan (mm/s)
  std::optional<sim::Machine> geometry;  // the CMM's geometric errors (none if empty)
  // Machine coordinates of the part's design origin (mm). Empty: the part's bounding box is
  // centred in the machine's travel.
  std::optional<Eigen::Vector3d> part_origin;
  double clearance = 30;  // the part's box grown by this must fit in the travel (mm)
  // The part as a solid, in its design frame, when its design names no STEP file (otherwise
  // that file's). The CMM moves it with the part's deviations and stops at any collision of
  // the ball, the stylus or the probe body with it, or with the table it stands on.
  std::shared_ptr<const solid::Mesh> solid;
  Stylus stylus;
  bool table = true;  // the part stands on the machine's table (a plane at its lowest point)
  // How far the stylus gives way past the probe's trigger before the probe is damaged (mm): a
  // free move that meets the part stops on the probe's trigger (UnexpectedTouch) when the machine
  // brakes, at path_acceleration, within this; beyond, it is a collision.
  double overtravel = 2.0;
};

class VirtualCmm : public Machine {
 public:
  VirtualCmm(sim::Part part, const VirtualCmmOptions& options,
             const Eigen::Vector3d& home = Eigen::Vector3d::Zero());
  double time() const override { return servo_.time(); }
  std::optional<double> probe_range() const override { return probe_.options().range; }
  std::optional<double> guarded_speed() const override;
  Eigen::Vector3d position() const override { return servo_.position(); }
  void orient(const Eigen::Vector3d& axis) override;
  void move(const Eigen::Vector3d& to, double speed) override;
  void move_through(const std::vector<Eigen::Vector3d>& way, double speed) override;
  void move_legs(const std::vector<Eigen::Vector3d>& way,
                 const std::vector<double>& speeds) override;
  std::optional<Touch> touch(const design::Plane& plane, const Eigen::Vector3d& start,
                             const Eigen::Vector3d& direction, double distance, double speed,
                             double trigger) override;
  ScanOutcome scan_path(const design::ScanPath& path, const ScanSettings& settings,
                        const Monitor& monitor) override;
  ScanOutcome scan_unknown(const design::Plane& plane, const Eigen::Vector3d& start,
                           const Eigen::Vector3d& approach, design::Side material, bool closed,
                           double length, double speed, const ScanSettings& settings) override;

  // Signed distance of p from the true part in `plane` (the nearest of the contours the part
  // has there; > 0 outside the material), for checks against the truth. Throws Error if the
  // part has no section in that plane.
  double distance(const design::Plane& plane, const Eigen::Vector3d& p) const;
  // The same for the part's section of that name as the probe meets it (a space curve's
  // surface, or the contours in the section's plane).
  double distance(const design::Section& section, const Eigen::Vector3d& p) const;
  const sim::Part& part() const { return part_; }
  // With geometric errors: the part's design origin in machine coordinates, and the CMM's
  // error (real − read ball centre, mm) at scale position p (part frame). Zero without.
  const Eigen::Vector3d& part_origin() const { return origin_; }
  Eigen::Vector3d machine_error(const Eigen::Vector3d& p) const;
  // The real part's solid (moved with its deviations; null without a solid), and the solid
  // checks made so far (a tick whose motion since the last check is less than the clearance
  // then found needs none).
  const std::shared_ptr<const solid::Mesh>& solid() const { return solid_; }
  long solid_checks() const { return solid_checks_; }

 private:
  sim::Part part_;
  VirtualCmmOptions o_;
  sim::Servo servo_;
  sim::Probe probe_;
  std::vector<std::pair<design::Plane, sim::Contour>> contours_;
  std::vector<std::pair<std::string, sim::SpaceCurve>> spaces_;  // space-curve sections
  const sim::SpaceCurve* space_ = nullptr;  // the surface of the space path being scanned
  const sim::SpaceCurve& space_curve(const std::string& name) const;
  // The contours of the part in a plane (a plane may cut several: an outline and its holes).
  std::vector<const sim::Contour*> in_plane(const design::Plane& plane) const;
  sim::ProbeReading read(const std::vector<const sim::Contour*>& part);
  const sim::Contour* last_contour_ = nullptr;
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
  Sample sample(const sim::ProbeReading& r, double arc) const;
  // Where the undeflected ball centre really is: the scale position plus the machine's error.
  Eigen::Vector3d free_ball_centre() const;
  // How far the ball sinks into the part's sections it straddles (mm; 0 when free). Space
  // curves, whose surface model holds only near them, are not checked.
  // `push` (if given) receives the deflection the deepest of them gives the ball.
  double penetration(Eigen::Vector3d* push = nullptr) const;
  // Brings the carriage to rest where it is (the end of a scan or touch, before retracting).
  void settle();
  // After a scan: `distance` away from the surface along the first of `along` the probe is not
  // stopped on (back to the scan's end after each that is); where none, the ball stays at the
  // end and out.fault says why.
  void retract(const std::vector<Eigen::Vector3d>& along, double distance, ScanOutcome& out);

  // The solid: the real part, the table's height, the faces the ball may touch (those crossing
  // the plane of the operation under way), how far the ball may enter the others, and where and
  // how much clearance the last check found.
  std::shared_ptr<const solid::Mesh> solid_;
  double table_z_ = -INFINITY;
  std::vector<char> touchable_;
  // The operation's plane normal (zero in a free move): a ball touching a face the plane does not
  // cross whose normal there lies near the plane is on the wall it scans, where the CAD file
  // splits it at or near the plane (solid::scans_on).
  Eigen::Vector3d plane_normal_ = Eigen::Vector3d::Zero();
  double ball_allowance_ = 0;
  // How deep the real part lies inside the moved design solid where it is dented (its deepest
  // dent and form noise, mm): the stylus may enter the solid that far.
  double dent_ = 0;
  Eigen::Vector3d deflection_ = Eigen::Vector3d::Zero();  // the probe's, as last read (true)
  // Where the ball stands off the deflected centre in a concave corner (mm, in the plane): the
  // probe reads the contact with the nearer wall, while the ball rests against both.
  Eigen::Vector3d corner_ = Eigen::Vector3d::Zero();
  // Per element (ball, stylus, body): where it was last checked and the clearance found then
  // (< 0: check at the next tick).
  std::array<Eigen::Vector3d, 3> guard_at_{};
  std::array<double, 3> guard_clear_{-1, -1, -1};
  long solid_checks_ = 0;
  // The operation in `plane`: its faces may be touched by the ball (null: none, a free move).
  void touch_faces(const design::Plane* plane);
  // Checks the ball, stylus and body at the carriage's position; throws Error at a collision.
  // In a guarded motion (a free move, a touch's approach) the ball or the stem meeting the part
  // is not thrown: it sets triggered_ (0 ball, 1 stem), and the motion brakes.
  void check_solid();
  bool guarded_ = false;
  int triggered_ = -1;
  bool on_table_ = false;      // what triggered it met the table, not the part
  double stem_allowance_ = 0;  // how deep the stem may be in the part (a move that starts there)
  // How far the ball and the stem are pushed into the part (the section's contours and the
  // solid) where the carriage stands (mm).
  double pushed_in() const;
  // After the probe triggered at `speed` along `dir` with the ball at `hit`: brakes, then throws
  // UnexpectedTouch (passed: waypoints reached), or Error when the stylus was pushed in beyond
  // the overtravel.
  // The braking: throws Error at a collision, else returns what met the part where, in words
  // (`doing`: "on a free move", "scanning").
  std::string brake(const Eigen::Vector3d& hit, const Eigen::Vector3d& target,
                    const Eigen::Vector3d& dir, double speed, double start, const char* doing);
  [[noreturn]] void stop_on_contact(const Eigen::Vector3d& hit, const Eigen::Vector3d& target,
                                    const Eigen::Vector3d& dir, double speed, double start,
                                    std::size_t passed);
  struct Operation;  // sets and restores the touchable faces
};

}  // namespace trueaxis::scan
