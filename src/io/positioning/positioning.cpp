#include "trueaxis/io/positioning/positioning.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <tuple>

#include "../fast_text.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/csv.hpp"
#include "trueaxis/io/json.hpp"

namespace trueaxis::io {
namespace {

using positioning::Direction;
using positioning::Reading;
using ojson = nlohmann::ordered_json;

enum Column { kTarget, kCycle, kDirection, kDeviation, kMaterial, kAir, kColumns };
// Each column's quantity and the unit it is read in (a name may give another unit of the same
// kind: "target [m]", "deviation (nm)"; see units.hpp). The direction is text: no unit.
constexpr const char* kQuantities[kColumns] = {"target",    "cycle",         "direction",
                                               "deviation", "material_temp", "air_temp"};
constexpr Unit kColumnUnits[kColumns] = {Unit::Millimetre, Unit::Count,   Unit::Count,
                                         Unit::Micrometre, Unit::Celsius, Unit::Celsius};
constexpr double kMinTemperature = -50, kMaxTemperature = 100;

using detail::is_blank;
using detail::kMaxDeviation;
using detail::kMaxTarget;
using detail::lower;

// Fields of one line: [begin, end) offsets, trimmed.
std::vector<std::pair<std::size_t, std::size_t>> split(std::string_view l) {
  std::vector<std::pair<std::size_t, std::size_t>> f;
  std::size_t b = 0;
  while (true) {
    std::size_t e = l.find(',', b);
    const std::size_t stop = e == std::string_view::npos ? l.size() : e;
    std::size_t x = b, y = stop;
    while (x < y && is_blank(l[x])) ++x;
    while (y > x && is_blank(l[y - 1])) --y;
    f.emplace_back(x, y);
    if (e == std::string_view::npos) break;
    b = e + 1;
  }
  return f;
}

}  // namespace

PositioningRuns parse_runs(std::string text, const std::string& path) {
  detail::normalize_text(text);
  // A spreadsheet's dialect (';' or tab with decimal commas, "sep=;", quotes) as plain CSV.
  if (std::optional<std::string> plain = detail::plain_csv(text, path)) text = std::move(*plain);
  const std::string_view all(text);
  PositioningRuns out;
  int col_of[kColumns];
  std::fill(std::begin(col_of), std::end(col_of), -1);
  std::string name_of[kColumns];  // each column's name as the header writes it
  double scale_of[kColumns];      // from the written unit to the column's unit
  std::fill(std::begin(scale_of), std::end(scale_of), 1.0);
  std::size_t ncol = 0, header_line = 0;
  std::map<std::tuple<long long, int, int>, std::size_t> seen;  // (target in 0.1 µm, cycle, dir)
  std::size_t pos = 0, line = 0;
  while (pos < all.size()) {
    const std::size_t nl = all.find('\n', pos);
    const std::size_t end = nl == std::string_view::npos ? all.size() : nl;
    const std::string_view l = all.substr(pos, end - pos);
    pos = nl == std::string_view::npos ? all.size() : nl + 1;
    ++line;
    std::size_t first = 0;
    while (first < l.size() && is_blank(l[first])) ++first;
    if (first == l.size() || l[first] == '#') continue;
    auto fail = [&](std::size_t col0, const std::string& what) {
      throw Error(fmt::format("{}:{}:{}: {}", path, line, col0 + 1, what));
    };
    const auto fields = split(l);
    if (header_line == 0) {
      header_line = line;
      ncol = fields.size();
      for (std::size_t c = 0; c < fields.size(); ++c) {
        const auto [b, e] = fields[c];
        const std::string_view name = l.substr(b, e - b);
        int which = -1;
        std::optional<Unit> written;
        for (int k = 0; k < kColumns && which < 0; ++k) {
          ColumnMatch m;
          try {
            m = column_matches(name, kQuantities[k]);
          } catch (const Error& err) {
            fail(b, err.what());
          }
          if (m.holds) {
            which = k;
            written = m.unit;
          }
        }
        if (which < 0)
          fail(b, fmt::format("unknown column '{}' (target_mm, cycle, direction, deviation_um, "
                              "material_temp_c, air_temp_c; a unit may be written in the name, "
                              "as in 'target [m]' or 'deviation (nm)')",
                              detail::quote_cut(name)));
        if (col_of[which] >= 0)
          fail(b, name == name_of[which]
                      ? fmt::format("column '{}' appears twice", detail::quote_cut(name))
                      : fmt::format("column '{}' holds the {} again (column '{}' before it)",
                                    detail::quote_cut(name), kQuantities[which], name_of[which]));
        if (written)
          if (const std::string why = unit_refusal(detail::quote_cut(name), *written,
                                                   kQuantities[which], kColumnUnits[which]);
              !why.empty())
            fail(b, why);
        col_of[which] = static_cast<int>(c);
        name_of[which] = std::string(name);
        scale_of[which] = written ? unit_factor(*written, kColumnUnits[which]) : 1.0;
      }
      for (int k = 0; k < kDeviation + 1; ++k)
        if (col_of[k] < 0)
          fail(0, fmt::format("the header has no '{}' column (target_mm, cycle, direction and "
                              "deviation_um are needed; a unit may be written in the name)",
                              kQuantities[k]));
      out.has_material = col_of[kMaterial] >= 0;
      out.has_air = col_of[kAir] >= 0;
      continue;
    }
    if (fields.size() != ncol)
      fail(fields.size() < ncol ? l.size() : fields[ncol].first - 1,
           fmt::format("{} fields, the header has {} columns", fields.size(), ncol));
    Reading r;
    auto number = [&](int k, double limit) {
      const auto [b, e] = fields[static_cast<std::size_t>(col_of[k])];
      if (b == e) fail(b, fmt::format("empty field in column '{}'", name_of[k]));
      const char* s = l.data() + b;
      const char* se = l.data() + e;
      if (*s == '+') ++s;
      double v = 0;
      const auto res = std::from_chars(s, se, v);
      if (res.ec != std::errc() || res.ptr != se || !std::isfinite(v))
        fail(b, fmt::format("'{}' is not a number (column '{}')",
                            detail::quote_cut(l.substr(b, e - b)), name_of[k]));
      v *= scale_of[k];
      if (std::abs(v) > limit)
        fail(b,
             fmt::format("{:g} {} is out of range in column '{}' (its size must be at most "
                         "{:g} {})",
                         v, symbol(kColumnUnits[k]), name_of[k], limit, symbol(kColumnUnits[k])));
      return v;
    };
    r.target = number(kTarget, kMaxTarget);
    r.deviation = number(kDeviation, kMaxDeviation) * 1e-3;
    {
      const auto [b, e] = fields[static_cast<std::size_t>(col_of[kCycle])];
      int c = 0;
      const auto res = std::from_chars(l.data() + b, l.data() + e, c);
      if (b == e || res.ec != std::errc() || res.ptr != l.data() + e || c < 1)
        fail(b, fmt::format("cycle '{}' is not a whole number from 1",
                            detail::quote_cut(l.substr(b, e - b))));
      r.cycle = c;
    }
    {
      const auto [b, e] = fields[static_cast<std::size_t>(col_of[kDirection])];
      const std::string d = lower(l.substr(b, e - b));
      if (d == "+" || d == "up")
        r.direction = Direction::Up;
      else if (d == "-" || d == "down")
        r.direction = Direction::Down;
      else
        fail(b, fmt::format("direction '{}': use '+' (approach moving in +) or '-'",
                            detail::quote_cut(l.substr(b, e - b))));
    }
    for (int k : {kMaterial, kAir}) {
      if (col_of[k] < 0) continue;
      const double t = number(k, 1e6);
      if (t < kMinTemperature || t > kMaxTemperature)
        fail(fields[static_cast<std::size_t>(col_of[k])].first,
             fmt::format("{:g} is not a plausible temperature in degrees Celsius (column '{}')", t,
                         name_of[k]));
      (k == kMaterial ? r.material_temperature : r.air_temperature) = t;
    }
    const auto key = std::make_tuple(std::llround(r.target * 1e4), r.cycle,
                                     r.direction == Direction::Up ? 0 : 1);
    const auto [it, fresh] = seen.emplace(key, line);
    if (!fresh)
      fail(fields[static_cast<std::size_t>(col_of[kTarget])].first,
           fmt::format("cycle {} '{}' at target {:g} mm was already read on line {}", r.cycle,
                       r.direction == Direction::Up ? '+' : '-', r.target, it->second));
    out.readings.push_back(r);
    out.lines.push_back(line);
  }
  if (header_line == 0)
    throw Error(
        fmt::format("{}: no header (expected target_mm,cycle,direction,deviation_um)", path));
  if (out.readings.empty())
    throw Error(fmt::format("{}:{}:1: no readings after the header", path, header_line));
  return out;
}

positioning::Log read_log(const std::string& path) {
  CsvTable t = CsvTable::read(path);
  const int ct = t.require("time", Unit::Second), cr = t.require("reading", Unit::Millimetre);
  if (t.cols() != 2)
    throw Error(fmt::format("{}:1:1: a log has two columns, time_s and reading_mm ({} found)", path,
                            t.cols()));
  if (t.rows() < 2) throw Error(fmt::format("{}: a log needs at least two samples", path));
  positioning::Log log;
  const Eigen::VectorXd &tv = t.column(ct), &rv = t.column(cr);
  for (Eigen::Index i = 0; i < tv.size(); ++i) {
    if (i > 0 && !(tv[i] > tv[i - 1]))
      throw Error(fmt::format("{}time {:g} s does not increase (previous sample: {:g} s)",
                              t.where(static_cast<long>(i), ct), tv[i], tv[i - 1]));
    log.time.push_back(tv[i]);
    log.reading.push_back(rv[i]);
  }
  return log;
}

bool is_log_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  if (!std::getline(in, line)) return false;
  if (line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);  // a UTF-8 byte-order mark
  std::vector<std::string> names;
  std::string name;
  for (char c : line + ",") {
    if (c == ',' || c == ';' || c == '\t') {
      names.push_back(name);
      name.clear();
    } else if (!std::isspace(static_cast<unsigned char>(c)) && c != '"') {
      name += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    }
  }
  if (names.size() != 2) return false;
  auto is = [&](const std::string& n, const char* word) { return n.rfind(word, 0) == 0; };
  return (is(names[0], "time") && is(names[1], "reading")) ||
         (is(names[0], "reading") && is(names[1], "time"));
}

