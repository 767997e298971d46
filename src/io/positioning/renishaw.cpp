#include "trueaxis/io/positioning/renishaw.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>

#include "../fast_text.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::io {
namespace {

using positioning::Direction;
using positioning::Reading;

// Larger than any run or target count a laser test has.
constexpr long kMaxCount = 100000;

using detail::is_blank;
using detail::kMaxDeviation;
using detail::kMaxTarget;
using detail::lower;
using detail::trim;

// "NAME::" with NAME of letters, digits, spaces and '-', starting with a letter.
std::optional<std::string> section_name(std::string_view s) {
  if (s.size() < 3 || s.substr(s.size() - 2) != "::") return std::nullopt;
  const std::string_view name = trim(s.substr(0, s.size() - 2));
  if (name.empty() || !std::isalpha(static_cast<unsigned char>(name.front())) ||
      name.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789 -_") !=
          std::string_view::npos)
    return std::nullopt;
  std::string up(name);
  for (char& c : up) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return up;
}

bool starts_numeric(std::string_view s) {
  return !s.empty() && (std::isdigit(static_cast<unsigned char>(s.front())) || s.front() == '-' ||
                        s.front() == '+' || s.front() == '.');
}

struct Entry {
  int run, target;
  double deviation;  // µm
  std::size_t line;
};

}  // namespace

bool looks_like_rtl(const std::string& text) {
  std::size_t pos = 0;
  if (text.compare(0, 3, "\xEF\xBB\xBF") == 0) pos = 3;
  while (pos < text.size()) {
    const std::size_t nl = text.find('\n', pos);
    const std::size_t end = nl == std::string::npos ? text.size() : nl;
    std::string_view l = trim(std::string_view(text).substr(pos, end - pos));
    if (!l.empty() && l.back() == '\r') l = trim(l.substr(0, l.size() - 1));
    if (!l.empty()) return section_name(l).has_value();
    pos = end + 1;
  }
  return false;
}

bool has_rtl_name(const std::string& path) {
  return lower(std::filesystem::path(path).extension().string()) == ".rtl";
}

