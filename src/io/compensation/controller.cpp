#include "trueaxis/io/compensation/controller.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <map>

#include "../fast_text.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::io {

int write_linuxcnc(const std::string& path, const compensation::AxisTable& t, int type) {
  if (type != 0 && type != 1) throw Error("the LinuxCNC compensation type must be 0 or 1");
  t.validate();
  const std::size_t n = t.position.size();
  if (n > kLinuxCncMaxPoints)
    throw Error(
        fmt::format("LinuxCNC accepts at most {} compensation points per joint; the table "
                    "has {}",
                    kLinuxCncMaxPoints, n));
  std::string text;
  for (std::size_t i = 0; i < n; ++i) {
    const double p = t.position[i];
    // Type 0: actual = nominal − trim; type 1: the trims themselves.
    const double f = type == 0 ? p - t.forward[i] : t.forward[i];
    const double r = type == 0 ? p - t.reverse[i] : t.reverse[i];
    text += fmt::format("{:.6f} {:.6f} {:.6f}\n", p, f, r);
  }
  detail::OutFile out(path);
  out.write(text);
  out.close();
  return static_cast<int>(n);
}

compensation::AxisTable parse_linuxcnc(std::string text, const std::string& path, int type) {
  if (type != 0 && type != 1) throw Error("the LinuxCNC compensation type must be 0 or 1");
  detail::normalize_text(text);
  compensation::AxisTable t;
  std::size_t pos = 0, line = 0;
  while (pos < text.size()) {
    const std::size_t nl = text.find('\n', pos);
    const std::size_t end = nl == std::string::npos ? text.size() : nl;
    const std::string_view l(text.data() + pos, end - pos);
    pos = end + 1;
    ++line;
    auto fail = [&](std::size_t col0, const std::string& what) {
      throw Error(fmt::format("{}:{}:{}: {}", path, line, col0 + 1, what));
    };
    if (l.find_first_not_of(" \t") == std::string_view::npos) {
      // LinuxCNC stops at a blank line: harmless at the end, silently truncating before more.
      const std::size_t more = text.find_first_not_of(" \t\n", std::min(pos, text.size()));
      if (more == std::string::npos) break;
      fail(0, "blank line: LinuxCNC stops reading here and would ignore the lines after it");
    }
    std::size_t c = 0;
    double v[3];
    for (int k = 0; k < 3; ++k) {
      while (c < l.size() && (l[c] == ' ' || l[c] == '\t')) ++c;
      std::size_t e = c;
      while (e < l.size() && l[e] != ' ' && l[e] != '\t') ++e;
      if (c == e)
        fail(c, fmt::format("expected three numbers 'nominal forward reverse' (LinuxCNC stops "
                            "reading at such a line), found {}",
                            k));
      const auto r = std::from_chars(l.data() + c, l.data() + e, v[k]);
      if (r.ec != std::errc() || r.ptr != l.data() + e || !std::isfinite(v[k]) ||
          std::abs(v[k]) > 1e7)
        fail(c, fmt::format("'{}' is not a number", detail::quote_cut(l.substr(c, e - c))));
      c = e;
    }
    while (c < l.size() && (l[c] == ' ' || l[c] == '\t')) ++c;
    if (c < l.size()) fail(c, "more than three numbers on a line");
    if (!t.position.empty() && !(v[0] > t.position.back()))
      fail(0,
           fmt::format("nominal {:g} does not increase (LinuxCNC needs ascending nominals)", v[0]));
    if (t.position.size() == kLinuxCncMaxPoints)
      fail(0, fmt::format("more than {} lines: LinuxCNC takes at most {} per joint",
                          kLinuxCncMaxPoints, kLinuxCncMaxPoints));
    t.position.push_back(v[0]);
    t.forward.push_back(type == 0 ? v[0] - v[1] : v[1]);
    t.reverse.push_back(type == 0 ? v[0] - v[2] : v[2]);
  }
  if (t.position.size() < 2)
    throw Error(fmt::format("{}: a compensation table needs at least two lines", path));
  return t;
}

compensation::AxisTable read_linuxcnc(const std::string& path, int type) {
  return parse_linuxcnc(detail::read_text(path), path, type);
}

}  // namespace trueaxis::io

