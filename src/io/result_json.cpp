#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "fast_text.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/csv.hpp"
#include "trueaxis/io/json.hpp"
#include "trueaxis/io/separation/probes.hpp"

namespace trueaxis::io {
namespace {

using separation::Profile;
using separation::Result;

// Arrays are written in the shortest round-trip form, formatted in parallel and streamed to the
// file (see fast_text.hpp). An x array that repeats the last one, or the start of it (the pitch
// grid is the station grid less its last point), reuses its text.
class JsonArrays {
 public:
  explicit JsonArrays(detail::OutFile& f) : f_(f) {}
  void array(const Eigen::VectorXd& v, double scale, bool cache) {
    f_.write("[");
    if (cache && scale == 1.0 && cached_ && cached_->size() > 0 && v.size() <= cached_->size() &&
        std::equal(v.begin(), v.end(), cached_->begin())) {
      write_prefix(static_cast<std::size_t>(cached_->size() - v.size()));
    } else {
      detail::format_numbers(v.data(), static_cast<std::size_t>(v.size()), scale, ',', pieces_);
      f_.write(pieces_);
      if (cache && scale == 1.0) {
        // Kept by exchange, not copied; the old cache's strings are reused for the next array.
        cached_ = &v;
        std::swap(cached_pieces_, pieces_);
      }
    }
    f_.write("]");
  }
  void profile(const char* name, const Profile& p, double scale) {
    f_.write(fmt::format("  \"{}\": {{\n    \"x\": ", name));
    array(p.x, 1.0, true);
    f_.write(",\n    \"value\": ");
    array(p.value, scale, false);
    if (p.uncertainty.size()) {
      f_.write(",\n    \"uncertainty\": ");
      array(p.uncertainty, scale, false);
    }
    f_.write("\n  },\n");
  }

 private:
  // The cached text without its last `drop` numbers: up to the drop-th separator from the end
  // (nothing when every number goes).
  void write_prefix(std::size_t drop) {
    const std::vector<std::string>& p = cached_pieces_;
    if (drop == 0) return f_.write(p);
    std::size_t seen = 0;
    for (std::size_t i = p.size(); i-- > 0;)
      for (std::size_t j = p[i].size(); j-- > 0;)
        if (p[i][j] == ',' && ++seen == drop) {
          for (std::size_t k = 0; k < i; ++k) f_.write(p[k]);
          return f_.write(std::string_view(p[i]).substr(0, j));
        }
  }

