// trueaxis::ippdme — a CMM driven over I++ DME as the scanning controller's machine: the
// error-tolerant scanning flow (scan::scan) runs unchanged against any I++ DME server, the
// virtual CMM of `trueaxis serve` or a real controller.
//
// The controller's operations, as I++ DME commands:
//   move          GoTo, at GoToPar.Speed.
//   touch         PtMeas along the direction (PtMeasPar: Approach 0, Search, Speed, Retract 1);
//                 the surface point and normal as the server reports them (OnPtMeasReport with
//                 IJK). Error 1006 (surface not found): no contact.
//   scan_path     ScanOnCurve through the design's surface points and normals (the stylus-centre
//                 path less the tip radius and pushing), ScanOnCurveHint with the largest deviation
//                 it may follow, the path's mean design speed as ScanPar.Speed. The trajectory
//                 error ΔL of every streamed point is computed here against the path; the monitor
//                 judges it as the points arrive, and a stop is an AbortE (then ClearAllErrors).
//   scan_unknown  PtMeas for the first contact, then ScanInPlaneEndIsSphere in the section's
//                 plane from it: closed contours end in a sphere around that contact (the server
//                 ends the scan), open ones after `length` mm of points (AbortE from here).
// Versions: the server is asked its I++ DME version first. Design-value scanning uses 1.4.2's
// ScanOnCurve; a server older than 1.4.2 scans point by point instead (point_scan below: a PtMeas
// every `point_step` mm of the path, each judged by the monitor as it comes), and the tip radius
// must then be given (Tool.AvrRadius is 1.4.2's too). Autonomous scanning needs 1.4.3's
// ScanInPlaneEndIsSphere: on an older server an autonomous scan ends its section with the
// reason.
// Frame: with `part_origin`, PartCsy is set to the part's design frame (SetCsyTransformation, a
// translation) and every command and point is in it; without, the server's current coordinate
// system is used as it is.
// Time: the wall-clock time since the session started (s), as the client sees it; with
// `trueaxis serve --time-scale 1` (real time) that is the machine time.
#pragma once

#include <Eigen/Core>
#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "trueaxis/ippdme/client.hpp"
#include "trueaxis/scan/machine.hpp"

namespace trueaxis::ippdme {

struct RemoteCmmOptions {
  ClientOptions client;
  std::optional<Eigen::Vector3d> part_origin;  // machine coordinates of the design origin (mm)
  // The stylus tip's radius (mm): the scanning path is built with it, and a streamed point's
  // ball centre is the surface point plus this along its normal. 0: the active tool's, as the
  // server reports it (GetProp(Tool.AvrRadius())).
  double tip_radius = 1;
  std::string tool = "Probe1";  // ChangeTool to this at the start ("" keeps the active tool)
  // Points of the nominal curve sent with ScanOnCurve, this far apart along the path (mm); at
  // most 1000 points (a path longer than 250 mm gets a wider step), so that the command fits
  // in one protocol line.
  double curve_step = 0.25;
  // ScanOnCurveHint's deviation: how far the server may follow the surface off the path (mm).
  double follow_deviation = 3;
  // Scanning point by point (servers before I++ DME 1.4.2): a point this far apart along the
  // path (mm), each probed at this speed (mm/s).
  double point_step = 0.5;
  double point_speed = 10;
  void validate() const;  // throws Error naming the option
};

class RemoteCmm : public scan::Machine {
 public:
  // Connects, starts a session, homes the CMM if it is not, selects the tool, the report formats
  // and the part frame. Throws Error (naming host and port, or the server's error) when any of
  // that fails.
  explicit RemoteCmm(const RemoteCmmOptions& options);
  ~RemoteCmm() override;  // EndSession (errors ignored)
  RemoteCmm(const RemoteCmm&) = delete;
  RemoteCmm& operator=(const RemoteCmm&) = delete;

