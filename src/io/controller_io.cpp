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
