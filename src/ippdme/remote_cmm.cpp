// The scanning controller's machine over I++ DME: each operation as the protocol's commands.
#include "trueaxis/ippdme/remote_cmm.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "trueaxis/error.hpp"
#include "trueaxis/scan/planner.hpp"

namespace trueaxis::ippdme {
namespace {

constexpr int kSurfaceNotFound = 1006;
constexpr int kCurvePoints = 1000;  // about 58 characters each: within a 65 536-character line

int severity(const Response& e) {
  return static_cast<int>(e.items.at(0).args.at(0).number());
}
int number(const Response& e) {
  return static_cast<int>(e.items.at(0).args.at(1).number());
}
std::string describe(const Response& e) {
  const auto& a = e.items.at(0).args;
  return fmt::format("error {:04d} {}", number(e), a.size() > 3 ? a[3].text : std::string());
}

std::string xyz(const Eigen::Vector3d& p) {
  return fmt::format("X({:.6f}), Y({:.6f}), Z({:.6f})", p.x(), p.y(), p.z());
}
std::string ijk(const Eigen::Vector3d& n) {
  return fmt::format("IJK({:.9f}, {:.9f}, {:.9f})", n.x(), n.y(), n.z());
}

// The numbers of one data line (bare scan numbers, or the arguments of X(), IJK(), ...).
std::vector<double> numbers_of(const Response& d) {
  std::vector<double> v;
  for (const auto& it : d.items) {
    if (it.kind == Value::Kind::Number) v.push_back(it.number());
    for (const auto& a : it.args)
      if (a.kind == Value::Kind::Number) v.push_back(a.number());
  }
  return v;
}

}  // namespace

void RemoteCmmOptions::validate() const {
  if (!(tip_radius >= 0) || !std::isfinite(tip_radius))
    throw Error("I++ DME CMM: the tip radius must be positive (mm), or 0 for the server's");
  if (!(curve_step > 0)) throw Error("I++ DME CMM: the curve step must be positive (mm)");
  if (!(follow_deviation > 0))
    throw Error("I++ DME CMM: the follow deviation must be positive (mm)");
  if (!(point_step >= 0.01 && point_step <= 10))
    throw Error("I++ DME CMM: the point step must be 0.01 to 10 mm");
  if (!(point_speed > 0 && point_speed <= 100))
    throw Error("I++ DME CMM: the point speed must be positive, at most 100 mm/s");
}

RemoteCmm::RemoteCmm(const RemoteCmmOptions& options) : o_(options) {
  o_.validate();
  client_ = std::make_unique<Client>(o_.client);
  t0_ = std::chrono::steady_clock::now();
  must("StartSession()");
  // What the server speaks: DMEVersion("1.4.3").
  {
    const auto tr = run("GetDMEVersion()");
    for (const auto& d : tr.data)
      for (const auto& it : d.items)
        if (it.is_call("DMEVersion") && !it.args.empty()) version_ = it.args[0].text;
    const auto v = tr.errors.empty() ? version_number(version_) : std::nullopt;
    if (!v)
      throw Error(fmt::format(
          "I++ DME server at {}:{} does not say which I++ DME it speaks {}: trueaxis does not "
          "guess which commands it has",
          o_.client.host, o_.client.port,
          !tr.errors.empty() ? "(GetDMEVersion refused: " + describe(tr.errors.front()) + ")"
          : version_.empty() ? std::string("(no version given)")
                             : "('" + version_ + "' is not a version)"));
    curve_scans_ = *v >= 10402;
    in_plane_scans_ = *v >= 10403;
    if (!curve_scans_ && o_.tip_radius == 0)
      throw Error(fmt::format(
          "I++ DME server at {}:{} speaks I++ DME {}, which has no Tool.AvrRadius (1.4.2): give "
          "the stylus tip's radius",
          o_.client.host, o_.client.port, version_));
  }
  const auto homed = must("IsHomed()").numbers();
  if (homed.empty() || homed[0] == 0) must("Home()");
  if (!o_.tool.empty()) must(fmt::format("ChangeTool(\"{}\")", o_.tool));
  if (o_.tip_radius == 0) {
    o_.tip_radius = tool_radius();
    if (!(o_.tip_radius > 0))
      throw Error("I++ DME CMM: the server's tool has no tip radius (GetProp(Tool.AvrRadius()))");
  }
  must("OnPtMeasReport(X(), Y(), Z(), IJK())");
  must("OnScanReport(X(), Y(), Z(), IJK())");
  if (o_.part_origin) {
    const auto& p = *o_.part_origin;
    must(fmt::format("SetCsyTransformation(PartCsy, {:.6f}, {:.6f}, {:.6f}, 0, 0, 0)", p.x(), p.y(),
                     p.z()));
    must("SetCoordSystem(PartCsy)");
  }
}

RemoteCmm::~RemoteCmm() {
  try {
    if (client_ && client_->connected()) call("EndSession()");
  } catch (...) {  // the session ends with the connection anyway
  }
}

Transaction RemoteCmm::call(const std::string& command) const {
  ++commands_;
  return client_->call(command);
}

Transaction RemoteCmm::run(const std::string& command) {
  auto tr = call(command);
  auto& e = tr.errors;
  e.erase(std::remove_if(e.begin(), e.end(), [](const Response& r) { return severity(r) < 2; }),
          e.end());
  if (!e.empty()) call("ClearAllErrors()");
  return tr;
}

Transaction RemoteCmm::scan(const std::string& command, const PointSink& take) {
  ++commands_;
  const Tag tag = client_->send(command);
  std::vector<double> pending;  // numbers of a point not complete yet
  bool stop = false, aborted = false;
  std::size_t points = 0;
  auto tr = client_->wait(tag, [&](const Response& d) {
    const auto v = numbers_of(d);
    pending.insert(pending.end(), v.begin(), v.end());
    std::size_t i = 0;
    for (; i + 6 <= pending.size() && !stop; i += 6, ++points)
      stop = !take(Eigen::Vector3d(pending[i], pending[i + 1], pending[i + 2]),
                   Eigen::Vector3d(pending[i + 3], pending[i + 4], pending[i + 5]).normalized());
    pending.erase(pending.begin(), pending.begin() + static_cast<std::ptrdiff_t>(i));
    if (stop && !aborted) {
      ++commands_;
      client_->send("AbortE()");
      aborted = true;
    }
  });
  // A warning is dropped when the scan ran; a scan that gave no point at all failed, whatever
  // the severity the server gave it (0504, an argument out of range, is a warning by number).
  auto& e = tr.errors;
  if (points > 0)
    e.erase(std::remove_if(e.begin(), e.end(), [](const Response& r) { return severity(r) < 2; }),
            e.end());
  if (!e.empty() || aborted) call("ClearAllErrors()");
  if (aborted) e.clear();  // the 0006 of the stop asked for
  return tr;
}

Transaction RemoteCmm::must(const std::string& command) {
  auto tr = run(command);
  if (!tr.errors.empty())
    throw Error(fmt::format("I++ DME server at {}:{}: {} failed: {}", o_.client.host,
                            o_.client.port, command.substr(0, command.find('(')),
                            describe(tr.errors.front())));
  return tr;
}

double RemoteCmm::time() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
}

