// The I++ DME server's command executor: sessions, tools, properties, PtMeas, GoTo and part
// handling (the scans: engine_scans.cpp).
#include <fmt/format.h>

#include "engine_state.hpp"

namespace trueaxis::ippdme::detail {

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
    // Boxes are set up a group at a time: the one whose box the nominal point is on is there.
    if (s_.boxes) s_.boxes->active->store(s_.boxes->group_at(x));
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
  // A server of an older version does not know what came later: ScanOnCurve and its hint and
  // density, the scanning parameters (Tool.ScanPar) and Tool.AvrRadius are I++ DME 1.4.2's.
  if (version_number(s_.o.version).value_or(10403) < 10402) {
    bool newer = n == "ScanOnCurve" || n == "ScanOnCurveHint" || n == "ScanOnCurveDensity";
    if (n == "SetProp" || n == "GetProp" || n == "GetPropE")
      for (const auto& a : m_.args)
        newer = newer || a.text.find("ScanPar") != std::string::npos ||
                a.text.find("AvrRadius") != std::string::npos;
    if (newer) throw Fail{501};
  }
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

}  // namespace trueaxis::ippdme::detail
