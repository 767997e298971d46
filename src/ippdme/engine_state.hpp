// Internal to the I++ DME server's engine (engine.cpp, engine_executor.cpp, engine_scans.cpp):
// the session's state and the command executor that works on it.
#pragma once

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <set>

#include "trueaxis/ippdme/commands.hpp"
#include "trueaxis/ippdme/engine.hpp"

namespace trueaxis::ippdme {
namespace detail {

constexpr double kDeg = M_PI / 180;

// The method name of a queued completion: a fast-queue command sent with an ordinary tag ends
// when the transactions before it have (no command read from a line can have this name).
constexpr const char* kCompletion = "%";

// An error a command ends with: the specification's number (its text and default severity go
// with it).
struct Fail {
  int number;
};

struct Param {
  double act, def, min, max;
};

struct ToolDef {
  std::string name, id;
  bool visible = true, measures = true;
  std::map<std::string, std::map<std::string, Param>> blocks;  // "GoToPar" → "Speed" → ...
  Eigen::Vector3d alignment{0, 0, 1};  // stylus direction, away from the surface
  void reset() {
    for (auto& [b, ps] : blocks)
      for (auto& [n, p] : ps) p.act = p.def;
  }
};

// The parameter blocks and their order (as EnumProp lists them).
const std::vector<std::pair<std::string, std::vector<std::string>>>& blocks() {
  static const std::vector<std::pair<std::string, std::vector<std::string>>> b = {
      {"GoToPar", {"Speed", "Accel"}},
      {"PtMeasPar", {"Speed", "Accel", "Approach", "Search", "Retract"}},
      {"ScanPar", {"Speed", "Accel", "Retract"}}};
  return b;
}

ToolDef make_tool(std::string name, std::string id, bool visible, bool measures,
                  const sim::ServoOptions& servo) {
  ToolDef t;
  t.name = std::move(name);
  t.id = std::move(id);
  t.visible = visible;
  t.measures = measures;
  const double vmax = servo.max_velocity, amax = servo.max_acceleration;
  t.blocks["GoToPar"] = {{"Speed", {100, 100, 1, vmax}}, {"Accel", {1000, 1000, 1, amax}}};
  t.blocks["PtMeasPar"] = {{"Speed", {5, 5, 0.1, 50}},
                           {"Accel", {500, 500, 1, amax}},
                           {"Approach", {2, 2, 0, 100}},
                           {"Search", {4, 4, 0.1, 100}},
                           {"Retract", {2, 2, -1, 100}}};
  t.blocks["ScanPar"] = {
      {"Speed", {10, 10, 0.1, 100}}, {"Accel", {500, 500, 1, amax}}, {"Retract", {2, 2, 0, 100}}};
  return t;
}

// A coordinate system: x_csy = M·(x_machine − x0), M from the specification's Euler angles.
struct Csy {
  Eigen::Vector3d x0 = Eigen::Vector3d::Zero();
  double theta = 0, psi = 0, phi = 0;
  Eigen::Matrix3d M = Eigen::Matrix3d::Identity();
  void set(const Eigen::Vector3d& origin, double th, double ps, double ph) {
    x0 = origin;
    theta = th;
    psi = std::fmod(std::fmod(ps, 360) + 360, 360);
    phi = std::fmod(std::fmod(ph, 360) + 360, 360);
    const double c1 = std::cos(th * kDeg), s1 = std::sin(th * kDeg);
    const double c2 = std::cos(ps * kDeg), s2 = std::sin(ps * kDeg);
    const double c3 = std::cos(ph * kDeg), s3 = std::sin(ph * kDeg);
    M << c2 * c3 - c1 * s2 * s3, s2 * c3 + c1 * c2 * s3, s1 * s3,   //
        -c2 * s3 - c1 * s2 * c3, -s2 * s3 + c1 * c2 * c3, s1 * c3,  //
        s1 * s2, -s1 * c2, c1;
  }
  Eigen::Vector3d to(const Eigen::Vector3d& x) const { return M * (x - x0); }
  Eigen::Vector3d from(const Eigen::Vector3d& p) const { return M.transpose() * p + x0; }
};

struct Daemon {
  Tag tag;
  std::vector<std::string> items;  // X, Y, Z, R, Tool.A, ...
  double every = 0, dis = 0;       // Time(s), Dis(mm); 0 when not given
  double last_t = -1e300;
  Eigen::Vector3d last_p = Eigen::Vector3d::Constant(1e300);
};

Value fixed(double v) {
  Value n;
  n.kind = Value::Kind::Number;
  n.text = fmt::format("{:.5f}", v);
  if (n.text == "-0.00000") n.text = "0.00000";
  return n;
}

// A section of the simulated part the probe can meet, in the part's frame.
struct PartSurface {
  std::vector<std::pair<design::Plane, sim::Contour>> planes;
  std::vector<sim::SpaceCurve> curves;
  Eigen::Vector3d origin;
  double reach;  // how far off a section plane the ball still meets it (mm)
  std::optional<Nearest> operator()(const Eigen::Vector3d& x) const {
    const Eigen::Vector3d p = x - origin;
    std::optional<Nearest> best;
    for (const auto& [pl, c] : planes) {
      if (std::abs((p - pl.origin).dot(pl.normal)) > reach) continue;
      auto n = c.nearest(p);
      if (!best || std::abs(n.distance) < std::abs(best->distance)) best = n;
    }
    for (const auto& c : curves) {
      auto n = c.nearest(p);
      if (std::abs(n.distance) > 5 || (n.point - p).norm() > 5 + reach) continue;
      if (!best || std::abs(n.distance) < std::abs(best->distance)) best = n;
    }
    if (best) best->point += origin;
    return best;
  }
};

// Balls standing in the machine (machine coordinates): the nearest one's surface, for balls
// within reach of the tip.
struct BallSurface {
  std::vector<sim::Ball> balls;
  double reach;  // mm beyond a ball's surface within which it is reported
  std::optional<Nearest> operator()(const Eigen::Vector3d& x) const {
    std::optional<Nearest> best;
    for (const auto& b : balls) {
      const Eigen::Vector3d v = x - b.centre;
      const double rho = v.norm(), dist = rho - b.radius;
      if (dist > reach || rho < 1e-9 || (best && dist >= best->distance)) continue;
      Nearest n;
      n.normal = v / rho;
      n.point = b.centre + b.radius * n.normal;
      n.distance = dist;
      best = n;
    }
    return best;
  }
};

// Boxes standing in the machine (machine coordinates), a group at a time: the nearest box's
// surface among the active group's, for boxes within reach of the tip.
struct BoxSurface {
  std::vector<sim::Box> boxes;
  double reach;
  double top = -INFINITY;  // the highest point of any box (mm, machine z)
  std::shared_ptr<std::atomic<int>> active = std::make_shared<std::atomic<int>>(-1);  // none yet
  std::optional<Nearest> operator()(const Eigen::Vector3d& x) const {
    std::optional<Nearest> best;
    const int group = active->load();
    for (const auto& b : boxes) {
      if (b.group != group) continue;
      const auto n = b.nearest(x);
      if (n.distance > reach || (best && n.distance >= best->distance)) continue;
      best = n;
    }
    return best;
  }
  // The group of the box nearest to x.
  int group_at(const Eigen::Vector3d& x) const {
    int group = active->load();
    double best = INFINITY;
    for (const auto& b : boxes)
      if (const double d = std::abs(b.nearest(x).distance); d < best) {
        best = d;
        group = b.group;
      }
    return group;
  }
};

}  // namespace detail

// The engine's state and its executor are used by the engine's own files only.
using namespace detail;

struct Engine::State {
  EngineOptions o;
  Send send;
  std::function<void()> flow;  // set before the worker starts (set_flow_control)
  SimulatedCmm cmm;
  std::shared_ptr<PartSurface> part;   // the part world (empty: the nominal world)
  std::shared_ptr<BallSurface> balls;  // balls on the table (empty: none)
  std::shared_ptr<BoxSurface> boxes;   // boxes (gauge blocks) in the machine (empty: none)