void write_log(const std::string& path, const positioning::Log& log) {
  const Eigen::VectorXd t = Eigen::Map<const Eigen::VectorXd>(
      log.time.data(), static_cast<Eigen::Index>(log.time.size()));
  const Eigen::VectorXd r = Eigen::Map<const Eigen::VectorXd>(
      log.reading.data(), static_cast<Eigen::Index>(log.reading.size()));
  write_csv(path, {"time_s", "reading_mm"}, {&t, &r});
}

PositioningRuns read_runs(const std::string& path) {
  return parse_runs(detail::read_text(path), path);
}

void write_runs(const std::string& path, const std::vector<Reading>& readings) {
  bool material = false, air = false;
  for (const auto& r : readings) {
    material = material || !std::isnan(r.material_temperature);
    air = air || !std::isnan(r.air_temperature);
  }
  std::string s = "target_mm,cycle,direction,deviation_um";
  if (material) s += ",material_temp_c";
  if (air) s += ",air_temp_c";
  s += '\n';
  char buf[32];
  auto num = [&](double v) {
    char* e = detail::write_number(buf, v);
    s.append(buf, e);
  };
  for (const auto& r : readings) {
    num(r.target);
    s += fmt::format(",{},{},", r.cycle, r.direction == Direction::Up ? '+' : '-');
    num(r.deviation * 1e3);
    if (material) {
      s += ',';
      num(r.material_temperature);
    }
    if (air) {
      s += ',';
      num(r.air_temperature);
    }
    s += '\n';
  }
  detail::OutFile f(path);
  f.write(s);
  f.close();
}

