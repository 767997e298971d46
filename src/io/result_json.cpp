#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "trueaxis/error.hpp"
#include "trueaxis/io/csv.hpp"
#include "trueaxis/io/probes.hpp"

namespace trueaxis::io {
namespace {

using separation::Profile;
using separation::Result;

// Arrays are written with fmt (shortest round-trip form): a million-point result is written in
// a few tens of milliseconds, which a DOM-building JSON writer does not manage.
void array(fmt::memory_buffer& b, const Eigen::VectorXd& v, double scale) {
  b.push_back('[');
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    if (i) b.push_back(',');
    fmt::format_to(std::back_inserter(b), "{}", v[i] * scale);
  }
  b.push_back(']');
}

void profile(fmt::memory_buffer& b, const char* name, const Profile& p, double scale) {
  fmt::format_to(std::back_inserter(b), "  \"{}\": {{\n    \"x\": ", name);
  array(b, p.x, 1.0);
  fmt::format_to(std::back_inserter(b), ",\n    \"value\": ");
  array(b, p.value, scale);
  if (p.uncertainty.size()) {
    fmt::format_to(std::back_inserter(b), ",\n    \"uncertainty\": ");
    array(b, p.uncertainty, scale);
  }
  fmt::format_to(std::back_inserter(b), "\n  }},\n");
}

std::string quoted(const std::string& s) {
  return nlohmann::json(s).dump();
}

void write_file(const std::string& path, const fmt::memory_buffer& b) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "wb"), &std::fclose);
  if (!f) throw Error(fmt::format("{}: cannot open file for writing", path));
  if (std::fwrite(b.data(), 1, b.size(), f.get()) != b.size() || std::fflush(f.get()) != 0)
    throw Error(fmt::format("{}: write error", path));
}

std::string line_col(const std::string& text, std::size_t byte) {
  std::size_t line = 1, col = 1;
  for (std::size_t i = 0; i < byte && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      col = 1;
    } else {
      ++col;
    }
  }
  return fmt::format("{}:{}", line, col);
}

}  // namespace

void write_result(const std::string& path, const Result& r) {
  fmt::memory_buffer b;
  fmt::format_to(std::back_inserter(b),
                 "{{\n  \"method\": {},\n  \"reference\": {},\n  \"gauge\": {},\n",
                 quoted(separation::to_string(r.method)),
                 quoted(separation::to_string(r.reference)), quoted(r.gauge));
  fmt::format_to(std::back_inserter(b), "  \"unobservable\": [");
  for (std::size_t i = 0; i < r.unobservable.size(); ++i)
    fmt::format_to(std::back_inserter(b), "{}{}", i ? ", " : "", quoted(r.unobservable[i]));
  fmt::format_to(std::back_inserter(b),
                 "],\n  \"units\": {{\"x\": \"mm\", \"workpiece\": \"um\", "
                 "\"guide\": \"um\", \"pitch\": \"urad\"}},\n");
  profile(b, "workpiece", r.workpiece, 1e3);
  profile(b, "guide", r.guide, 1e3);
  if (r.pitch) profile(b, "pitch", *r.pitch, 1e6);
  fmt::format_to(std::back_inserter(b),
                 "  \"straightness\": {{\"workpiece\": {{\"ls\": {}, \"min_zone\": {}}}, "
                 "\"guide\": {{\"ls\": {}, \"min_zone\": {}}}}},\n",
                 r.workpiece_straightness.ls * 1e3, r.workpiece_straightness.min_zone * 1e3,
                 r.guide_straightness.ls * 1e3, r.guide_straightness.min_zone * 1e3);
  if (r.sigma) fmt::format_to(std::back_inserter(b), "  \"sigma_um\": {},\n", *r.sigma * 1e3);
  fmt::format_to(std::back_inserter(b),
                 "  \"sigma_estimated\": {},\n  \"dof\": {},\n  \"residual_rms_um\": {}\n}}\n",
                 r.sigma_estimated, r.dof, r.residual_rms * 1e3);
  write_file(path, b);
}

