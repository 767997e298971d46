// Backlash parameters and a cross-axis table in four controllers' forms; the formats and their
// sources are stated in the header.
#include "trueaxis/io/compensation/parameters.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>

#include "../fast_text.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::io {
namespace {

constexpr const char* kAxes = "XYZ";

void write_text(const std::string& path, const std::string& text) {
  detail::OutFile out(path);
  out.write(text);
  out.close();
}

bool any(const AxisValues& v) {
  for (const auto& x : v)
    if (x) return true;
  return false;
}

void check_range(const AxisValues& v, double lo, double hi, const char* what) {
  if (!any(v)) throw Error(fmt::format("{}: no axis has a value to write", what));
  for (int k = 0; k < 3; ++k)
    if (v[static_cast<std::size_t>(k)] &&
        !(*v[static_cast<std::size_t>(k)] >= lo && *v[static_cast<std::size_t>(k)] <= hi))
      throw Error(fmt::format("{}: {}'s value {:g} mm is outside {:g} … {:g} mm", what, kAxes[k],
                              *v[static_cast<std::size_t>(k)], lo, hi));
}

// A number filling all of `s` (a leading '+' allowed), or fail at `col0`.
template <class Fail>
double number(std::string_view s, std::size_t col0, Fail&& fail) {
  const char* b = s.data();
  const char* e = b + s.size();
  if (b != e && *b == '+') ++b;
  double v = 0;
  const auto r = std::from_chars(b, e, v);
  if (b == e || r.ec != std::errc() || r.ptr != e || !std::isfinite(v) || std::abs(v) > 1e7)
    fail(col0, fmt::format("'{}' is not a number", detail::quote_cut(s)));
  return v;
}

template <class Fail>
long integer(std::string_view s, std::size_t col0, Fail&& fail) {
  const char* b = s.data();
  const char* e = b + s.size();
  long v = 0;
  const auto r = std::from_chars(b, e, v);
  if (b == e || r.ec != std::errc() || r.ptr != e)
    fail(col0, fmt::format("'{}' is not a whole number", detail::quote_cut(s)));
  return v;
}

// Calls fn(line, offset of the text, text) for each line with what is left after the comment
// (from `comment` on) and the surrounding blanks are removed; empty lines are skipped.
template <class Fn>
void content_lines(const std::string& text, char comment, Fn&& fn) {
  detail::for_each_line(text, [&](std::size_t line, std::string_view l) {
    if (const auto c = l.find(comment); c != std::string_view::npos) l = l.substr(0, c);
    const std::size_t b = l.find_first_not_of(" \t");
    if (b == std::string_view::npos) return;
    const std::size_t e = l.find_last_not_of(" \t") + 1;
    fn(line, b, l.substr(b, e - b));
  });
}

void set_once(AxisValues& v, int axis, double value, const std::string& path, std::size_t line,
              std::size_t col0) {
  if (axis < 0 || axis > 2)
    detail::fail_at(path, line, col0,
                    fmt::format("axis {} is not X, Y or Z (the first three axes)", axis));
  if (v[static_cast<std::size_t>(axis)])
    detail::fail_at(path, line, col0, fmt::format("a second value for {}", kAxes[axis]));
  v[static_cast<std::size_t>(axis)] = value;
}

AxisValues nonempty(AxisValues v, const std::string& path, const char* what) {
  if (!any(v)) throw Error(fmt::format("{}: no {} in the file", path, what));
  return v;
}

std::string comments(const std::vector<std::string>& lines, const char* open,
                     const char* close = "") {
  std::string s;
  for (const auto& l : lines) s += fmt::format("{} {}{}\n", open, l, close);
  return s;
}

}  // namespace

// LinuxCNC -------------------------------------------------------------------------------------

void write_linuxcnc_backlash(const std::string& path, const AxisValues& v,
                             const std::vector<std::string>& comment) {
  check_range(v, 0, 1e3, "LinuxCNC BACKLASH (not negative)");
  std::string text = comments(comment, "#");
  for (int k = 0; k < 3; ++k)
    if (v[static_cast<std::size_t>(k)])
      text += fmt::format("[JOINT_{}]\n# axis {}\nBACKLASH = {:.6f}\n", k, kAxes[k],
                          *v[static_cast<std::size_t>(k)]);
  write_text(path, text);
}