  double time() const override;
  Eigen::Vector3d position() const override;
  void move(const Eigen::Vector3d& to, double speed) override;
  std::optional<scan::Touch> touch(const design::Plane& plane, const Eigen::Vector3d& start,
                                   const Eigen::Vector3d& direction, double distance, double speed,
                                   double trigger) override;
  scan::ScanOutcome scan_path(const design::ScanPath& path, const scan::ScanSettings& settings,
                              const scan::Monitor& monitor) override;
  scan::ScanOutcome scan_unknown(const design::Plane& plane, const Eigen::Vector3d& start,
                                 const Eigen::Vector3d& approach, design::Side material,
                                 bool closed, double length, double speed,
                                 const scan::ScanSettings& settings) override;

  // One point as measuring software takes it: PtMeas of the nominal surface point `at` with
  // its outward normal, the tip starting `approach` mm (plus its radius) out along the normal
  // and searching `search` mm beyond `at` at `speed` (mm/s), retracting 1 mm. The surface point
  // and normal as reported; nothing when no surface was met (1006). Throws Error for any other
  // error of the server.
  std::optional<scan::Touch> measure(const Eigen::Vector3d& at, const Eigen::Vector3d& normal,
                                     double approach, double search, double speed);

  // The stylus stays as the server's tool has it (taken to be vertical): any other orientation
  // is refused (scan::NoWay: the section is not scanned, the machine has not moved).
  void orient(const Eigen::Vector3d& axis) override;

  // The I++ DME version the server reports (GetDMEVersion), e.g. "1.4.3".
  const std::string& version() const { return version_; }
  // Whether design-value scans run point by point (the server predates ScanOnCurve).
  bool scans_by_points() const { return !curve_scans_; }

  // The active tool's mean tip radius as the server knows it (GetProp(Tool.AvrRadius()), mm).
  double tool_radius();
  // The tip radius in use (options.tip_radius, or the server's when that was 0), mm.
  double tip_radius() const { return o_.tip_radius; }

  // The commands sent so far, AbortE and ClearAllErrors included (for logs and tests).
  long commands() const { return commands_; }
  Client& client() { return *client_; }

 private:
  RemoteCmmOptions o_;
  std::unique_ptr<Client> client_;
  std::chrono::steady_clock::time_point t0_;
  std::string version_;
  bool in_plane_scans_ = true;  // ScanInPlaneEndIsSphere in its 1.4.3 form
  bool curve_scans_ = true;     // ScanOnCurve (1.4.2)
  double goto_speed_ = -1, scan_speed_ = -1;
  // PtMeasPar as last set (by measure(), through which touch() goes too).
  double touch_search_ = -1, touch_speed_ = -1, touch_approach_ = 0;
  mutable long commands_ = 0;
  // Every command goes through call(), which counts it.
  Transaction call(const std::string& command) const;
  // Runs a command; errors of severity ≥ 2 are cleared (ClearAllErrors) and returned as the
  // transaction's, lower ones (warnings such as a clamped value) are dropped.
  Transaction run(const std::string& command);
  // Runs a command that must succeed; throws Error with the server's error otherwise.
  Transaction must(const std::string& command);
  // Runs a scan command (points reported as X(), Y(), Z(), IJK()), passing each point to `take`
  // as it arrives; when `take` returns false the scan is stopped (AbortE) and its points after
  // that are not passed on. Errors as run() gives them, less the stop's own 0006.
  using PointSink =
      std::function<bool(const Eigen::Vector3d& surface, const Eigen::Vector3d& normal)>;
  Transaction scan(const std::string& command, const PointSink& take);
  // Design-value scanning by single points along the path (servers before 1.4.2).
  scan::ScanOutcome point_scan(const design::ScanPath& path, const scan::ScanSettings& settings,
                               const scan::Monitor& monitor);
  void set_goto_speed(double speed);
  void set_scan_speed(double speed);
};

}  // namespace trueaxis::ippdme
