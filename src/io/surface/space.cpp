#include "trueaxis/io/surface/space.hpp"

#include <fmt/format.h>

#include "../fast_text.hpp"
#include "../grid_json.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/compensation/controller.hpp"
#include "trueaxis/io/csv.hpp"
#include "trueaxis/io/json.hpp"

namespace trueaxis::io {
namespace {

using ptr = JsonFile::pointer;
using ojson = nlohmann::ordered_json;

ojson scaled(const Eigen::Ref<const Eigen::RowVectorXd>& v, double scale) {
  ojson a = ojson::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back(v[i] * scale);
  return a;
}

}  // namespace

namespace detail {
ojson grid_json(const map::ErrorMap& m) {
  ojson g;
  const char* names[3] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a)
    g[names[a]] = scaled(m.axes[static_cast<std::size_t>(a)].transpose(), 1.0);
  g["layout"] = "node n = i + nx*(j + ny*k) for x[i], y[j], z[k]";
  if (m.plane >= 0) {
    const auto& x = m.axes[static_cast<std::size_t>(m.plane)];
    g["plane"] = {{"normal", names[m.plane]},
                  {"at", (x[0] + x[1]) / 2},
                  {"band_mm", (x[1] - x[0]) / 2},
                  {"meaning",
                   "a ball plate's map: it holds the plane only; the two nodes along its normal "
                   "are the plane +- band, with the plane's errors"}};
  }
  const char* en[3] = {"ex", "ey", "ez"};
  const char* un[3] = {"ux", "uy", "uz"};
  for (int c = 0; c < 3; ++c) g[en[c]] = scaled(m.error.row(c), 1e3);
  if (m.uncertainty.size() != 0)
    for (int c = 0; c < 3; ++c) g[un[c]] = scaled(m.uncertainty.row(c), 1e3);
  return g;
}
}  // namespace detail

namespace {
constexpr int kMaxMonteCarlo = 1000;
}  // namespace

surface::SpacePlan read_plan(const std::string& path) {
  const JsonFile f = JsonFile::read(path);
  const auto& o = f.object(ptr());
  surface::SpacePlan p;
  for (const auto& [key, value] : o.items()) {
    const ptr k = ptr() / key;
    if (key == "spacing") {
      p.spacing = f.number(k);
      // A campaign runs lines along every grid line: below a millimetre the grid has hundreds of
      // millions of nodes on any real machine, which no campaign measures.
      if (!(p.spacing >= 1 && p.spacing <= 1e5))
        f.fail(k, fmt::format("spacing {:g} mm: must be between 1 and 100000 mm", p.spacing));
    } else if (key == "probes") {
      const std::string s = f.string(k);
      if (s == "three-point")
        p.probes = surface::ProbeMethod::ThreePoint;
      else if (s == "two-point")
        p.probes = surface::ProbeMethod::TwoPoint;
      else
        f.fail(k, fmt::format("probes must be \"three-point\" or \"two-point\", not \"{}\"", s));
    } else if (key == "probe_noise_um" || key == "laser_noise_um" || key == "profile_um") {
      const double v = f.number(k);
      if (!(v >= 0 && v <= 1000))
        f.fail(k, fmt::format("{} {:g} µm: must be between 0 and 1000 µm", key, v));
      (key == "probe_noise_um"   ? p.probe_noise
       : key == "laser_noise_um" ? p.laser_noise
                                 : p.profile_amplitude) = v * 1e-3;
    } else if (key == "diagonals") {
      if (!value.is_boolean()) f.fail(k, "'diagonals' must be true or false");
      p.diagonals = value.get<bool>();
    } else if (key == "monte_carlo" || key == "seed") {
      const double v = f.number(k);
      if (v < 0 || v != std::floor(v))
        f.fail(k, fmt::format("'{}' must be a whole number >= 0, not {:g}", key, v));
      if (key == "monte_carlo" && v > kMaxMonteCarlo)
        f.fail(k, fmt::format("monte_carlo {:g}: at most {} repetitions (each one is a whole "
                              "campaign; 20 to 100 give the uncertainty to 10-15 %)",
                              v, kMaxMonteCarlo));
      if (key == "seed")
        p.seed = static_cast<std::uint64_t>(v);
      else
        p.monte_carlo = static_cast<int>(v);
    } else {
      f.fail(k, fmt::format("unknown key '{}' (spacing, probes, probe_noise_um, laser_noise_um, "
                            "profile_um, diagonals, monte_carlo, seed)",
                            key));
    }
  }
  try {
    p.validate();
  } catch (const Error& e) {
    // Point at the key the complaint is about, when it names one.
    const std::string what = e.what();
    for (const auto& [key, value] : o.items())
      if (what.find(key) != std::string::npos) f.fail(ptr() / key, what);
    f.fail(ptr(), what);
  }
  return p;
}

