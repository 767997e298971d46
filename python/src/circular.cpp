// Python bindings for the circular test (ISO 230-4): trueaxis.circular and
// trueaxis.simulate_circular, with the command line's units and names.
#include "trueaxis/circular/circular.hpp"

#include <fmt/format.h>
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <cstring>
#include <memory>
#include <optional>
#include <variant>

#include "bindings.hpp"
#include "trueaxis/circular/compensation.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/circular/circular.hpp"
#include "trueaxis/io/circular/compensation.hpp"
#include "trueaxis/sim/circular.hpp"

namespace py = pybind11;

namespace trueaxis::python {
namespace {

constexpr double kDegree = 3.14159265358979323846 / 180;

// A trace from a path, or from a dict of its columns (direction: 'ccw'/'cw' per sample, angle_deg,
// deviation_um).
circular::Trace trace_of(const std::variant<std::string, py::dict>& input,
                         const io::TimeSeriesOptions* series = nullptr) {
  if (const auto* path = std::get_if<std::string>(&input)) return io::read_trace(*path, series);
  const auto& d = std::get<py::dict>(input);
  for (const char* k : {"direction", "angle_deg", "deviation_um"})
    if (!d.contains(k))
      throw Error(
          fmt::format("trace: no '{}' (the trace has direction, angle_deg, deviation_um)", k));
  const auto dir = d["direction"].cast<py::sequence>();
  const auto angle = d["angle_deg"].cast<Eigen::VectorXd>();
  const auto dev = d["deviation_um"].cast<Eigen::VectorXd>();
  if (static_cast<Eigen::Index>(dir.size()) != angle.size() || angle.size() != dev.size())
    throw Error("trace: direction, angle_deg and deviation_um differ in length");
  circular::Trace t;
  t.direction.reserve(dir.size());
  // Compared in place, through the list's own item array when it is one: no string and no new
  // reference made per sample (10⁵ of them in a long trace).
  const py::object items = py::reinterpret_steal<py::object>(
      PySequence_Fast(dir.ptr(), "trace: direction must be a sequence"));
  if (!items) throw py::error_already_set();
  PyObject** item = PySequence_Fast_ITEMS(items.ptr());
  auto is = [](PyObject* o, const char* text, std::size_t size) {
    return PyUnicode_Check(o) && PyUnicode_KIND(o) == PyUnicode_1BYTE_KIND &&
           static_cast<std::size_t>(PyUnicode_GET_LENGTH(o)) == size &&
           std::memcmp(PyUnicode_1BYTE_DATA(o), text, size) == 0;
  };
  for (std::size_t k = 0; k < dir.size(); ++k) {
    if (is(item[k], "ccw", 3))
      t.direction.push_back(circular::Direction::Ccw);
    else if (is(item[k], "cw", 2))
      t.direction.push_back(circular::Direction::Cw);
    else
      throw Error(fmt::format("trace: direction[{}] = {}: use 'ccw' or 'cw'", k,
                              py::repr(py::handle(item[k])).cast<std::string>()));
  }
  t.angle = angle * kDegree;
  t.deviation = dev * 1e-3;
  return t;
}

// The result and its trace are shared with the save function, not copied (a 10⁵-sample trace
// and its model are megabytes).
py::dict result_dict(std::shared_ptr<const circular::Result> rp,
                     std::shared_ptr<const circular::Trace> tp) {
  const circular::Result& r = *rp;
  py::dict d, g, f;
  for (const auto* x : {&r.ccw, &r.cw}) {
    if (!x->present) continue;
    const char* name = x == &r.ccw ? "ccw" : "cw";
    g[name] = x->G * 1e3;
    py::dict mm;
    mm["min"] = x->F_min * 1e3;
    mm["max"] = x->F_max * 1e3;
    f[name] = mm;
  }
  d["G_um"] = g;
  d["F_um"] = f;
  d["H_um"] = r.H ? py::cast(*r.H * 1e3) : py::none();
  py::dict causes;
  for (const auto& c : r.causes) {
    py::dict one;
    one["name"] = c.name;
    one["unit"] = c.unit;
    one["value"] = c.separated && std::isfinite(c.value) ? py::cast(c.value) : py::none();
    one["u"] = c.separated && c.u ? py::cast(*c.u) : py::none();
    one["share"] = c.share;
    one["separated"] = c.separated;
    if (!c.separated) one["not_separated_from"] = c.confused_with;
    causes[py::str(c.key)] = one;
  }
  d["diagnosis"] = causes;
  d["unexplained_rms_um"] = r.unexplained_rms * 1e3;
  d["spike_decay_deg"] = r.spike_decay / kDegree;
  d["spike_decay_u_deg"] =
      r.spike_decay_u ? py::object(py::float_(*r.spike_decay_u / kDegree)) : py::object(py::none());
  if (!r.spike_decay_u) d["spike_decay_note"] = r.spike_decay_note;
  d["reversal_delay_resolution_deg"] = r.reversal_delay_resolution / kDegree;
  py::dict delay;
  delay[py::str(std::string(1, "XYZ"[r.plane.a]))] = r.reversal_delay[0] / kDegree;
  delay[py::str(std::string(1, "XYZ"[r.plane.b]))] = r.reversal_delay[1] / kDegree;
  d["reversal_delay_deg"] = delay;
  d["model_um"] = Eigen::VectorXd(r.model * 1e3);
  d["residual_um"] = Eigen::VectorXd(r.residual * 1e3);
  d["warnings"] = r.warnings;
  d["summary"] = r.summary();
  savable(d, [rp, tp](const std::string& path) { io::write_circular_result(path, *rp, tp.get()); });
  return d;
}

}  // namespace

void bind_circular(py::module_& m) {
  m.def(
      "circular",
      [](const std::variant<std::string, py::dict>& trace, const std::string& plane, double radius,
         double feed, double spike_decay, std::optional<std::pair<double, double>> pitch,
         const std::optional<std::string>& compensation, std::pair<double, double> active_backlash,
         double active_squareness, std::optional<std::pair<double, double>> travel,
         double start_angle, const std::string& order) {
        io::TimeSeriesOptions series;
        series.feed = feed;
        series.radius = radius;
        series.start_angle = start_angle * kDegree;
        series.order = io::TimeSeriesOptions::order_of(order);
        auto tp = std::make_shared<const circular::Trace>(trace_of(trace, &series));
        const circular::Trace& t = *tp;
        circular::Options o;
        o.plane = circular::Plane::parse(plane);
        o.radius = radius;
        o.feed = feed;
        o.spike_decay = spike_decay * kDegree;
        if (pitch) {
          o.pitch_a = pitch->first;
          o.pitch_b = pitch->second;
        }
        std::shared_ptr<const circular::Result> rp;
        {
          py::gil_scoped_release release;
          rp = std::make_shared<const circular::Result>(circular::evaluate(t, o));
        }
        const circular::Result& r = *rp;
        py::dict d = result_dict(rp, tp);
        if (compensation) {
          circular::CompensationOptions co;
          co.active_backlash = {active_backlash.first * 1e-3, active_backlash.second * 1e-3};
          co.active_squareness = active_squareness * 1e-6;
          io::CompensationFilesOptions fo;
          if (travel) fo.travel = std::array<double, 2>{travel->first, travel->second};
          const auto c = circular::compensation_from(r, co);
          const auto files = io::write_compensation_files(*compensation, c, fo);
          py::dict cd, backlash;
          const char* axes = "XYZ";
          backlash[py::str(std::string(1, axes[o.plane.a]))] = c.backlash[0].value * 1e3;
          backlash[py::str(std::string(1, axes[o.plane.b]))] = c.backlash[1].value * 1e3;
          cd["backlash_um"] = backlash;
          cd["squareness_um_per_m"] = c.squareness.value * 1e6;
          std::vector<std::string> written;
          for (const auto& w : files.written) written.push_back(w.path);
          cd["files"] = written;
          cd["json"] = files.json_path;
          cd["summary"] = c.summary();
          d["compensation"] = cd;
        }
        return d;
      },
      py::arg("trace"), py::kw_only(), py::arg("plane") = "XY", py::arg("radius") = 100.0,
      py::arg("feed") = 1000.0, py::arg("spike_decay") = 0.0, py::arg("pitch") = py::none(),
      py::arg("compensation") = py::none(),
      py::arg("active_backlash") = std::pair<double, double>{0, 0},
      py::arg("active_squareness") = 0.0, py::arg("travel") = py::none(),
      py::arg("start_angle") = 0.0, py::arg("order") = "ccw,cw",
      R"doc(A circular test with a telescoping ballbar (ISO 230-4), as 'trueaxis circular'.

trace: trace.csv's path (or a raw time series t_s, deviation_um: its runs in `order`, each
starting at `start_angle` degrees, turned into angles with feed and radius), or a dict {'direction': ['ccw' | 'cw', ...], 'angle_deg': [...],
'deviation_um': [...]} (what simulate_circular returns). plane 'XY', 'YZ' or 'ZX'; radius (mm,
the ballbar's calibrated length); feed (mm/min); spike_decay (degrees; 0: found from the data);
pitch: (first, second) ball screw pitches (mm) to fit cyclic errors of. Returns {'G_um': {'ccw',
'cw'}, 'F_um': {'ccw': {'min', 'max'}, ...}, 'H_um', 'diagnosis': {key: {'name', 'unit',
'value', 'u', 'share', 'separated'}} (value and u None where the data cannot tell the cause
from another, named in 'not_separated_from'), 'unexplained_rms_um', 'spike_decay_deg' and
'spike_decay_u_deg' (None, with 'spike_decay_note', when given or not resolved),
'reversal_delay_deg' per axis and 'reversal_delay_resolution_deg' (the samples' spacing),
'model_um', 'residual_um' (per sample), 'warnings', 'summary'}. trueaxis.save() writes
circular.json. compensation: a folder to write the backlash and squareness compensation to for
LinuxCNC, HEIDENHAIN, FANUC and Siemens, as 'trueaxis circular --compensation' (with
active_backlash (µm, first and second axis) and active_squareness (µm/m) in force during the test,
travel (low, high) of the second axis in mm for the squareness tables); the result then has
'compensation': {'backlash_um', 'squareness_um_per_m', 'files', 'json', 'summary'}.)doc");

  m.def(
      "simulate_circular",
      [](const sim::Machine& machine, const std::string& plane, double radius, double feed,
         std::optional<std::vector<double>> centre, double arc, double overshoot,
         const std::string& directions, const std::optional<std::string>& servo,
         std::vector<double> pivot_offset, double length_error, double drift, double noise,
         double sample_rate, std::uint64_t seed, const std::optional<std::string>& compensation) {
        sim::CircularOptions o;
        o.plane = circular::Plane::parse(plane);
        o.radius = radius;
        o.feed = feed;
        if (centre) {
          if (centre->size() != 3) throw Error("centre needs [x, y, z] (mm)");
          o.centre = {(*centre)[0], (*centre)[1], (*centre)[2]};
        }
        o.arc = arc * kDegree;
        o.overshoot = overshoot * kDegree;
        if (directions != "both" && directions != "ccw" && directions != "cw")
          throw Error(fmt::format("directions '{}': use 'both', 'ccw' or 'cw'", directions));
        o.ccw = directions != "cw";
        o.cw = directions != "ccw";
        if (servo) o.servo = io::read_servo(*servo);
        if (compensation) {
          io::read_compensation_json(*compensation).apply(o);
        }
        if (pivot_offset.size() != 3) throw Error("pivot_offset needs [x, y, z] (µm)");
        o.pivot_offset = Eigen::Vector3d(pivot_offset[0], pivot_offset[1], pivot_offset[2]) * 1e-3;
        o.length_error = length_error * 1e-3;
        o.drift = drift * 1e-3;
        o.noise = noise * 1e-3;
        o.sample_rate = sample_rate;
        o.seed = seed;
        sim::CircularRun run;
        {
          py::gil_scoped_release release;
          run = sim::simulate_circular(machine, o);
        }
        py::dict trace, truth;
        std::vector<std::string> dir;
        for (const auto d : run.trace.direction)
          dir.push_back(d == circular::Direction::Ccw ? "ccw" : "cw");
        trace["direction"] = dir;
        trace["angle_deg"] = Eigen::VectorXd(run.trace.angle / kDegree);
        trace["deviation_um"] = Eigen::VectorXd(run.trace.deviation * 1e3);
        trace["t_s"] = run.time;
        const auto t = sim::circular_truth(machine, o);
        const std::string A(1, "XYZ"[o.plane.a]), B(1, "XYZ"[o.plane.b]);
        py::dict centre_offset, backlash, spike;
        centre_offset[py::str(A)] = t.centre_offset.x() * 1e3;
        centre_offset[py::str(B)] = t.centre_offset.y() * 1e3;
        backlash[py::str(A)] = t.backlash[0] * 1e3;
        backlash[py::str(B)] = t.backlash[1] * 1e3;
        spike[py::str(A)] = t.spike[0] * 1e3;
        spike[py::str(B)] = t.spike[1] * 1e3;
        truth["centre_offset_um"] = centre_offset;
        truth["squareness_um_per_m"] = t.squareness * 1e6;
        truth["scale_mismatch_um_per_m"] = t.scale_mismatch * 1e6;
        truth["lag_mismatch_ms"] = t.lag_mismatch * 1e3;
        truth["backlash_um"] = backlash;
        truth["reversal_spike_um"] = spike;
        return py::make_tuple(trace, truth);
      },
      py::arg("machine"), py::kw_only(), py::arg("plane") = "XY", py::arg("radius") = 100.0,
      py::arg("feed") = 1000.0, py::arg("centre") = py::none(), py::arg("arc") = 360.0,
      py::arg("overshoot") = 180.0, py::arg("directions") = "both", py::arg("servo") = py::none(),
      py::arg("pivot_offset") = std::vector<double>{0, 0, 0}, py::arg("length_error") = 0.0,
      py::arg("drift") = 0.0, py::arg("noise") = 0.0, py::arg("sample_rate") = 100.0,
      py::arg("seed") = 1, py::arg("compensation") = py::none(),
      R"doc(A circular test with a ballbar on a trueaxis.Machine, as 'trueaxis simulate circular'.

plane, radius (mm), feed (mm/min), centre [x, y, z] (mm; default mid-range), arc and overshoot
(degrees), directions 'both' | 'ccw' | 'cw', servo: a servo.json path (per axis gain, backlash,
spikes, cyclic error), pivot_offset [x, y, z], length_error, drift, noise (µm), sample_rate (Hz),
seed, compensation: a compensation.json (from circular(..., compensation=...)) loaded in the
controller. Returns (trace, truth): trace is the dict trueaxis.circular() reads (with t_s), truth what
its diagnosis should find.)doc");
}

}  // namespace trueaxis::python
