#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>

#include "fast_text.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/controller.hpp"

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
  std::size_t pos = 0, line = 0;
  while (pos < text.size()) {
    const std::size_t nl = text.find('\n', pos);
    const std::size_t end = nl == std::string::npos ? text.size() : nl;
    std::string_view l(text.data() + pos, end - pos);
    pos = end + 1;
    ++line;
    auto fail = [&](std::size_t col0, const std::string& what) {
      throw Error(fmt::format("{}:{}:{}: {}", path, line, col0 + 1, what));
    };
    if (const auto sc = l.find(';'); sc != std::string_view::npos) l = l.substr(0, sc);
    std::size_t b = l.find_first_not_of(" \t");
    if (b == std::string_view::npos) continue;
    const std::size_t e = l.find_last_not_of(" \t") + 1;
    const std::string_view s = l.substr(b, e - b);
    if (ended) fail(b, "text after M17 (the end of the program)");
    if (s.substr(0, 3) == "%_N" || s == "CHANDATA(1)") continue;
    if (s == "M17" || s == "M30") {
      ended = true;
      continue;
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
  }
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