  std::mutex m;  // guards everything below (the CMM belongs to the worker)
  std::condition_variable cv;
  std::deque<Command> queue;
  bool running = false, stopping = false;
  std::atomic<bool> abort{false};
  std::optional<Tag> abort_tag;  // an AbortE waiting for its transaction complete
  bool session = false, homed = false, user_enabled = false;
  int latched = 0;  // the error that stops further work (severity ≥ 2), 0: none
  std::vector<ToolDef> tools;
  std::size_t active = 0;
  // UnDefTool: the server does not know which tool is loaded (specification 6.3.2.14; e.g. at
  // start with EngineOptions::tool "UnDefTool"); everything that needs the tool answers 1503
  // until a ChangeTool or SetTool succeeds.
  bool tool_undefined = false;
  std::optional<std::size_t> found;  // FindTool's; none: UnDefTool
  std::map<std::string, Csy> csys;
  std::string csy = "MachineCsy";
  std::vector<std::string> pt_format{"X", "Y", "Z"}, scan_format{"X", "Y", "Z", "Q"};
  std::vector<Daemon> daemons;
  double table = 0, head_a = 0, head_b = 0, head_c = 0;  // degrees
  std::set<std::string> locked;
  double unknown_density = 0.5;  // ScanUnknownDensity(Dis()) (mm)
  double curve_density = 0.5;    // ScanOnCurveDensity(Dis()) (mm)
  // ScanOnCurveHint's deviation: how far ScanOnCurve may follow the surface off the nominal
  // curve before it gives up (mm).
  double curve_deviation = 3;
  // Pacing: machine time against the wall clock.
  std::chrono::steady_clock::time_point wall0;
  double machine0 = 0;
  std::uint64_t ticks = 0;