  detail::OutFile& f_;
  std::vector<std::string> pieces_, cached_pieces_;
  const Eigen::VectorXd* cached_ = nullptr;  // the result's own array, alive while it is written
};

std::string quoted(const std::string& s) {
  return nlohmann::json(s).dump();
}

}  // namespace

void write_result(const std::string& path, const Result& r) {
  // Never a bare inf or nan token in the file (invalid JSON that 'report' would refuse).
  for (const Profile* p : {&r.workpiece, &r.guide, r.pitch ? &*r.pitch : nullptr})
    if (p && (!p->value.allFinite() || !p->uncertainty.allFinite()))
      throw Error(
          fmt::format("{}: the separated profiles are not finite: the readings are "
                      "beyond what the method can handle; nothing was written",
                      path));
  detail::OutFile f(path);
  fmt::memory_buffer b;
  fmt::format_to(std::back_inserter(b),
                 "{{\n  \"kind\": \"separation\",\n  \"method\": {},\n  \"reference\": {},\n  "
                 "\"gauge\": {},\n",
                 quoted(separation::to_string(r.method)),
                 quoted(separation::to_string(r.reference)), quoted(r.gauge));
  fmt::format_to(std::back_inserter(b), "  \"unobservable\": [");
  for (std::size_t i = 0; i < r.unobservable.size(); ++i)
    fmt::format_to(std::back_inserter(b), "{}{}", i ? ", " : "", quoted(r.unobservable[i]));
  fmt::format_to(std::back_inserter(b), "],\n  \"warnings\": [");
  const std::vector<std::string> warnings = r.warnings();
  for (std::size_t i = 0; i < warnings.size(); ++i)
    fmt::format_to(std::back_inserter(b), "{}{}", i ? ", " : "", quoted(warnings[i]));
  fmt::format_to(std::back_inserter(b),
                 "],\n  \"units\": {{\"x\": \"mm\", \"workpiece\": \"um\", "
                 "\"guide\": \"um\", \"pitch\": \"urad\"}},\n");
  f.write(std::string_view(b.data(), b.size()));
  JsonArrays arrays(f);
  arrays.profile("workpiece", r.workpiece, 1e3);
  arrays.profile("guide", r.guide, 1e3);
  if (r.pitch) arrays.profile("pitch", *r.pitch, 1e6);
  b.clear();
  // Each figure with its expanded uncertainty (95 %) and whether the data resolve it; null
  // when no uncertainty can be stated, the reason in "no_uncertainty".
  const auto figure = [](const separation::Straightness& st) {
    return fmt::format("{{\"ls\": {}, \"min_zone\": {}, \"U_um\": {}, \"resolved\": {}}}",
                       st.ls * 1e3, st.min_zone * 1e3,
                       st.U ? fmt::format("{}", *st.U * 1e3) : "null",
                       st.resolved() ? (*st.resolved() ? "true" : "false") : "null");
  };
  fmt::format_to(std::back_inserter(b),
                 "  \"straightness\": {{\"workpiece\": {}, \"guide\": {}}},\n",
                 figure(r.workpiece_straightness), figure(r.guide_straightness));
  if (r.sigma)
    fmt::format_to(std::back_inserter(b), "  \"sigma_um\": {},\n", *r.sigma * 1e3);
  else
    fmt::format_to(std::back_inserter(b), "  \"sigma_um\": null,\n");
  if (!r.no_uncertainty.empty())
    fmt::format_to(std::back_inserter(b), "  \"no_uncertainty\": {},\n", quoted(r.no_uncertainty));
  if (r.noise_gain && std::isfinite(*r.noise_gain))
    fmt::format_to(std::back_inserter(b), "  \"noise_gain\": {},\n", *r.noise_gain);
  if (!r.offsets.empty()) {
    fmt::format_to(std::back_inserter(b), "  \"offsets_mm\": [");
    for (std::size_t i = 0; i < r.offsets.size(); ++i)
      fmt::format_to(std::back_inserter(b), "{}{}", i ? ", " : "", r.offsets[i]);
    fmt::format_to(std::back_inserter(b), "],\n  \"offsets_assumed\": {},\n", r.offsets_assumed);
  }
  fmt::format_to(std::back_inserter(b),
                 "  \"sigma_estimated\": {},\n  \"dof\": {},\n  \"residual_rms_um\": {}\n}}\n",
                 r.sigma_estimated, r.dof, r.residual_rms * 1e3);
  f.write(std::string_view(b.data(), b.size()));
  f.close();
}

Result read_result(const std::string& path) {
  const JsonFile doc = JsonFile::read(path);
  using P = JsonFile::pointer;
  const auto& j = doc.object(P());
  auto vec = [&](const P& at, double scale, bool required) {
    Eigen::VectorXd v;
    if (!doc.has(at)) {
      if (required) doc.array(at);  // throws "missing", located at the parent
      return v;
    }
    return doc.numbers(at, scale);
  };
  auto prof = [&](const char* name, double scale) {
    const P o = P() / name;
    doc.object(o);
    Profile p{vec(o / "x", 1.0, true), vec(o / "value", scale, true),
              vec(o / "uncertainty", scale, false)};
    if (p.x.size() != p.value.size())
      doc.fail(o / "value", fmt::format("'{}': x has {} values but value has {}", name, p.x.size(),
                                        p.value.size()));
    if (p.uncertainty.size() && p.uncertainty.size() != p.x.size())
      doc.fail(o / "uncertainty", fmt::format("'{}': uncertainty has {} values for {} points", name,
                                              p.uncertainty.size(), p.x.size()));
    if (p.x.size() < 2) doc.fail(o / "x", fmt::format("'{}': needs at least two points", name));
    return p;
  };
  Result r;
  try {
    r.method = separation::method_from_string(j.value("method", "lsq"));
  } catch (const Error& e) {
    doc.fail(P("/method"), e.what());
  } catch (const nlohmann::json::exception&) {
    doc.fail(P("/method"), "'method' must be a string");
  }
  try {
    r.reference = separation::reference_from_string(j.value("reference", "ls"));
  } catch (const Error& e) {
    doc.fail(P("/reference"), e.what());
  } catch (const nlohmann::json::exception&) {
    doc.fail(P("/reference"), "'reference' must be a string");
  }
  if (doc.has(P("/gauge"))) r.gauge = doc.string(P("/gauge"));
  if (doc.has(P("/unobservable"))) {
    const auto& u = doc.array(P("/unobservable"));
    for (std::size_t i = 0; i < u.size(); ++i)
      r.unobservable.push_back(doc.string(P("/unobservable") / i));
  }
  r.workpiece = prof("workpiece", 1e-3);
  r.guide = prof("guide", 1e-3);
  if (j.contains("pitch") && !j["pitch"].is_null()) r.pitch = prof("pitch", 1e-6);
  if (doc.has(P("/straightness"))) {
    auto get = [&](const char* a, const char* b) {
      return doc.number(P("/straightness") / a / b) * 1e-3;
    };
    auto U = [&](const char* a) -> std::optional<double> {
      const P at = P("/straightness") / a / "U_um";
      if (!doc.has(at) || doc.root().at(at).is_null()) return std::nullopt;
      return doc.number(at) * 1e-3;
    };
    r.workpiece_straightness = {get("workpiece", "ls"), get("workpiece", "min_zone"),
                                U("workpiece")};
    r.guide_straightness = {get("guide", "ls"), get("guide", "min_zone"), U("guide")};
  }
  if (doc.has(P("/sigma_um")) && !doc.root().at(P("/sigma_um")).is_null())
    r.sigma = doc.number(P("/sigma_um")) * 1e-3;
  if (doc.has(P("/no_uncertainty"))) r.no_uncertainty = doc.string(P("/no_uncertainty"));
  if (doc.has(P("/sigma_estimated"))) {
    if (!j["sigma_estimated"].is_boolean())
      doc.fail(P("/sigma_estimated"), "'sigma_estimated' must be true or false");
    r.sigma_estimated = j["sigma_estimated"].get<bool>();
  }
  if (doc.has(P("/noise_gain"))) r.noise_gain = doc.number(P("/noise_gain"));
  if (doc.has(P("/offsets_mm"))) {
    const Eigen::VectorXd o = doc.numbers(P("/offsets_mm"));
    r.offsets.assign(o.data(), o.data() + o.size());
  }
  if (doc.has(P("/offsets_assumed")))
    r.offsets_assumed = doc.root().at(P("/offsets_assumed")).get<bool>();
  if (doc.has(P("/dof"))) r.dof = static_cast<long>(doc.number(P("/dof")));
  if (doc.has(P("/residual_rms_um"))) r.residual_rms = doc.number(P("/residual_rms_um")) * 1e-3;
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
  detail::OutFile f(path);
  std::string head;
  for (std::size_t c = 0; c < header.size(); ++c) head += (c ? "," : "") + header[c];
  f.write(head + "\n");
  std::vector<const double*> ptrs;
  for (const auto& c : cols) ptrs.push_back(c.data());
  std::vector<std::string> pieces;
  detail::format_rows(ptrs, static_cast<std::size_t>(m), pieces);
  f.write(pieces);
  f.close();
}

}  // namespace trueaxis::io
