// The I++ DME server's session core: commands in, responses out, against the virtual CMM.
#include "trueaxis/ippdme/engine.hpp"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <set>
#include <thread>

#include "trueaxis/ippdme/commands.hpp"

namespace trueaxis::ippdme {
namespace {

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

}  // namespace

struct Engine::State {
  EngineOptions o;
  Send send;
  std::function<void()> flow;  // set before the worker starts (set_flow_control)
  SimulatedCmm cmm;
  std::shared_ptr<PartSurface> part;   // the part world (empty: the nominal world)
  std::shared_ptr<BallSurface> balls;  // balls on the table (empty: none)

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
  Eigen::Vector3d to_machine(const Eigen::Vector3d& p) { return frame().from(p); }
  Eigen::Vector3d dir_to_machine(const Eigen::Vector3d& v) { return frame().M.transpose() * v; }
  Eigen::Vector3d to_csy(const Eigen::Vector3d& x) { return frame().to(x); }
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
    if (!part && !balls) return {};
    auto ps = part;
    auto bs = balls;
    if (!bs) return [ps](const Eigen::Vector3d& x) { return (*ps)(x); };
    if (!ps) return [bs](const Eigen::Vector3d& x) { return (*bs)(x); };
    return [ps, bs](const Eigen::Vector3d& x) {
      auto a = (*ps)(x), b = (*bs)(x);
      if (a && b) return std::abs(a->distance) <= std::abs(b->distance) ? a : b;
      return a ? a : b;
    };
  }
  void go(const Eigen::Vector3d& x, double speed, double accel) {
    if (!cmm.within_travel(x)) throw Fail{2500};
    if (!cmm.move(x, speed, accel, world())) throw Fail{2504};
  }
};

// ---- the command executor ----------------------------------------------------------------

namespace {

// Releases a lock for the duration of a motion.
struct Unlocked {
  std::unique_lock<std::mutex>& lk;
  explicit Unlocked(std::unique_lock<std::mutex>& l) : lk(l) { lk.unlock(); }
  ~Unlocked() { lk.lock(); }
};

std::vector<double> numbers(const Value& m) {
  std::vector<double> v;
  for (const auto& a : m.args) v.push_back(a.kind == Value::Kind::Number ? a.number() : 0.0);
  return v;
}

Eigen::Vector3d vec(const std::vector<double>& v, std::size_t i) {
  return {v.at(i), v.at(i + 1), v.at(i + 2)};
}

Eigen::Vector3d unit(const Eigen::Vector3d& v) {
  if (!(v.norm() > 1e-12)) throw Fail{1010};
  return v.normalized();
}

}  // namespace

