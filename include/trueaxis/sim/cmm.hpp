// trueaxis::sim — the moving parts of a virtual scanning CMM: a servo-controlled 3-axis
// carriage, a workpiece section contour the probe can touch, and a spring-mounted scanning probe
// with a ball tip.
//
// Units: mm, s. Frame: the machine's (which is also the part's: the part is clamped with its
// design frame on the machine frame). Time advances in servo ticks; machine time is counted in
// simulated seconds, independent of how fast the simulation runs.
//
// Servo. Each axis runs the same discrete position loop at `rate_hz`: commanded velocity
//   v_cmd = v_ff + kp·(target − position), clamped to ±max_velocity,
// the drive follows it as a first-order lag of time constant `lag`, its acceleration clamped to
// ±max_acceleration, and the position integrates the drive's velocity. With the path's velocity
// fed forward, a straight line at constant speed is followed with no error once the transient
// has died; on a curve of radius R at speed v the following error is of order lag²·v²/R.
//
// Probe. The ball (radius r) centre sits at the carriage's position when free. Where the true
// surface is closer than r, the ball is pushed out along the surface normal by the penetration:
// the deflection. The probe reads the deflection (3-D) with Gaussian noise; no contact means no
// deflection (lifted off); a deflection beyond the measuring range is an over-push. The ball
// centre is position + deflection, and the surface point is the ball centre − r·normal.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <random>
#include <vector>

namespace trueaxis::sim {

struct ServoOptions {
  double rate_hz = 1000;           // control-loop rate (Hz)
  double max_velocity = 250;       // per axis (mm/s)
  double max_acceleration = 3000;  // per axis (mm/s²)
  double lag = 0.002;              // drive time constant (s)
  double position_gain = 200;      // kp (1/s)
  // Throws Error naming the option when out of range (rate 10 Hz–100 kHz; the lag at least two
  // ticks and below 1 s; positive limits and gain; kp·lag ≤ 0.5 so that the loop is stable).
  void validate() const;
  double dt() const { return 1.0 / rate_hz; }
};

class Servo {
 public:
  Servo(const ServoOptions& options, const Eigen::Vector3d& start);
  // One control tick: `target` is the path's position at the current machine time (the start of
  // the tick) and `feed` its velocity, fed forward (mm, mm/s). After the tick, time() has
  // advanced by one period.
  void step(const Eigen::Vector3d& target, const Eigen::Vector3d& feed);
  const Eigen::Vector3d& position() const { return position_; }
  const Eigen::Vector3d& velocity() const { return velocity_; }
  double time() const { return time_; }  // simulated seconds since construction
  long ticks() const { return ticks_; }
  const ServoOptions& options() const { return o_; }

 private:
  ServoOptions o_;
  Eigen::Vector3d position_, velocity_ = Eigen::Vector3d::Zero();
  double time_ = 0;
  long ticks_ = 0;
};

// A workpiece section: a closed or open polyline in a plane, with the material on one side.
// Nearest-point queries are exact: a first bound from the segments around the one found last (a
// probe moving along the contour finds its minimum there), then a uniform grid of the segments
// searched in rings outward from the query until no closer segment can remain. Near the contour
// that costs a few cells, whatever the contour's length.
class Contour {
 public:
  // points: 3 × n (n ≥ 2), in the plane through points with unit normal `plane_normal`.
  // material_left: the material is on the left walking along the points, seen from the normal.
  Contour(Eigen::Matrix3Xd points, const Eigen::Vector3d& plane_normal, bool closed,
          bool material_left);

  struct Nearest {
    Eigen::Vector3d point;   // foot on the contour (mm)
    Eigen::Vector3d normal;  // unit, in the plane, away from the material
    double distance = 0;     // signed in-plane distance: > 0 on the free side, < 0 in material
    double arc = 0;          // arc length of the foot from the contour's start (mm)
  };
  // The nearest point of the contour to q's projection into the plane.
  Nearest nearest(const Eigen::Vector3d& q) const;
  // The same, if it lies closer than `radius` (mm; in the plane): cheap when nothing does.
  std::optional<Nearest> nearest_within(const Eigen::Vector3d& q, double radius) const;

  const Eigen::Matrix3Xd& points() const { return p_; }
  const Eigen::Vector3d& plane_normal() const { return n_; }
  bool closed() const { return closed_; }
  double length() const { return arc_[arc_.size() - 1]; }