AxisValues parse_linuxcnc_backlash(std::string text, const std::string& path) {
  detail::normalize_text(text);
  AxisValues v;
  int joint = -1;
  content_lines(text, '#', [&](std::size_t line, std::size_t b, std::string_view s) {
    auto fail = [&](std::size_t c, const std::string& w) { detail::fail_at(path, line, c, w); };
    if (s.front() == ';') return;  // LinuxCNC takes ';' comments too
    if (s.front() == '[') {
      if (s.back() != ']') fail(b, "a section name ends with ']'");
      const std::string_view name = s.substr(1, s.size() - 2);
      joint = -1;
      if (name.substr(0, 6) == "JOINT_")
        joint = static_cast<int>(std::clamp(integer(name.substr(6), b + 7, fail), -1L, 1000L));
      return;
    }
    const std::size_t eq = s.find('=');
    if (eq == std::string_view::npos) fail(b, "expected NAME = value");
    if (detail::trim(s.substr(0, eq)) != "BACKLASH") return;  // other keys are the INI's own
    if (joint < 0) fail(b, "BACKLASH outside a [JOINT_n] section");
    const std::string_view value = detail::trim(s.substr(eq + 1));
    const std::size_t col = b + static_cast<std::size_t>(value.data() - s.data());
    const double x = number(value, col, fail);
    if (x < 0) fail(col, "a LinuxCNC BACKLASH is not negative");
    set_once(v, joint, x, path, line, b);
  });
  return nonempty(v, path, "[JOINT_n] BACKLASH");
}

// HEIDENHAIN -----------------------------------------------------------------------------------

void write_heidenhain_backlash(const std::string& path, const AxisValues& v,
                               const std::vector<std::string>& comment) {
  check_range(v, -1, 1, "HEIDENHAIN MP710 (backlash)");
  std::string text = comments(comment, ";");
  text +=
      "; iTNC 530: MP710.x, backlash compensation (mm), x = the axis index; TNC 640/620: "
      "CfgAxisComp backLash of the axis\n";
  for (int k = 0; k < 3; ++k)
    if (v[static_cast<std::size_t>(k)])
      text += fmt::format("MP710.{}: {:+.4f} ; {}\n", k, *v[static_cast<std::size_t>(k)], kAxes[k]);
  write_text(path, text);
}

AxisValues parse_heidenhain_backlash(std::string text, const std::string& path) {
  detail::normalize_text(text);
  AxisValues v;
  content_lines(text, ';', [&](std::size_t line, std::size_t b, std::string_view s) {
    auto fail = [&](std::size_t c, const std::string& w) { detail::fail_at(path, line, c, w); };
    const std::size_t colon = s.find(':');
    if (s.substr(0, 2) != "MP" || colon == std::string_view::npos)
      fail(b, fmt::format("'{}': expected MPnnn.x: value", detail::quote_cut(s)));
    const std::string_view name = s.substr(2, colon - 2);
    const std::size_t dot = name.find('.');
    if (dot == std::string_view::npos || name.substr(0, dot) != "710")
      fail(b, fmt::format("MP{}: only MP710.x (backlash) is read here", name));
    const long axis = integer(name.substr(dot + 1), b + 3 + dot, fail);
    const std::string_view value = detail::trim(s.substr(colon + 1));
    const std::size_t col = b + static_cast<std::size_t>(value.data() - s.data());
    const double x = number(value, col, fail);
    if (std::abs(x) > 1) fail(col, "MP710 takes −1 … +1 mm");
    set_once(v, static_cast<int>(std::clamp(axis, -1L, 3L)), x, path, line, b);
  });
  return nonempty(v, path, "MP710.x");
}

// FANUC ----------------------------------------------------------------------------------------

AxisValues write_fanuc_backlash(const std::string& path, const AxisValues& v, double unit,
                                const std::vector<std::string>& comment) {
  if (!(unit > 0) || !std::isfinite(unit)) throw Error("FANUC: the detection unit must be > 0 mm");
  check_range(v, -9999 * unit, 9999 * unit, "FANUC No. 1851 (backlash)");
  std::vector<std::string> upper;
  for (const auto& c : comment) {  // a tape comment cannot hold parentheses
    std::string u = detail::upper(c);
    for (char& ch : u)
      if (ch == '(' || ch == ')') ch = ch == '(' ? '[' : ']';
    upper.push_back(std::move(u));
  }
  std::string text = "%\n" + comments(upper, "(", ")");
  text += fmt::format("(NO. 1851 BACKLASH COMPENSATION, DETECTION UNIT {:g} MM)\n", unit);
  AxisValues written;
  for (int k = 0; k < 3; ++k)
    if (const auto& x = v[static_cast<std::size_t>(k)]) {
      const long units = std::lround(*x / unit);
      written[static_cast<std::size_t>(k)] = static_cast<double>(units) * unit;
      text += fmt::format("N1851A{}P{}\n", k + 1, units);
    }
  text += "%\n";
  write_text(path, text);
  return written;
}