  State(EngineOptions options, Send s) : o(std::move(options)), send(std::move(s)), cmm(o.cmm) {
    const auto& servo = o.cmm.servo;
    tools.push_back(make_tool("BaseTool", "0", false, true, servo));
    tools.push_back(make_tool("RefTool", "1", true, true, servo));
    tools.push_back(make_tool("NoTool", "2", true, false, servo));
    tools.push_back(make_tool("Probe1", "3", true, true, servo));
    active = 3;
    if (o.tool == "UnDefTool") {
      tool_undefined = true;
    } else {
      const auto t = tool_index(o.tool);
      if (!t) throw Error(fmt::format("I++ DME server: no tool '{}' to start with", o.tool));
      active = *t;
    }
    for (const char* c : {"MachineCsy", "MoveableMachineCsy", "MultipleArmCsy", "PartCsy",
                          "JogDisplayCsy", "JogMoveCsy", "SensorCsy"})
      csys[c] = Csy{};
    if (o.part) {
      auto ps = std::make_shared<PartSurface>();
      o.part->validate();
      for (const auto& sec : o.part->design.sections) {
        if (sec.space_curve()) {
          ps->curves.push_back(sim::true_space_curve(*o.part, sec));
        } else {
          design::Plane pl = sec.plane;
          pl.normal.normalize();
          ps->planes.emplace_back(pl, sim::true_contour(*o.part, sec));
        }
      }
      ps->origin = o.part_origin;
      ps->reach = cmm.tip_radius();
      part = std::move(ps);
    }
    if (!o.balls.empty()) {
      for (const auto& b : o.balls)
        if (!b.centre.allFinite() || !(b.radius > 0) || !std::isfinite(b.radius))
          throw Error("I++ DME server: a ball needs a finite centre and a positive radius");
      balls = std::make_shared<BallSurface>(BallSurface{o.balls, cmm.tip_radius() + 5});
    }
    if (!o.boxes.empty()) {
      for (const auto& b : o.boxes)
        if (!b.centre.allFinite() || !b.axes.allFinite() || !(b.half.array() > 0).all())
          throw Error("I++ DME server: a box needs a finite centre and axes and a positive size");
      boxes = std::make_shared<BoxSurface>(BoxSurface{o.boxes, cmm.tip_radius() + 5});
      for (const auto& b : o.boxes) boxes->top = std::max(boxes->top, b.top());
    }
    cmm.set_hook([this] { return on_tick(); });
  }