void write_space(const std::string& path, const surface::SpaceResult& s,
                 const surface::SpacePlan& plan, const std::optional<surface::Verification>& v) {
  const map::ErrorMap& m = s.map;
  m.validate();
  ojson j;
  j["kind"] = "space";
  j["frame"] =
      "machine coordinates (mm); error = actual - nominal tool point (µm), at the nodes of the "
      "grid";
  j["reference"] = "least-squares rigid-body motion removed";
  j["unobservable"] = s.unobservable;
  j["gauge"] = s.gauge;
  j["plan"] = {
      {"spacing", plan.spacing},
      {"probes", plan.probes == surface::ProbeMethod::TwoPoint ? "two-point" : "three-point"},
      {"probe_noise_um", plan.probe_noise * 1e3},
      {"laser_noise_um", plan.laser_noise * 1e3},
      {"profile_um", plan.profile_amplitude * 1e3},
      {"diagonals", plan.diagonals},
      {"monte_carlo", plan.monte_carlo},
      {"seed", plan.seed}};
  j["campaign"] = {{"straightness_runs", s.straightness_runs}, {"laser_runs", s.laser_runs}};
  j["grid"] = detail::grid_json(m);
  auto& sf = j["surfaces"] = ojson::array();
  for (const auto& l : s.surfaces)
    sf.push_back({{"component", std::string("e") + "xyz"[l.component]},
                  {"level", l.level},
                  {"closure_rms", l.closure_rms * 1e3},
                  {"flatness_ls", l.flatness_ls * 1e3}});
  j["truth"] = {{"rms", s.truth_rms * 1e3}, {"max", s.truth_max * 1e3}};
  if (v)
    j["verification"] = {{"points", v->points},
                         {"before_rms", v->before_rms * 1e3},
                         {"before_max", v->before_max * 1e3},
                         {"after_rms", v->after_rms * 1e3},
                         {"after_max", v->after_max * 1e3},
                         {"improvement", v->improvement()},
                         {"interpolation_rms", v->interpolation_rms * 1e3}};
  if (v && v->uncertainty_known) {
    j["verification"]["uncertainty_rms"] = v->uncertainty_rms * 1e3;
    j["verification"]["predicted_rms"] = v->predicted_rms * 1e3;
  } else if (v) {
    // Not computed: no number, and the prediction is only a lower bound.
    j["verification"]["uncertainty_rms"] = nullptr;
    j["verification"]["predicted_rms_at_least"] = v->predicted_rms * 1e3;
  }
  j["warnings"] = surface::space_warnings(s, v ? &*v : nullptr);
  write_json(path, j);
}