AxisValues parse_fanuc_backlash(std::string text, const std::string& path, double unit) {
  if (!(unit > 0) || !std::isfinite(unit)) throw Error("FANUC: the detection unit must be > 0 mm");
  detail::normalize_text(text);
  AxisValues v;
  int percents = 0;
  detail::for_each_line(text, [&](std::size_t line, std::string_view l) {
    auto fail = [&](std::size_t c, const std::string& w) { detail::fail_at(path, line, c, w); };
    // Comments in parentheses, anywhere on the line.
    std::string s(l);
    for (std::size_t open; (open = s.find('(')) != std::string::npos;) {
      const std::size_t close = s.find(')', open);
      if (close == std::string::npos) fail(open, "a comment '(' not closed on its line");
      s.replace(open, close - open + 1, close - open + 1, ' ');
    }
    const std::string_view t = detail::trim(s);
    if (t.empty()) return;
    const std::size_t b = s.find_first_not_of(" \t");
    if (t == "%") {
      ++percents;
      return;
    }
    if (percents != 1) fail(b, "data outside the '%' lines of the tape");
    const std::size_t a = t.find('A'), p = t.find('P');
    if (t.front() != 'N' || a == std::string_view::npos || p == std::string_view::npos || p < a)
      fail(b, fmt::format("'{}': expected N<parameter>A<axis>P<value>", detail::quote_cut(t)));
    const long param = integer(t.substr(1, a - 1), b + 1, fail);
    if (param != 1851) fail(b + 1, fmt::format("parameter {}: only No. 1851 is read here", param));
    const long axis = integer(t.substr(a + 1, p - a - 1), b + a + 1, fail);
    const long value = integer(t.substr(p + 1), b + p + 1, fail);
    if (value < -9999 || value > 9999) fail(b + p + 1, "No. 1851 takes −9999 … 9999");
    set_once(v, static_cast<int>(std::clamp(axis, 0L, 4L)) - 1, static_cast<double>(value) * unit,
             path, line, b);
  });
  if (percents != 2)
    throw Error(fmt::format("{}: a FANUC tape starts and ends with a '%' line", path));
  return nonempty(v, path, "No. 1851 value");
}

// Siemens --------------------------------------------------------------------------------------

namespace {

// NAME[i,j]=value or NAME[i]=value or NAME[i]=(AXn): the name, the indices, the value text.
struct Assignment {
  std::string_view name, value;
  std::vector<std::string_view> index;
  std::size_t value_col = 0;
};

template <class Fail>
Assignment assignment(std::string_view s, std::size_t b, Fail&& fail) {
  const std::size_t open = s.find('['), close = s.find(']'), eq = s.find('=');
  if (open == std::string_view::npos || close == std::string_view::npos || close < open ||
      eq == std::string_view::npos || eq < close)
    fail(b, fmt::format("'{}': expected NAME[index]=value", detail::quote_cut(s)));
  Assignment a;
  a.name = s.substr(0, open);
  for (std::size_t q = open + 1;;) {
    const std::size_t c = s.find(',', q);
    if (c == std::string_view::npos || c > close) {
      a.index.push_back(detail::trim(s.substr(q, close - q)));
      break;
    }
    a.index.push_back(detail::trim(s.substr(q, c - q)));
    q = c + 1;
  }
  if (detail::trim(s.substr(close + 1, eq - close - 1)).size())
    fail(b + close + 1, "expected '=' after ']'");
  a.value = detail::trim(s.substr(eq + 1));
  a.value_col = b + static_cast<std::size_t>(a.value.data() - s.data());
  return a;
}

// "AX1" or "(AX1)" → machine axis 0.
template <class Fail>
int machine_axis(std::string_view s, std::size_t col0, Fail&& fail) {
  if (s.size() > 2 && s.front() == '(' && s.back() == ')') s = s.substr(1, s.size() - 2);
  if (s.substr(0, 2) != "AX")
    fail(col0, fmt::format("'{}': expected a machine axis AX1, AX2 or AX3", detail::quote_cut(s)));
  const long n = integer(s.substr(2), col0 + 2, fail);
  if (n < 1 || n > 3) fail(col0, fmt::format("AX{}: only AX1 … AX3 (X, Y, Z) are read here", n));
  return static_cast<int>(n) - 1;
}

}  // namespace

