// Python bindings: numpy arrays in and out, in the units of trueaxis' files (x in mm,
// deviations in µm, angles in µrad). trueaxis::Error becomes trueaxis.Error (a ValueError).
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/geometry/straightness.hpp"
#include "trueaxis/io/separation/probes.hpp"
#include "trueaxis/separation/separation.hpp"
#include "trueaxis/sim/straightness.hpp"

namespace py = pybind11;
using namespace trueaxis;
using trueaxis::python::savable;

namespace {

py::dict profile(const separation::Profile& p, double scale) {
  py::dict d;
  d["x"] = Eigen::VectorXd(p.x);
  d["value"] = Eigen::VectorXd(p.value * scale);
  if (p.uncertainty.size())
    d["uncertainty"] = Eigen::VectorXd(p.uncertainty * scale);
  else
    d["uncertainty"] = py::none();
  return d;
}

py::dict separate(const Eigen::VectorXd& x, const Eigen::MatrixXd& readings,
                  std::optional<std::vector<double>> offsets, const std::string& method,
                  std::optional<Eigen::VectorXd> angle, std::optional<double> zero_difference,
                  const std::string& reference, std::optional<double> sigma, double angle_sigma,
                  bool invert, double filter_cutoff) {
  separation::ProbeData d;
  d.x = x;
  d.readings = readings * (invert ? -1e-3 : 1e-3);
  if (readings.rows() != x.size())
    throw Error("readings must have one row per station (shape (len(x), probes))");
  if (offsets) {
    d.offsets = *offsets;
  } else {
    const double h =
        x.size() > 1 ? (x[x.size() - 1] - x[0]) / static_cast<double>(x.size() - 1) : 1.0;
    for (Eigen::Index i = 0; i < readings.cols(); ++i)
      d.offsets.push_back(static_cast<double>(i) * h);
    d.offsets_assumed = true;  // the result's warnings say so
  }
  if (angle) d.angle = *angle * 1e-6;
  separation::Options o;
  o.method = separation::method_from_string(method);
  o.reference = separation::reference_from_string(reference);
  if (zero_difference) o.zero_difference = *zero_difference * 1e-3;
  if (sigma) o.sigma = *sigma * 1e-3;
  o.angle_sigma = angle_sigma * 1e-6;
  o.filter_cutoff = filter_cutoff;
  separation::Result r;
  {
    py::gil_scoped_release release;
    r = separation::separate(d, o);
  }
  py::dict out;
  out["method"] = separation::to_string(r.method);
  out["reference"] = separation::to_string(r.reference);
  out["gauge"] = r.gauge;
  out["unobservable"] = r.unobservable;
  out["workpiece"] = profile(r.workpiece, 1e3);
  out["guide"] = profile(r.guide, 1e3);
  out["pitch"] = r.pitch ? py::object(profile(*r.pitch, 1e6)) : py::object(py::none());
  // Each figure with its expanded uncertainty (95 %) and whether the data resolve it; None when
  // no uncertainty can be stated, the reason in 'no_uncertainty'.
  const auto figure = [](const separation::Straightness& st) {
    py::dict d;
    d["ls"] = st.ls * 1e3;
    d["min_zone"] = st.min_zone * 1e3;
    d["U_um"] = st.U ? py::object(py::float_(*st.U * 1e3)) : py::object(py::none());
    d["resolved"] = st.resolved() ? py::object(py::bool_(*st.resolved())) : py::object(py::none());
    return d;
  };
  py::dict s;
  s["workpiece"] = figure(r.workpiece_straightness);
  s["guide"] = figure(r.guide_straightness);
  out["straightness"] = s;
  out["sigma"] = r.sigma ? py::object(py::float_(*r.sigma * 1e3)) : py::object(py::none());
  out["no_uncertainty"] =
      r.no_uncertainty.empty() ? py::object(py::none()) : py::object(py::str(r.no_uncertainty));
  out["sigma_estimated"] = r.sigma_estimated;
  out["dof"] = r.dof;
  out["offsets"] = r.offsets;
  out["offsets_assumed"] = r.offsets_assumed;
  out["warnings"] = r.warnings();
  out["summary"] = r.summary();
  savable(out, [r](const std::string& path) { io::write_result(path, r); });
  return out;
}

py::dict simulate_straightness(long stations, double step, std::vector<double> offsets,
                               double noise, double pitch, double workpiece, double guide,
                               bool angle, double angle_noise, std::uint64_t seed) {
  sim::StraightnessOptions o;
  o.stations = stations;
  o.step = step;
  o.offsets = std::move(offsets);
  o.noise = noise * 1e-3;
  o.pitch_amplitude = pitch * 1e-6;
  o.workpiece_amplitude = workpiece * 1e-3;
  o.guide_amplitude = guide * 1e-3;
  o.angle = angle;
  o.angle_noise = angle_noise * 1e-6;
  o.seed = seed;
  const auto c = sim::simulate_straightness(o);
  py::dict d, t;
  d["x"] = c.data.x;
  d["readings"] = Eigen::MatrixXd(c.data.readings * 1e3);
  d["offsets"] = c.data.offsets;
  d["angle"] = c.data.angle.size() ? py::object(py::cast(Eigen::VectorXd(c.data.angle * 1e6)))
                                   : py::object(py::none());
  t["x"] = c.truth.x;
  t["workpiece"] = Eigen::VectorXd(c.truth.workpiece * 1e3);
  t["guide"] = Eigen::VectorXd(c.truth.guide * 1e3);
  t["pitch"] = Eigen::VectorXd(c.truth.pitch * 1e6);
  d["truth"] = t;
  return d;
}

}  // namespace

