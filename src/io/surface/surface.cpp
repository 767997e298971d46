#include "trueaxis/io/surface/surface.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <map>

#include "../fast_text.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/json.hpp"
#include "trueaxis/io/separation/probes.hpp"

namespace trueaxis::io {
namespace {

std::string_view trim(std::string_view s, std::size_t& lead) {
  lead = 0;
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1), ++lead;
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r'))
    s.remove_suffix(1);
  return s;
}

double parse_number(std::string_view s, const std::string& path, std::size_t line,
                    std::size_t col) {
  double v = 0;
  const char* b = s.data() + (!s.empty() && s[0] == '+' ? 1 : 0);
  const auto r = std::from_chars(b, s.data() + s.size(), v);
  if (r.ec != std::errc() || r.ptr != s.data() + s.size())
    throw Error(
        fmt::format("{}:{}:{}: '{}' is not a number", path, line, col, detail::quote_cut(s)));
  if (!std::isfinite(v))
    throw Error(
        fmt::format("{}:{}:{}: {} is not allowed", path, line, col, std::isnan(v) ? "NaN" : "Inf"));
  if (std::abs(v) > 1e12)
    throw Error(fmt::format("{}:{}:{}: {:g} is out of range (its size must be below 1e+12)", path,
                            line, col, v));
  return v;
}

// Calls fn(line number, column of the first character, trimmed text) for every line that is not
// blank and not a '#' comment; stops early when fn returns false.
template <class Fn>
void for_each_content_line(const std::string& text, Fn&& fn) {
  std::size_t line = 0, pos = 0;
  while (pos < text.size()) {
    const std::size_t nl = std::min(text.find('\n', pos), text.size());
    ++line;
    std::size_t lead = 0;
    const std::string_view l = trim(std::string_view(text).substr(pos, nl - pos), lead);
    pos = nl + 1;
    if (l.empty() || l[0] == '#') continue;
    if (!fn(line, lead + 1, l)) return;
  }
}

}  // namespace

surface::MoodyData read_moody(const std::string& dir) {
  namespace fs = std::filesystem;
  if (!fs::is_directory(dir))
    throw Error(fmt::format("{}: not a directory (Moody's files expected)", dir));
  surface::MoodyData d;
  std::map<std::string, std::vector<std::size_t>> lines_of;  // the line of every reading
  std::map<std::string, std::size_t> last_line;
  for (const char* name : surface::kMoodyLines) {
    const std::string path = (fs::path(dir) / (std::string(name) + ".txt")).string();
    std::vector<double> v;
    const std::string text = detail::read_text(path);
    last_line[name] = static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n')) + 1;
    for_each_content_line(text, [&](std::size_t line, std::size_t col, std::string_view l) {
      v.push_back(parse_number(l, path, line, col));
      lines_of[name].push_back(line);
      return true;
    });
    if (v.size() < 2)
      throw Error(fmt::format("{}: needs at least 2 readings, found {}", path, v.size()));
    d.readings[name] = Eigen::Map<Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
  }
  // Lines that must have as many readings as another: the message points at the first reading
  // too many, or at the end of a file one short.
  const auto require_eq = [&](const char* a, const char* b, const char* why) {
    const std::size_t na = lines_of[a].size(), nb = lines_of[b].size();
    if (na == nb) return;
    const std::string path = (fs::path(dir) / (std::string(a) + ".txt")).string();
    const std::size_t line = na > nb ? lines_of[a][nb] : last_line[a];
    throw Error(
        fmt::format("{}:{}:1: {} readings, but {}.txt ({}) has {}", path, line, na, b, why, nb));
  };
  require_eq("SE_SW", "NE_NW", "the opposite edge");
  require_eq("E_W", "NE_NW", "the parallel centre line");
  require_eq("NW_SW", "NE_SE", "the opposite edge");
  require_eq("N_S", "NE_SE", "the parallel centre line");
  require_eq("NE_SW", "NW_SE", "the other diagonal");
  const std::string cpath = (fs::path(dir) / "Config.txt").string();
  bool found = false;  // only the first spacing counts (as in Moody-Method)
  for_each_content_line(
      detail::read_text(cpath), [&](std::size_t line, std::size_t col, std::string_view l) {
        if ((l[0] != 'I' && l[0] != 'M') || l.size() < 3 || (l[1] != ' ' && l[1] != '\t'))
          throw Error(fmt::format("{}:{}:{}: expected 'I <inches>' or 'M <mm>' (the foot spacing)",
                                  cpath, line, col));
        std::size_t lead2 = 0;
        const std::string_view num = trim(l.substr(2), lead2);
        const double s = parse_number(num, cpath, line, col + 2 + lead2);
        if (!(s > 0))
          throw Error(fmt::format("{}:{}:{}: the foot spacing must be positive", cpath, line,
                                  col + 2 + lead2));
        d.foot_spacing = l[0] == 'I' ? s * 25.4 : s;
        found = true;
        return false;
      });
  if (!found)
    throw Error(fmt::format("{}: no foot spacing found (a line 'I <inches>' or 'M <mm>')", cpath));
  return d;
}