void write_sinumerik_backlash(const std::string& path, const AxisValues& v,
                              const std::vector<std::string>& comment) {
  check_range(v, -1e3, 1e3, "Siemens MD32450 (backlash)");
  std::string text = "%_N_BACKLASH_INI\n" + comments(comment, ";");
  text += "; MD32450 $MA_BACKLASH[0,AXn]: backlash of machine axis n, first measuring system, mm\n";
  for (int k = 0; k < 3; ++k)
    if (v[static_cast<std::size_t>(k)])
      text += fmt::format("$MA_BACKLASH[0,AX{}]={:.6f} ; {}\n", k + 1,
                          *v[static_cast<std::size_t>(k)], kAxes[k]);
  text += "M17\n";
  write_text(path, text);
}

AxisValues parse_sinumerik_backlash(std::string text, const std::string& path) {
  detail::normalize_text(text);
  AxisValues v;
  bool ended = false;
  content_lines(text, ';', [&](std::size_t line, std::size_t b, std::string_view s) {
    auto fail = [&](std::size_t c, const std::string& w) { detail::fail_at(path, line, c, w); };
    if (ended) fail(b, "text after M17 (the end of the program)");
    if (s.substr(0, 3) == "%_N") return;
    if (s == "M17" || s == "M30") {
      ended = true;
      return;
    }
    const Assignment a = assignment(s, b, fail);
    if (a.name != "$MA_BACKLASH")
      fail(b, fmt::format("{}: only $MA_BACKLASH is read here", a.name));
    if (a.index.size() != 2 || a.index[0] != "0")
      fail(b, "expected $MA_BACKLASH[0,AXn] (the first measuring system)");
    const int axis = machine_axis(a.index[1], b, fail);
    set_once(v, axis, number(a.value, a.value_col, fail), path, line, b);
  });
  if (!ended) throw Error(fmt::format("{}: the program does not end with M17", path));
  return nonempty(v, path, "$MA_BACKLASH value");
}

double CrossTable::at(double x) const {
  const auto n = static_cast<double>(values.size());
  const double u = std::clamp((x - min) / step, 0.0, n - 1);
  const auto i = std::min(static_cast<std::size_t>(u), values.size() - 2);
  const double f = u - static_cast<double>(i);
  return (1 - f) * values[i] + f * values[i + 1];
}

void write_sinumerik_cec(const std::string& path, const CrossTable& t,
                         const std::vector<std::string>& comment) {
  if (t.table < 0) throw Error("Siemens CEC: the table number must be >= 0");
  if (t.input < 0 || t.input > 2 || t.output < 0 || t.output > 2)
    throw Error("Siemens CEC: input and output are machine axes 0..2 (X, Y, Z)");
  if (!(t.step > 0) || !std::isfinite(t.step) || !std::isfinite(t.min))
    throw Error("Siemens CEC: the step must be > 0 mm and the start finite");
  if (t.values.size() < 2) throw Error("Siemens CEC: a table needs at least two points");
  for (double x : t.values)
    if (!std::isfinite(x)) throw Error("Siemens CEC: the values must be finite");
  const int n = static_cast<int>(t.values.size());
  std::string text = "%_N_NC_CEC_INI\n" + comments(comment, ";");
  text += fmt::format(
      "; sag and angularity compensation: the correction added to AX{} (mm) over AX{}'s position; "
      "needs MD18342 $MN_MM_CEC_MAX_POINTS[{}] >= {}\nCHANDATA(1)\n",
      t.output + 1, t.input + 1, t.table, n);
  for (int k = 0; k < n; ++k)
    text +=
        fmt::format("$AN_CEC[{},{}]={:.6f}\n", t.table, k, t.values[static_cast<std::size_t>(k)]);
  text += fmt::format(
      "$AN_CEC_INPUT_AXIS[{0}]=(AX{1})\n$AN_CEC_OUTPUT_AXIS[{0}]=(AX{2})\n"
      "$AN_CEC_STEP[{0}]={3:.6f}\n$AN_CEC_MIN[{0}]={4:.6f}\n$AN_CEC_MAX[{0}]={5:.6f}\n"
      "$AN_CEC_DIRECTION[{0}]=0\n$AN_CEC_MULT_BY_TABLE[{0}]=0\n$AN_CEC_IS_MODULO[{0}]=0\nM17\n",
      t.table, t.input + 1, t.output + 1, t.step, t.min, t.min + (n - 1) * t.step);
  write_text(path, text);
}