 private:
  Nearest at_segment(Eigen::Index i, const Eigen::Vector3d& q) const;
  double dist2(Eigen::Index i, const Eigen::Vector3d& q) const;  // squared, unsigned
  Eigen::Matrix3Xd p_;
  Eigen::Vector3d n_;
  bool closed_, left_;
  Eigen::VectorXd arc_;       // cumulative length at each point
  Eigen::Matrix3Xd normals_;  // per segment, away from the material
  Eigen::Matrix3Xd dir_;      // per segment: end − start
  Eigen::VectorXd inv_len2_;  // per segment: 1 / |end − start|²
  // The grid: cell (i, j) of size h_ in the plane frame (e1_, e2_) from corner lo_.
  Eigen::Vector3d e1_, e2_;
  Eigen::Vector2d lo_;
  double h_ = 1;
  int nx_ = 1, ny_ = 1;
  std::vector<int> cell_start_, cell_items_;  // segments of cell c: items[start[c] .. start[c+1])
  mutable Eigen::Index hint_ = -1;
};

// A workpiece surface along a space curve (e.g. a spiral over a sphere): the curve's points with
// their surface normals (away from the material). Near the curve the surface is taken as its
// tangent plane at the nearest curve point: the signed distance of q is (q − foot)·normal, the
// normal interpolated along each segment. That is exact on the curve and good to
// (lateral offset)²/2R on a surface of radius R, for a probe that follows the curve. Nearest
// points by a scan of all segments (O(n) per query; space-curve sections are short).
class SpaceCurve {
 public:
  // points, normals: 3 × n (n ≥ 2); normals of non-zero length.
  SpaceCurve(Eigen::Matrix3Xd points, Eigen::Matrix3Xd normals);
  Contour::Nearest nearest(const Eigen::Vector3d& q) const;
  const Eigen::Matrix3Xd& points() const { return p_; }

 private:
  Eigen::Matrix3Xd p_, n_;
  Eigen::VectorXd arc_;
};

// A ball standing in the machine's volume, such as one of a ball gauge's: its true centre (mm,
// machine coordinates) and radius (mm).
struct Ball {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double radius = 0;
};

// A box standing in the machine, such as a gauge block: its centre, its axes (the columns of
// `axes`, orthonormal) and half its size along each (mm, machine coordinates). `group`: which
// set-up it belongs to (artefacts set up one after another).
struct Box {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
  Eigen::Vector3d half = Eigen::Vector3d::Ones();
  int group = 0;
  // The nearest point of its surface to x, the outward normal there, and the signed distance
  // (> 0 outside; inside, to the nearest face).
  Contour::Nearest nearest(const Eigen::Vector3d& x) const;
  double top() const;  // its highest point's z (mm)
};

// A touch-trigger probe's pre-travel variation with the probing direction d (unit, machine
// frame; the stylus along −Z): lobing·cos(3φ)·sin²θ, φ the azimuth of d and θ its angle from
// the stylus axis — the three lobes of a kinematic probe's three contacts, its mean taken out by
// the probe's qualification (mm). The point latched lies this much further along d.
double pretravel_lobing(double lobing, const Eigen::Vector3d& d);

struct ProbeOptions {
  double tip_radius = 1.0;  // ball radius (mm)
  double range = 1.0;       // measuring range of the deflection (mm)
  double noise = 0;         // standard deviation of each deflection component (mm)
  double lobing = 0;        // single points: pre-travel variation (pretravel_lobing, mm)
  std::uint64_t seed = 1;
  // Throws Error: radius in (0, 50], range in (0, 10], noise and lobing in [0, 0.1].
  void validate() const;
};

struct ProbeReading {
  bool contact = false;     // the ball touches the surface (deflection > 0)
  bool overtravel = false;  // deflection beyond the measuring range
  Eigen::Vector3d deflection = Eigen::Vector3d::Zero();  // as read, with noise (mm)
  Eigen::Vector3d true_deflection = Eigen::Vector3d::Zero();
  Contour::Nearest surface;  // where the ball touches (or the nearest point when free)
};

class Probe {
 public:
  explicit Probe(const ProbeOptions& options);
  // The reading with the carriage (free ball centre) at `position` against `part`.
  ProbeReading read(const Eigen::Vector3d& position, const Contour& part);
  // The same, given the nearest point of the part already found for that position.
  ProbeReading read(const Contour::Nearest& surface);
  const ProbeOptions& options() const { return o_; }

 private:
  ProbeOptions o_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> gauss_{0.0, 1.0};
};

}  // namespace trueaxis::sim