namespace {

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

SimulatedCmm::Contact Executor::probe(const Eigen::Vector3d& x, const Eigen::Vector3d& n,
                                      std::optional<double> retract_override) {
  const double approach = s_.par("PtMeasPar", "Approach"), search = s_.par("PtMeasPar", "Search");
  const double speed = s_.par("PtMeasPar", "Speed"), go_speed = s_.par("GoToPar", "Speed");
  const double go_accel = s_.par("GoToPar", "Accel");
  const double retract = retract_override.value_or(s_.par("PtMeasPar", "Retract"));
  // The nominal point is on the surface: the ball centre starts `approach` mm plus its radius
  // off it and searches to `search` mm beyond it.
  const double r = s_.cmm.tip_radius();
  const Eigen::Vector3d start = x + (approach + r) * n;
  Surface surface = s_.world();
  if (!surface) surface = plane_surface(x, n);
  std::optional<SimulatedCmm::Contact> c;
  {
    Unlocked u(lk_);
    s_.go(start, go_speed, go_accel);
    c = s_.cmm.touch(-n, approach + r + search, speed, surface);
    if (!c) {
      s_.go(start, go_speed, go_accel);
    } else if (retract > 0) {
      const Eigen::Vector3d back = s_.cmm.position() + retract * n;
      if (s_.cmm.within_travel(back)) s_.cmm.move(back, go_speed, go_accel);
    } else if (retract < 0) {
      s_.go(start, go_speed, go_accel);
    }
  }
  if (!c) throw Fail{1006};
  return *c;
}

void Executor::report_point(const std::vector<std::string>& format, const SimulatedCmm::Contact& c,
                            std::vector<Value>* items, std::vector<Value>* bare) {
  // The surface point: the ball centre compensated by the tip radius along the measured normal.
  const Eigen::Vector3d p = s_.to_csy(c.centre - s_.cmm.tip_radius() * c.normal);
  const Eigen::Vector3d n = s_.dir_to_csy(c.normal);
  for (const auto& f : format) {
    std::vector<Value> v;
    if (f == "X")
      v = {fixed(p.x())};
    else if (f == "Y")
      v = {fixed(p.y())};
    else if (f == "Z")
      v = {fixed(p.z())};
    else if (f == "IJK")
      v = {fixed(n.x()), fixed(n.y()), fixed(n.z())};
    else if (f == "ER")
      v = {fixed(s_.cmm.tip_radius())};
    else if (f == "Q")
      v = {number(0)};
    else if (f == "R")
      v = {fixed(s_.table)};
    else if (f == "Tool.A")
      v = {fixed(s_.head_a)};
    else if (f == "Tool.B")
      v = {fixed(s_.head_b)};
    else if (f == "Tool.C")
      v = {fixed(s_.head_c)};
    else
      continue;
    if (items) items->push_back(call(f, v));
    if (bare) bare->insert(bare->end(), v.begin(), v.end());
  }
}

void Executor::ptmeas() {
  need_measuring();
  auto t = s_.target(m_);
  Eigen::Vector3d n;
  if (t.ijk) {
    n = unit(s_.dir_to_machine(*t.ijk));
  } else {
    n = unit(s_.cmm.position() - t.x);  // from the nominal point to where the probe is
  }
  const auto c = probe(t.x, n, std::nullopt);
  std::vector<Value> items;
  report_point(s_.pt_format, c, &items, nullptr);
  s_.data(c_.tag, items);
}

void Executor::goto_() {
  need_session();
  need_homed();
  need_tool();
  const auto t = s_.target(m_);
  if (t.r && *t.r != s_.table && (s_.part || s_.balls)) throw Fail{506};
  if (!s_.cmm.within_travel(t.x)) throw Fail{2500};
  const double speed = s_.par("GoToPar", "Speed"), accel = s_.par("GoToPar", "Accel");
  s_.user_enabled = false;
  {
    Unlocked u(lk_);
    s_.go(t.x, speed, accel);
  }
  if (t.r) s_.table = *t.r;
  if (t.a) s_.head_a = *t.a;
  if (t.b) s_.head_b = *t.b;
  if (t.c) s_.head_c = *t.c;
}

// Runs a scan body that emits points; streams them as bare numbers, kPointsPerLine per line.
void Executor::scan(
    const std::function<void(const std::function<void(const SimulatedCmm::Point&)>&)>& body) {
  std::vector<Value> bare;
  int in_line = 0;
  const auto format = s_.scan_format;
  auto flush = [&](bool streaming) {
    if (bare.empty()) return;
    if (streaming && s_.flow) s_.flow();  // no lock is held while the scan streams
    s_.data(c_.tag, bare);
    bare.clear();
    in_line = 0;
  };
  auto emit = [&](const SimulatedCmm::Point& p) {
    report_point(format, SimulatedCmm::Contact{p.centre, p.normal}, nullptr, &bare);
    if (++in_line == kPointsPerLine) flush(true);
  };
  body(emit);
  flush(false);
}

namespace {

// Where an unknown-contour scan's arguments stand, per form (argument count): its direction
// vectors, the points that must lie in the travel, the start and direction points, and the
// cylinder's point and axis (−1: none).
struct ScanLayout {
  std::vector<std::size_t> dirs, points;
  std::size_t start = 0, direction = 0;
  int cylinder = -1;
};
const ScanLayout* scan_layout(const std::string& name, std::size_t count) {
  static const std::map<std::pair<std::string, std::size_t>, ScanLayout> layouts = {
      {{"ScanInPlaneEndIsSphere", 17}, {{3, 14}, {0, 6, 10}, 0, 6}},
      {{"ScanInPlaneEndIsSphere", 21}, {{3, 6, 18}, {0, 9, 13}, 0, 9}},
      {{"ScanInPlaneEndIsPlane", 20}, {{3, 13, 17}, {0, 6}, 0, 6}},
      {{"ScanInPlaneEndIsPlane", 23}, {{3, 6, 16, 20}, {0, 9}, 0, 9}},
      {{"ScanInPlaneEndIsCyl", 21}, {{3, 13, 18}, {0, 6}, 0, 6}},
      {{"ScanInPlaneEndIsCyl", 24}, {{3, 6, 16, 21}, {0, 9}, 0, 9}},
      {{"ScanInCylEndIsSphere", 23}, {{3, 9, 20}, {6, 12, 16}, 6, 12, 0}},
      {{"ScanInCylEndIsSphere", 24}, {{3, 9, 21}, {6, 12, 16}, 6, 12, 0}},
      {{"ScanInCylEndIsPlane", 26}, {{3, 9, 19, 23}, {6, 12}, 6, 12, 0}},
  };
  const auto it = layouts.find({name, count});
  return it == layouts.end() ? nullptr : &it->second;
}

}  // namespace

void Executor::check_arguments() {
  const auto v = numbers(m_);
  auto zero = [&](std::size_t i) { return !(vec(v, i).norm() > 1e-12); };
  auto outside = [&](std::size_t i) { return !s_.cmm.within_travel(s_.to_machine(vec(v, i))); };
  if (name_ == "ScanOnLine") {
    if (zero(6)) throw Fail{1010};
    if (!((vec(v, 3) - vec(v, 0)).norm() > 0)) throw Fail{502};
    if (outside(0) || outside(3)) throw Fail{504};
    return;
  }
  if (name_ == "ScanOnCircle") {
    if (zero(6)) throw Fail{1010};
    const Eigen::Vector3d r = vec(v, 3) - vec(v, 0);
    if (!(r.norm() > 0)) throw Fail{502};
    if (std::abs(r.normalized().dot(vec(v, 6).normalized())) > 1e-3) throw Fail{502};
    if (outside(3)) throw Fail{504};
    return;
  }
  const ScanLayout* l = scan_layout(name_, v.size());
  if (!l) return;
  for (std::size_t d : l->dirs)
    if (zero(d)) throw Fail{1010};
  for (std::size_t p : l->points)
    if (outside(p)) throw Fail{504};
  const Eigen::Vector3d S = vec(v, l->start);
  if (!((vec(v, l->direction) - S).norm() > 0)) throw Fail{502};
  if (l->cylinder >= 0) {
    const auto c = static_cast<std::size_t>(l->cylinder);
    const Eigen::Vector3d a = vec(v, c + 3).normalized(), w = S - vec(v, c);
    if ((w - w.dot(a) * a).norm() < 1e-9) throw Fail{502};
  }
}

void Executor::density_cap(double step, double speed) {
  const double per_tick = speed * s_.cmm.options().servo.dt();
  if (step < per_tick)
    s_.error(c_.tag, 504,
             fmt::format("{}: a point every {:.4g} mm asked for, but at {:g} mm/s the probe moves "
                         "{:.4g} mm per servo tick: one point per tick is recorded",
                         name_, step, speed, per_tick));
}

void Executor::scan_on_line() {
  need_measuring();
  check_arguments();
  const auto v = numbers(m_);
  const Eigen::Vector3d S = s_.to_machine(vec(v, 0)), E = s_.to_machine(vec(v, 3));
  const Eigen::Vector3d n = unit(s_.dir_to_machine(vec(v, 6)));
  const double step = v.at(9), L = (E - S).norm();
  if (!(L > 0) || !(step > 0)) throw Fail{509};
  const Eigen::Vector3d along = (E - S) / L;
  // The surface normal must be square to the line: a normal along it describes no surface.
  if (std::abs(n.dot(along)) > 1e-3) throw Fail{509};
  const Eigen::Vector3d cn = unit(n.cross(along));
  const auto c = probe(S, n, 0.0);
  Surface surface = s_.world();
  if (!surface) surface = plane_surface(S, n);
  const double speed = s_.par("ScanPar", "Speed"), retract = s_.par("ScanPar", "Retract");
  density_cap(step, speed);
  SimulatedCmm::ScanEnd end;
  scan([&](const auto& emit) {
    Unlocked u(lk_);
    emit(SimulatedCmm::Point{c.centre, c.normal, 0});
    SimulatedCmm::Constraint plane{[&](const Eigen::Vector3d& p) {
      return std::pair<Eigen::Vector3d, double>(cn, (p - c.centre).dot(cn));
    }};
    end = s_.cmm.follow(
        surface, plane, along, speed, 0.2, step, 2 * L + 10,
        [&](const SimulatedCmm::Point& p, double) { return (p.centre - c.centre).norm() >= L; },
        emit);
    retract_from(n, retract);
  });
  ended(end);
}

void Executor::scan_on_circle() {
  need_measuring();
  check_arguments();
  const auto v = numbers(m_);
  const Eigen::Vector3d C = s_.to_machine(vec(v, 0)), S = s_.to_machine(vec(v, 3));
  const Eigen::Vector3d ax = unit(s_.dir_to_machine(vec(v, 6)));
  const double delta = v.at(9), sfa = v.at(10), stepw = v.at(11);
  Eigen::Vector3d radial = S - C;
  radial -= radial.dot(ax) * ax;
  const double R = radial.norm();
  if (!(R > 0) || !(stepw > 0) || delta == 0) throw Fail{509};
  radial /= R;
  const Eigen::Vector3d n0 = std::cos(sfa * kDeg) * radial + std::sin(sfa * kDeg) * ax;
  const auto c = probe(S, n0, 0.0);
  Surface surface = s_.world();
  if (!surface) surface = cone_surface(C, ax, R, sfa);
  const bool on_plane = std::abs(std::cos(sfa * kDeg)) < 0.5;
  Eigen::Vector3d rc = c.centre - C;
  const double hc = rc.dot(ax);
  rc -= hc * ax;
  const double rho = rc.norm();
  const Eigen::Vector3d u0 = rc / rho;
  const double speed = s_.par("ScanPar", "Speed"), retract = s_.par("ScanPar", "Retract");
  const Eigen::Vector3d hint = (delta > 0 ? 1.0 : -1.0) * ax.cross(u0);
  density_cap(rho * stepw * kDeg, speed);
  SimulatedCmm::ScanEnd end;
  scan([&](const auto& emit) {
    Unlocked u(lk_);
    emit(SimulatedCmm::Point{c.centre, c.normal, 0});
    SimulatedCmm::Constraint k{[&](const Eigen::Vector3d& p) {
      if (!on_plane) return std::pair<Eigen::Vector3d, double>(ax, (p - C).dot(ax) - hc);
      Eigen::Vector3d w = p - C;
      w -= w.dot(ax) * ax;
      const double r = w.norm();
      return std::pair<Eigen::Vector3d, double>(r > 0 ? Eigen::Vector3d(w / r) : u0, r - rho);
    }};
    double swept = 0;
    Eigen::Vector3d last = u0;
    end = s_.cmm.follow(
        surface, k, hint, speed, 0.2, std::max(1e-3, rho * stepw * kDeg),
        std::abs(delta) * kDeg * (rho + 1) * 2 + 10,
        [&](const SimulatedCmm::Point& p, double) {
          Eigen::Vector3d w = p.centre - C;
          w -= w.dot(ax) * ax;
          if (w.norm() == 0) return false;
          w.normalize();
          swept += std::atan2(last.cross(w).dot(ax), last.dot(w));
          last = w;
          return std::abs(swept) >= std::abs(delta) * kDeg;
        },
        emit);
    retract_from(c.normal, retract);
  });
  ended(end);
}

void Executor::scan_on_curve() {
  need_measuring();
  // Closed(c), Format(X(), Y(), Z(), IJK(), tag[, pi, pj, pk[, si, sj, sk]]), Data(...)
  bool closed = false;
  std::size_t width = 0;
  const Value* data = nullptr;
  for (const auto& a : m_.args) {
    if (a.is_call("Closed")) closed = !a.args.empty() && a.args[0].number() != 0;
    if (a.is_call("Format")) {
      for (const auto& f : a.args) width += f.is_call("IJK") ? 3 : 1;
    }
    if (a.is_call("Data")) data = &a;
  }
  if (!data || width < 7 || data->args.size() % width != 0) throw Fail{502};
  std::vector<Eigen::Vector3d> pts, nrm;
  const auto v = numbers(*data);
  for (std::size_t i = 0; i + width <= v.size(); i += width) {
    if (v[i + 6] < 0) continue;  // a point off the surface
    pts.push_back(s_.to_machine(vec(v, i)));
    nrm.push_back(unit(s_.dir_to_machine(vec(v, i + 3))));
  }
  if (pts.size() < 2) throw Fail{509};
  if (closed && (pts.front() - pts.back()).norm() > 1e-9) {
    pts.push_back(pts.front());
    nrm.push_back(nrm.front());
  }
  const double r = s_.cmm.tip_radius(), push = 0.2;
  std::vector<Eigen::Vector3d> path;
  for (std::size_t i = 0; i < pts.size(); ++i) path.push_back(pts[i] + (r - push) * nrm[i]);
  Surface surface = s_.world();
  if (!surface) {
    Eigen::Matrix3Xd P(3, pts.size()), N(3, pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) {
      P.col(i) = pts[i];
      N.col(i) = nrm[i];
    }
    auto curve = std::make_shared<sim::SpaceCurve>(P, N);
    surface = [curve](const Eigen::Vector3d& q) -> std::optional<Nearest> {
      return curve->nearest(q);
    };
  }
  const double speed = s_.par("ScanPar", "Speed"), retract = s_.par("ScanPar", "Retract");
  const double go_speed = s_.par("GoToPar", "Speed"), go_accel = s_.par("GoToPar", "Accel");
  density_cap(s_.curve_density, speed);
  SimulatedCmm::ScanEnd end;
  scan([&](const auto& emit) {
    Unlocked u(lk_);
    s_.go(path.front() + (s_.par("PtMeasPar", "Approach") + push) * nrm.front(), go_speed,
          go_accel);
    end = s_.cmm.along(path, nrm, surface, speed, push, s_.curve_deviation, s_.curve_density, emit);
    retract_from(nrm.back(), retract);
  });
  ended(end);
}

// ScanInPlaneEndIs{Sphere,Plane,Cyl} and ScanInCylEndIs{Sphere,Plane}.
void Executor::scan_unknown() {
  need_measuring();
  check_arguments();
  auto v = numbers(m_);
  const bool in_cyl = name_.rfind("ScanInCyl", 0) == 0;
  const bool ends_in_sphere = name_.find("EndIsSphere") != std::string::npos;
  // The forms before 1.4.3 (NIST's; their direction point follows the start direction, at
  // argument 6): an in-plane scan's plane is the one through the start point's surface direction
  // and the direction point, and a sphere end counts once. Brought to the 1.4.3 layout here.
  const ScanLayout* l = scan_layout(name_, v.size());
  if (!in_cyl && l && l->direction == 6) {
    const Eigen::Vector3d N = vec(v, 3).cross(vec(v, 6) - vec(v, 0));
    if (!(N.norm() > 1e-9)) throw Fail{502};
    const Eigen::Vector3d u = N.normalized();
    v.insert(v.begin() + 6, {u.x(), u.y(), u.z()});
    if (ends_in_sphere) v.insert(v.begin() + 17, 1.0);
  }
  if (in_cyl && ends_in_sphere && v.size() == 23) v.insert(v.begin() + 20, 1.0);
  const std::size_t o = in_cyl ? 6 : 0;  // the cylinder's axis comes first
  const Eigen::Vector3d S = s_.to_machine(vec(v, o)), Sn = unit(s_.dir_to_machine(vec(v, o + 3)));
  Eigen::Vector3d N = Eigen::Vector3d::Zero(), A0 = Eigen::Vector3d::Zero(), Ad = N;
  if (in_cyl) {
    A0 = s_.to_machine(vec(v, 0));
    Ad = unit(s_.dir_to_machine(vec(v, 3)));
  } else {
    N = unit(s_.dir_to_machine(vec(v, 6)));
  }
  const Eigen::Vector3d D = s_.to_machine(vec(v, 9 + (in_cyl ? 3 : 0)));
  const std::size_t k = in_cyl ? 15 : 12;  // StepW
  double step = v.at(k);
  if (step <= 0) step = s_.unknown_density;
  if (!((D - S).norm() > 0)) throw Fail{509};
  // The stop criterion.
  enum {
    Sphere,
    Plane,
    Cyl
  } kind = name_.find("Sphere") != std::string::npos       ? Sphere
           : name_.find("EndIsPlane") != std::string::npos ? Plane
                                                           : Cyl;
  Eigen::Vector3d E = s_.to_machine(vec(v, k + 1)), En = Eigen::Vector3d::UnitZ();
  double size = 0;
  int n = 1;
  if (kind == Sphere) {
    size = v.at(k + 4) / 2;
    if (v.size() > k + 5 + (in_cyl ? 3 : 0)) n = static_cast<int>(v.at(k + 5));
  } else {
    En = unit(s_.dir_to_machine(vec(v, k + 4)));
    if (kind == Cyl) {
      size = v.at(k + 7) / 2;
      n = static_cast<int>(v.at(k + 8));
    } else {
      n = static_cast<int>(v.at(k + 7));
    }
  }
  n = std::max(n, 1);
  const auto c = probe(S, Sn, 0.0);
  Surface surface = s_.world();
  if (!surface) surface = plane_surface(S, Sn);
  Eigen::Vector3d rc = c.centre - A0;
  rc -= rc.dot(Ad) * Ad;
  const double rho = rc.norm();
  if (in_cyl && !(rho > 0)) throw Fail{509};
  const double speed = s_.par("ScanPar", "Speed"), retract = s_.par("ScanPar", "Retract");
  density_cap(step, speed);
  const double start_gap = (D - S).norm();
  SimulatedCmm::ScanEnd end;
  scan([&](const auto& emit) {
    Unlocked u(lk_);
    emit(SimulatedCmm::Point{c.centre, c.normal, 0});
    SimulatedCmm::Constraint con{[&](const Eigen::Vector3d& p) {
      if (!in_cyl) return std::pair<Eigen::Vector3d, double>(N, (p - c.centre).dot(N));
      Eigen::Vector3d w = p - A0;
      w -= w.dot(Ad) * Ad;
      const double r = w.norm();
      return std::pair<Eigen::Vector3d, double>(r > 0 ? Eigen::Vector3d(w / r) : Ad, r - rho);
    }};
    auto measure = [&](const Eigen::Vector3d& p) {
      if (kind == Sphere) return (p - E).norm() - size;
      if (kind == Plane) return (p - E).dot(En);
      Eigen::Vector3d w = p - E;
      w -= w.dot(En) * En;
      return w.norm() - size;
    };
    // The stop criteria are judged on the scanned points (the surface points reported), as the
    // specification words them: the ball centre less the tip radius along the measured normal.
    const double tip = s_.cmm.tip_radius();
    auto scanned = [&](const Eigen::Vector3d& centre, const Eigen::Vector3d& normal) {
      return measure(centre - tip * normal);
    };
    double prev = scanned(c.centre, c.normal), prev_d = 1e300;
    bool armed = kind == Plane ? false : prev > 0;
    int count = 0;
    const Eigen::Vector3d diag = s_.cmm.travel_high() - s_.cmm.travel_low();
    end = s_.cmm.follow(
        surface, con, D - S, speed, 0.2, step, 4 * diag.norm(),
        [&](const SimulatedCmm::Point& p, double arc) {
          const double d = scanned(p.centre, p.normal);
          bool stop = false;
          if (kind == Plane) {
            armed = armed || arc > start_gap;
            if (armed && (d > 0) != (prev > 0) && ++count >= n) stop = true;
          } else if (kind == Sphere) {
            if (!armed && d > 0) armed = true;
            // Inside the sphere, the n-th local minimum of the distance from its centre.
            if (armed && d < 0 && d > prev_d && prev < 0 && ++count >= n) stop = true;
            prev_d = d;
          } else {
            if (!armed && d > 0) armed = true;
            if (armed && (d > 0) != (prev > 0) && ++count >= n) stop = true;
          }
          prev = d;
          return stop;
        },
        emit);
    retract_from(c.normal, retract);
  });
  ended(end);
}

// AlignPart, CenterPart, TiltPart, TiltCenterPart: the rotary table turns about the machine's
// Z axis through table_centre.
void Executor::part_handling() {
  need_session();
  need_homed();
  const auto v = numbers(m_);
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  if (name_ == "AlignPart") {
    // One rotary table: both vectors projected into its plane; the table turns the first part
    // vector onto the first machine vector. A second pair can only be checked: with one axis
    // its part vector goes where that turn takes it, and beta bounds the angle left.
    auto flat = [&](Eigen::Vector3d a) { return unit(a - a.dot(z) * z); };
    const Eigen::Vector3d p = flat(s_.dir_to_machine(vec(v, 0))), q = flat(vec(v, 3));
    const double turn = std::atan2(p.cross(q).dot(z), p.dot(q));
    if ((s_.part || s_.balls) && std::abs(turn) > 1e-9) throw Fail{506};
    std::vector<Value> out = {number(q.x()), number(q.y()), number(q.z())};
    if (v.size() == 14) {
      const Eigen::Vector3d p2 = Eigen::AngleAxisd(turn, z) * flat(s_.dir_to_machine(vec(v, 6)));
      const Eigen::Vector3d q2 = flat(vec(v, 9));
      const double left = std::acos(std::clamp(p2.dot(q2), -1.0, 1.0)) / kDeg;
      if (v[13] > 0 && left > v[13]) throw Fail{2506};
      out.insert(out.end(), {number(p2.x()), number(p2.y()), number(p2.z())});
    }
    if (v[v.size() == 14 ? 12 : 6] < 0) throw Fail{509};
    s_.table = std::fmod(s_.table + turn / kDeg, 360.0);
    s_.data(c_.tag, {call("", out)});
    return;
  }
  auto off_axis = [&](const Eigen::Vector3d& p) {
    Eigen::Vector3d w = s_.to_machine(p) - s_.o.table_centre;
    return (w - w.dot(z) * z).norm();
  };
  if (name_ == "CenterPart") {
    const double d = off_axis(vec(v, 0));
    if (d >= v[3] && (s_.part || s_.balls)) throw Fail{506};
    s_.data(c_.tag, {call("CenterPart", {number(d < v[3] ? 1 : 0)})});
    return;
  }
  auto tilt_ok = [&](const Eigen::Vector3d& dir, double limit) {
    const Eigen::Vector3d d = unit(s_.dir_to_machine(dir));
    const double angle = std::acos(std::min(1.0, std::abs(d.dot(z))));
    return std::tan(angle) * 100 < limit;
  };
  if (name_ == "TiltPart") {
    const bool ok = tilt_ok(vec(v, 0), v[3]);
    if (!ok && (s_.part || s_.balls)) throw Fail{506};
    s_.data(c_.tag, {call("TiltPart", {number(ok ? 1 : 0)})});
    return;
  }
  const Eigen::Vector3d p1 = vec(v, 0), p2 = vec(v, 3);
  unit(p2 - p1);  // the axis through the two points: 1010 when they coincide
  const bool ok = off_axis(p1) < v[6] && off_axis(p2) < v[6] && tilt_ok(p2 - p1, v[6]);
  if (!ok && (s_.part || s_.balls)) throw Fail{506};
  s_.data(c_.tag, {call("TiltCenterPart", {number(ok ? 1 : 0)})});
}

void Executor::run() {
  const Tag& tag = c_.tag;
  const std::string& n = name_;
  // Refusals after an error or outside a session.
  if (n == "EndSession") {
    s_.session = false;
    s_.latched = 0;
    s_.daemons.clear();
    return;
  }
  if (n == "StartSession") {
    if (s_.session) throw Fail{8};
    s_.session = true;
    s_.latched = 0;
    s_.pt_format = {"X", "Y", "Z"};
    s_.scan_format = {"X", "Y", "Z", "Q"};
    s_.daemons.clear();
    return;
  }
  if (n == "ClearAllErrors") {
    s_.latched = 0;
    return;
  }
  if (!s_.session) throw Fail{8};
  if (n == "GetXtdErrStatus") {
    s_.data(tag, {call("IsHomed", {number(s_.homed ? 1 : 0)})});
    s_.data(tag, {call("IsUserEnabled", {number(s_.user_enabled ? 1 : 0)})});
    return;
  }
  if (s_.latched) throw Fail{514};
  if (n == "GetDMEVersion") return s_.data(tag, {call("DMEVersion", {string(s_.o.version)})});
  if (n == "GetMachineClass")
    return s_.data(tag, {call("GetMachineClass", {string("CartCMMWithRotaryTable")})});
  if (n == "GetErrorInfo") {
    const auto info = error_info(static_cast<int>(m_.args.at(0).number()));
    if (!info) throw Fail{504};
    return s_.data(tag, {string(std::string(info->text))});
  }
  if (n == "StopDaemon") {
    const std::string want = m_.args.at(0).text;
    const auto it = std::find_if(s_.daemons.begin(), s_.daemons.end(),
                                 [&](const Daemon& d) { return d.tag.text() == want; });
    if (it == s_.daemons.end()) throw Fail{513};
    s_.daemons.erase(it);
    return;
  }
  if (n == "StopAllDaemons") {
    if (s_.daemons.empty()) throw Fail{512};
    s_.daemons.clear();
    return;
  }
  if (n == "Home") {
    const double speed = s_.par("GoToPar", "Speed"), accel = s_.par("GoToPar", "Accel");
    {
      Unlocked u(lk_);
      s_.cmm.move(s_.o.cmm.home, speed, accel);
    }
    s_.homed = true;
    return;
  }
  if (n == "IsHomed") return s_.data(tag, {call("IsHomed", {number(s_.homed ? 1 : 0)})});
  if (n == "EnableUser") {
    s_.user_enabled = true;
    return;
  }
  if (n == "DisableUser") {
    s_.user_enabled = false;
    return;
  }
  if (n == "IsUserEnabled")
    return s_.data(tag, {call("IsUserEnabled", {number(s_.user_enabled ? 1 : 0)})});
  if (n == "Get") {
    std::vector<std::string> items;
    for (const auto& a : m_.args) items.push_back(a.text);
    return s_.data(tag, s_.axes(items));
  }
  if (n == "GoTo") return goto_();
  if (n == "PtMeas") return ptmeas();
  if (n == "OnPtMeasReport" || n == "OnScanReport") {
    std::vector<std::string> f;
    for (const auto& a : m_.args) f.push_back(a.text);
    (n == "OnPtMeasReport" ? s_.pt_format : s_.scan_format) = f;
    return;
  }
  if (n == "EnumTools") {
    for (const auto& t : s_.tools)
      if (t.visible) s_.data(tag, {string(t.name)});
    return;
  }
  if (n == "FindTool") {
    const auto i = s_.tool_index(m_.args.at(0).text);
    s_.found = i;
    if (!i) throw Fail{1502};
    return;
  }
  if (n == "ChangeTool" || n == "SetTool") {
    const std::string& want = m_.args.at(0).text;
    if (want == "UnDefTool") throw Fail{1503};
    const auto i = s_.tool_index(want);
    if (!i) throw Fail{1502};  // an unknown name changes nothing
    s_.tool_undefined = false;
    s_.active = *i;
    s_.tool().reset();
    s_.locked.clear();
    return;
  }
  if (n == "GetChangeToolAction") {
    if (m_.args.at(0).text == "UnDefTool") throw Fail{1503};
    if (!s_.tool_index(m_.args.at(0).text)) throw Fail{1502};
    const Eigen::Vector3d x = s_.to_csy(s_.cmm.position());
    return s_.data(
        tag, {call("ChangeToolAction", {name("Switch"), call("X", {fixed(x.x())}),
                                        call("Y", {fixed(x.y())}), call("Z", {fixed(x.z())})})});
  }
  if (n == "AlignTool") {
    need_homed();
    const auto v = numbers(m_);
    // The vectors must be unit vectors (NIST's checker: 0502).
    for (std::size_t i = 0; i + 3 <= (v.size() == 8 ? 6u : 3u); i += 3)
      if (std::abs(vec(v, i).norm() - 1) > 1e-4) throw Fail{502};
    const Eigen::Vector3d a = unit(vec(v, 0));
    s_.tool().alignment = s_.dir_to_machine(a);
    s_.head_a = std::acos(std::clamp(s_.tool().alignment.z(), -1.0, 1.0)) / kDeg;
    s_.head_b = std::atan2(s_.tool().alignment.y(), s_.tool().alignment.x()) / kDeg;
    std::vector<Value> out = {number(a.x()), number(a.y()), number(a.z())};
    if (v.size() == 8) {
      const Eigen::Vector3d b = unit(vec(v, 3));
      out.insert(out.end(), {number(b.x()), number(b.y()), number(b.z())});
    }
    return s_.data(tag, {call("", out)});
  }
  if (n == "GetProp" || n == "GetPropE") {
    std::vector<Value> out;
    for (const auto& a : m_.args) out.push_back(s_.get_property(a));
    return s_.data(tag, out);
  }
  if (n == "SetProp") {
    bool clamped = false;
    for (const auto& a : m_.args) clamped = !s_.set_property(a) || clamped;
    if (clamped) s_.error(tag, 504, n);
    return;
  }
  if (n == "EnumProp" || n == "EnumAllProp")
    return s_.enumerate(tag, m_.args.at(0), n == "EnumAllProp");
  if (n == "SetCoordSystem") {
    s_.csy = m_.args.at(0).text;
    return;
  }
  if (n == "GetCoordSystem") return s_.data(tag, {call("CoordSystem", {name(s_.csy)})});
  if (n == "SetCsyTransformation") {
    const auto v = numbers(m_);
    if (v[4] < 0 || v[4] > 180) throw Fail{1007};
    s_.csys[m_.args.at(0).text].set(vec(v, 1), v[4], v[5], v[6]);
    return;
  }
  if (n == "GetCsyTransformation") {
    const Csy& c = s_.csys[m_.args.at(0).text];
    return s_.data(
        tag, {call("GetCsyTransformation", {number(c.x0.x()), number(c.x0.y()), number(c.x0.z()),
                                            number(c.theta), number(c.psi), number(c.phi)})});
  }
  if (n == "LockAxis") {
    s_.locked.clear();
    for (const auto& a : m_.args) s_.locked.insert(a.text);
    return;
  }
  if (n == "ReQualify") {
    need_homed();
    need_probe();  // 1503 with UnDefTool, 0507 with NoTool
    return;
  }
  if (n == "ScanOnLine") return scan_on_line();
  if (n == "ScanOnCircle") return scan_on_circle();
  if (n == "ScanOnCurve") return scan_on_curve();
  if (n.rfind("ScanIn", 0) == 0) return scan_unknown();
  if (n == "ScanUnknownDensity") {
    for (const auto& a : m_.args)
      if (a.is_call("Dis")) s_.unknown_density = a.args.at(0).number();
    return;
  }
  if (n == "ScanOnCurveDensity") {
    for (const auto& a : m_.args)
      if (a.is_call("Dis")) s_.curve_density = a.args.at(0).number();
    return;
  }
  if (n == "ScanOnCurveHint") {
    s_.curve_deviation = m_.args.at(0).number();
    return;
  }
  if (n == "ScanOnLineHint" || n == "ScanOnCircleHint" || n == "ScanUnknownHint") return;
  if (n == "AlignPart" || n == "CenterPart" || n == "TiltPart" || n == "TiltCenterPart")
    return part_handling();
  throw Fail{501};
}

}  // namespace