PYBIND11_MODULE(_trueaxis, m) {
  m.doc() = "trueaxis: geometric error separation and compensation (C++ core)";
  static py::exception<Error> exc(m, "Error", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Error& e) {
      exc(e.what());
    }
  });
  m.def("separate", &separate, py::arg("x"), py::arg("readings"), py::kw_only(),
        py::arg("offsets") = py::none(), py::arg("method") = "lsq", py::arg("angle") = py::none(),
        py::arg("zero_difference") = py::none(), py::arg("reference") = "ls",
        py::arg("sigma") = py::none(), py::arg("angle_sigma") = 1.0, py::arg("invert") = false,
        py::arg("filter_cutoff") = 0.0,
        R"doc(Straightness error separation with displacement probes (two-point, three-point after
JPH0464003B2, or least squares).

x: station positions (mm, equal steps); readings: array (stations, probes) in µm; offsets: probe
offsets from the first probe in mm (default 0, h, 2h, ...); method: 'two-point', 'three-point' or
'lsq'; angle: pitch channel in µrad (lsq); zero_difference: µm; reference: 'ls', 'patent' or
'min-zone'; sigma: probe noise in µm; angle_sigma: µrad.

Returns a dict with 'workpiece', 'guide' and 'pitch' (each {'x', 'value', 'uncertainty'}; µm or
µrad), 'straightness', 'unobservable', 'gauge', 'summary'. Raises trueaxis.Error on bad input or
an unobservable layout.)doc");
  m.def(
      "simulate_straightness", &simulate_straightness, py::kw_only(), py::arg("stations") = 201,
      py::arg("step") = 10.0, py::arg("offsets") = std::vector<double>{0, 10, 20},
      py::arg("noise") = 0.0, py::arg("pitch") = 5.0, py::arg("workpiece") = 5.0,
      py::arg("guide") = 3.0, py::arg("angle") = false, py::arg("angle_noise") = 0.0,
      py::arg("seed") = 1,
      "Seeded virtual carriage: returns {'x', 'readings' (µm), 'offsets', 'angle' (µrad) or None, "
      "'truth': {'x', 'workpiece', 'guide', 'pitch'}}.");
  m.def(
      "straightness",
      [](const Eigen::VectorXd& x, const Eigen::VectorXd& values) {
        py::dict d;
        d["ls"] = geometry::ls_straightness(x, values * 1e-3) * 1e3;
        d["min_zone"] = geometry::min_zone(x, values * 1e-3).width * 1e3;
        return d;
      },
      py::arg("x"), py::arg("values"),
      "Least-squares and minimum-zone straightness (µm) of a profile (x in mm, values in µm).");
  m.def(
      "analyze_layout",
      [](const std::vector<long>& steps, bool angle, bool zero_difference, long stations) {
        const auto a = separation::analyze_layout(steps, angle, zero_difference, stations);
        py::dict d;
        d["observable"] = a.observable;
        d["unobservable"] = a.unobservable;
        d["extra_null_modes"] = a.extra_null_modes;
        d["pitch_modelled"] = a.pitch_modelled;
        d["message"] = a.message;
        return d;
      },
      py::arg("steps"), py::kw_only(), py::arg("angle") = false, py::arg("zero_difference") = false,
      py::arg("stations") = 201,
      R"doc(What a probe layout can determine, before measuring.

steps: probe offsets in whole carriage steps (e.g. [0, 2, 3, 5]); angle: an angle channel is
present; zero_difference: the probes' zero difference is known. Returns {'observable',
'unobservable' (names of the undetermined modes), 'extra_null_modes', 'pitch_modelled',
'message' (why, when not observable)}.)doc");
  trueaxis::python::bind_space(m);
  trueaxis::python::bind_guideway(m);
  trueaxis::python::bind_fit(m);
  trueaxis::python::bind_ballgauge(m);
  trueaxis::python::bind_scan(m);
  trueaxis::python::bind_positioning(m);
  trueaxis::python::bind_results(m);
  trueaxis::python::bind_export(m);
  trueaxis::python::bind_design(m);
  trueaxis::python::bind_circular(m);
  trueaxis::python::bind_acceptance(m);
  trueaxis::python::bind_records(m);
}