  // ---- responses -------------------------------------------------------------------------
  void line(const Tag& t, char kind, const std::string& rest = "") {
    std::string s = t.text();
    s += ' ';
    s += kind;
    if (!rest.empty()) {
      s += ' ';
      s += rest;
    }
    send(s);
  }
  void data(const Tag& t, const std::vector<Value>& items) {
    Response r;
    r.tag = t;
    r.kind = Response::Kind::Data;
    r.items = items;
    send(format(r));
  }
  // `cause` (the method, or what is wrong with a line) becomes the error's third field: a
  // string, so its quotes become apostrophes and anything unprintable a '?'.
  // `latch`: false for a notice that stops nothing (an error the command ran despite).
  void error(const Tag& t, int number, std::string cause, bool latch = true) {
    const auto info = error_info(number);
    const int severity = info ? info->severity : 3;
    for (char& ch : cause)
      if (ch == '"')
        ch = '\'';
      else if (ch < 32 || ch > 126)
        ch = '?';
    line(t, '!',
         fmt::format("Error({}, {:04d}, \"{}\", \"{}\")", severity, number,
                     cause.empty() ? std::string("Server") : cause,
                     info ? std::string(info->text) : std::string("Error")));
    if (latch && severity >= 2 && !latched) latched = number;
  }

  // ---- machine time, abort, daemons ------------------------------------------------------
  bool on_tick() {
    if (abort.load(std::memory_order_relaxed)) return false;
    if (o.time_scale > 0 && (++ticks & 15) == 0) {
      const double ahead =
          (cmm.time() - machine0) * o.time_scale -
          std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
      if (ahead > 0.002) std::this_thread::sleep_for(std::chrono::duration<double>(ahead));
    }
    std::lock_guard lk(m);
    for (auto& d : daemons) report_move(d, false);
    return true;
  }
  void report_move(Daemon& d, bool now) {
    const double t = cmm.time();
    const Eigen::Vector3d& p = cmm.position();
    const double moved = (p - d.last_p).norm();
    const double every = d.every > 0 ? d.every : (d.dis > 0 ? 0 : 1.0);
    if (d.items.empty()) return;  // a daemon that reports nothing
    if (!now && (t - d.last_t < every || moved < std::max(d.dis, 1e-6))) return;
    d.last_t = t;
    d.last_p = p;
    data(d.tag, axes(d.items));
  }
  std::vector<Value> axes(const std::vector<std::string>& items) {
    const Eigen::Vector3d x = csys[csy].to(cmm.position());
    std::vector<Value> out;
    for (const auto& it : items) {
      double v = 0;
      if (it == "X")
        v = x.x();
      else if (it == "Y")
        v = x.y();
      else if (it == "Z")
        v = x.z();
      else if (it == "R")
        v = table;
      else if (it == "Tool.A")
        v = head_a;
      else if (it == "Tool.B")
        v = head_b;
      else if (it == "Tool.C")
        v = head_c;
      else
        continue;
      out.push_back(call(it, {fixed(v)}));
    }
    return out;
  }
  void pace_start() {
    wall0 = std::chrono::steady_clock::now();
    machine0 = cmm.time();
  }