// ---- the engine ----------------------------------------------------------------------------

Engine::Engine(EngineOptions options, Send send)
    : s_(std::make_unique<State>(std::move(options), std::move(send))) {}

Engine::~Engine() = default;

const SimulatedCmm& Engine::cmm() const {
  return s_->cmm;
}
double Engine::machine_time() const {
  return s_->cmm.time();
}

void Engine::receive(std::string_view text) {
  State& s = *s_;
  std::unique_lock lk(s.m);
  if (text.size() > kMaxLine) {
    s.error(parse_tag(text).value_or(Tag{true, 0}), 8, "line longer than 65536 characters");
    return;
  }
  auto parsed = parse_command(text);
  std::optional<SyntaxError> bad;
  if (!parsed)
    bad = parsed.error;
  else
    bad = check(*parsed.value);
  // A fast-queue command with an ordinary tag (error 0001 of the check) runs all the same,
  // reported on E0000 below.
  if (bad && parsed && bad->error == 1 && is_event_command(parsed.value->method.text) &&
      !parsed.value->tag.event)
    bad.reset();
  if (bad) {
    // The cause names the column and the reason, e.g. "column 18: GoTo: X is given twice".
    const Tag t = parsed ? parsed.value->tag : parse_tag(text).value_or(Tag{true, 0});
    const bool tagged = !(t.event && t.number == 0);
    if (tagged) s.line(t, '&');
    s.error(t, bad->error, fmt::format("column {}: {}", bad->column, bad->what));
    if (tagged) s.line(t, '%');
    return;
  }
  Command c = std::move(*parsed.value);
  const std::string& n = c.method.text;
  s.line(c.tag, '&');
  if (!is_event_command(n)) {
    s.queue.push_back(std::move(c));
    s.cv.notify_all();
    return;
  }
  // The fast queue, whatever the tag. A command sent with an ordinary tag is reported on
  // E0000 (error 0001, which stops nothing here: the command runs), and its completion waits
  // for the transactions before it, so that a '%' never comes before an earlier one's.
  const bool ordinary = !c.tag.event;
  if (ordinary)
    s.error(Tag{true, 0}, 1,
            fmt::format("{} with tag {}: a fast-queue command, run at once", n, c.tag.text()),
            false);
  auto complete = [&] {
    if (ordinary && (s.running || !s.queue.empty())) {
      Command done;
      done.tag = c.tag;
      done.method.text = kCompletion;
      s.queue.push_back(std::move(done));
      s.cv.notify_all();
      return;
    }
    s.line(c.tag, '%');
  };
  if (n == "AbortE") {
    if (!s.running && s.queue.empty()) {
      if (s.session) s.latched = 6;
      complete();
      return;
    }
    s.abort_tag = c.tag;
    s.abort = true;
    s.daemons.clear();  // a daemon is a transaction too: AbortE ends it
    s.cv.notify_all();
    return;
  }
  if (!s.session) {
    s.error(c.tag, 8, n);
    complete();
    return;
  }
  try {
    if (n == "GetErrStatusE") {
      s.data(c.tag, {call("ErrStatus", {number(s.latched ? 1 : 0)})});
    } else if (n == "GetPropE") {
      std::vector<Value> out;
      for (const auto& a : c.method.args) out.push_back(s.get_property(a));
      s.data(c.tag, out);
    } else if (n == "OnMoveReportE") {
      Daemon d;
      d.tag = c.tag;
      for (const auto& a : c.method.args) {
        if (a.is_call("Time"))
          d.every = a.args.at(0).number();
        else if (a.is_call("Dis"))
          d.dis = a.args.at(0).number();
        else
          d.items.push_back(a.text);
      }
      // Time at least 0.1 s and a positive distance (6.3.2.7), one daemon at a time (0515, as
      // NIST's checker: stop it before starting another).
      for (const auto& a : c.method.args)
        if ((a.is_call("Time") && !(a.args.at(0).number() >= 0.1)) ||
            (a.is_call("Dis") && !(a.args.at(0).number() > 0)))
          throw Fail{510};
      if (std::any_of(s.daemons.begin(), s.daemons.end(),
                      [&](const Daemon& e) { return !(e.tag == d.tag); }))
        throw Fail{515};
      s.daemons.erase(std::remove_if(s.daemons.begin(), s.daemons.end(),
                                     [&](const Daemon& e) { return e.tag == d.tag; }),
                      s.daemons.end());
      s.daemons.push_back(d);
      complete();
      // The first report tells where the machine is now.
      s.report_move(s.daemons.back(), true);
      return;
    }
  } catch (const Fail& f) {
    s.error(c.tag, f.number, n);
  }
  complete();
}