CrossTable parse_sinumerik_cec(std::string text, const std::string& path) {
  detail::normalize_text(text);
  CrossTable t;
  t.table = -1;
  std::vector<std::optional<double>> values;
  std::optional<double> step, lo, hi;
  std::optional<int> input, output;
  bool ended = false;
  content_lines(text, ';', [&](std::size_t line, std::size_t b, std::string_view s) {
    auto fail = [&](std::size_t c, const std::string& w) { detail::fail_at(path, line, c, w); };
    if (ended) fail(b, "text after M17 (the end of the program)");
    if (s.substr(0, 3) == "%_N" || s == "CHANDATA(1)") return;
    if (s == "M17" || s == "M30") {
      ended = true;
      return;
    }
    const Assignment a = assignment(s, b, fail);
    const long table = integer(a.index[0], b + a.name.size() + 1, fail);
    if (table < 0 || table > 1000) fail(b, fmt::format("table {}: 0 … 1000", table));
    if (t.table < 0) t.table = static_cast<int>(table);
    if (table != t.table) fail(b, fmt::format("table {}: one table per file is read here", table));
    if (a.name == "$AN_CEC") {
      if (a.index.size() != 2) fail(b, "expected $AN_CEC[t,N]");
      const long k = integer(a.index[1], b, fail);
      if (k < 0 || k > 100000) fail(b, fmt::format("interpolation point {} out of range", k));
      if (static_cast<std::size_t>(k) >= values.size())
        values.resize(static_cast<std::size_t>(k) + 1);
      if (values[static_cast<std::size_t>(k)]) fail(b, fmt::format("point {} given twice", k));
      values[static_cast<std::size_t>(k)] = number(a.value, a.value_col, fail);
      return;
    }
    if (a.index.size() != 1) fail(b, fmt::format("expected {}[t]", a.name));
    if (a.name == "$AN_CEC_INPUT_AXIS") {
      input = machine_axis(a.value, a.value_col, fail);
    } else if (a.name == "$AN_CEC_OUTPUT_AXIS") {
      output = machine_axis(a.value, a.value_col, fail);
    } else if (a.name == "$AN_CEC_STEP") {
      step = number(a.value, a.value_col, fail);
    } else if (a.name == "$AN_CEC_MIN") {
      lo = number(a.value, a.value_col, fail);
    } else if (a.name == "$AN_CEC_MAX") {
      hi = number(a.value, a.value_col, fail);
    } else if (a.name == "$AN_CEC_DIRECTION" || a.name == "$AN_CEC_MULT_BY_TABLE" ||
               a.name == "$AN_CEC_IS_MODULO") {
      if (a.value != "0")
        fail(a.value_col, fmt::format("{} = {}: only 0 is read here (a plain table for both "
                                      "directions)",
                                      a.name, a.value));
    } else {
      fail(b, fmt::format("{}: not a sag and angularity compensation variable", a.name));
    }
  });
  if (!ended) throw Error(fmt::format("{}: the program does not end with M17", path));
  if (!input || !output || !step || !lo || !hi)
    throw Error(
        fmt::format("{}: the table needs $AN_CEC_INPUT_AXIS, _OUTPUT_AXIS, _STEP, _MIN "
                    "and _MAX",
                    path));
  if (values.size() < 2) throw Error(fmt::format("{}: a table needs at least two points", path));
  for (std::size_t k = 0; k < values.size(); ++k)
    if (!values[k]) throw Error(fmt::format("{}: interpolation point {} is missing", path, k));
  if (!(*step > 0)) throw Error(fmt::format("{}: $AN_CEC_STEP must be > 0", path));
  const double expect = *lo + static_cast<double>(values.size() - 1) * *step;
  if (std::abs(*hi - expect) > 1e-6 * std::max(1.0, std::abs(expect)))
    throw Error(fmt::format("{}: $AN_CEC_MAX {:g} is not MIN + (points − 1)·STEP = {:g}", path, *hi,
                            expect));
  t.input = *input;
  t.output = *output;
  t.min = *lo;
  t.step = *step;
  for (const auto& x : values) t.values.push_back(*x);
  return t;
}

AxisValues read_linuxcnc_backlash(const std::string& path) {
  return parse_linuxcnc_backlash(detail::read_text(path), path);
}
AxisValues read_heidenhain_backlash(const std::string& path) {
  return parse_heidenhain_backlash(detail::read_text(path), path);
}
AxisValues read_fanuc_backlash(const std::string& path, double detection_unit) {
  return parse_fanuc_backlash(detail::read_text(path), path, detection_unit);
}
AxisValues read_sinumerik_backlash(const std::string& path) {
  return parse_sinumerik_backlash(detail::read_text(path), path);
}
CrossTable read_sinumerik_cec(const std::string& path) {
  return parse_sinumerik_cec(detail::read_text(path), path);
}

}  // namespace trueaxis::io