namespace trueaxis::io {

int write_sinumerik(const std::string& path, const compensation::AxisTable& t,
                    const SinumerikOptions& o) {
  t.validate();
  if (t.bidirectional())
    throw Error(
        "a Sinumerik LEC table is one curve for both directions: make a unidirectional table "
        "(the reversal belongs in MD32450 BACKLASH)");
  if (o.encoder != 0 && o.encoder != 1) throw Error("the measuring system must be 0 or 1");
  if (o.axis.empty() ||
      o.axis.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_") !=
          std::string::npos)
    throw Error(fmt::format("'{}' is not a Sinumerik axis name (letters, digits, '_')", o.axis));
  const double lo = t.position.front(), hi = t.position.back();
  const std::size_t n = t.position.size();
  const double step = std::isnan(o.step) ? (hi - lo) / static_cast<double>(n - 1) : o.step;
  if (!(step > 0) || !std::isfinite(step))
    throw Error(fmt::format("the distance between points must be positive (got {:g} mm)", step));
  const double k = std::floor((hi - lo) / step + 1e-9);
  if (k + 1 > o.max_points)
    throw Error(
        fmt::format("{:g} points of {:g} mm exceed MD38000 $MA_MM_ENC_COMP_MAX_POINTS = "
                    "{} (raise it on the machine, or give a larger step)",
                    k + 1, step, o.max_points));
  if (k < 1) throw Error("the table needs at least two points: the step exceeds the range");
  const int points = static_cast<int>(k) + 1;
  const std::string ax = fmt::format("{},{}", o.encoder, o.axis);
  std::string text = "%_N_AX_EEC_INI\nCHANDATA(1)\n";
  for (int i = 0; i < points; ++i) {
    const double p = lo + i * step;
    // The error (actual − nominal): a positive value moves the axis in the negative direction.
    const double value = -t.correction(p, positioning::Direction::Up);
    text += fmt::format("$AA_ENC_COMP[{},{},{}]={:.6f}\n", o.encoder, i, o.axis, value);
  }
  text += fmt::format("$AA_ENC_COMP_STEP[{}]={:.6f}\n", ax, step);
  text += fmt::format("$AA_ENC_COMP_MIN[{}]={:.6f}\n", ax, lo);
  text += fmt::format("$AA_ENC_COMP_MAX[{}]={:.6f}\n", ax, lo + (points - 1) * step);
  text += fmt::format("$AA_ENC_COMP_IS_MODULO[{}]=0\nM17\n", ax);
  detail::OutFile out(path);
  out.write(text);
  out.close();
  return points;
}

compensation::AxisTable parse_sinumerik(std::string text, const std::string& path,
                                        std::string* axis_out) {
  detail::normalize_text(text);
  std::vector<double> values;
  std::vector<bool> have;
  double step = NAN, lo = NAN, hi = NAN;
  std::string axis;
  int encoder = -1;
  bool ended = false, modulo_seen = false;
  detail::for_each_line(text, [&](std::size_t line, std::string_view l) {
    auto fail = [&](std::size_t col0, const std::string& what) {
      detail::fail_at(path, line, col0, what);
    };
    if (const auto sc = l.find(';'); sc != std::string_view::npos) l = l.substr(0, sc);
    std::size_t b = l.find_first_not_of(" \t");
    if (b == std::string_view::npos) return;
    const std::size_t e = l.find_last_not_of(" \t") + 1;
    const std::string_view s = l.substr(b, e - b);
    if (ended) fail(b, "text after M17 (the end of the program)");
    if (s.substr(0, 3) == "%_N" || s == "CHANDATA(1)") return;
    if (s == "M17" || s == "M30") {
      ended = true;
      return;
    }
    const std::string_view prefix = "$AA_ENC_COMP";
    if (s.substr(0, prefix.size()) != prefix)
      fail(b, fmt::format("'{}': expected $AA_ENC_COMP... = value", detail::quote_cut(s)));
    const std::size_t open = s.find('['), close = s.find(']'), eq = s.find('=');
    if (open == std::string_view::npos || close == std::string_view::npos || eq != close + 1)
      fail(b, "expected NAME[index,...]=value");
    const std::string_view name = s.substr(0, open);
    // Indices: e,N,AX for the values; e,AX for the parameters.
    std::vector<std::string_view> idx;
    for (std::size_t q = open + 1;;) {
      const std::size_t c = s.find(',', q);
      if (c == std::string_view::npos || c > close) {
        idx.push_back(s.substr(q, close - q));
        break;
      }
      idx.push_back(s.substr(q, c - q));
      q = c + 1;
    }
    auto integer = [&](std::string_view v, std::size_t col0) {
      long x = 0;
      const auto r = std::from_chars(v.data(), v.data() + v.size(), x);
      if (v.empty() || r.ec != std::errc() || r.ptr != v.data() + v.size() || x < 0)
        fail(col0, fmt::format("'{}' is not an index", detail::quote_cut(v)));
      return x;
    };
    const std::string_view value_text = s.substr(eq + 1);
    double value = 0;
    {
      const char* vb = value_text.data();
      const char* ve = vb + value_text.size();
      if (vb != ve && *vb == '+') ++vb;
      const auto r = std::from_chars(vb, ve, value);
      if (vb == ve || r.ec != std::errc() || r.ptr != ve || !std::isfinite(value) ||
          std::abs(value) > 1e7)
        fail(b + eq + 1, fmt::format("'{}' is not a number", detail::quote_cut(value_text)));
    }
    const std::size_t nidx = name == "$AA_ENC_COMP" ? 3 : 2;
    if (idx.size() != nidx) fail(b + open, fmt::format("{} takes {} indices", name, nidx));
    const long enc = integer(idx[0], b + open + 1);
    if (enc > 1) fail(b + open + 1, "the measuring system index must be 0 or 1");
    const std::string_view ax = idx.back();
    if (encoder < 0) {
      encoder = static_cast<int>(enc);
      axis = std::string(ax);
    }
    if (enc != encoder || ax != axis)
      fail(b + open + 1,
           fmt::format("this file is for measuring system {} of axis {}", encoder, axis));
    if (name == "$AA_ENC_COMP") {
      const long n = integer(idx[1], b + open + 1 + idx[0].size() + 1);
      if (n >= 1000000) fail(b + open, "interpolation point beyond 999999");
      const auto un = static_cast<std::size_t>(n);
      if (un >= values.size()) {
        values.resize(un + 1, 0.0);
        have.resize(un + 1, false);
      }
      if (have[un]) fail(b, fmt::format("interpolation point {} is given twice", n));
      values[un] = value;
      have[un] = true;
    } else if (name == "$AA_ENC_COMP_STEP") {
      step = value;
    } else if (name == "$AA_ENC_COMP_MIN") {
      lo = value;
    } else if (name == "$AA_ENC_COMP_MAX") {
      hi = value;
    } else if (name == "$AA_ENC_COMP_IS_MODULO") {
      if (value != 0) fail(b + eq + 1, "modulo tables (rotary axes) are not read");
      modulo_seen = true;
    } else {
      fail(b, fmt::format("unknown variable '{}'", detail::quote_cut(name)));
    }
  });
  (void)modulo_seen;
  if (values.size() < 2)
    throw Error(fmt::format("{}: a compensation table needs at least two points", path));
  for (std::size_t n = 0; n < values.size(); ++n)
    if (!have[n]) throw Error(fmt::format("{}: interpolation point {} is missing", path, n));
  if (std::isnan(step) || std::isnan(lo) || std::isnan(hi))
    throw Error(fmt::format("{}: $AA_ENC_COMP_STEP, _MIN and _MAX are all needed", path));
  if (!(step > 0)) throw Error(fmt::format("{}: $AA_ENC_COMP_STEP must be positive", path));
  const double span = static_cast<double>(values.size() - 1) * step;
  if (std::abs(lo + span - hi) > 1e-6 * std::max(1.0, std::abs(hi)))
    throw Error(
        fmt::format("{}: {} points of {:g} mm from {:g} mm end at {:g} mm, not at "
                    "$AA_ENC_COMP_MAX = {:g} mm",
                    path, values.size(), step, lo, lo + span, hi));
  compensation::AxisTable t;
  for (std::size_t n = 0; n < values.size(); ++n) {
    t.position.push_back(lo + static_cast<double>(n) * step);
    t.forward.push_back(-values[n]);
    t.reverse.push_back(-values[n]);
  }
  if (axis_out) *axis_out = axis;
  return t;
}

compensation::AxisTable read_sinumerik(const std::string& path, std::string* axis) {
  return parse_sinumerik(detail::read_text(path), path, axis);
}

}  // namespace trueaxis::io