bool is_rtl_file(const std::string& path) {
  if (has_rtl_name(path)) return true;
  std::ifstream in(path, std::ios::binary);
  std::string head(4096, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  return looks_like_rtl(head);
}

RunDirections run_directions_from(const std::string& name) {
  if (name == "order") return RunDirections::FromOrder;
  if (name == "+-") return RunDirections::UpDown;
  if (name == "-+") return RunDirections::DownUp;
  if (name == "+") return RunDirections::AllUp;
  if (name == "-") return RunDirections::AllDown;
  throw Error(fmt::format("run directions '{}': use 'order', '+-', '-+', '+' or '-'", name));
}

RtlFile parse_rtl(std::string text, const std::string& path, const RtlOptions& options) {
  detail::normalize_text(text);
  RtlFile f;
  std::string section;
  bool collecting_targets = false, in_data = false, have_data_key = false;
  long target_count = -1, run_count = -1;
  std::size_t targets_line = 0, count_line = 0;
  std::vector<Entry> entries;
  std::vector<std::size_t> target_lines;
  detail::for_each_line(text, [&](std::size_t line, std::string_view l) {
    auto fail = [&](std::size_t col0, const std::string& what) {
      detail::fail_at(path, line, col0, what);
    };
    const std::size_t b = l.find_first_not_of(" \t");
    if (b == std::string_view::npos) return;
    const std::string_view s = trim(l);
    if (const auto name = section_name(s)) {
      section = *name;
      collecting_targets = in_data = false;
      return;
    }
    if (section.empty())
      fail(b, fmt::format("'{}': expected a section line such as 'HEADER::' (is this a "
                          "Renishaw .rtl file?)",
                          detail::quote_cut(s)));
    // The numbers of a line, with the offset of each.
    auto numbers = [&](std::size_t from, std::size_t to) {
      std::vector<std::pair<double, std::size_t>> v;
      std::size_t c = from;
      while (true) {
        while (c < to && is_blank(l[c])) ++c;
        if (c >= to) break;
        std::size_t e = c;
        while (e < to && !is_blank(l[e])) ++e;
        const char* nb = l.data() + c;
        if (*nb == '+') ++nb;
        double x = 0;
        const auto r = std::from_chars(nb, l.data() + e, x);
        if (nb == l.data() + e || r.ec != std::errc() || r.ptr != l.data() + e || !std::isfinite(x))
          fail(c, fmt::format("'{}' is not a number", detail::quote_cut(l.substr(c, e - c))));
        v.emplace_back(x, c);
        c = e;
      }
      return v;
    };
    auto count_value = [&](std::string_view v, std::size_t col0, const char* key) {
      long x = 0;
      const auto r = std::from_chars(v.data(), v.data() + v.size(), x);
      if (v.empty() || r.ec != std::errc() || r.ptr != v.data() + v.size() || x < 1 ||
          x > kMaxCount)
        fail(col0, fmt::format("{} '{}' is not a whole number from 1 to {}", key,
                               detail::quote_cut(v), kMaxCount));
      return x;
    };
    const std::size_t colon = l.find(':', b);
    const bool keyed = colon != std::string_view::npos &&
                       std::isalpha(static_cast<unsigned char>(l[b])) &&
                       !(section == "DEVIATIONS" && in_data && starts_numeric(s));
    const std::string key = keyed ? lower(trim(l.substr(b, colon - b))) : std::string();
    const std::size_t vcol = keyed ? l.find_first_not_of(" \t", colon + 1) : 0;
    const std::string_view value =
        keyed ? trim(l.substr(std::min(colon + 1, l.size()))) : std::string_view();
    if (section == "TARGET DATA") {
      if (!keyed && collecting_targets && starts_numeric(s)) {
        for (const auto& [x, c] : numbers(b, l.size())) {
          if (std::abs(x) > kMaxTarget) fail(c, fmt::format("target {:g} mm is out of range", x));
          f.targets.push_back(x);
          target_lines.push_back(line);
        }
        return;
      }
      if (!keyed)
        fail(b, fmt::format("'{}': expected 'Key : value' or target positions (mm)",
                            detail::quote_cut(s)));
      collecting_targets = false;
      if (key == "target-count") {
        target_count =
            count_value(value, vcol == std::string_view::npos ? colon : vcol, "Target-count");
        count_line = line;
      } else if (key == "targets") {
        if (targets_line != 0) fail(b, "a second 'Targets' list");
        targets_line = line;
        collecting_targets = true;
        if (!value.empty())
          for (const auto& [x, c] : numbers(vcol, l.size())) {
            if (std::abs(x) > kMaxTarget) fail(c, fmt::format("target {:g} mm is out of range", x));
            f.targets.push_back(x);
            target_lines.push_back(line);
          }
      } else {
        if (key == "filetype") {
          const std::string kind = lower(value);
          for (const char* other :
               {"angular", "rotary", "straight", "square", "flat", "diagonal", "velocity"})
            if (kind.find(other) != std::string::npos)
              fail(vcol, fmt::format("Filetype '{}': only linear positioning tests are read",
                                     detail::quote_cut(value)));
          if (kind.find("linear") == std::string::npos)
            f.warnings.push_back(fmt::format(
                "{}:{}: Filetype '{}' does not say linear: read as a linear positioning test "
                "(targets in mm, deviations in µm)",
                path, line, detail::quote_cut(value)));
        }
        f.fields.emplace_back(std::string(trim(l.substr(b, colon - b))), std::string(value));
      }
      return;
    }
    if (section == "RUNS") {
      if (!keyed) fail(b, fmt::format("'{}': expected 'Key : value'", detail::quote_cut(s)));
      if (key == "run-count") {
        run_count = count_value(value, vcol == std::string_view::npos ? colon : vcol, "Run-count");
      } else {
        f.fields.emplace_back(std::string(trim(l.substr(b, colon - b))), std::string(value));
      }
      return;
    }
    if (section == "DEVIATIONS") {
      if (in_data && starts_numeric(s)) {
        const auto v = numbers(b, l.size());
        if (v.size() != 3)
          fail(v.size() > 3 ? v[3].second : l.size(),
               fmt::format("expected 'run target deviation' (3 numbers), found {}", v.size()));
        auto index = [&](std::size_t k, long hi, const char* what) {
          const double x = v[k].first;
          if (x != std::floor(x) || x < 1 || x > static_cast<double>(hi))
            fail(v[k].second,
                 fmt::format("{} '{:g}' is not a whole number from 1 to {}{}", what, x, hi,
                             hi == kMaxCount ? "" : fmt::format(" (the file's {}-count)", what)));
          return static_cast<int>(x);
        };
        const int run = index(0, run_count > 0 ? run_count : kMaxCount, "run");
        const int target = index(1, target_count > 0 ? target_count : kMaxCount, "target");
        if (std::abs(v[2].first) > kMaxDeviation)
          fail(v[2].second, fmt::format("deviation {:g} µm is out of range", v[2].first));
        entries.push_back({run, target, v[2].first, line});
        return;
      }
      if (!keyed)
        fail(b, fmt::format("'{}': expected 'Run Target Data:' and lines 'run target deviation'",
                            detail::quote_cut(s)));
      if (key == "run target data") {
        if (have_data_key) fail(b, "a second 'Run Target Data' list");
        if (!value.empty()) fail(vcol, "the readings start on the next line");
        have_data_key = in_data = true;
      } else {
        in_data = false;
        f.fields.emplace_back(std::string(trim(l.substr(b, colon - b))), std::string(value));
      }
      return;
    }
    // HEADER, USER-TEXT and sections this reader does not interpret: keep what is keyed.
    if (keyed) f.fields.emplace_back(std::string(trim(l.substr(b, colon - b))), std::string(value));
  });

  auto missing = [&](const char* what, const char* where) {
    throw Error(
        fmt::format("{}: no '{}' in {} (is this a Renishaw .rtl file?)", path, what, where));
  };
  if (target_count < 0) missing("Target-count", "TARGET DATA::");
  if (targets_line == 0) missing("Targets", "TARGET DATA::");
  if (run_count < 0) missing("Run-count", "RUNS::");
  if (!have_data_key) missing("Run Target Data", "DEVIATIONS::");
  if (static_cast<long>(f.targets.size()) != target_count)
    throw Error(fmt::format("{}:{}:1: Target-count is {} (line {}) but the Targets list has {}",
                            path, targets_line, target_count, count_line, f.targets.size()));
  {
    std::vector<std::size_t> order(f.targets.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return f.targets[a] < f.targets[b]; });
    for (std::size_t k = 1; k < order.size(); ++k) {
      const std::size_t i = std::max(order[k], order[k - 1]), j = std::min(order[k], order[k - 1]);
      if (f.targets[i] == f.targets[j])
        throw Error(fmt::format("{}:{}:1: target {} ({:g} mm) is listed twice (also target {})",
                                path, target_lines[i], i + 1, f.targets[i], j + 1));
    }
  }
  if (entries.empty()) throw Error(fmt::format("{}: the file has no readings", path));
  // A RUNS:: or TARGET DATA:: section after the readings: their numbers checked now.
  for (const Entry& e : entries) {
    if (e.run > run_count)
      throw Error(fmt::format("{}:{}:1: run {} is beyond the file's Run-count {}", path, e.line,
                              e.run, run_count));
    if (e.target > target_count)
      throw Error(fmt::format("{}:{}:1: target {} is beyond the file's Target-count {}", path,
                              e.line, e.target, target_count));
  }
  f.run_count = static_cast<int>(run_count);

  // Readings per run in file order, each (run, target) once.
  std::vector<std::vector<const Entry*>> by_run(static_cast<std::size_t>(run_count) + 1);
  std::set<std::pair<int, int>> seen;
  for (const Entry& e : entries) {
    if (!seen.insert({e.run, e.target}).second)
      throw Error(fmt::format("{}:{}:1: run {} has a second reading at target {}", path, e.line,
                              e.run, e.target));
    by_run[static_cast<std::size_t>(e.run)].push_back(&e);
  }
  std::vector<Direction> dir(by_run.size(), Direction::Up);
  int up_runs = 0, down_runs = 0, used_runs = 0;
  for (int r = 1; r <= run_count; ++r) {
    const auto& list = by_run[static_cast<std::size_t>(r)];
    if (list.empty()) {
      f.warnings.push_back(fmt::format("{}: run {} has no readings", path, r));
      continue;
    }
    ++used_runs;
    Direction d = Direction::Up;
    switch (options.directions) {
      case RunDirections::UpDown:
        d = r % 2 == 1 ? Direction::Up : Direction::Down;
        break;
      case RunDirections::DownUp:
        d = r % 2 == 1 ? Direction::Down : Direction::Up;
        break;
      case RunDirections::AllUp:
        d = Direction::Up;
        break;
      case RunDirections::AllDown:
        d = Direction::Down;
        break;
      case RunDirections::FromOrder: {
        if (list.size() < 2)
          throw Error(fmt::format(
              "{}:{}:1: run {} has one reading: its direction cannot be read from the order of "
              "its targets; give the runs' directions",
              path, list.front()->line, r));
        auto at = [&](std::size_t k) {
          return f.targets[static_cast<std::size_t>(list[k]->target - 1)];
        };
        d = at(1) > at(0) ? Direction::Up : Direction::Down;
        for (std::size_t k = 1; k < list.size(); ++k)
          if ((at(k) > at(k - 1)) != (d == Direction::Up))
            throw Error(fmt::format(
                "{}:{}:1: run {} goes {} to {:g} mm and then back to {:g} mm: its direction "
                "cannot be read from the order of its targets; give the runs' directions",
                path, list[k]->line, r, d == Direction::Up ? "up" : "down", at(k - 1), at(k)));
        break;
      }
    }
    dir[static_cast<std::size_t>(r)] = d;
    (d == Direction::Up ? up_runs : down_runs)++;
  }
  if (options.directions == RunDirections::FromOrder && used_runs > 1 &&
      (up_runs == 0 || down_runs == 0))
    f.warnings.push_back(fmt::format(
        "{}: every run lists its targets {}: read as a one-direction ('{}') test. If the runs "
        "went both ways and the file lists each run in target order, give the runs' directions",
        path, up_runs ? "in increasing order" : "in decreasing order", up_runs ? '+' : '-'));

  int cycle[2] = {0, 0};
  for (int r = 1; r <= run_count; ++r) {
    const auto& list = by_run[static_cast<std::size_t>(r)];
    if (list.empty()) continue;
    const Direction d = dir[static_cast<std::size_t>(r)];
    const int c = ++cycle[d == Direction::Up ? 0 : 1];
    for (const Entry* e : list) {
      Reading rd;
      rd.target = f.targets[static_cast<std::size_t>(e->target - 1)];
      rd.cycle = c;
      rd.direction = d;
      rd.deviation = e->deviation * 1e-3;
      f.runs.readings.push_back(rd);
      f.runs.lines.push_back(e->line);
    }
  }
  return f;
}

