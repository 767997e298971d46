// trueaxis::ippdme — the I++ DME server's session core, without I/O: command lines in, response
// lines out, against the virtual CMM (simulated_cmm.hpp).
//
// What it implements of I++ DME 1.4.3 (VDMA 8722):
// - Sessions: only StartSession and EndSession outside one (else 0008); StartSession in a
//   session is 0008; EndSession always works (it stops daemons and ends the session).
// - Errors: a response Error(severity, number, method, text) with the specification's text. After
//   severity ≥ 2 (or AbortE) the server refuses everything but ClearAllErrors, GetErrStatusE,
//   GetXtdErrStatus and EndSession with 0514 until ClearAllErrors. Pending commands behind an
//   error or an AbortE end with 0006 "Transaction aborted".
// - The fast queue: AbortE, GetErrStatusE, GetPropE and OnMoveReportE (daemons) are answered
//   when received, also while a long move runs; AbortE stops the motion at the next servo tick.
// - The machine (class CartCMMWithRotaryTable): Home, IsHomed, GoTo and Get of X, Y, Z (in the
//   coordinate system chosen), R (the rotary table, degrees) and Tool.A/B/C (the probe head,
//   degrees); the travel checked before a move (2500); LockAxis; EnableUser/DisableUser.
// - Tools: BaseTool, RefTool, NoTool, UnDefTool and Probe1 (the ball of the probe options);
//   FindTool/FoundTool, ChangeTool, SetTool, EnumTools, GetChangeToolAction, AlignTool; the
//   GoToPar, PtMeasPar and ScanPar blocks with Act/Def/Min/Max, values outside clamped with
//   warning 0504; GetProp, SetProp, EnumProp, EnumAllProp. With no tool known (UnDefTool, e.g.
//   at start with EngineOptions::tool) whatever needs the tool answers 1503; NoTool moves but
//   may not measure nor use PtMeasPar (0507), as NIST's command checker answers.
// - Coordinate systems: MachineCsy, MoveableMachineCsy, MultipleArmCsy and PartCsy, each with
//   the transformation SetCsyTransformation gives (x_csy = M(θ, ψ, φ)·(x_machine − X0), the
//   specification's Euler angles); JogDisplayCsy, JogMoveCsy and SensorCsy are kept.
// - Measuring: PtMeas (approach, search, retract as PtMeasPar says; 1006 when no surface is met,
//   1010 for a zero direction), reports as OnPtMeasReport sets (X, Y, Z: the surface point, the
//   ball centre as read compensated by the tip radius along the measured normal, as the servers
//   in NIST's recordings report; IJK: the measured normal; ER: the tip radius; Q, R,
//   Tool.A/B/C); the scans ScanOnLine,
//   ScanOnCircle, ScanOnCurve and the unknown-contour scans ScanInPlaneEndIsSphere/Plane/Cyl and
//   ScanInCylEndIsSphere/Plane (both argument forms: NIST's, and 1.4.3's with the scanning
//   plane's normal and the number of crossings), their hints and OnScanReport; scan data
//   as bare numbers, up to kPointsPerLine points per line, streamed while the scan runs. Their
//   arguments are checked before anything moves: a zero direction 1010, a scan point beyond the
//   travel 0504, coinciding points or a circle's radius off its plane 0502. The stop criteria
//   are judged on the scanned (surface) points.
// - Daemons: OnMoveReportE with Time at least 0.1 s and a positive Dis (else 0510), one at a
//   time (0515); AbortE ends it.
// - Rotary-table part handling: AlignPart (one vector pair), CenterPart, TiltPart and
//   TiltCenterPart answer from the geometry (the table's axis is the machine's Z axis through
//   `table_centre`).
//
// The world the probe meets: with a part (sections of a simulated part, placed at
// `part_origin`) the probe meets its sections, and with balls (a ball gauge standing on the
// table) their spheres, and with boxes (gauge blocks) theirs; with none, each command meets the
// surface it describes (the nominal
// world: PtMeas meets the plane through its point normal to its direction, ScanOnCircle the cone of
// its circle, ScanOnCurve its curve).
//
// Threads: receive() may run on a reader thread while execute_next() runs on a worker thread;
// `send` is called from both and must be thread-safe.
#pragma once

#include <Eigen/Core>
#include <atomic>
#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "trueaxis/ippdme/protocol.hpp"
#include "trueaxis/ippdme/simulated_cmm.hpp"
#include "trueaxis/sim/part.hpp"

namespace trueaxis::ippdme {

inline constexpr int kPointsPerLine = 16;

struct EngineOptions {
  SimulatedCmmOptions cmm;
  std::optional<sim::Part> part;  // the simulated part (none: the nominal world)
  Eigen::Vector3d part_origin = Eigen::Vector3d::Zero();  // its design origin (machine, mm)
  std::vector<sim::Ball> balls;  // spheres the probe meets, with or without a part
  // Boxes the probe meets (gauge blocks). Those of one group are set up together, the groups
  // one after another, as an operator sets up the position being measured: a group is there
  // from a PtMeas whose nominal point is nearest one of its boxes until the probe is moved above
  // every box (then none is, until the next PtMeas).
  std::vector<sim::Box> boxes;
  // The controller's error correction (an error map or a model): it maps a point as the scales
  // read it to the corrected one. Every position and point reported is corrected, and every
  // position commanded is reached through it (its inverse). Empty: none.
  std::function<Eigen::Vector3d(const Eigen::Vector3d&)> correction;
  Eigen::Vector3d table_centre = Eigen::Vector3d::Zero();  // on the rotary table's axis (mm)
  // Machine time against the wall clock: 1 runs in real time, 0 as fast as the simulation goes
  // (for tests and batch runs), 0.1 ten times faster than real time.
  double time_scale = 1;
  std::string version = "1.4.3";  // GetDMEVersion
  // The tool active at start: Probe1, RefTool, NoTool, or UnDefTool (no tool known, as NIST's
  // command checker starts: everything that needs a tool answers 1503 until ChangeTool).
  std::string tool = "Probe1";
};

class Engine {
 public:
  using Send = std::function<void(const std::string& line)>;  // one line, without CR LF
  Engine(EngineOptions options, Send send);
  ~Engine();
  Engine(const Engine&) = delete;
  Engine& operator=(const Engine&) = delete;

  // A received line (without CR LF): syntax errors are answered, a valid command acknowledged;
  // fast-queue commands run at once, the others are queued for execute_next().
  void receive(std::string_view line);
  // A line longer than kMaxLine that the transport skipped: error 0008 with the tag of its start.
  void refuse_overlong(std::string_view start);
  // Runs the next queued command. With `wait`, waits for one (or for stop()); returns false when
  // there was nothing to run.
  bool execute_next(bool wait);
  // Runs queued commands until none is left (single-threaded use).
  void drain();
  // The client went away: stop any motion, drop queued commands and daemons, end the session.
  // The next client finds a clean server (homed state, tools and coordinate systems kept).
  void disconnect();
  // Wakes a waiting execute_next() for good (server shutdown).
  void stop();
  // Flow control for streamed scan data: called on the worker, with no lock held, before each
  // data line of a running scan; it may block until the transport can take more (a slow
  // reader then holds the scan back). `send` itself must never block: it is also called with
  // the engine's state locked, and from receive().
  void set_flow_control(std::function<void()> wait_until_writable);

  const SimulatedCmm& cmm() const;
  double machine_time() const;

  struct State;  // opaque

 private:
  std::unique_ptr<State> s_;
};

}  // namespace trueaxis::ippdme