  // ---- tools and properties --------------------------------------------------------------
  ToolDef& tool() { return tools[active]; }
  std::optional<std::size_t> tool_index(const std::string& name) const {
    for (std::size_t i = 0; i < tools.size(); ++i)
      if (tools[i].name == name) return i;
    return std::nullopt;
  }
  double par(const char* block, const char* name) { return tool().blocks[block][name].act; }
  ToolDef& pointer(const std::string& which) {
    if (which == "FoundTool") {
      if (!found) throw Fail{1503};
      return tools[*found];
    }
    if (tool_undefined) throw Fail{1503};
    return tool();
  }
  static std::vector<std::string> split(const std::string& s) {
    std::vector<std::string> out;
    std::size_t a = 0;
    for (;;) {
      const auto b = s.find('.', a);
      out.push_back(s.substr(a, b == std::string::npos ? b : b - a));
      if (b == std::string::npos) return out;
      a = b + 1;
    }
  }
  // A tool that cannot measure (NoTool) has no PtMeasPar to read or set: 0507, as NIST's checker
  // answers.
  static void need_block(const ToolDef& t, const std::vector<std::string>& p) {
    if (p.size() >= 2 && p[1] == "PtMeasPar" && !t.measures) throw Fail{507};
  }
  Param& param(ToolDef& t, const std::vector<std::string>& p) {
    need_block(t, p);
    if (p.size() < 3 || !t.blocks.count(p[1]) || !t.blocks[p[1]].count(p[2])) throw Fail{510};
    return t.blocks[p[1]][p[2]];
  }
  Value get_property(const Value& a) {
    const auto p = split(a.text);
    ToolDef& t = pointer(p[0]);
    if (p.size() == 2) {
      const std::string& k = p[1];
      if (k == "Name") return call(a.text, {string(t.name)});
      if (k == "Id") return call(a.text, {string(t.id)});
      if (k == "AvrRadius") return call(a.text, {number(t.measures ? cmm.tip_radius() : 0)});
      if (k == "Alignment")
        return call(a.text,
                    {number(t.alignment.x()), number(t.alignment.y()), number(t.alignment.z())});
      if (k == "CollisionVolume" || k == "AlignmentVolume") return call(a.text);
      if (k == "A") return call(a.text, {number(head_a)});
      if (k == "B") return call(a.text, {number(head_b)});
      if (k == "C") return call(a.text, {number(head_c)});
      throw Fail{510};
    }
    Param& q = param(t, p);
    const std::string sub = p.size() > 3 ? p[3] : "Act";
    const double v = sub == "Def" ? q.def : sub == "Min" ? q.min : sub == "Max" ? q.max : q.act;
    return call(a.text, {number(v)});
  }
  // Sets a property; false if the value was clamped into [Min, Max].
  bool set_property(const Value& a) {
    const auto p = split(a.text);
    ToolDef& t = pointer(p[0]);
    Param& q = param(t, p);
    const double v = a.args.at(0).number();
    q.act = std::clamp(v, q.min, q.max);
    return q.act == v;
  }
  void enumerate(const Tag& tag, const Value& a, bool all) {
    const auto p = split(a.text);
    ToolDef& t = pointer(p[0]);
    auto pair = [&](const std::string& name, const char* kind) {
      data(tag, {string(name), string(kind)});
    };
    if (p.size() == 1) {
      for (const auto& [b, names] : blocks()) {
        pair(b, "Property");
        if (!all) continue;
        for (const auto& n : names) {
          pair(b + "." + n, "Number");
          pair(b + "." + n, "Property");
          for (const char* s : {"Act", "Def", "Max", "Min"})
            pair(fmt::format("{}.{}.{}", b, n, s), "Number");
        }
      }
      return;
    }
    need_block(t, p);
    if (!t.blocks.count(p[1])) throw Fail{510};
    if (p.size() == 2) {
      for (const auto& [b, names] : blocks()) {
        if (b != p[1]) continue;
        for (const auto& n : names) {
          pair(all ? b + "." + n : n, "Number");
          pair(all ? b + "." + n : n, "Property");
          if (all)
            for (const char* s : {"Act", "Def", "Max", "Min"})
              pair(fmt::format("{}.{}.{}", b, n, s), "Number");
        }
      }
      return;
    }
    param(t, p);
    if (p.size() == 3) {
      for (const char* s : {"Act", "Def", "Max", "Min"})
        pair(all ? fmt::format("{}.{}", p[2], s) : std::string(s), "Number");
      return;
    }
    pair(p[3], "Number");
  }