RtlFile read_rtl(const std::string& path, const RtlOptions& options) {
  return parse_rtl(detail::read_text(path), path, options);
}

void write_rtl(const std::string& path, const std::vector<Reading>& readings,
               const std::vector<std::pair<std::string, std::string>>& fields) {
  if (readings.empty()) throw Error("no readings to write");
  std::vector<double> targets;
  for (const auto& r : readings) {
    if (!std::isfinite(r.target) || !std::isfinite(r.deviation))
      throw Error("a reading is not finite");
    targets.push_back(r.target);
  }
  std::sort(targets.begin(), targets.end());
  targets.erase(std::unique(targets.begin(), targets.end()), targets.end());
  // Runs in the order of the test cycle: cycle 1 '+', cycle 1 '-', cycle 2 '+', ...
  std::map<std::pair<int, int>, std::vector<const Reading*>> runs;  // (cycle, 0 up / 1 down)
  for (const auto& r : readings)
    runs[{r.cycle, r.direction == Direction::Up ? 0 : 1}].push_back(&r);
  for (const auto& [key, list] : runs) {
    std::set<double> at;
    for (const Reading* r : list)
      if (!at.insert(r->target).second)
        throw Error(fmt::format("cycle {} '{}' has two readings at {:g} mm", key.first,
                                key.second == 0 ? '+' : '-', r->target));
  }
  std::string t = "HEADER::\r\nFile type : RTL\r\nOwner : trueaxis\r\nVersion no : 1\r\n";
  t += "TARGET DATA::\r\nFiletype : Linear\r\n";
  t += fmt::format("Target-count : {}\r\nTargets :\r\n", targets.size());
  for (std::size_t i = 0; i < targets.size(); ++i)
    t += fmt::format("{:12.4f}{}", targets[i], i % 5 == 4 || i + 1 == targets.size() ? "\r\n" : "");
  t += "USER-TEXT::\r\n";
  for (const auto& [k, v] : fields) t += fmt::format("{} : {}\r\n", k, v);
  t += fmt::format("RUNS::\r\nRun-count : {}\r\nDEVIATIONS::\r\nRun Target Data:\r\n", runs.size());
  int run = 0;
  for (const auto& [key, list] : runs) {
    ++run;
    std::vector<const Reading*> l = list;
    std::sort(l.begin(), l.end(), [up = key.second == 0](const Reading* a, const Reading* b) {
      return up ? a->target < b->target : a->target > b->target;
    });
    for (const Reading* r : l) {
      const auto k = std::lower_bound(targets.begin(), targets.end(), r->target) - targets.begin();
      t += fmt::format("{}  {}  {:.4f}\r\n", run, k + 1, r->deviation * 1e3);
    }
  }
  detail::OutFile out(path);
  out.write(t);
  out.close();
}

}  // namespace trueaxis::io
