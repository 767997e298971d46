// Python bindings for positioning accuracy by ISO 230-2 / VDI 3441 and the virtual laser runs.
// Positions in mm, deviations and parameters in µm; parameters the runs cannot define are None.
#include "trueaxis/positioning/positioning.hpp"

#include <fmt/format.h>
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <cmath>
#include <map>
#include <optional>
#include <utility>

#include "bindings.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/positioning/positioning.hpp"
#include "trueaxis/io/positioning/renishaw.hpp"
#include "trueaxis/sim/positioning.hpp"

namespace py = pybind11;

namespace trueaxis::python {
namespace {

using positioning::Direction;

py::object um(double mm) {
  return std::isnan(mm) ? py::object(py::none()) : py::object(py::float_(mm * 1e3));
}

Eigen::VectorXd column(const std::vector<positioning::Target>& t, double positioning::Target::*f,
                       double scale) {
  Eigen::VectorXd v(static_cast<Eigen::Index>(t.size()));
  for (std::size_t i = 0; i < t.size(); ++i) v[static_cast<Eigen::Index>(i)] = t[i].*f * scale;
  return v;
}

// Readings from a runs.csv or Renishaw .rtl path, or a dict of equally long sequences named like
// runs.csv's columns. An .rtl file's warnings go to `warnings`.
std::vector<positioning::Reading> readings_in(const py::object& runs,
                                              const std::string& run_directions,
                                              std::vector<std::string>* warnings) {
  if (py::isinstance<py::str>(runs)) {
    const auto path = py::cast<std::string>(runs);
    if (io::is_rtl_file(path)) {
      io::RtlOptions o;
      o.directions = io::run_directions_from(run_directions);
      auto f = io::read_rtl(path, o);
      *warnings = std::move(f.warnings);
      return std::move(f.runs.readings);
    }
    if (run_directions != "order") throw Error("run_directions belongs to a Renishaw .rtl file");
    return io::read_runs(path).readings;
  }
  if (!py::isinstance<py::dict>(runs))
    throw Error(
        "runs: give a runs.csv or .rtl path, or a dict with target_mm, cycle, direction, "
        "deviation_um (and optionally material_temp_c, air_temp_c)");
  const auto d = py::cast<py::dict>(runs);
  for (auto kv : d) {
    const std::string k = py::cast<std::string>(kv.first);
    if (k != "target_mm" && k != "cycle" && k != "direction" && k != "deviation_um" &&
        k != "material_temp_c" && k != "air_temp_c")
      throw Error(
          fmt::format("runs: unknown key '{}' (target_mm, cycle, direction, deviation_um, "
                      "material_temp_c, air_temp_c)",
                      k));
  }
  for (const char* k : {"target_mm", "cycle", "direction", "deviation_um"})
    if (!d.contains(k)) throw Error(fmt::format("runs: '{}' is missing", k));
  const auto target = py::cast<std::vector<double>>(d["target_mm"]);
  const auto cycle = py::cast<std::vector<long>>(d["cycle"]);
  const auto dev = py::cast<std::vector<double>>(d["deviation_um"]);
  std::vector<std::string> dir;
  for (auto x : py::iterable(d["direction"])) dir.push_back(py::str(x));
  std::vector<double> mat, air;
  if (d.contains("material_temp_c")) mat = py::cast<std::vector<double>>(d["material_temp_c"]);
  if (d.contains("air_temp_c")) air = py::cast<std::vector<double>>(d["air_temp_c"]);
  const std::size_t n = target.size();
  if (cycle.size() != n || dev.size() != n || dir.size() != n ||
      (!mat.empty() && mat.size() != n) || (!air.empty() && air.size() != n))
    throw Error("runs: every column needs one value per reading");
  std::vector<positioning::Reading> r(n);
  for (std::size_t k = 0; k < n; ++k) {
    if (cycle[k] < 1 || cycle[k] > 1000000)
      throw Error(fmt::format("runs: reading {}: cycle {} (cycles count from 1)", k, cycle[k]));
    r[k].target = target[k];
    r[k].cycle = static_cast<int>(cycle[k]);
    r[k].deviation = dev[k] * 1e-3;
    if (dir[k] == "+" || dir[k] == "up")
      r[k].direction = Direction::Up;
    else if (dir[k] == "-" || dir[k] == "down")
      r[k].direction = Direction::Down;
    else
      throw Error(fmt::format("runs: reading {}: direction '{}' (use '+' or '-')", k, dir[k]));
    if (!mat.empty()) r[k].material_temperature = mat[k];
    if (!air.empty()) r[k].air_temperature = air[k];
  }
  return r;
}

py::dict evaluate(const py::object& runs, const std::string& standard,
                  const std::map<std::string, double>& tolerance, double expansion,
                  std::optional<double> datum, bool temperature_correction, bool allow_incomplete,
                  const std::string& output, const std::string& run_directions) {
  if (standard != "iso230-2" && standard != "vdi3441")
    throw Error(fmt::format("standard '{}': use 'iso230-2' or 'vdi3441'", standard));
  std::vector<std::string> source_warnings;
  const auto readings = readings_in(runs, run_directions, &source_warnings);
  positioning::Options o;
  o.expansion_coefficient = expansion * 1e-6;
  if (datum) o.datum = *datum;
  o.correct_temperature = temperature_correction;
  o.allow_incomplete = allow_incomplete;
  positioning::Result r;
  {
    py::gil_scoped_release release;
    r = positioning::evaluate(readings, o);
  }
  r.warnings.insert(r.warnings.begin(), source_warnings.begin(), source_warnings.end());
  std::vector<std::pair<std::string, double>> tol;
  for (const auto& [k, v] : tolerance) tol.emplace_back(k, v * 1e-3);
  const auto verdicts = positioning::check(r, tol);
  const bool vdi = standard == "vdi3441";
  if (!output.empty())
    io::write_positioning_result(
        output, r, vdi ? positioning::Standard::Vdi3441 : positioning::Standard::Iso230_2,
        verdicts);
  py::dict d, t, tv;
  d["standard"] = vdi ? "VDI/DGQ 3441" : "ISO 230-2:2014";
  for (const auto& n : positioning::parameter_names())
    d[n.c_str()] = um(positioning::parameter(r, n));
  d["Ps_mean"] = um(r.vdi.Ps_mean);
  d["U_mean"] = um(r.vdi.U_mean);
  d["cycles"] = r.cycles;
  using T = positioning::Target;
  t["position"] = column(r.targets, &T::position, 1.0);
  t["mean_up"] = column(r.targets, &T::mean_up, 1e3);
  t["mean_down"] = column(r.targets, &T::mean_down, 1e3);
  t["s_up"] = column(r.targets, &T::s_up, 1e3);
  t["s_down"] = column(r.targets, &T::s_down, 1e3);
  t["mean"] = column(r.targets, &T::mean, 1e3);
  t["B"] = column(r.targets, &T::B, 1e3);
  t["R"] = column(r.targets, &T::R, 1e3);
  t["U"] = column(r.targets, &T::U, 1e3);
  t["Ps"] = column(r.targets, &T::Ps, 1e3);
  d["targets"] = t;  // arrays; NaN where not defined
  bool pass = true;
  for (const auto& v : verdicts) {
    py::dict e;
    e["limit"] = v.limit * 1e3;
    e["value"] = um(v.value);
    e["pass"] = v.pass;
    tv[v.name.c_str()] = e;
    pass = pass && v.pass;
  }
  d["tolerances"] = tv;
  d["pass"] = verdicts.empty() ? py::object(py::none()) : py::object(py::bool_(pass));
  d["temperature_corrected"] = r.temperature_corrected;
  d["max_correction"] = r.max_correction * 1e3;
  d["warnings"] = r.warnings;
  d["summary"] = r.summary(vdi);
  savable(d, [r, vdi, verdicts](const std::string& path) {
    io::write_positioning_result(
        path, r, vdi ? positioning::Standard::Vdi3441 : positioning::Standard::Iso230_2, verdicts);
  });
  return d;
}

}  // namespace

void bind_positioning(py::module_& m) {
  m.def("positioning", &evaluate, py::arg("runs"), py::kw_only(), py::arg("standard") = "iso230-2",
        py::arg("tolerance") = std::map<std::string, double>{}, py::arg("expansion") = 11.5,
        py::arg("datum") = py::none(), py::arg("temperature_correction") = true,
        py::arg("allow_incomplete") = false, py::arg("output") = "",
        py::arg("run_directions") = "order",
        R"doc(Accuracy and repeatability of positioning of a linear axis by ISO 230-2:2014 or
VDI/DGQ 3441.

runs: a runs.csv path, a Renishaw .rtl file (each run's direction from the order it lists its
targets, or run_directions '+-' for odd runs '+', '-+', '+' or '-'), or a dict of sequences target_mm, cycle, direction ('+'/'-'),
deviation_um (actual - target), optionally material_temp_c (then deviations are corrected to
20 C with `expansion` in ppm/K about `datum` mm, default the lowest target) and air_temp_c.
tolerance: {'A': 12, 'R': 4, ...} in µm (the command line's --tolerance A=12,R=4). output: also
write positioning.json.

Returns a dict: 'A', 'A_up', 'A_down', 'E', 'E_up', 'E_down', 'M', 'R', 'R_up', 'R_down', 'B',
'B_mean', 'P', 'Pa', 'Ps', 'U', 'Ps_mean', 'U_mean' (µm; None where the runs do not define
them), 'targets' (arrays: position mm, mean_up, mean_down, s_up, s_down, mean, B, R, U, Ps µm),
'cycles', 'tolerances', 'pass', 'warnings', 'summary'.)doc");

  m.def(
      "simulate_positioning",
      [](const sim::Machine& machine, const std::string& axis, const std::vector<double>& targets,
         int cycles, double backlash, double noise, double drift, double growth,
         std::optional<std::pair<double, double>> temperature, double expansion,
         std::uint64_t seed) {
        if (axis != "x" && axis != "y" && axis != "z")
          throw Error(fmt::format("axis '{}': use 'x', 'y' or 'z'", axis));
        sim::PositioningRunOptions o;
        o.axis = axis[0] - 'x';
        o.targets = targets;
        o.cycles = cycles;
        o.backlash = backlash * 1e-3;
        o.noise = noise * 1e-3;
        o.drift = drift * 1e-3;
        o.growth = growth * 1e-3;
        if (temperature) {
          o.temperature_start = temperature->first;
          o.temperature_end = temperature->second;
        }
        o.expansion_coefficient = expansion * 1e-6;
        o.seed = seed;
        const auto run = sim::simulate_positioning(machine, o);
        const std::size_t n = run.readings.size();
        Eigen::VectorXd target(static_cast<Eigen::Index>(n)), dev(static_cast<Eigen::Index>(n)),
            mat(static_cast<Eigen::Index>(n));
        Eigen::VectorXi cycle(static_cast<Eigen::Index>(n));
        py::list dir;
        for (std::size_t k = 0; k < n; ++k) {
          const auto i = static_cast<Eigen::Index>(k);
          target[i] = run.readings[k].target;
          dev[i] = run.readings[k].deviation * 1e3;
          mat[i] = run.readings[k].material_temperature;
          cycle[i] = run.readings[k].cycle;
          dir.append(run.readings[k].direction == Direction::Up ? "+" : "-");
        }
        py::dict d, truth;
        d["target_mm"] = target;
        d["cycle"] = cycle;
        d["direction"] = dir;
        d["deviation_um"] = dev;
        if (temperature) d["material_temp_c"] = mat;
        truth["target_mm"] = run.targets;
        truth["geometric_um"] = Eigen::VectorXd(run.geometric * 1e3);
        truth["up_um"] = Eigen::VectorXd(run.up * 1e3);
        truth["down_um"] = Eigen::VectorXd(run.down * 1e3);
        return py::make_tuple(d, truth);
      },
      py::arg("machine"), py::kw_only(), py::arg("axis") = "x", py::arg("targets"),
      py::arg("cycles") = 5, py::arg("backlash") = 0.0, py::arg("noise") = 0.0,
      py::arg("drift") = 0.0, py::arg("growth") = 0.0, py::arg("temperature") = py::none(),
      py::arg("expansion") = 11.5, py::arg("seed") = 1,
      R"doc(Virtual laser runs (ISO 230-2 test cycle) on one axis of a Machine.

targets in mm; backlash, noise (standard deviation), drift (over the test) in µm; growth in µm
per metre reached at the end; temperature (T0, T1) a material temperature ramp in C with
`expansion` ppm/K. Returns (runs, truth): runs is the dict trueaxis.positioning() reads, truth
has target_mm, geometric_um, up_um, down_um (noise-free means at 20 C).)doc");
}

}  // namespace trueaxis::python