namespace {

ojson um(double mm) {
  return std::isnan(mm) ? ojson(nullptr) : ojson(mm * 1e3);
}

// The axis parameters as (name in the file, value, belongs to VDI 3441), for writing and reading.
template <class R>
auto parameter_fields(R& r) {
  auto& p = r.iso;
  auto& v = r.vdi;
  using D = decltype(&p.A);
  struct Field {
    const char* name;
    D value;
    bool vdi;
  };
  return std::array<Field, 18>{{{"A", &p.A, false},
                                {"A_up", &p.A_up, false},
                                {"A_down", &p.A_down, false},
                                {"E", &p.E, false},
                                {"E_up", &p.E_up, false},
                                {"E_down", &p.E_down, false},
                                {"M", &p.M, false},
                                {"R", &p.R, false},
                                {"R_up", &p.R_up, false},
                                {"R_down", &p.R_down, false},
                                {"B", &p.B, false},
                                {"B_mean", &p.B_mean, false},
                                {"P", &v.P, true},
                                {"Pa", &v.Pa, true},
                                {"Ps", &v.Ps, true},
                                {"Ps_mean", &v.Ps_mean, true},
                                {"U", &v.U, true},
                                {"U_mean", &v.U_mean, true}}};
}

ojson range(double lo, double hi) {
  return std::isnan(lo) ? ojson(nullptr) : ojson::array({lo, hi});
}

}  // namespace