std::vector<surface::Line> read_lines(const std::string& path) {
  namespace fs = std::filesystem;
  const JsonFile doc = JsonFile::read(path);
  using P = JsonFile::pointer;
  const auto& arr = doc.array(P("/lines"));
  std::vector<surface::Line> out;
  auto vec2 = [&](const P& p) {
    const auto& a = doc.array(p);
    if (a.size() != 2) doc.fail(p, fmt::format("'{}' must have 2 numbers [x, y]", dotted(p)));
    return Eigen::Vector2d(doc.number(p / 0), doc.number(p / 1));
  };
  for (std::size_t i = 0; i < arr.size(); ++i) {
    const P at = P("/lines") / i;
    doc.object(at);
    surface::Line l;
    l.name = doc.string(at / "name");
    if (l.name.empty()) doc.fail(at / "name", "a line's name must not be empty");
    for (const auto& other : out)
      if (other.name == l.name)
        doc.fail(at / "name", fmt::format("duplicated line name '{}'", l.name));
    l.start = vec2(at / "start");
    l.direction = vec2(at / "direction");
    if (l.direction.norm() == 0) doc.fail(at / "direction", "direction must not be zero");
    const int kinds = doc.has(at / "heights") + doc.has(at / "slopes") + doc.has(at / "from");
    if (kinds != 1)
      doc.fail(at,
               fmt::format("line '{}': give exactly one of 'heights', 'slopes' or 'from'", l.name));
    if (doc.has(at / "from")) {
      std::string from = doc.string(at / "from");
      if (fs::path(from).is_relative()) from = (fs::path(path).parent_path() / from).string();
      separation::Result r;
      try {
        r = read_result(from);
      } catch (const Error& e) {
        // Say which line of lines.json asked for the file, then what is wrong with it.
        doc.fail(at / "from", fmt::format("line '{}': {}", l.name, e.what()));
      }
      std::string curve = doc.has(at / "curve") ? doc.string(at / "curve") : "guide";
      if (curve != "guide" && curve != "workpiece")
        doc.fail(at / "curve", "'curve' must be \"guide\" or \"workpiece\"");
      const separation::Profile& p = curve == "guide" ? r.guide : r.workpiece;
      l.heights = p.value;
      l.spacing = (p.x[p.x.size() - 1] - p.x[0]) / static_cast<double>(p.x.size() - 1);
      if (doc.has(at / "spacing") &&
          std::abs(doc.number(at / "spacing") - l.spacing) > 1e-9 * l.spacing)
        doc.fail(at / "spacing",
                 fmt::format("spacing {} mm does not match the result's station step {} mm",
                             doc.number(at / "spacing"), l.spacing));
    } else {
      l.spacing = doc.number(at / "spacing");
      if (!(l.spacing >= 1e-6))
        doc.fail(at / "spacing",
                 fmt::format("spacing {:g} mm: must be at least 1e-6 mm (positive)", l.spacing));
      if (doc.has(at / "heights")) {
        l.heights = doc.numbers(at / "heights", 1e-3);
      } else {
        l.heights = surface::heights_from_slopes(doc.numbers(at / "slopes", 1e-6), l.spacing);
      }
      if (l.heights.size() < 2)
        doc.fail(at, fmt::format("line '{}': needs at least 2 stations", l.name));
      if (!l.heights.allFinite() || l.heights.cwiseAbs().maxCoeff() > 1e6)  // mm: a kilometre
        doc.fail(at / (doc.has(at / "heights") ? "heights" : "slopes"),
                 fmt::format("line '{}': the heights run beyond a kilometre: check the units "
                             "(heights in µm, slopes in µrad)",
                             l.name));
    }
    out.push_back(std::move(l));
  }
  return out;
}