  // ---- coordinates -----------------------------------------------------------------------
  const Csy& frame() const { return csys.at(csy); }
  // Between the scales and the machine coordinates reported, the controller's correction (a
  // point read at x is reported at correction(x); a commanded point p is reached at the x that
  // corrects to it, by fixed-point iteration: the correction is within micrometres of x).
  Eigen::Vector3d to_machine(const Eigen::Vector3d& p) {
    const Eigen::Vector3d m = frame().from(p);
    if (!o.correction) return m;
    Eigen::Vector3d x = m;
    for (int it = 0; it < 8; ++it) x = m - (o.correction(x) - x);
    return x;
  }
  Eigen::Vector3d dir_to_machine(const Eigen::Vector3d& v) { return frame().M.transpose() * v; }
  Eigen::Vector3d to_csy(const Eigen::Vector3d& x) {
    return frame().to(o.correction ? o.correction(x) : x);
  }
  Eigen::Vector3d dir_to_csy(const Eigen::Vector3d& v) { return frame().M * v; }

  // X(), Y(), Z(), IJK() of a command; missing coordinates from the current position.
  struct Target {
    Eigen::Vector3d x;
    std::optional<Eigen::Vector3d> ijk;
    std::optional<double> r, a, b, c;
  };
  Target target(const Value& m) {
    Target t;
    Eigen::Vector3d p = to_csy(cmm.position());
    for (const auto& a : m.args) {
      if (a.kind != Value::Kind::Call) continue;
      if (a.text == "X" && !locked.count("X")) p.x() = a.args.at(0).number();
      if (a.text == "Y" && !locked.count("Y")) p.y() = a.args.at(0).number();
      if (a.text == "Z" && !locked.count("Z")) p.z() = a.args.at(0).number();
      if (a.text == "IJK")
        t.ijk =
            Eigen::Vector3d(a.args.at(0).number(), a.args.at(1).number(), a.args.at(2).number());
      if (a.text == "R" && !locked.count("R")) t.r = a.args.at(0).number();
      if (a.text == "Tool.A" && !locked.count("A")) t.a = a.args.at(0).number();
      if (a.text == "Tool.B" && !locked.count("B")) t.b = a.args.at(0).number();
      if (a.text == "Tool.C" && !locked.count("C")) t.c = a.args.at(0).number();
    }
    t.x = to_machine(p);
    return t;
  }

  // ---- motion (called with the lock released) --------------------------------------------
  Surface world() const {
    std::vector<Surface> all;
    if (part) all.push_back([ps = part](const Eigen::Vector3d& x) { return (*ps)(x); });
    if (balls) all.push_back([bs = balls](const Eigen::Vector3d& x) { return (*bs)(x); });
    if (boxes) all.push_back([xs = boxes](const Eigen::Vector3d& x) { return (*xs)(x); });
    if (all.empty()) return {};
    if (all.size() == 1) return all.front();
    return [all](const Eigen::Vector3d& x) {
      std::optional<Nearest> best;
      for (const auto& s : all)
        if (auto n = s(x); n && (!best || std::abs(n->distance) < std::abs(best->distance)))
          best = n;
      return best;
    };
  }
  void go(const Eigen::Vector3d& x, double speed, double accel) {
    if (!cmm.within_travel(x)) throw Fail{2500};
    // The probe stopped the move on the part: an illegal touch when the machine stopped within
    // the probe's overtravel, a collision beyond.
    if (!cmm.move(x, speed, accel, world()))
      throw Fail{cmm.last_push() <= cmm.options().overtravel ? 1001 : 2504};
    // With the probe above every box, the operator may change the set-up: none is there until
    // a PtMeas aims at one.
    if (boxes && cmm.position().z() > boxes->top + cmm.tip_radius()) boxes->active->store(-1);
  }
};

// ---- the command executor ----------------------------------------------------------------

namespace detail {

// Releases a lock for the duration of a motion.
struct Unlocked {
  std::unique_lock<std::mutex>& lk;
  explicit Unlocked(std::unique_lock<std::mutex>& l) : lk(l) { lk.unlock(); }
  ~Unlocked() { lk.lock(); }
};

inline std::vector<double> numbers(const Value& m) {
  std::vector<double> v;
  for (const auto& a : m.args) v.push_back(a.kind == Value::Kind::Number ? a.number() : 0.0);
  return v;
}

inline Eigen::Vector3d vec(const std::vector<double>& v, std::size_t i) {
  return {v.at(i), v.at(i + 1), v.at(i + 2)};
}

inline Eigen::Vector3d unit(const Eigen::Vector3d& v) {
  if (!(v.norm() > 1e-12)) throw Fail{1010};
  return v.normalized();
}

class Executor {
 public:
  Executor(Engine::State& s, std::unique_lock<std::mutex>& lk, const Command& c)
      : s_(s), lk_(lk), c_(c), m_(c.method), name_(c.method.text) {}
  void run();