namespace trueaxis::io {
namespace {

using detail::is_blank;
using detail::upper;

// Whitespace-separated fields of a line with their offsets.
std::vector<std::pair<std::string_view, std::size_t>> fields_of(std::string_view l) {
  std::vector<std::pair<std::string_view, std::size_t>> f;
  std::size_t c = 0;
  while (true) {
    while (c < l.size() && is_blank(l[c])) ++c;
    if (c >= l.size()) return f;
    std::size_t e = c;
    while (e < l.size() && !is_blank(l[e])) ++e;
    f.emplace_back(l.substr(c, e - c), c);
    c = e;
  }
}

// A number as controllers write it: optional sign (also '+'), digits, optional decimals.
bool to_number(std::string_view v, double& x) {
  const char* b = v.data();
  const char* e = b + v.size();
  if (b != e && *b == '+') ++b;
  const auto r = std::from_chars(b, e, x);
  return b != e && r.ec == std::errc() && r.ptr == e && std::isfinite(x) && std::abs(x) <= 1e7;
}

// "50.0", "33.3333": at least one decimal (a FANUC real parameter without a decimal point is
// read in the least input increment), at most four, no trailing zeros beyond the first.
std::string decimal(double v) {
  std::string s = fmt::format("{:.4f}", v);
  while (s.size() > 2 && s.back() == '0' && s[s.size() - 2] != '.') s.pop_back();
  return s;
}

}  // namespace

int write_heidenhain(const std::string& path, const compensation::AxisTable& t,
                     const HeidenhainOptions& o) {
  t.validate();
  const std::size_t n = t.position.size();
  if (n > kHeidenhainMaxPoints)
    throw Error(fmt::format(
        "a HEIDENHAIN compensation value table takes at most {} points; the table has {}",
        kHeidenhainMaxPoints, n));
  const std::string axis = upper(o.axis);
  if (axis.empty() || axis.size() > 8 ||
      axis.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_") != std::string::npos ||
      !std::isalpha(static_cast<unsigned char>(axis[0])) || axis == "NR" || axis == "AXISPOS" ||
      axis == "BACKLASH")
    throw Error(
        fmt::format("'{}' is not an axis name for a HEIDENHAIN table (e.g. X, Y, Z)", o.axis));
  std::string name = o.name;
  if (name.empty()) {
    const std::size_t slash = path.find_last_of('/');
    name = upper(slash == std::string::npos ? path : path.substr(slash + 1));
    if (name.size() < 4 || name.substr(name.size() - 4) != ".COM") name += ".COM";
  }
  if (name.find_first_of(" \t\n") != std::string::npos)
    throw Error(fmt::format("'{}': a table name has no spaces", name));
  std::string text = fmt::format("BEGIN {} MM\n", name);
  text += fmt::format("{:<6}{:<16}{:<16}{}\n", "NR", "AXISPOS", axis, "BACKLASH");
  for (std::size_t i = 0; i < n; ++i)
    text += fmt::format("{:<6}{:<+16.4f}{:<+16.4f}{:+.4f}\n", i, t.position[i], t.forward[i],
                        t.forward[i] - t.reverse[i]);
  text += "[END]\n";
  detail::OutFile out(path);
  out.write(text);
  out.close();
  return static_cast<int>(n);
}

compensation::AxisTable parse_heidenhain(std::string text, const std::string& path,
                                         std::string* axis_io) {
  detail::normalize_text(text);
  compensation::AxisTable t;
  double unit = 1;
  int stage = 0;  // 0: BEGIN line, 1: column names, 2: points, 3: after [END]
  std::size_t c_nr = 0, c_pos = 0, c_axis = 0, ncols = 0;
  std::size_t c_back = std::string::npos;
  std::string axis = axis_io ? upper(*axis_io) : std::string();
  detail::for_each_line(text, [&](std::size_t line, std::string_view l) {
    auto fail = [&](std::size_t col0, const std::string& what) {
      detail::fail_at(path, line, col0, what);
    };
    const auto f = fields_of(l);
    if (f.empty()) return;
    if (stage == 3) fail(f[0].second, "text after [END]");
    if (stage == 0) {
      if (upper(f[0].first) != "BEGIN" || f.size() < 2 || f.size() > 3)
        fail(f[0].second, fmt::format("'{}': expected 'BEGIN NAME.COM MM' (a HEIDENHAIN table)",
                                      detail::quote_cut(l.substr(f[0].second))));
      const std::string u = f.size() == 3 ? upper(f[2].first) : "MM";
      if (u == "INCH")
        unit = 25.4;
      else if (u != "MM")
        fail(f[2].second, fmt::format("unit '{}': MM or INCH", detail::quote_cut(f[2].first)));
      stage = 1;
      return;
    }
    if (stage == 1) {
      ncols = f.size();
      bool nr = false, ap = false;
      std::vector<std::size_t> axes;
      for (std::size_t k = 0; k < f.size(); ++k) {
        const std::string name = upper(f[k].first);
        for (std::size_t j = 0; j < k; ++j)
          if (upper(f[j].first) == name)
            fail(f[k].second, fmt::format("column '{}' appears twice", name));
        if (name == "NR") {
          nr = true;
          c_nr = k;
        } else if (name == "AXISPOS") {
          ap = true;
          c_pos = k;
        } else if (name == "BACKLASH") {
          c_back = k;
        } else {
          axes.push_back(k);
        }
      }
      if (!nr || !ap)
        fail(f[0].second, "the column names need NR and AXISPOS (a compensation value table)");
      if (axes.empty()) fail(f[0].second, "no axis column (the compensation values)");
      if (axis.empty()) {
        if (axes.size() > 1) {
          std::string names;
          for (auto k : axes) names += (names.empty() ? "" : ", ") + upper(f[k].first);
          fail(f[axes[1]].second,
               fmt::format("the table compensates several axes ({}): say which to read", names));
        }
        c_axis = axes[0];
        axis = upper(f[c_axis].first);
      } else {
        const auto it = std::find_if(axes.begin(), axes.end(),
                                     [&](std::size_t k) { return upper(f[k].first) == axis; });
        if (it == axes.end()) fail(f[0].second, fmt::format("no column for axis {}", axis));
        c_axis = *it;
      }
      stage = 2;
      return;
    }
    if (upper(f[0].first) == "[END]") {
      if (f.size() > 1) fail(f[1].second, "text after [END]");
      stage = 3;
      return;
    }
    if (f.size() != ncols)
      fail(f.size() > ncols ? f[ncols].second : l.size(),
           fmt::format("{} fields, the table has {} columns", f.size(), ncols));
    double v[4] = {0, 0, 0, 0};
    const std::size_t cols[4] = {c_nr, c_pos, c_axis, c_back};
    for (int k = 0; k < 4; ++k) {
      if (cols[k] == std::string::npos) continue;
      if (!to_number(f[cols[k]].first, v[k]))
        fail(f[cols[k]].second,
             fmt::format("'{}' is not a number", detail::quote_cut(f[cols[k]].first)));
    }
    if (v[0] != static_cast<double>(t.position.size()))
      fail(f[c_nr].second,
           fmt::format("NR {:g}: the points are numbered 0, 1, 2, ... (expected {})", v[0],
                       t.position.size()));
    if (t.position.size() == kHeidenhainMaxPoints)
      fail(f[0].second, fmt::format("more than {} points: the control takes at most {}",
                                    kHeidenhainMaxPoints, kHeidenhainMaxPoints));
    const double p = v[1] * unit;
    if (!t.position.empty() && !(p > t.position.back()))
      fail(f[c_pos].second, fmt::format("AXISPOS {:g} does not increase", v[1]));
    t.position.push_back(p);
    t.forward.push_back(v[2] * unit);
    t.reverse.push_back((v[2] - v[3]) * unit);
  });
  if (stage < 2)
    throw Error(fmt::format("{}: not a HEIDENHAIN table (no BEGIN line and column names)", path));
  if (stage == 2) throw Error(fmt::format("{}: no [END] line (the table is cut short)", path));
  if (t.position.size() < 2)
    throw Error(fmt::format("{}: a compensation table needs at least two points", path));
  if (axis_io) *axis_io = axis;
  return t;
}

compensation::AxisTable read_heidenhain(const std::string& path, std::string* axis) {
  return parse_heidenhain(detail::read_text(path), path, axis);
}

FanucTable write_fanuc(const std::string& path, const compensation::AxisTable& t,
                       const FanucOptions& o) {
  t.validate();
  if (t.bidirectional())
    throw Error(
        "FANUC pitch error compensation is one curve for both directions: make a unidirectional "
        "table (the reversal belongs in parameter 1851, backlash compensation)");
  if (o.axis_number < 1 || o.axis_number > 32) throw Error("the axis number must be 1 to 32");
  if (o.magnification < 0 || o.magnification > 100)
    throw Error("the magnification (parameter 3623) must be 1 to 100, or 0 to choose it");
  if (!(o.detection_unit > 0) || !std::isfinite(o.detection_unit))
    throw Error("the detection unit must be positive");
  if (o.first_number < 0 || o.max_number < o.first_number)
    throw Error("the point numbers must satisfy 0 <= first <= highest");
  if (!(o.min_value < 0 && o.max_value > 0)) throw Error("the value range must include zero");
  const double lo = t.position.front(), hi = t.position.back();
  const std::size_t n = t.position.size();
  const double ref = std::isnan(o.reference) ? lo : o.reference;
  if (!std::isfinite(ref) || ref < lo - 1e-9 || ref > hi + 1e-9)
    throw Error(fmt::format(
        "the reference position {:g} mm lies outside the table ({:g} .. {:g} mm)", ref, lo, hi));
  const double d = std::isnan(o.interval) ? (hi - lo) / static_cast<double>(n - 1) : o.interval;
  if (!(d > 0) || !std::isfinite(d))
    throw Error(fmt::format("the interval between points must be positive (got {:g} mm)", d));
  if (!std::isnan(o.max_feedrate) && d < o.max_feedrate / 7500 - 1e-12)
    throw Error(fmt::format(
        "an interval of {:g} mm is below the control's minimum, the maximum feedrate / 7500 = "
        "{:g} mm",
        d, o.max_feedrate / 7500));
  const double k_neg = std::ceil((ref - lo) / d - 1e-9), k_pos = std::ceil((hi - ref) / d - 1e-9);
  if (k_neg + k_pos > 100000) throw Error("more than 100000 compensation points");
  FanucTable ft;
  ft.interval = d;
  ft.negative_number = o.first_number;
  ft.reference_number = o.first_number + (k_neg > 0 ? static_cast<int>(k_neg) - 1 : 0);
  ft.positive_number = ft.reference_number + static_cast<int>(k_pos);
  if (ft.positive_number > o.max_number)
    throw Error(fmt::format(
        "points {} to {} ({:g} mm apart) go beyond the control's highest point number {}: use a "
        "larger interval",
        ft.negative_number, ft.positive_number, d, o.max_number));
  // Absolute compensation in detection units at each point, zero at the reference position.
  const double c_ref = t.correction(ref, positioning::Direction::Up);
  std::vector<double> cum;  // points negative_number − 1 .. positive_number
  for (int k = ft.negative_number - 1; k <= ft.positive_number; ++k) {
    const double p = ref + (k - ft.reference_number) * d;
    cum.push_back((t.correction(p, positioning::Direction::Up) - c_ref) / o.detection_unit);
  }
  auto fits = [&](int m, std::vector<int>* out) {
    long before = std::lround(cum[0] / m);
    for (std::size_t i = 1; i < cum.size(); ++i) {
      const long now = std::lround(cum[i] / m);
      if (now - before < o.min_value || now - before > o.max_value) return false;
      if (out) out->push_back(static_cast<int>(now - before));
      before = now;
    }
    return true;
  };
  int m = o.magnification;
  if (m == 0) {
    for (m = 1; m <= 100 && !fits(m, nullptr); ++m) {
    }
    if (m > 100) {
      double worst = 0;
      for (std::size_t i = 1; i < cum.size(); ++i)
        worst = std::max(worst, std::abs(cum[i] - cum[i - 1]));
      throw Error(fmt::format(
          "the compensation changes by up to {:g} µm between points {:g} mm apart: more than {} "
          "detection units even at magnification 100; use a smaller interval",
          worst * o.detection_unit * 1e3, d, o.max_value));
    }
  } else if (!fits(m, nullptr)) {
    throw Error(fmt::format(
        "at magnification {} a point's value leaves {}..{} detection units: give a larger one "
        "(or 0 to choose)",
        m, o.min_value, o.max_value));
  }
  ft.magnification = m;
  fits(m, &ft.values);
  const int a = o.axis_number;
  std::string text = "%\n";
  text += fmt::format("(FANUC PITCH ERROR COMPENSATION, AXIS {} {}, WRITTEN BY TRUEAXIS)\n", a,
                      upper(o.axis_name));
  text += fmt::format(
      "(REFERENCE POSITION AT {} MM OF THE LASER TABLE, DETECTION UNIT {} MM, VALUES "
      "INCREMENTAL)\n",
      decimal(ref), decimal(o.detection_unit));
  text += fmt::format("N3620A{}P{}\nN3621A{}P{}\nN3622A{}P{}\nN3623A{}P{}\nN3624A{}P{}\n", a,
                      ft.reference_number, a, ft.negative_number, a, ft.positive_number, a, m, a,
                      decimal(d));
  for (std::size_t i = 0; i < ft.values.size(); ++i)
    text += fmt::format("N{}P{}\n", 10000 + ft.negative_number + static_cast<int>(i), ft.values[i]);
  text += "%\n";
  detail::OutFile out(path);
  out.write(text);
  out.close();
  return ft;
}

compensation::AxisTable parse_fanuc(std::string text, const std::string& path,
                                    const FanucOptions& o, FanucTable* raw) {
  detail::normalize_text(text);
  const int axis_number = o.axis_number;
  const double detection_unit = o.detection_unit;
  const double reference = std::isnan(o.reference) ? 0.0 : o.reference;
  if (!(detection_unit > 0)) throw Error("the detection unit must be positive");
  std::map<int, double> param;                        // this axis' 3620..3624
  std::map<int, std::pair<int, std::size_t>> points;  // number -> value, line
  int percent = 0;
  detail::for_each_line(text, [&](std::size_t line, std::string_view text_line) {
    auto fail = [&](std::size_t col0, const std::string& what) {
      detail::fail_at(path, line, col0, what);
    };
    std::string l(text_line);
    // Comments in parentheses are blanked out (columns stay where they were).
    for (std::size_t c = 0; c < l.size(); ++c) {
      if (l[c] != '(') continue;
      const std::size_t close = l.find(')', c);
      if (close == std::string::npos) fail(c, "a comment '(' is not closed on its line");
      for (std::size_t k = c; k <= close; ++k) l[k] = ' ';
      c = close;
    }
    const std::size_t b = l.find_first_not_of(" \t;");
    if (b == std::string::npos) return;
    if (l[b] == '%') {
      if (l.find_first_not_of(" \t;", b + 1) != std::string::npos) fail(b + 1, "text after '%'");
      if (++percent > 2) fail(b, "a third '%': the data ends at the second");
      return;
    }
    if (percent == 2) fail(b, "text after the closing '%'");
    // N<number>[A<axis>]P<value>, optionally ending with ';'.
    std::size_t c = b;
    auto integer_after = [&](char letter, long& v) {
      if (c >= l.size() || std::toupper(static_cast<unsigned char>(l[c])) != letter)
        fail(c, fmt::format("expected '{}'", letter));
      const std::size_t s = ++c;
      while (c < l.size() && std::isdigit(static_cast<unsigned char>(l[c]))) ++c;
      if (c == s || c - s > 6) fail(s, fmt::format("'{}' needs a whole number", letter));
      std::from_chars(l.data() + s, l.data() + c, v);
    };
    long number = 0, axis = 0;
    integer_after('N', number);
    const bool has_axis = c < l.size() && std::toupper(static_cast<unsigned char>(l[c])) == 'A';
    if (has_axis) integer_after('A', axis);
    if (c >= l.size() || std::toupper(static_cast<unsigned char>(l[c])) != 'P')
      fail(c, "expected 'P' and the value");
    const std::size_t vs = ++c;
    std::size_t ve = l.find_first_of(" \t;", vs);
    if (ve == std::string::npos) ve = l.size();
    double value = 0;
    if (!to_number(std::string_view(l).substr(vs, ve - vs), value))
      fail(vs, fmt::format("'{}' is not a number", detail::quote_cut(l.substr(vs, ve - vs))));
    if (l.find_first_not_of(" \t;", ve) != std::string::npos)
      fail(l.find_first_not_of(" \t;", ve), "one record per line: N...P...");
    if (number >= 10000 && number < 20000) {
      if (has_axis) fail(b, "pitch error data (N10000 and up) have no axis address");
      if (value != std::floor(value) || value < o.min_value || value > o.max_value)
        fail(vs, fmt::format("point value {:g}: a whole number from {} to {}", value, o.min_value,
                             o.max_value));
      if (!points
               .emplace(static_cast<int>(number - 10000),
                        std::pair<int, std::size_t>{static_cast<int>(value), line})
               .second)
        fail(b, fmt::format("point {} is given twice", number - 10000));
    } else if (has_axis && axis == axis_number && number >= 3620 && number <= 3624) {
      if (param.count(static_cast<int>(number)))
        fail(b, fmt::format("parameter {} is given twice for axis {}", number, axis));
      if (number != 3624 && (value != std::floor(value) || value < 0))
        fail(vs, fmt::format("parameter {}: a whole number from 0", number));
      param[static_cast<int>(number)] = value;
    } else if (!has_axis) {
      fail(b, fmt::format("parameter {} needs an axis address (A1, A2, ...)", number));
    }
  });
  for (int p : {3620, 3621, 3622, 3624})
    if (!param.count(p))
      throw Error(fmt::format("{}: parameter {} for axis {} is missing", path, p, axis_number));
  FanucTable ft;
  ft.reference_number = static_cast<int>(param[3620]);
  ft.negative_number = static_cast<int>(param[3621]);
  ft.positive_number = static_cast<int>(param[3622]);
  ft.magnification = param.count(3623) ? static_cast<int>(param[3623]) : 1;
  if (ft.magnification == 0) ft.magnification = 1;  // the control reads 0 as 1
  ft.interval = param[3624];
  if (ft.magnification > 100)
    throw Error(fmt::format("{}: parameter 3623 (magnification) must be 0 to 100", path));
  if (!(ft.interval > 0))
    throw Error(fmt::format("{}: parameter 3624 (interval) must be positive", path));
  if (!(ft.negative_number <= ft.reference_number && ft.reference_number <= ft.positive_number) ||
      ft.positive_number == ft.negative_number)
    throw Error(fmt::format(
        "{}: the points must satisfy 3621 <= 3620 <= 3622 with 3621 < 3622 (got {}, {}, {})", path,
        ft.negative_number, ft.reference_number, ft.positive_number));
  compensation::AxisTable t;
  long cum = 0;
  std::vector<long> cums;
  for (int k = ft.negative_number; k <= ft.positive_number; ++k) {
    const auto it = points.find(k);
    if (it == points.end())
      throw Error(fmt::format("{}: point {} (N{}) has no value", path, k, 10000 + k));
    ft.values.push_back(it->second.first);
    cum += it->second.first;
    cums.push_back(cum);
  }
  // cums[i] is the compensation at point negative_number + i relative to the one before the
  // first; shift so that it is zero at the reference position.
  const long at_ref = cums[static_cast<std::size_t>(ft.reference_number - ft.negative_number)];
  const double unit = detection_unit * ft.magnification;
  for (int k = ft.negative_number - 1; k <= ft.positive_number; ++k) {
    const long c =
        k < ft.negative_number ? 0 : cums[static_cast<std::size_t>(k - ft.negative_number)];
    t.position.push_back(reference + (k - ft.reference_number) * ft.interval);
    t.forward.push_back(static_cast<double>(c - at_ref) * unit);
  }
  t.reverse = t.forward;
  if (raw) *raw = ft;
  return t;
}

compensation::AxisTable read_fanuc(const std::string& path, const FanucOptions& options,
                                   FanucTable* raw) {
  return parse_fanuc(detail::read_text(path), path, options, raw);
}

}  // namespace trueaxis::io