Result read_result(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(fmt::format("{}: cannot open file for reading", path));
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw Error(fmt::format("{}:{}: invalid JSON: {}", path,
                            line_col(text, e.byte ? e.byte - 1 : 0), e.what()));
  }
  auto fail = [&](const std::string& what) { return Error(fmt::format("{}: {}", path, what)); };
  if (!j.is_object()) throw fail("expected a JSON object at the top level");
  auto vec = [&](const nlohmann::json& o, const std::string& obj, const char* key, double scale,
                 bool required) {
    Eigen::VectorXd v;
    if (!o.contains(key)) {
      if (required) throw fail(fmt::format("'{}.{}' is missing", obj, key));
      return v;
    }
    const auto& a = o[key];
    if (!a.is_array()) throw fail(fmt::format("'{}.{}' must be an array of numbers", obj, key));
    v.resize(static_cast<Eigen::Index>(a.size()));
    for (std::size_t i = 0; i < a.size(); ++i) {
      if (!a[i].is_number()) throw fail(fmt::format("'{}.{}[{}]' is not a number", obj, key, i));
      const double x = a[i].get<double>();
      if (!std::isfinite(x)) throw fail(fmt::format("'{}.{}[{}]' is not finite", obj, key, i));
      v[static_cast<Eigen::Index>(i)] = x * scale;
    }
    return v;
  };
  auto prof = [&](const char* name, double scale) {
    if (!j.contains(name) || !j[name].is_object())
      throw fail(fmt::format("object '{}' is missing", name));
    const auto& o = j[name];
    Profile p{vec(o, name, "x", 1.0, true), vec(o, name, "value", scale, true),
              vec(o, name, "uncertainty", scale, false)};
    if (p.x.size() != p.value.size())
      throw fail(
          fmt::format("'{}': x has {} values but value has {}", name, p.x.size(), p.value.size()));
    if (p.uncertainty.size() && p.uncertainty.size() != p.x.size())
      throw fail(fmt::format("'{}': uncertainty has {} values for {} points", name,
                             p.uncertainty.size(), p.x.size()));
    if (p.x.size() < 2) throw fail(fmt::format("'{}': needs at least two points", name));
    return p;
  };
  Result r;
  try {
    r.method = separation::method_from_string(j.value("method", "lsq"));
    r.reference = separation::reference_from_string(j.value("reference", "ls"));
  } catch (const Error& e) {
    throw fail(e.what());
  }
  r.gauge = j.value("gauge", "");
  if (j.contains("unobservable") && j["unobservable"].is_array())
    for (const auto& u : j["unobservable"])
      if (u.is_string()) r.unobservable.push_back(u.get<std::string>());
  r.workpiece = prof("workpiece", 1e-3);
  r.guide = prof("guide", 1e-3);
  if (j.contains("pitch") && !j["pitch"].is_null()) r.pitch = prof("pitch", 1e-6);
  if (j.contains("straightness")) {
    const auto& s = j["straightness"];
    auto get = [&](const char* a, const char* b) {
      if (!s.contains(a) || !s[a].contains(b) || !s[a][b].is_number())
        throw fail(fmt::format("'straightness.{}.{}' must be a number", a, b));
      return s[a][b].get<double>() * 1e-3;
    };
    r.workpiece_straightness = {get("workpiece", "ls"), get("workpiece", "min_zone")};
    r.guide_straightness = {get("guide", "ls"), get("guide", "min_zone")};
  }
  if (j.contains("sigma_um") && j["sigma_um"].is_number())
    r.sigma = j["sigma_um"].get<double>() * 1e-3;
  r.sigma_estimated = j.value("sigma_estimated", false);
  r.dof = j.value("dof", 0L);
  r.residual_rms = j.value("residual_rms_um", 0.0) * 1e-3;
  return r;
}

void write_result_csv(const std::string& path, const Result& r) {
  // One row per workpiece position; guide and pitch values where their stations coincide.
  const Eigen::Index m = r.workpiece.x.size();
  const double h =
      m > 1 ? (r.workpiece.x[m - 1] - r.workpiece.x[0]) / static_cast<double>(m - 1) : 1.0;
  auto spread = [&](const Eigen::VectorXd& x, const Eigen::VectorXd& v, double scale) {
    Eigen::VectorXd out = Eigen::VectorXd::Constant(m, std::nan(""));
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      const long k = std::lround((x[i] - r.workpiece.x[0]) / h);
      if (k >= 0 && k < m) out[k] = v[i] * scale;
    }
    return out;
  };
  std::vector<std::string> header{"x", "workpiece_um"};
  std::vector<Eigen::VectorXd> cols{r.workpiece.x, r.workpiece.value * 1e3};
  if (r.workpiece.uncertainty.size()) {
    header.push_back("workpiece_u_um");
    cols.push_back(r.workpiece.uncertainty * 1e3);
  }
  header.push_back("guide_um");
  cols.push_back(spread(r.guide.x, r.guide.value, 1e3));
  if (r.guide.uncertainty.size()) {
    header.push_back("guide_u_um");
    cols.push_back(spread(r.guide.x, r.guide.uncertainty, 1e3));
  }
  if (r.pitch) {
    header.push_back("pitch_urad");
    cols.push_back(spread(r.pitch->x, r.pitch->value, 1e6));
    if (r.pitch->uncertainty.size()) {
      header.push_back("pitch_u_urad");
      cols.push_back(spread(r.pitch->x, r.pitch->uncertainty, 1e6));
    }
  }
  // NaN marks "not defined here"; written as an empty field.
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "wb"), &std::fclose);
  if (!f) throw Error(fmt::format("{}: cannot open file for writing", path));
  fmt::memory_buffer b;
  for (std::size_t c = 0; c < header.size(); ++c)
    fmt::format_to(std::back_inserter(b), "{}{}", c ? "," : "", header[c]);
  b.push_back('\n');
  for (Eigen::Index i = 0; i < m; ++i) {
    for (std::size_t c = 0; c < cols.size(); ++c) {
      if (c) b.push_back(',');
      if (!std::isnan(cols[c][i])) fmt::format_to(std::back_inserter(b), "{}", cols[c][i]);
    }
    b.push_back('\n');
  }
  if (std::fwrite(b.data(), 1, b.size(), f.get()) != b.size())
    throw Error(fmt::format("{}: write error", path));
}

}  // namespace trueaxis::io