Eigen::Vector3d RemoteCmm::position() const {
  const auto v = call("Get(X(), Y(), Z())").numbers();
  if (v.size() < 3) throw Error("I++ DME: Get(X(), Y(), Z()) returned no position");
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

void RemoteCmm::orient(const Eigen::Vector3d& axis) {
  const Eigen::Vector3d u = axis.normalized();
  if ((u - Eigen::Vector3d::UnitZ()).norm() > 1e-9)
    throw scan::NoWay(fmt::format(
        "the stylus along ({:.3f}, {:.3f}, {:.3f}): over I++ DME trueaxis scans with the server's "
        "tool as it is, taken to be vertical; turning a probe head is not supported",
        u.x(), u.y(), u.z()));
  scan::Machine::orient(u);
}

double RemoteCmm::tool_radius() {
  const auto v = must("GetProp(Tool.AvrRadius())").numbers();
  if (v.empty() || !(v[0] >= 0)) throw Error("I++ DME: GetProp(Tool.AvrRadius()) gave no radius");
  return v[0];
}

void RemoteCmm::set_goto_speed(double speed) {
  if (speed == goto_speed_) return;
  must(fmt::format("SetProp(Tool.GoToPar.Speed({:g}))", speed));
  goto_speed_ = speed;
}

void RemoteCmm::set_scan_speed(double speed) {
  if (speed == scan_speed_) return;
  must(fmt::format("SetProp(Tool.ScanPar.Speed({:g}))", speed));
  scan_speed_ = speed;
}

void RemoteCmm::move(const Eigen::Vector3d& to, double speed) {
  set_goto_speed(speed);
  const auto tr = run(fmt::format("GoTo({})", xyz(to)));
  if (tr.errors.empty()) return;
  const auto& e = tr.errors.front();
  if (number(e) == 1001)
    throw scan::UnexpectedTouch(
        fmt::format("the probe stopped the move to ({:.3f}, {:.3f}, {:.3f}) mm on the part (I++ "
                    "DME {})",
                    to.x(), to.y(), to.z(), describe(e)),
        position(), 0);
  if (number(e) == 2504)
    throw Error(
        fmt::format("collision: the stylus met the part on the way to ({:.3f}, {:.3f}, "
                    "{:.3f}) mm (I++ DME {})",
                    to.x(), to.y(), to.z(), describe(e)));
  throw Error(fmt::format("I++ DME: GoTo ({:.3f}, {:.3f}, {:.3f}) mm failed: {}", to.x(), to.y(),
                          to.z(), describe(e)));
}

std::optional<scan::Touch> RemoteCmm::touch(const design::Plane&, const Eigen::Vector3d& start,
                                            const Eigen::Vector3d& direction, double distance,
                                            double speed, double) {
  // PtMeas starts `Approach` plus the tip radius off its nominal point, along IJK, and searches
  // `Search` beyond it: with Approach 0 the nominal point is one tip radius ahead of the start.
  const Eigen::Vector3d d = direction.normalized();
  const double r = o_.tip_radius;
  return measure(start + r * d, -d, 0, std::max(0.1, distance - r), speed);
}

std::optional<scan::Touch> RemoteCmm::measure(const Eigen::Vector3d& at,
                                              const Eigen::Vector3d& normal, double approach,
                                              double search, double speed) {
  if (search != touch_search_ || speed != touch_speed_ || approach != touch_approach_) {
    must(
        fmt::format("SetProp(Tool.PtMeasPar.Approach({:g}), Tool.PtMeasPar.Search({:g}), "
                    "Tool.PtMeasPar.Speed({:g}), Tool.PtMeasPar.Retract(1))",
                    approach, search, speed));
    touch_search_ = search;
    touch_speed_ = speed;
    touch_approach_ = approach;
  }
  const auto tr = run(fmt::format("PtMeas({}, {})", xyz(at), ijk(normal.normalized())));
  const double t = time();
  if (!tr.errors.empty()) {
    if (number(tr.errors.front()) == kSurfaceNotFound) return std::nullopt;
    throw Error(fmt::format("I++ DME: PtMeas failed: {}", describe(tr.errors.front())));
  }
  const auto v = tr.numbers();
  if (v.size() < 6) throw Error("I++ DME: PtMeas reported no point with its normal");
  return scan::Touch{Eigen::Vector3d(v[0], v[1], v[2]),
                     Eigen::Vector3d(v[3], v[4], v[5]).normalized(), t};
}

scan::ScanOutcome RemoteCmm::scan_path(const design::ScanPath& path,
                                       const scan::ScanSettings& settings,
                                       const scan::Monitor& monitor) {
  if (!curve_scans_) return point_scan(path, settings, monitor);
  // The nominal surface curve: the stylus-centre path less its offset along the normals.
  const double L = path.length();
  // At most kCurvePoints points, so that the command stays within the protocol's line length.
  const int n = std::clamp(static_cast<int>(std::ceil(L / o_.curve_step)) + 1, 2, kCurvePoints);
  // Path stations: their arcs and stylus-centre points, for the nearest-point search below.
  std::vector<double> arcs(static_cast<std::size_t>(n));
  std::vector<Eigen::Vector3d> centres(arcs.size());
  std::string data;
  for (std::size_t i = 0; i < arcs.size(); ++i) {
    arcs[i] = L * static_cast<double>(i) / static_cast<double>(n - 1);
    const auto q = path.at(arcs[i]);
    centres[i] = q.p;
    const Eigen::Vector3d p = q.p - path.offset * q.normal;
    data += fmt::format("{}{:.4f},{:.4f},{:.4f},{:.6f},{:.6f},{:.6f},1", i ? "," : "", p.x(), p.y(),
                        p.z(), q.normal.x(), q.normal.y(), q.normal.z());
  }
  // The straight parts' speed: the server slows down on the curve's turns itself.
  double fastest = 0;
  for (const auto& g : path.segments) fastest = std::max(fastest, g.speed);
  set_scan_speed(fastest);
  // The server approaches the curve's start from this far outside it, as the controller does.
  must(fmt::format("SetProp(Tool.PtMeasPar.Approach({:g}))", settings.approach_clearance));
  touch_search_ = -1;  // touch() sets its PtMeasPar again
  must(fmt::format("ScanOnCurveHint({:g}, {:g})", o_.follow_deviation, o_.tip_radius));
  must(fmt::format("ScanOnCurveDensity(Dis({:g}))", settings.record_spacing));

  scan::ScanOutcome out;
  bool stopped = false;
  std::size_t k = 0;  // the station nearest the last point: points arrive in path order
  const auto tr =
      scan(fmt::format("ScanOnCurve(Closed({}), Format(X(), Y(), Z(), IJK(), tag), Data({}))",
                       path.closed ? 1 : 0, data),
           [&](const Eigen::Vector3d& surface, const Eigen::Vector3d& normal) {
             const Eigen::Vector3d ball = surface + o_.tip_radius * normal;
             // The arc of the nearest path point: the best station ahead, refined on its segments.
             auto dist = [&](std::size_t i) { return (centres[i] - ball).squaredNorm(); };
             while (k + 1 < arcs.size() && dist(k + 1) <= dist(k)) ++k;
             double best = arcs[k], bd = dist(k);
             for (std::size_t j : {k > 0 ? k - 1 : k, k}) {
               if (j + 1 >= arcs.size()) continue;
               for (int m = 1; m < 8; ++m) {
                 const double s = arcs[j] + (arcs[j + 1] - arcs[j]) * m / 8;
                 const double e = (path.at(s).p - ball).squaredNorm();
                 if (e < bd) bd = e, best = s;
               }
             }
             const auto q = path.at(best);
             scan::Sample smp;
             smp.t = time();
             smp.arc = best;
             smp.surface = surface;
             smp.normal = normal;
             smp.delta_l = (ball - q.p).dot(q.normal) - settings.pushing;
             smp.contact = true;
             out.stop = smp;
             out.samples.push_back(smp);
             stopped = !monitor(smp);
             return !stopped;
           });
  if (stopped) return out;  // the points after the stop (the server's run-on) were not taken
  if (!tr.errors.empty()) {
    const auto& e = tr.errors.front();
    out.fault = number(e) == 2001 ? "the probe was pushed beyond its measuring range (I++ DME "
                                    "error 2001)"
                : number(e) == kSurfaceNotFound
                    ? fmt::format(
                          "the surface was lost: more than {:g} mm off the path (I++ DME "
                          "error 1006)",
                          o_.follow_deviation)
                    : fmt::format("the CMM stopped the scan: I++ DME {}", describe(e));
    return out;
  }
  out.completed = true;
  return out;
}

scan::ScanOutcome RemoteCmm::point_scan(const design::ScanPath& path,
                                        const scan::ScanSettings& settings,
                                        const scan::Monitor& monitor) {
  // Stations every point_step mm of the path. At each, a PtMeas of the design's surface point
  // along its normal: the ball starts the approach clearance out (and as far again as the last
  // point was found outside the design, so that a part standing proud is not met on the way),
  // searches follow_deviation beyond it, and retracts 1 mm. The free moves between stations go
  // straight from one retract to the next approach: a station whose approach point stands nearer
  // another part of the path than the pushing and half the clearance (beside a concave corner,
  // where the ball would meet the other wall on the way) is left out.
  const double L = path.length();
  const int n = std::max(2, static_cast<int>(std::ceil(L / o_.point_step)) + 1);
  const int m = path.closed ? n - 1 : n;
  std::vector<Eigen::Vector3d> line;  // the path every 0.1 mm, for the stations' room
  const int k = std::max(2, static_cast<int>(std::ceil(L / 0.1)) + 1);
  for (int i = 0; i < k; ++i) line.push_back(path.at(L * i / (k - 1)).p);
  auto room = [&](const Eigen::Vector3d& x) {
    double best = INFINITY;
    for (const auto& p : line) best = std::min(best, (p - x).squaredNorm());
    return std::sqrt(best);
  };
  constexpr double kApproachStep = 0.5;  // mm: the approach grows in these steps (fewer SetProps)
  scan::ScanOutcome out;
  double outside = 0;  // how far the last point was found outside the design (mm, ≥ 0)
  for (int i = 0; i < m; ++i) {
    const double s = L * i / (n - 1);
    const auto q = path.at(s);
    const Eigen::Vector3d nominal = q.p - path.offset * q.normal;
    const double approach =
        settings.approach_clearance + kApproachStep * std::ceil(outside / kApproachStep);
    const double out_along = approach + settings.pushing;  // from the path point
    if (room(q.p + out_along * q.normal) < settings.pushing + 0.5 * approach) continue;
    const auto t = measure(nominal, q.normal, approach, o_.follow_deviation, o_.point_speed);
    if (!t) {
      out.fault = fmt::format(
          "the surface was lost {:.1f} mm along the path: no contact within {:g} mm inside the "
          "design (I++ DME error 1006)",
          s, o_.follow_deviation);
      return out;
    }
    scan::Sample smp;
    smp.t = t->t;
    smp.arc = s;
    smp.surface = t->surface;
    smp.normal = t->normal;
    smp.delta_l = (t->surface + o_.tip_radius * t->normal - q.p).dot(q.normal) - settings.pushing;
    smp.contact = true;
    out.stop = smp;
    out.samples.push_back(smp);
    if (!monitor(smp)) return out;
    outside = std::max(0.0, (t->surface - nominal).dot(q.normal));
  }
  out.completed = true;
  return out;
}

scan::ScanOutcome RemoteCmm::scan_unknown(const design::Plane& plane, const Eigen::Vector3d& start,
                                          const Eigen::Vector3d& approach, design::Side material,
                                          bool closed, double length, double speed,
                                          const scan::ScanSettings& settings) {
  scan::ScanOutcome out;
  if (!in_plane_scans_) {
    out.fault = fmt::format(
        "autonomous scanning needs ScanInPlaneEndIsSphere of I++ DME 1.4.3; the server speaks {}",
        version_);
    return out;
  }
  const Eigen::Vector3d a = approach.normalized(), N = plane.normal.normalized();
  const auto first =
      touch(plane, start, a, 2 * (settings.approach_clearance + settings.approach_limit) + 10, 10,
            settings.pushing);
  if (!first) {
    out.fault = "autonomous scan: no surface found on the approach";
    out.missed_surface = true;
    return out;
  }
  // The direction of travel with the material on its `material` side (seen from N).
  const Eigen::Vector3d nm = first->normal;
  const Eigen::Vector3d t =
      material == design::Side::Left ? Eigen::Vector3d(N.cross(nm)) : Eigen::Vector3d(nm.cross(N));
  const Eigen::Vector3d S = first->surface, D = S + 5 * t;
  // The end sphere (Ø2), which the scanned (surface) points enter: around the first contact
  // (closed), or 3 mm off the plane (open: never met by points in the plane, the scan is stopped
  // here after `length`; near the first contact, since the server wants it within its travel).
  const Eigen::Vector3d E = closed ? S : Eigen::Vector3d(S + 3 * N);
  set_scan_speed(speed);
  must("SetProp(Tool.PtMeasPar.Approach(2), Tool.PtMeasPar.Search(4))");
  touch_search_ = -1;
  double arc = 0, next = 0;
  bool done = false;
  Eigen::Vector3d last = S;
  const auto tr = scan(
      // The 1.4.3 form: S, Si, the scanning plane's normal N, D, StepW, E, Dia, n, Ei.
      fmt::format("ScanInPlaneEndIsSphere({:.6f}, {:.6f}, {:.6f}, {:.9f}, {:.9f}, {:.9f}, {:.9f}, "
                  "{:.9f}, {:.9f}, {:.6f}, {:.6f}, {:.6f}, {:g}, {:.6f}, {:.6f}, {:.6f}, {:g}, 1, "
                  "{:.9f}, {:.9f}, {:.9f})",
                  S.x(), S.y(), S.z(), nm.x(), nm.y(), nm.z(), N.x(), N.y(), N.z(), D.x(), D.y(),
                  D.z(), settings.record_spacing, E.x(), E.y(), E.z(), 2.0, nm.x(), nm.y(), nm.z()),
      [&](const Eigen::Vector3d& surface, const Eigen::Vector3d& normal) {
        arc += (surface - last).norm();
        last = surface;
        scan::Sample smp;
        smp.t = time();
        smp.arc = arc;
        smp.surface = surface;
        smp.normal = normal;
        smp.contact = true;
        out.stop = smp;
        if (arc >= next) {
          out.samples.push_back(smp);
          next += settings.record_spacing;
        }
        done = !closed && arc >= length;
        return !done;
      });
  if (done) {
    out.completed = true;
    return out;
  }
  if (!tr.errors.empty()) {
    out.fault =
        fmt::format("autonomous scan: the CMM stopped it: I++ DME {}", describe(tr.errors.front()));
    return out;
  }
  out.completed = closed;
  if (!closed)
    out.fault = fmt::format("autonomous scan: the CMM ended after {:.1f} mm of the {:g} mm asked",
                            arc, length);
  return out;
}

}  // namespace trueaxis::ippdme