void write_positioning_result(const std::string& path, const positioning::Result& r,
                              positioning::Standard standard,
                              const std::vector<positioning::Verdict>& verdicts) {
  const bool vdi = standard == positioning::Standard::Vdi3441;
  ojson j;
  j["kind"] = "positioning";
  j["standard"] = vdi ? "VDI/DGQ 3441" : "ISO 230-2:2014";
  j["units"] = "um";
  for (const auto& [name, value, of_vdi] : parameter_fields(r))
    if (of_vdi == vdi) j[name] = um(*value);
  j["cycles"] = r.cycles;
  ojson dirs = ojson::array();
  if (r.has_up) dirs.push_back("+");
  if (r.has_down) dirs.push_back("-");
  j["directions"] = dirs;
  ojson targets = ojson::array();
  for (const auto& t : r.targets) {
    ojson o;
    o["position"] = t.position;
    o["n_up"] = t.n_up;
    o["n_down"] = t.n_down;
    o["mean_up"] = um(t.mean_up);
    o["mean_down"] = um(t.mean_down);
    o["s_up"] = um(t.s_up);
    o["s_down"] = um(t.s_down);
    o["mean"] = um(t.mean);
    if (vdi) {
      o["U"] = um(t.U);
      o["Ps"] = um(t.Ps);
    } else {
      o["B"] = um(t.B);
      o["R"] = um(t.R);
      o["R_up"] = um(t.R_up);
      o["R_down"] = um(t.R_down);
    }
    targets.push_back(o);
  }
  j["targets"] = targets;
  ojson temp;
  temp["material"] = range(r.material_min, r.material_max);
  temp["air"] = range(r.air_min, r.air_max);
  temp["corrected"] = r.temperature_corrected;
  if (r.temperature_corrected) {
    temp["reference"] = r.reference_temperature;
    temp["expansion_coefficient"] = r.expansion_coefficient;
    temp["datum_mm"] = r.datum;
    temp["max_correction_um"] = r.max_correction * 1e3;
  }
  j["temperature"] = temp;
  ojson tol = ojson::object();
  bool pass = true;
  for (const auto& v : verdicts) {
    tol[v.name] = {{"limit", v.limit * 1e3}, {"value", um(v.value)}, {"pass", v.pass}};
    if (!v.not_judged.empty()) tol[v.name]["not_judged"] = v.not_judged;
    pass = pass && v.pass;
  }
  j["tolerances"] = tol;
  j["pass"] = verdicts.empty() ? ojson(nullptr) : ojson(pass);
  j["warnings"] = r.warnings;
  ojson tm = ojson::array(), cy = ojson::array(), dv = ojson::array();
  std::string dirs_s;
  for (const auto& x : r.readings) {
    tm.push_back(x.target);
    cy.push_back(x.cycle);
    dirs_s += x.direction == Direction::Up ? '+' : '-';
    dv.push_back(x.deviation * 1e3);
  }
  j["readings"] = {{"target_mm", tm}, {"cycle", cy}, {"direction", dirs_s}, {"deviation_um", dv}};
  write_json(path, j);
}