map::ErrorMap read_error_map(const std::string& path) {
  const JsonFile f = JsonFile::read(path);
  f.object(ptr());
  const ptr g("/grid");
  f.object(g);
  map::ErrorMap m;
  const char* names[3] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) {
    auto& x = m.axes[static_cast<std::size_t>(a)];
    x = f.numbers(g / names[a]);
    if (x.size() < 2)
      f.fail(g / names[a], fmt::format("the grid needs at least two {} nodes", names[a]));
    for (Eigen::Index i = 1; i < x.size(); ++i)
      if (!(x[i] > x[i - 1]))
        f.fail(g / names[a] / static_cast<std::size_t>(i),
               fmt::format("grid {} nodes must increase strictly", names[a]));
  }
  if (f.has(g / "plane")) {
    const ptr pl = g / "plane";
    const std::string normal = f.string(pl / "normal");
    for (int a = 0; a < 3; ++a)
      if (normal == names[a]) m.plane = a;
    if (m.plane < 0)
      f.fail(pl / "normal", fmt::format("normal must be x, y or z, not '{}'", normal));
    if (m.axes[static_cast<std::size_t>(m.plane)].size() != 2)
      f.fail(g / names[m.plane],
             fmt::format("a plane map has two {} nodes (the plane's band)", normal));
  }
  const char* en[3] = {"ex", "ey", "ez"};
  const char* un[3] = {"ux", "uy", "uz"};
  // The node count is checked against the values the file holds before anything is allocated:
  // 5000 nodes per axis declare 1.25e11 nodes in a few kilobytes.
  const double declared = static_cast<double>(m.axes[0].size()) *
                          static_cast<double>(m.axes[1].size()) *
                          static_cast<double>(m.axes[2].size());
  for (int c = 0; c < 3; ++c) {
    const std::size_t held = f.array(g / en[c]).size();
    if (static_cast<double>(held) != declared)
      f.fail(g / en[c], fmt::format("'{}' has {} values for {} x {} x {} = {:.0f} grid nodes",
                                    dotted(g / en[c]), held, m.axes[0].size(), m.axes[1].size(),
                                    m.axes[2].size(), declared));
  }
  m.error.resize(3, m.nodes());
  const bool has_u = f.has(g / "ux");
  if (has_u) m.uncertainty.resize(3, m.nodes());
  for (int c = 0; c < 3; ++c) {
    const Eigen::VectorXd e = f.numbers(g / en[c], 1e-3);
    if (e.size() != m.nodes())
      f.fail(g / en[c], fmt::format("'{}' has {} values for {} grid nodes", dotted(g / en[c]),
                                    e.size(), m.nodes()));
    m.error.row(c) = e.transpose();
    if (has_u) {
      const Eigen::VectorXd u = f.numbers(g / un[c], 1e-3);
      if (u.size() != m.nodes())
        f.fail(g / un[c], fmt::format("'{}' has {} values for {} grid nodes", dotted(g / un[c]),
                                      u.size(), m.nodes()));
      m.uncertainty.row(c) = u.transpose();
    }
  }
  if (m.plane >= 0) {
    try {
      m.validate();
    } catch (const Error& e) {
      f.fail(g / "plane", e.what());
    }
  }
  return m;
}

void write_map_csv(const std::string& path, const map::ErrorMap& m) {
  m.validate();
  std::vector<Eigen::VectorXd> cols(m.uncertainty.size() != 0 ? 9 : 6, Eigen::VectorXd(m.nodes()));
  for (Eigen::Index n = 0; n < m.nodes(); ++n) {
    const Eigen::Vector3d p = m.node(n);
    for (int a = 0; a < 3; ++a) {
      cols[static_cast<std::size_t>(a)][n] = p[a];
      cols[static_cast<std::size_t>(3 + a)][n] = m.error(a, n) * 1e3;
      if (cols.size() == 9) cols[static_cast<std::size_t>(6 + a)][n] = m.uncertainty(a, n) * 1e3;
    }
  }
  std::vector<std::string> header{"x", "y", "z", "ex_um", "ey_um", "ez_um"};
  if (cols.size() == 9) header.insert(header.end(), {"ux_um", "uy_um", "uz_um"});
  std::vector<const Eigen::VectorXd*> ptrs;
  for (const auto& c : cols) ptrs.push_back(&c);
  write_csv(path, header, ptrs);
}

int write_linuxcnc(const std::string& path, const map::ErrorMap& m, int axis,
                   const Eigen::Vector3d& at, int type) {
  if (axis < 0 || axis > 2) throw Error("the axis must be x, y or z");
  const auto n = m.axes[static_cast<std::size_t>(axis)].size();
  if (n > kLinuxCncMaxPoints)
    throw Error(
        fmt::format("LinuxCNC accepts at most {} compensation points; the map has {} "
                    "nodes along the axis",
                    kLinuxCncMaxPoints, n));
  return write_linuxcnc(path, compensation::from_map(m, axis, at), type);
}

}  // namespace trueaxis::io