 private:
  Engine::State& s_;
  std::unique_lock<std::mutex>& lk_;
  const Command& c_;
  const Value& m_;
  const std::string& name_;

  void need_session() {
    if (!s_.session) throw Fail{8};
  }
  // Not homed: NIST's reference server answers 0507 (illegal command) to motion then.
  void need_homed() {
    if (!s_.homed) throw Fail{507};
  }
  // The tool must be known (else 1503) and measure: NoTool only moves (0507, as NIST's checker
  // answers).
  void need_probe() {
    need_tool();
    if (!s_.tool().measures) throw Fail{507};
  }
  void need_tool() {
    if (s_.tool_undefined) throw Fail{1503};
  }
  // The arguments of a measuring command, checked before anything moves as NIST's command
  // checker does: a zero direction 1010, a point outside the travel 0504, coinciding points or a
  // circle's radius off its plane 0502.
  void check_arguments();
  // A measuring command: a session, a homed machine and a tool that measures.
  void need_measuring() {
    need_session();
    need_homed();
    need_probe();
  }
  // After a scan: back off the surface along n by `distance` (within the travel; no lock held).
  void retract_from(const Eigen::Vector3d& n, double distance) {
    const Eigen::Vector3d back = s_.cmm.position() + distance * n;
    if (s_.cmm.within_travel(back)) s_.cmm.move(back, s_.par("GoToPar", "Speed"), 1000);
  }
  // How a scan ended, as the specification's errors: over-push 2001, the travel 2500, the
  // surface lost or never met 1006.
  static void ended(SimulatedCmm::ScanEnd end) {
    if (end == SimulatedCmm::ScanEnd::OverPushed) throw Fail{2001};
    if (end == SimulatedCmm::ScanEnd::Travel) throw Fail{2500};
    if (end != SimulatedCmm::ScanEnd::Done) throw Fail{1006};
  }
  // One probing as PtMeas does it; the contact, or Fail 1006.
  SimulatedCmm::Contact probe(const Eigen::Vector3d& x, const Eigen::Vector3d& n,
                              std::optional<double> retract_override);
  void report_point(const std::vector<std::string>& format, const SimulatedCmm::Contact& c,
                    std::vector<Value>* items, std::vector<Value>* bare);
  void scan(
      const std::function<void(const std::function<void(const SimulatedCmm::Point&)>&)>& body);
  // A warning (0504) when the points asked for are closer than the probe moves in one servo
  // tick at the scan's speed: the server records at most one point per tick.
  void density_cap(double step, double speed);
  void ptmeas();
  void goto_();
  void scan_on_line();
  void scan_on_circle();
  void scan_on_curve();
  void scan_unknown();
  void part_handling();
};

}  // namespace detail
}  // namespace trueaxis::ippdme