PositioningFile read_positioning_result(const std::string& path) {
  using ptr = JsonFile::pointer;
  const JsonFile f = JsonFile::read(path);
  PositioningFile out;
  positioning::Result& r = out.result;
  const ptr root;
  if (!f.has(root / "standard")) f.fail(root, "'standard' is missing");
  const std::string standard = f.string(root / "standard");
  if (standard == "VDI/DGQ 3441")
    out.standard = positioning::Standard::Vdi3441;
  else if (standard != "ISO 230-2:2014")
    f.fail(root / "standard", fmt::format("unknown standard '{}'", standard));
  // A parameter in µm or null (NaN).
  auto um_or_nan = [&](const ptr& p) {
    if (!f.has(p) || f.root()[p].is_null()) return positioning::kNaN;
    return f.number(p) * 1e-3;
  };
  // A count: a whole number 0 .. 10^6.
  auto count = [&](const ptr& q) {
    const double x = f.number(q);
    if (!(x >= 0 && x <= 1e6) || x != std::floor(x)) f.fail(q, "expected a whole number 0 .. 1e6");
    return static_cast<int>(x);
  };
  for (const auto& field : parameter_fields(r)) *field.value = um_or_nan(root / field.name);
  if (f.has(root / "cycles")) r.cycles = count(root / "cycles");
  const ptr ts = root / "targets";
  if (!f.has(ts)) f.fail(root, "'targets' is missing");
  const auto& arr = f.array(ts);
  if (arr.empty()) f.fail(ts, "no targets");
  for (std::size_t i = 0; i < arr.size(); ++i) {
    const ptr t = ts / i;
    f.object(t);
    positioning::Target x;
    if (!f.has(t / "position")) f.fail(t, "'position' is missing");
    x.position = f.number(t / "position");
    if (f.has(t / "n_up")) x.n_up = count(t / "n_up");
    if (f.has(t / "n_down")) x.n_down = count(t / "n_down");
    x.mean_up = um_or_nan(t / "mean_up");
    x.mean_down = um_or_nan(t / "mean_down");
    x.s_up = um_or_nan(t / "s_up");
    x.s_down = um_or_nan(t / "s_down");
    x.mean = um_or_nan(t / "mean");
    x.B = um_or_nan(t / "B");
    x.R = um_or_nan(t / "R");
    x.R_up = um_or_nan(t / "R_up");
    x.R_down = um_or_nan(t / "R_down");
    x.U = um_or_nan(t / "U");
    x.Ps = um_or_nan(t / "Ps");
    if (i > 0 && !(x.position > r.targets.back().position))
      f.fail(t / "position", "target positions must increase");
    r.has_up = r.has_up || x.n_up > 0;
    r.has_down = r.has_down || x.n_down > 0;
    r.targets.push_back(x);
  }
  if (f.has(root / "warnings")) {
    const auto& w = f.array(root / "warnings");
    for (std::size_t i = 0; i < w.size(); ++i)
      r.warnings.push_back(f.string(root / "warnings" / i));
  }
  const ptr tp = root / "temperature";
  if (f.has(tp)) {
    f.object(tp);
    for (const char* which : {"material", "air"}) {
      const ptr q = tp / which;
      if (!f.has(q) || f.root()[q].is_null()) continue;
      const Eigen::VectorXd mm = f.numbers(q);
      if (mm.size() != 2) f.fail(q, "expected [min, max]");
      (which[0] == 'm' ? r.material_min : r.air_min) = mm[0];
      (which[0] == 'm' ? r.material_max : r.air_max) = mm[1];
    }
    if (f.has(tp / "corrected") && f.root()[tp / "corrected"].is_boolean())
      r.temperature_corrected = f.root()[tp / "corrected"].get<bool>();
    if (r.temperature_corrected) {
      r.reference_temperature = f.has(tp / "reference") ? f.number(tp / "reference") : 20.0;
      if (f.has(tp / "expansion_coefficient"))
        r.expansion_coefficient = f.number(tp / "expansion_coefficient");
      if (f.has(tp / "datum_mm")) r.datum = f.number(tp / "datum_mm");
      if (f.has(tp / "max_correction_um"))
        r.max_correction = f.number(tp / "max_correction_um") * 1e-3;
    }
  }
  const ptr tol = root / "tolerances";
  if (f.has(tol)) {
    for (const auto& [name, value] : f.object(tol).items()) {
      positioning::Verdict vd;
      vd.name = name;
      vd.limit = f.number(tol / name / "limit") * 1e-3;
      vd.value = um_or_nan(tol / name / "value");
      const ptr ps = tol / name / "pass";
      if (!f.has(ps) || !f.root()[ps].is_boolean())
        f.fail(tol / name, "'pass' must be true or false");
      vd.pass = f.root()[ps].get<bool>();
      out.verdicts.push_back(vd);
    }
  }
  const ptr rd = root / "readings";
  if (f.has(rd)) {
    const Eigen::VectorXd t = f.numbers(rd / "target_mm"), c = f.numbers(rd / "cycle"),
                          d = f.numbers(rd / "deviation_um", 1e-3);
    const std::string dirs = f.string(rd / "direction");
    const auto n = static_cast<std::size_t>(t.size());
    if (static_cast<std::size_t>(c.size()) != n || static_cast<std::size_t>(d.size()) != n ||
        dirs.size() != n)
      f.fail(rd, "target_mm, cycle, direction and deviation_um need one entry per reading");
    for (std::size_t k = 0; k < n; ++k) {
      const auto i = static_cast<Eigen::Index>(k);
      if (dirs[k] != '+' && dirs[k] != '-') f.fail(rd / "direction", "directions are '+' or '-'");
      if (!(c[i] >= 1 && c[i] <= 1e6) || c[i] != std::floor(c[i]))
        f.fail(rd / "cycle" / k, "cycles are whole numbers from 1");
      positioning::Reading x;
      x.target = t[i];
      x.cycle = static_cast<int>(c[i]);
      x.direction = dirs[k] == '+' ? Direction::Up : Direction::Down;
      x.deviation = d[i];
      r.readings.push_back(x);
    }
  }
  return out;
}

}  // namespace trueaxis::io