void write_surface(const std::string& path, const surface::Result& r) {
  nlohmann::ordered_json j;
  j["kind"] = "surface";
  j["method"] = r.method;
  j["units"] = {{"x", "mm"}, {"y", "mm"}, {"height", "um"}};
  j["reference"] = r.reference;
  j["lines"] = r.lines;
  auto& pts = j["points"] = nlohmann::ordered_json::array();
  for (const auto& p : r.points)
    pts.push_back({{"line", r.lines[static_cast<std::size_t>(p.line)]},
                   {"station", p.station},
                   {"x", p.xy.x()},
                   {"y", p.xy.y()},
                   {"height", p.height * 1e3}});
  if (r.grid) {
    auto& g = j["grid"];
    g["x"] = std::vector<double>(r.grid->x.begin(), r.grid->x.end());
    g["y"] = std::vector<double>(r.grid->y.begin(), r.grid->y.end());
    auto& rows = g["height"] = nlohmann::ordered_json::array();
    for (Eigen::Index a = 0; a < r.grid->height.rows(); ++a) {
      std::vector<double> row;
      for (Eigen::Index b = 0; b < r.grid->height.cols(); ++b)
        row.push_back(r.grid->height(a, b) * 1e3);
      rows.push_back(row);
    }
  } else {
    j["grid"] = nullptr;
  }
  // U from the closure at the crossings; null with the reason when the network cannot show the
  // readings' noise.
  j["flatness"] = {{"ls", r.flatness_ls * 1e3},
                   {"min_zone", r.flatness_min_zone * 1e3},
                   {"U_um", r.U ? nlohmann::ordered_json(*r.U * 1e3) : nullptr},
                   {"resolved", r.U ? nlohmann::ordered_json(*r.resolved()) : nullptr}};
  if (r.U) {
    j["flatness"]["uncertainty"] = {{"sigma", r.sigma},
                                    {"sigma_unit", r.sigma_unit},
                                    {"crossings", r.crossings.size()},
                                    {"degrees_of_freedom", r.redundancy},
                                    {"u_max_um", r.u_max * 1e3},
                                    {"basis", r.uncertainty_basis()}};
  } else {
    j["flatness"]["no_uncertainty"] = r.no_uncertainty();
  }
  j["closure"] = {{"rms", r.closure_rms * 1e3}, {"max", r.closure_max * 1e3}};
  auto& cs = j["crossings"] = nlohmann::ordered_json::array();
  for (const auto& c : r.crossings)
    cs.push_back(
        {{"lines",
          {r.lines[static_cast<std::size_t>(c.a)], r.lines[static_cast<std::size_t>(c.b)]}},
         {"x", c.xy.x()},
         {"y", c.xy.y()},
         {"residual", c.residual * 1e3}});
  j["unobservable"] = r.unobservable;
  j["gauge"] = r.gauge;
  write_json(path, j);
}

}  // namespace trueaxis::io
