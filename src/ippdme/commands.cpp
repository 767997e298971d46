// The commands of I++ DME 1.4.3 and the arguments each takes.
#include "trueaxis/ippdme/commands.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <functional>
#include <map>
#include <set>

namespace trueaxis::ippdme {
namespace {

constexpr int kTag = 1, kArguments = 502, kCommand = 507, kValue = 509, kTheta = 1007;

struct Bad {
  SyntaxError e;
};

// The parameters of a tool's GoToPar and PtMeasPar blocks (6.3.6, 6.3.7), and the values each
// has: shared by the command and the response checks.
// The parameter blocks of a tool (GoToPar, PtMeasPar, and ScanPar of section 6.3.15).
bool is_block(const std::string& block) {
  return block == "GoToPar" || block == "PtMeasPar" || block == "ScanPar";
}
bool is_parameter(const std::string& block, const std::string& name) {
  static const std::set<std::string, std::less<>> go = {"Speed", "Accel"},
                                                  pt = {"Speed", "Accel", "Approach", "Search",
                                                        "Retract"},
                                                  scan = {"Speed", "Accel", "Retract"};
  return (block == "GoToPar" ? go : block == "ScanPar" ? scan : pt).count(name) > 0;
}
bool is_parameter_value(const std::string& name) {
  return name == "Act" || name == "Def" || name == "Min" || name == "Max";
}

[[noreturn]] void bad(int error, const Value& at, std::string what) {
  throw Bad{{error, at.column ? at.column : 1, std::move(what)}};
}

// The property path of a call or name, split at its dots.
std::vector<std::string> parts(const Value& v) {
  std::vector<std::string> out;
  std::size_t a = 0;
  for (;;) {
    const std::size_t b = v.text.find('.', a);
    out.push_back(v.text.substr(a, b == std::string::npos ? std::string::npos : b - a));
    if (b == std::string::npos) return out;
    a = b + 1;
  }
}

bool is_integer(const Value& v) {
  return v.kind == Value::Kind::Number && v.text.find_first_of(".eE") == std::string::npos;
}

void none(const Value& m) {
  if (!m.args.empty()) bad(kArguments, m.args[0], m.text + " takes no arguments");
}

void count(const Value& m, std::initializer_list<std::size_t> allowed) {
  if (std::find(allowed.begin(), allowed.end(), m.args.size()) != allowed.end()) return;
  std::string list;
  for (std::size_t n : allowed) list += fmt::format("{}{}", list.empty() ? "" : " or ", n);
  bad(kArguments, m, fmt::format("{} takes {} arguments, not {}", m.text, list, m.args.size()));
}

void one_string(const Value& m) {
  count(m, {1});
  if (m.args[0].kind != Value::Kind::String)
    bad(kValue, m.args[0], m.text + "'s argument is a string (a tool's name)");
}

void all_numbers(const Value& m) {
  for (const auto& a : m.args)
    if (a.kind != Value::Kind::Number)
      bad(kArguments, a, fmt::format("{}'s arguments are numbers", m.text));
}

void numbers(const Value& m, std::initializer_list<std::size_t> allowed) {
  count(m, allowed);
  all_numbers(m);
}

void positive(const Value& m, std::size_t i, const char* what) {
  if (i < m.args.size() && !(m.args[i].number() > 0))
    bad(kValue, m.args[i], fmt::format("{}: the {} must be positive", m.text, what));
}

void positive_integer(const Value& m, std::size_t i, const char* what) {
  positive(m, i, what);
  if (i < m.args.size() && !is_integer(m.args[i]))
    bad(kValue, m.args[i], fmt::format("{}: the {} must be a whole number", m.text, what));
}

// The scan commands of 1.4.3 with their argument counts (the 1.4 form first; a later form
// where there is one), and where their step width, diameter and number of crossings stand.
struct ScanForm {
  std::vector<std::size_t> counts;
  int step = -1, diameter = -1, through = -1;  // argument index, or −1
};
const std::map<std::string, ScanForm, std::less<>>& scan_forms() {
  static const std::map<std::string, ScanForm, std::less<>> f = {
      {"ScanOnLine", {{10}, 9, -1, -1}},
      {"ScanOnLineHint", {{2}, -1, -1, -1}},
      {"ScanOnCircle", {{12}, -1, -1, -1}},
      {"ScanOnCircleHint", {{2}, -1, -1, -1}},
      // 1.4.3 adds the scanning plane's normal (Ni, Nj, Nk) to the in-plane scans and the
      // number of reachings n to the sphere ends.
      {"ScanInPlaneEndIsSphere", {{17, 21}, 9, 13, -1}},
      {"ScanInPlaneEndIsPlane", {{20, 23}, 9, -1, 16}},
      {"ScanInPlaneEndIsCyl", {{21, 24}, 9, 16, 17}},
      {"ScanInCylEndIsSphere", {{23, 24}, 15, 19, -1}},
      {"ScanInCylEndIsPlane", {{26}, 15, -1, 22}},
  };
  return f;
}

void scan(const Value& m, const ScanForm& f) {
  if (std::find(f.counts.begin(), f.counts.end(), m.args.size()) == f.counts.end())
    bad(kArguments, m,
        fmt::format("{} takes {} numbers, not {}", m.text, f.counts.front(), m.args.size()));
  all_numbers(m);
  const bool first_form = m.args.size() == f.counts.front();
  if (!first_form) return;  // the later form's positions differ; its numbers are checked
  if (f.step >= 0) positive(m, static_cast<std::size_t>(f.step), "step width");
  if (f.diameter >= 0) positive(m, static_cast<std::size_t>(f.diameter), "diameter");
  if (f.through >= 0)
    positive_integer(m, static_cast<std::size_t>(f.through), "number of crossings");
}

// Axis lists: Get(X(), Tool.A()), LockAxis(X()), OnPtMeasReport(X(), IJK()), GoTo(X(1)), ...
// `with_number`: the axes carry one number; `numbered`: extra items that carry one number.
void axes(const Value& m, const std::set<std::string, std::less<>>& allowed, bool with_number,
          const std::set<std::string, std::less<>>& numbered = {}, bool ijk_numbers = false) {
  if (m.args.empty()) bad(kArguments, m, m.text + " needs at least one item");
  std::set<std::string> seen;
  for (const auto& a : m.args) {
    if (a.kind != Value::Kind::Call || (!allowed.count(a.text) && !numbered.count(a.text)))
      bad(kArguments, a,
          fmt::format("{} does not take {}", m.text,
                      a.kind == Value::Kind::Call ? fmt::format("{}(...)", a.text)
                                                  : fmt::format("'{}'", format(a))));
    if (!seen.insert(a.text).second)
      bad(kArguments, a, fmt::format("{}: {} is given twice", m.text, a.text));
    const bool wants = numbered.count(a.text) || (with_number && a.text != "IJK");
    if (a.text == "IJK" && ijk_numbers) {
      if (a.args.size() != 3 || std::any_of(a.args.begin(), a.args.end(), [](const Value& x) {
            return x.kind != Value::Kind::Number;
          }))
        bad(kArguments, a, m.text + ": IJK takes three numbers, IJK(i, j, k)");
    } else if (wants) {
      if (a.args.size() != 1 || a.args[0].kind != Value::Kind::Number)
        bad(numbered.count(a.text) || m.text == "PtMeas" ? kValue : kArguments, a,
            fmt::format("{}: {} takes one number, {}(n)", m.text, a.text, a.text));
    } else if (!a.args.empty()) {
      bad(kArguments, a, fmt::format("{}: {} takes no number here, {}()", m.text, a.text, a.text));
    }
  }
}

const std::set<std::string, std::less<>> kReportAxes = {"X",      "Y",      "Z",     "R",
                                                        "Tool.A", "Tool.B", "Tool.C"};

// Property paths: Tool|FoundTool . (GoToPar|PtMeasPar) . parameter . (Act|Def|Min|Max), or a
// tool's own properties (Name, Id, ...).
void property(const Value& m, const Value& a, bool set) {
  if (a.kind == Value::Kind::Name)
    bad(kArguments, a,
        fmt::format("{}: '{}' is not a property; properties are written with dots and end in "
                    "parentheses, e.g. Tool.PtMeasPar.Speed()",
                    m.text, a.text));
  if (a.kind != Value::Kind::Call)
    bad(kArguments, a, fmt::format("{}: '{}' is not a property", m.text, format(a)));
  const auto p = parts(a);
  if (p[0] != "Tool" && p[0] != "FoundTool")
    bad(kValue, a,
        fmt::format("{}: a property starts with Tool or FoundTool, not {}", m.text, p[0]));
  static const std::set<std::string, std::less<>> own = {
      "Name", "Id", "CollisionVolume", "Alignment", "AvrRadius", "AlignmentVolume", "A", "B", "C"};
  if (p.size() >= 2 && own.count(p[1]) && !set && (m.text == "GetProp" || m.text == "GetPropE")) {
    if (p.size() > 2) bad(kValue, a, fmt::format("{}: {} has no sub-properties", m.text, p[1]));
    if (p[0] == "FoundTool" && p[1] != "Name" && p[1] != "Id")
      bad(kArguments, a, fmt::format("{}: FoundTool has no {}", m.text, p[1]));
    if (!a.args.empty()) bad(kArguments, a, m.text + ": a property asked for ends in ()");
    return;
  }
  if (p.size() == 1) {
    if (set || m.text == "GetProp" || m.text == "GetPropE")
      bad(kArguments, a, fmt::format("{}: {}() alone is not a value", m.text, p[0]));
    if (!a.args.empty()) bad(kValue, a, m.text + ": the property ends in ()");
    return;
  }
  if (!is_block(p[1]))
    bad(kValue, a,
        fmt::format("{}: {} has no {} (GoToPar, PtMeasPar or ScanPar)", m.text, p[0], p[1]));
  if (p.size() == 2) {
    if (set) bad(kArguments, a, m.text + ": set one parameter, e.g. Tool.PtMeasPar.Speed(10)");
    if (!a.args.empty()) bad(kValue, a, m.text + ": the property ends in ()");
    return;
  }
  if (!is_parameter(p[1], p[2]))
    bad(kValue, a, fmt::format("{}: {} has no parameter {}", m.text, p[1], p[2]));
  if (p.size() > 4) bad(kValue, a, fmt::format("{}: {} is too deep", m.text, a.text));
  if (p.size() == 4) {
    if (!is_parameter_value(p[3]) || (set && p[3] != "Act"))
      bad(kValue, a,
          fmt::format("{}: {} is not {}", m.text, p[3],
                      set ? "Act (only the actual value can be set)" : "Act, Def, Min or Max"));
  }
  if (set) {
    if (a.args.size() != 1 || a.args[0].kind != Value::Kind::Number)
      bad(p.size() == 4 ? kValue : kArguments, a,
          fmt::format("{}: {} takes one number", m.text, a.text));
  } else if (!a.args.empty()) {
    bad(kValue, a, m.text + ": a property asked for ends in ()");
  }
}

void properties(const Value& m, bool set, bool single) {
  if (m.args.empty() || (single && m.args.size() != 1))
    bad(kArguments, m, fmt::format("{} takes {}", m.text, single ? "one property" : "properties"));
  for (const auto& a : m.args) property(m, a, set);
}

void csy(const Value& m, const std::set<std::string, std::less<>>& allowed) {
  count(m, {1});
  if (m.args[0].kind != Value::Kind::Name || !allowed.count(m.args[0].text))
    bad(kArguments, m.args[0], fmt::format("{} does not take {}", m.text, format(m.args[0])));
}

const std::set<std::string, std::less<>> kTransformable = {
    "PartCsy", "JogDisplayCsy", "JogMoveCsy", "SensorCsy", "MoveableMachineCsy", "MultipleArmCsy"};

using Check = std::function<void(const Value&)>;

const std::map<std::string, Check, std::less<>>& table() {
  static const std::map<std::string, Check, std::less<>> t = [] {
    std::map<std::string, Check, std::less<>> c;
    for (const char* n :
         {"AbortE", "ClearAllErrors", "DisableUser", "EnableUser", "EndSession", "EnumTools",
          "GetCoordSystem", "GetDMEVersion", "GetErrStatusE", "GetMachineClass", "GetXtdErrStatus",
          "Home", "IsHomed", "IsUserEnabled", "ReQualify", "StartSession", "StopAllDaemons"})
      c[n] = none;
    for (const char* n : {"ChangeTool", "FindTool", "GetChangeToolAction", "SetTool"})
      c[n] = one_string;
    c["GetErrorInfo"] = [](const Value& m) {
      count(m, {1});
      if (!is_integer(m.args[0])) bad(kValue, m.args[0], "GetErrorInfo takes an error number");
    };
    c["AlignPart"] = [](const Value& m) { numbers(m, {7, 14}); };
    c["AlignTool"] = [](const Value& m) { numbers(m, {4, 8}); };
    c["CenterPart"] = [](const Value& m) { numbers(m, {4}); };
    c["TiltPart"] = [](const Value& m) { numbers(m, {4}); };
    c["TiltCenterPart"] = [](const Value& m) { numbers(m, {7}); };
    for (const auto& [n, f] : scan_forms()) c[n] = [f = f](const Value& m) { scan(m, f); };
    c["ScanUnknownHint"] = [](const Value& m) {
      count(m, {1});
      if (m.args[0].kind != Value::Kind::Number)
        bad(kValue, m.args[0], "ScanUnknownHint takes a number (the smallest radius, mm)");
      positive(m, 0, "radius");
    };
    c["ScanUnknownDensity"] = [](const Value& m) {
      if (m.args.empty()) bad(kArguments, m, "ScanUnknownDensity needs Dis(...) and/or Angle(...)");
      axes(m, {}, true, {"Dis", "Angle", "AtNominals", "Hull"});
    };
    c["ScanOnCurveHint"] = [](const Value& m) {
      numbers(m, {2});
      positive(m, 0, "deviation");
      positive(m, 1, "radius");
    };
    c["ScanOnCurveDensity"] = [](const Value& m) {
      if (m.args.empty()) bad(kArguments, m, "ScanOnCurveDensity needs Dis(...) and/or Angle(...)");
      axes(m, {}, true, {"Dis", "Angle", "AtNominals"});
    };
    // Later versions' scan along a given curve: Closed(0|1), Format(...), Data(...).
    c["ScanOnCurve"] = [](const Value& m) {
      if (m.args.size() < 3) bad(kArguments, m, "ScanOnCurve takes Closed(), Format() and Data()");
      for (const auto& a : m.args)
        if (a.kind != Value::Kind::Call) bad(kArguments, a, "ScanOnCurve takes calls");
    };
    c["Get"] = [](const Value& m) { axes(m, kReportAxes, false); };
    c["LockAxis"] = [](const Value& m) { axes(m, {"X", "Y", "Z", "R", "C", "Phi"}, false); };
    // OnMoveReportE() with nothing in it stops the move reports.
    c["OnMoveReportE"] = [](const Value& m) {
      if (!m.args.empty()) axes(m, kReportAxes, false, {"Time", "Dis"});
    };
    c["OnPtMeasReport"] = [](const Value& m) {
      axes(m, {"X", "Y", "Z", "R", "IJK", "ER", "Tool.A", "Tool.B", "Tool.C"}, false);
    };
    c["OnScanReport"] = [](const Value& m) {
      axes(m, {"X", "Y", "Z", "R", "IJK", "ER", "Q", "Tool.A", "Tool.B", "Tool.C"}, false);
    };
    c["GoTo"] = [](const Value& m) {
      axes(m, {"X", "Y", "Z", "Tool.A", "Tool.B", "Tool.C", "IJK"}, true, {}, true);
    };
    c["PtMeas"] = [](const Value& m) {
      axes(m, {"X", "Y", "Z", "IJK"}, true, {}, true);
      if (std::none_of(m.args.begin(), m.args.end(), [](const Value& a) {
            return a.text == "X" || a.text == "Y" || a.text == "Z";
          }))
        bad(kArguments, m, "PtMeas needs at least one of X(), Y(), Z()");
    };
    c["GetProp"] = [](const Value& m) { properties(m, false, false); };
    c["GetPropE"] = [](const Value& m) { properties(m, false, false); };
    c["SetProp"] = [](const Value& m) { properties(m, true, false); };
    c["EnumProp"] = [](const Value& m) { properties(m, false, true); };
    c["EnumAllProp"] = [](const Value& m) { properties(m, false, true); };
    c["SetCoordSystem"] = [](const Value& m) {
      csy(m,
          {"MachineCsy", "MoveableMachineCsy", "MultipleArmCsy", "RotaryTableVarCsy", "PartCsy"});
    };
    c["GetCsyTransformation"] = [](const Value& m) { csy(m, kTransformable); };
    c["SetCsyTransformation"] = [](const Value& m) {
      count(m, {7});
      if (m.args[0].kind != Value::Kind::Name)
        bad(kArguments, m.args[0], "SetCsyTransformation starts with a coordinate system name");
      if (!kTransformable.count(m.args[0].text))
        bad(kValue, m.args[0],
            fmt::format("SetCsyTransformation: {} cannot be transformed", m.args[0].text));
      for (std::size_t i = 1; i < 7; ++i)
        if (m.args[i].kind != Value::Kind::Number)
          bad(kArguments, m.args[i],
              "SetCsyTransformation: X0, Y0, Z0, Theta, Psi, Phi are numbers");
      const double theta = m.args[4].number();
      if (!(theta >= 0 && theta <= 180))
        bad(kTheta, m.args[4], fmt::format("theta {:g}° is outside 0..180°", theta));
    };
    c["StopDaemon"] = [](const Value& m) {
      count(m, {1});
      if (m.args[0].kind != Value::Kind::ETag)
        bad(kValue, m.args[0], "StopDaemon takes the event tag of the daemon, e.g. E0017");
    };
    return c;
  }();
  return t;
}

}  // namespace

namespace {

// Responses.
constexpr int kProtocol = 8;

void rbad(const Value& at, std::string what) {
  throw Bad{{kProtocol, at.column ? at.column : 1, std::move(what)}};
}

bool one_flag(const Value& v) {
  return v.args.size() == 1 && v.args[0].kind == Value::Kind::Number &&
         (v.args[0].text == "0" || v.args[0].text == "1");
}

bool numbers_only(const Value& v, std::size_t n) {
  return v.args.size() == n && std::all_of(v.args.begin(), v.args.end(), [](const Value& a) {
           return a.kind == Value::Kind::Number;
         });
}

bool is_position_item(const std::string& name) {
  static const std::set<std::string, std::less<>> names = {"X",      "Y",      "Z",      "R",  "ER",
                                                           "Tool.A", "Tool.B", "Tool.C", "IJK"};
  return names.count(name) > 0;
}

// X(1), Y(2), Z(3), IJK(0, 0, 1), R(0.5), ER(0.001), Tool.A(90), ... each once.
void position_items(const std::vector<Value>& items, bool zero_ijk) {
  std::set<std::string> seen;
  for (const auto& a : items) {
    if (a.kind != Value::Kind::Call) rbad(a, fmt::format("'{}' is not a data item", format(a)));
    if (!is_position_item(a.text)) rbad(a, fmt::format("{}(...) is not a position item", a.text));
    if (!seen.insert(a.text).second) rbad(a, a.text + " is given twice");
    if (a.text == "IJK") {
      if (!numbers_only(a, 3)) rbad(a, "IJK(i, j, k) has three numbers");
      if (zero_ijk &&
          std::any_of(a.args.begin(), a.args.end(), [](const Value& x) { return x.number() != 0; }))
        rbad(a, "a move reports IJK(0, 0, 0)");
    } else if (!numbers_only(a, 1)) {
      rbad(a, fmt::format("{}(n) has one number", a.text));
    }
  }
}

// A property in a response: Tool.PtMeasPar.Speed(10), Tool.Name("probe"), Tool.Alignment(...).
void property_item(const Value& a, bool set_event) {
  const auto p = parts(a);
  if (p.size() < 2 || (p[0] != "Tool" && p[0] != "FoundTool"))
    rbad(a, fmt::format("{}(...) is not a property of Tool or FoundTool", a.text));
  if (p[1] == "Name" || p[1] == "Id") {
    if (p.size() != 2 || a.args.size() != 1 || a.args[0].kind != Value::Kind::String)
      rbad(a, fmt::format("{}(\"...\") has one string", a.text));
    return;
  }
  if (p[1] == "Alignment" || p[1] == "CollisionVolume" || p[1] == "AvrRadius" ||
      p[1] == "AlignmentVolume") {
    if (p[0] == "FoundTool" || p.size() != 2) rbad(a, a.text + " is not a property");
    const std::size_t n = a.args.size();
    if (p[1] == "Alignment" && !(numbers_only(a, 3) || numbers_only(a, 6)))
      rbad(a, "Alignment has three or six numbers");
    // Shapes, each a name and its numbers (OBB, 150, 10, ...), or nothing.
    if (p[1] == "CollisionVolume" && ((n > 0 && a.args[0].kind != Value::Kind::Name) || n == 1 ||
                                      std::any_of(a.args.begin(), a.args.end(), [](const Value& x) {
                                        return x.kind != Value::Kind::Number &&
                                               x.kind != Value::Kind::Name;
                                      })))
      rbad(a, "CollisionVolume has shapes, each a name and its numbers");
    if (p[1] == "AvrRadius" && !numbers_only(a, 1)) rbad(a, "AvrRadius has one number");
    return;
  }
  if (!is_block(p[1])) rbad(a, a.text + " is not a property");
  if (p.size() < 3 || !is_parameter(p[1], p[2]))
    rbad(a, fmt::format("{} has no such parameter", p[1]));
  if (p.size() > 4 ||
      (p.size() == 4 && (!is_parameter_value(p[3]) || (set_event && p[3] != "Act"))))
    rbad(a, a.text + " is not a parameter value");
  if (!numbers_only(a, 1)) rbad(a, fmt::format("{}(n) has one number", a.text));
}

void check_data(const Response& r) {
  const auto& it = r.items;
  const Value& f = it.front();
  if (f.kind != Value::Kind::Call) {
    for (const auto& v : it)
      if (v.kind != Value::Kind::Number && v.kind != Value::Kind::String)
        rbad(v, fmt::format("'{}' is not data", format(v)));
    return;  // numbers (scan data, ...) or strings (tool names, property names)
  }
  static const std::set<std::string, std::less<>> flags = {
      "CenterPart", "TiltPart", "TiltCenterPart", "IsHomed", "IsUserEnabled", "ErrStatus"};
  auto alone = [&] {
    if (it.size() != 1) rbad(it[1], f.text + "(...) is the whole response");
  };
  if (f.text.empty()) {  // AlignPart's and AlignTool's vectors
    alone();
    if (!(numbers_only(f, 3) || numbers_only(f, 6))) rbad(f, "an alignment has 3 or 6 numbers");
  } else if (flags.count(f.text)) {
    alone();
    if (!one_flag(f)) rbad(f, f.text + "(0) or " + f.text + "(1)");
  } else if (f.text == "ChangeToolAction") {
    alone();
    static const std::set<std::string, std::less<>> act = {"Switch", "Rotate", "MoveAuto",
                                                           "MoveMan"};
    if (f.args.size() != 4 || f.args[0].kind != Value::Kind::Name || !act.count(f.args[0].text))
      rbad(f, "ChangeToolAction(Switch|Rotate|MoveAuto|MoveMan, X(), Y(), Z())");
    position_items({f.args.begin() + 1, f.args.end()}, false);
  } else if (f.text == "CoordSystem") {
    alone();
    static const std::set<std::string, std::less<>> csys = {
        "MachineCsy", "MoveableMachineCsy", "MultipleArmCsy", "RotaryTableVarCsy", "PartCsy"};
    if (f.args.size() != 1 || f.args[0].kind != Value::Kind::Name || !csys.count(f.args[0].text))
      rbad(f, "CoordSystem(...) names a coordinate system");
  } else if (f.text == "GetCsyTransformation") {
    alone();
    if (!numbers_only(f, 6)) rbad(f, "GetCsyTransformation has six numbers");
  } else if (f.text == "DMEVersion" || f.text == "KeyPress" || f.text == "ChangeTool") {
    alone();
    if (f.args.size() != 1 || f.args[0].kind != Value::Kind::String)
      rbad(f, f.text + "(\"...\") has one string");
  } else if (f.text == "GetMachineClass") {
    alone();
    if (f.args.size() != 1 || f.args[0].kind != Value::Kind::String ||
        (f.args[0].text != "CartCMM" && f.args[0].text != "CartCMMWithRotaryTable"))
      rbad(f, "GetMachineClass(\"CartCMM\") or GetMachineClass(\"CartCMMWithRotaryTable\")");
  } else if (f.text == "GoTo" || f.text == "PtMeas") {
    alone();
    if (f.args.empty()) rbad(f, f.text + "(...) reports a position");
    position_items(f.args, f.text == "GoTo");
  } else if (f.text == "SetProp") {
    alone();
    if (f.args.empty()) rbad(f, "SetProp(...) reports properties");
    for (const auto& a : f.args) {
      if (a.kind != Value::Kind::Call) rbad(a, "SetProp(...) reports properties");
      property_item(a, true);
    }
  } else {
    // Positions (Get, PtMeas) and properties (GetProp), in any order.
    std::vector<Value> positions;
    for (const auto& a : it) {
      if (a.kind != Value::Kind::Call) rbad(a, fmt::format("'{}' is not a data item", format(a)));
      if (is_position_item(a.text))
        positions.push_back(a);
      else if (a.text.rfind("Tool.", 0) == 0 || a.text.rfind("FoundTool.", 0) == 0)
        property_item(a, false);
      else
        rbad(a, fmt::format("{}(...) is neither a position item nor a property", a.text));
    }
    position_items(positions, false);
  }
}

}  // namespace

std::optional<ErrorInfo> error_info(int number) {
  static const std::map<int, ErrorInfo> t = {
      {0, {0, "Buffer full"}},
      {1, {2, "Illegal tag"}},
      {2, {2, "No space at pos. 6"}},
      {3, {2, "Reserved"}},
      {4, {2, "Reserved"}},
      {5, {2, "Reserved"}},
      {6, {2, "Transaction aborted (Use ClearAllErrors To Continue)"}},
      {7, {3, "Illegal character"}},
      {8, {3, "Protocol error"}},
      {500, {3, "Emergency stop"}},
      {501, {3, "Unsupported command"}},
      {502, {3, "Incorrect arguments"}},
      {503, {9, "Controller communications failure"}},
      {504, {1, "Argument out of range"}},
      {505, {3, "Argument not recognized"}},
      {506, {3, "Argument not supported"}},
      {507, {3, "Illegal command"}},
      {508, {3, "Bad context"}},
      {509, {3, "Bad argument"}},
      {510, {3, "Bad property"}},
      {511, {3, "Error processing method"}},
      {512, {1, "No daemons are active"}},
      {513, {2, "Daemon does not exist"}},
      {514, {2, "Use ClearAllErrors to continue"}},
      {515, {2, "Daemon already exists"}},
      {1000, {3, "Machine in error state"}},
      {1001, {2, "Illegal touch"}},
      {1002, {9, "Axis does not exist"}},
      {1003, {2, "No touch"}},
      {1004, {9, "Number of angles not supported on current device"}},
      {1005, {3, "Error during home"}},
      {1006, {2, "Surface not found"}},
      {1007, {3, "Theta out of range"}},
      {1008, {3, "Target position out of machine volume"}},
      {1009, {3, "Air pressure out of range"}},
      {1010, {2, "Vector has no norm"}},
      {1011, {2, "Unable to move"}},
      {1012, {2, "Bad lock combinations"}},
      {1500, {3, "Failed to re-seat head"}},
      {1501, {3, "Probe not armed"}},
      {1502, {3, "Tool not found"}},
      {1503, {3, "Tool not defined"}},
      {2000, {3, "Tool not calibrated"}},
      {2001, {2, "Head error excessive force"}},
      {2002, {3, "Type of probe does not allow this operation"}},
      {2500, {3, "Machine limit encountered [Move Out Of Limits]"}},
      {2501, {3, "Axis not active"}},
      {2502, {3, "Axis position error"}},
      {2503, {9, "Scale read head failure"}},
      {2504, {3, "Collision"}},
      {2505, {2, "Specified angle out of range"}},
      {2506, {2, "Part not aligned"}},
  };
  const auto it = t.find(number);
  if (it == t.end()) return std::nullopt;
  return it->second;
}

std::optional<SyntaxError> check(const Response& r) {
  try {
    if (r.tag.event && r.tag.number == 0 &&
        (r.kind == Response::Kind::Ack || r.kind == Response::Kind::Done))
      throw Bad{{kProtocol, 1, "E0000 carries events (data or errors), not '&' or '%'"}};
    if (r.kind == Response::Kind::Error) {
      const auto& a = r.items[0].args;
      const int number = static_cast<int>(a[1].number());
      const auto info = error_info(number);
      if (!info) rbad(a[1], fmt::format("{} is not an I++ DME error number", a[1].text));
      auto lower = [](std::string_view x) {
        std::string o(x);
        for (char& ch : o) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
        return o;
      };
      // Servers differ in capitals ("Bad Argument"); the words must be the specification's.
      if (lower(a[3].text) != lower(info->text))
        rbad(a[3], fmt::format("the text of error {} is \"{}\"", a[1].text, info->text));
      if (static_cast<int>(a[0].number()) != info->severity)
        rbad(a[0], fmt::format("error {} has severity {}", a[1].text, info->severity));
    } else if (r.kind == Response::Kind::Data) {
      if (r.tag.event && r.tag.number == 0 && r.items.front().kind != Value::Kind::Call)
        rbad(r.items.front(), "an event (E0000) names what it reports");
      check_data(r);
    }
  } catch (const Bad& b) {
    return b.e;
  }
  return std::nullopt;
}

bool is_event_command(std::string_view name) {
  return name == "AbortE" || name == "GetErrStatusE" || name == "GetPropE" ||
         name == "OnMoveReportE";
}

const std::vector<std::string_view>& command_names() {
  static const std::vector<std::string_view> n = [] {
    std::vector<std::string_view> out;
    for (const auto& [k, v] : table()) out.push_back(k);
    return out;
  }();
  return n;
}

std::optional<SyntaxError> check(const Command& c) {
  try {
    const Value& m = c.method;
    const auto it = table().find(m.text);
    if (it == table().end()) bad(kCommand, m, fmt::format("unknown command '{}'", m.text));
    it->second(m);
    // The tag last: a server may still run a fast-queue command sent with an ordinary tag
    // (ippdme::Engine does, as an abort must abort), once its arguments are right.
    if (is_event_command(m.text) && !c.tag.event)
      bad(kTag, m, fmt::format("{} goes through the fast queue: it needs an E tag", m.text));
    if (!is_event_command(m.text) && c.tag.event)
      bad(kTag, m, fmt::format("{} is not a fast-queue command: no E tag", m.text));
  } catch (const Bad& b) {
    return b.e;
  }
  return std::nullopt;
}

}  // namespace trueaxis::ippdme