void Engine::refuse_overlong(std::string_view start) {
  std::lock_guard lk(s_->m);
  s_->error(parse_tag(start).value_or(Tag{true, 0}), 8, "line longer than 65536 characters");
}

bool Engine::execute_next(bool wait) {
  State& s = *s_;
  std::unique_lock lk(s.m);
  if (wait) s.cv.wait(lk, [&] { return s.stopping || !s.queue.empty() || s.abort_tag; });
  auto finish_abort = [&] {
    if (!s.abort_tag) return;
    for (const auto& q : s.queue) {
      if (q.method.text != kCompletion) s.error(q.tag, 6, q.method.text);
      s.line(q.tag, '%');
    }
    s.queue.clear();
    s.line(*s.abort_tag, '%');
    s.abort_tag.reset();
    s.abort = false;
    if (s.session) s.latched = 6;
  };
  if (s.queue.empty()) {
    finish_abort();
    return false;
  }
  const Command c = std::move(s.queue.front());
  s.queue.pop_front();
  if (c.method.text == kCompletion) {
    // A fast-queue command's completion, in its turn.
    s.line(c.tag, '%');
    finish_abort();
    s.cv.notify_all();
    return true;
  }
  s.running = true;
  s.pace_start();
  try {
    Executor(s, lk, c).run();
  } catch (const Stopped&) {
    s.error(c.tag, 6, c.method.text);
  } catch (const Fail& f) {
    s.error(c.tag, f.number, c.method.text);
  } catch (const std::exception&) {
    s.error(c.tag, 511, c.method.text);
  }
  if (!s.abort_tag) s.abort = false;  // a stop for a client that went away
  s.line(c.tag, '%');
  s.running = false;
  finish_abort();
  // Behind an error the pending transactions are aborted, up to one that may run in the error
  // state.
  while (s.latched && s.latched != 6 && !s.queue.empty()) {
    const Command& q = s.queue.front();
    const std::string& n = q.method.text;
    if (n == "ClearAllErrors" || n == "EndSession" || n == "GetXtdErrStatus") break;
    if (n != kCompletion) s.error(q.tag, 6, n);
    s.line(q.tag, '%');
    s.queue.pop_front();
  }
  s.cv.notify_all();  // disconnect() waits for the command to end
  return true;
}

void Engine::drain() {
  while (execute_next(false)) {
  }
}

void Engine::disconnect() {
  State& s = *s_;
  {
    std::lock_guard lk(s.m);
    s.queue.clear();
    s.daemons.clear();
    if (s.running) s.abort = true;
  }
  // Wait for a running command to stop (the worker clears `running` and notifies).
  std::unique_lock lk(s.m);
  s.cv.wait(lk, [&] { return !s.running; });
  s.abort = false;
  s.abort_tag.reset();
  s.session = false;
  s.latched = 0;
}

void Engine::set_flow_control(std::function<void()> wait_until_writable) {
  std::lock_guard lk(s_->m);
  s_->flow = std::move(wait_until_writable);
}

void Engine::stop() {
  std::lock_guard lk(s_->m);
  s_->stopping = true;
  s_->cv.notify_all();
}

}  // namespace trueaxis::ippdme
