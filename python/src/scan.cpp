// Python bindings for design data and error-tolerant scanning on the virtual CMM (after JP 6484108
// B2).
#include "trueaxis/io/scan/scan.hpp"

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "trueaxis/design/design.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/design/design.hpp"
#include "trueaxis/io/sim/machine.hpp"
#include "trueaxis/scan/controller.hpp"

namespace py = pybind11;

namespace trueaxis::python {
namespace {

py::dict times(const scan::MachineTime& t) {
  py::dict d;
  d["total"] = t.total;
  d["design"] = t.design;
  d["touch"] = t.touch;
  d["autonomous"] = t.autonomous;
  d["moves"] = t.moves;
  return d;
}

py::dict run_scan(const std::string& design, const std::string& part, const std::string& strategy,
                  double tolerance, int max_autonomous, double tip_radius, double pushing,
                  bool passive, double probe_noise, std::uint64_t seed,
                  const std::string& corrected_design, const std::string& machine) {
  scan::ControllerOptions o;
  o.strategy = scan::strategy_from_string(strategy);
  o.tolerance = tolerance;
  o.max_autonomous = max_autonomous;
  o.path.tip_radius = tip_radius;
  o.path.pushing = pushing;
  o.active = !passive;
  o.validate();
  const design::Design d = io::read_design(design);
  const sim::Part p = io::read_part(part);
  scan::VirtualCmmOptions vo;
  vo.probe.tip_radius = tip_radius;
  vo.probe.noise = probe_noise * 1e-3;
  vo.probe.seed = seed;
  vo.probe.range = std::max(1.0, 3 * pushing);
  if (!machine.empty()) vo.geometry = io::read_machine(machine);
  const auto smp = design::sample(d.sections.front(), 1.0);
  scan::Result r;
  std::vector<std::vector<double>> truth;
  std::optional<Eigen::Vector3d> origin;  // with geometric errors: where the part stood
  {
    py::gil_scoped_release release;
    scan::VirtualCmm cmm(p, vo, smp.points.col(0) + (tip_radius + 20) * smp.normals.col(0));
    r = scan::scan(cmm, d, o);
    if (vo.geometry) origin = cmm.part_origin();
    for (std::size_t i = 0; i < r.sections.size(); ++i) {
      std::vector<double> t;
      for (const auto& x : r.sections[i].points)
        t.push_back(cmm.distance(r.planned.sections[i], x.surface) * 1e3);
      truth.push_back(std::move(t));
    }
  }
  if (!corrected_design.empty()) io::write_design(corrected_design, r.design);
  py::list sections;
  for (std::size_t i = 0; i < r.sections.size(); ++i) {
    const auto& s = r.sections[i];
    const Eigen::Index n = static_cast<Eigen::Index>(s.points.size());
    Eigen::MatrixX3d pts(n, 3), nrm(n, 3);
    Eigen::VectorXd t(n);
    for (Eigen::Index k = 0; k < n; ++k) {
      pts.row(k) = s.points[static_cast<std::size_t>(k)].surface.transpose();
      nrm.row(k) = s.points[static_cast<std::size_t>(k)].normal.transpose();
      t[k] = s.points[static_cast<std::size_t>(k)].t;
    }
    py::list corr;
    for (const auto& c : s.corrections) {
      py::dict cd, params;
      for (const auto& [k, v] : c.parameters) params[py::str(k)] = v;
      cd["type"] = c.type;
      cd["parameters"] = params;
      cd["accepted"] = c.accepted;
      cd["residual_before_mm"] = c.residual_before;
      if (c.diverged.empty()) {
        cd["residual_after_mm"] = c.residual_after;
      } else {
        cd["residual_after_mm"] = py::none();  // never applied: the fit diverged
        cd["diverged"] = c.diverged;
      }
      if (!c.found_on.empty()) cd["found_on"] = c.found_on;  // carried over from that section
      corr.append(cd);
    }
    py::dict sd;
    sd["name"] = s.name;
    sd["status"] = s.status();
    sd["reason"] = s.reason;
    sd["machine_time_s"] = times(s.time);
    sd["corrections"] = corr;
    sd["autonomous_count"] = s.autonomous_count;
    sd["trajectory_errors"] = s.trajectory_errors;
    sd["points"] = pts;
    sd["normals"] = nrm;
    sd["t"] = t;
    sd["truth_um"] = Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(
        truth[i].data(), static_cast<Eigen::Index>(truth[i].size())));
    sections.append(sd);
  }
  const Eigen::Index ne = static_cast<Eigen::Index>(r.events.size());
  Eigen::VectorXd et(ne), arc(ne), dl(ne);
  std::vector<std::string> sec, mode, ev, dec;
  for (Eigen::Index k = 0; k < ne; ++k) {
    const auto& e = r.events[static_cast<std::size_t>(k)];
    et[k] = e.t;
    arc[k] = e.arc;
    dl[k] = e.delta_l;
    sec.push_back(e.section);
    mode.push_back(e.mode);
    ev.push_back(e.event);
    dec.push_back(e.decision);
  }
  py::dict events;
  events["t"] = et;
  events["section"] = sec;
  events["arc_mm"] = arc;
  events["delta_l_mm"] = dl;
  events["mode"] = mode;
  events["event"] = ev;
  events["decision"] = dec;
  py::dict out;
  out["ok"] = r.ok();
  out["summary"] = r.summary();
  out["machine_time_s"] = times(r.time);
  out["sections"] = sections;
  out["events"] = events;
  io::ScanCmm cmm_record;
  cmm_record.tip_radius = tip_radius;
  cmm_record.probe_noise_um = probe_noise;
  if (vo.geometry) cmm_record.machine = vo.geometry->name.empty() ? machine : vo.geometry->name;
  cmm_record.part_origin = origin;
  savable(out,
          [r, o, cmm_record](const std::string& path) { io::write_scan(path, r, o, cmm_record); });
  return out;
}

}  // namespace

void bind_scan(py::module_& m) {
  m.def("scan", &run_scan, py::arg("design"), py::arg("part"), py::kw_only(),
        py::arg("strategy") = "error-tolerant", py::arg("tolerance") = 1.5,
        py::arg("max_autonomous") = 3, py::arg("tip_radius") = 1.0, py::arg("pushing") = 0.3,
        py::arg("passive") = false, py::arg("probe_noise") = 0.0, py::arg("seed") = 1,
        py::arg("corrected_design") = "", py::arg("machine") = "",
        "Scan a simulated part (part.json) along its design data (design.json) on the virtual "
        "CMM, as 'trueaxis scan' does. Returns a dict: ok, summary, machine_time_s, sections "
        "(each with points and normals as (n, 3) arrays in mm, t in s, truth_um: each point's "
        "distance from the simulated part, corrections, counts) and events (arrays: t, section, "
        "arc_mm, delta_l_mm, mode, event, decision). corrected_design: a design.json to write "
        "for the next part of the batch. machine: a machine.json whose 21 geometric errors the "
        "CMM has (the part centred in its travel). probe_noise: the probe's noise, standard "
        "deviation in µm (the command line's --probe-noise).");
}

}  // namespace trueaxis::python
