// Python bindings for the CMM acceptance tests (ISO 10360-2 and -5): trueaxis.acceptance_e0,
// trueaxis.acceptance_probing and trueaxis.acceptance_setup, with the command line's units.
#include "trueaxis/acceptance/acceptance.hpp"

#include <fmt/format.h>
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <memory>
#include <optional>

#include "bindings.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/acceptance/acceptance.hpp"
#include "trueaxis/sim/machine.hpp"

namespace py = pybind11;

namespace trueaxis::python {
namespace {

acceptance::Touch probe(const sim::Machine& m, double lobing, double noise, std::uint64_t seed) {
  acceptance::VirtualProbeOptions o;
  o.lobing = lobing * 1e-3;
  o.noise = noise * 1e-3;
  o.seed = seed;
  return acceptance::virtual_touch(m, o);
}

py::list xyz(const Eigen::Vector3d& v) {
  return py::cast(std::vector<double>{v.x(), v.y(), v.z()});
}

}  // namespace

void bind_acceptance(py::module_& m) {
  m.def(
      "acceptance_setup",
      [](const sim::Machine& machine, const std::string& path) {
        io::write_acceptance_setup(path,
                                   acceptance::example_setup(acceptance::Volume::of(machine)));
        return path;
      },
      py::arg("machine"), py::arg("path"),
      R"doc(Writes an ISO 10360-2 and -5 artefact set-up (acceptance.json) that fits the travel of a
trueaxis.Machine: 35 gauge blocks in the 7 positions (the 4 space diagonals, along X, Y and Z) and a
Ø25 mm reference sphere, as 'trueaxis examples' writes for the default machine. Returns the path.)doc");

  m.def(
      "acceptance_e0",
      [](const sim::Machine& machine, const std::string& artefacts, const std::string& mpe,
         const std::optional<std::string>& r0_mpe, std::optional<double> stylus_offset,
         double lobing, double noise, std::uint64_t seed) {
        acceptance::E0Options o;
        o.mpe = ballgauge::Mpe::parse(mpe);
        if (r0_mpe) o.r0 = ballgauge::Mpe::parse(*r0_mpe);
        o.stylus_offset = stylus_offset;
        const auto setup = io::read_acceptance_setup(artefacts);
        auto r = std::make_shared<acceptance::E0Result>(acceptance::run_e0(
            setup, acceptance::Volume::of(machine), probe(machine, lobing, noise, seed), o));
        py::dict d;
        d["kind"] = "acceptance-e0";
        d["mpe"] = r->mpe_text;
        d["E0_max_um"] = r->lengths.empty() ? py::object(py::none()) : py::float_(r->e0_max * 1e3);
        d["R0_max_um"] = r->r0.empty() ? py::object(py::none()) : py::float_(r->r0_max * 1e3);
        d["verdict"] = acceptance::to_string(r->verdict);
        d["pass"] = r->verdict == acceptance::Verdict::Conforms && r->r0_pass.value_or(true);
        d["rule"] = r->rule;
        d["complete"] = r->complete;
        if (!r->complete) d["stopped"] = r->stopped;
        py::list lengths;
        for (const auto& l : r->lengths) {
          py::dict one;
          one["position"] = l.position;
          one["block"] = l.block;
          one["repetition"] = l.repetition;
          one["nominal_mm"] = l.nominal;
          one["measured_mm"] = l.measured;
          one["error_um"] = l.error * 1e3;
          one["mpe_um"] = l.mpe * 1e3;
          one["U_um"] = l.U * 1e3;
          one["endpoints"] = py::make_tuple(xyz(l.a), xyz(l.b));
          lengths.append(one);
        }
        d["lengths"] = lengths;
        py::list r0;
        for (const auto& x : r->r0) {
          py::dict one;
          one["position"] = x.position;
          one["block"] = x.block;
          one["nominal_mm"] = x.nominal;
          one["range_um"] = x.range * 1e3;
          r0.append(one);
        }
        d["r0"] = r0;
        d["summary"] = r->summary();
        savable(d, [r](const std::string& path) { io::write_e0_result(path, *r); });
        return d;
      },
      py::arg("machine"), py::arg("artefacts"), py::arg("mpe"), py::arg("r0_mpe") = py::none(),
      py::arg("stylus_offset") = py::none(), py::arg("lobing") = 0.0, py::arg("noise") = 0.0,
      py::arg("seed") = 1,
      R"doc(The length measuring error test of ISO 10360-2 on the virtual CMM of a trueaxis.Machine,
as 'trueaxis acceptance e0'. artefacts: acceptance.json's path; mpe: "A+L/K" (µm, L in mm);
lobing, noise: the virtual probe's (µm). Returns {'E0_max_um', 'R0_max_um', 'verdict'
('conforms', 'does not conform', 'not proven': ISO 14253-1 with the test's U), 'pass', 'rule',
'complete', 'lengths': [{'position', 'block', 'repetition', 'nominal_mm', 'measured_mm',
'error_um', 'mpe_um', 'U_um', 'endpoints'}], 'r0', 'summary'}; trueaxis.save() writes e0.json.)doc");

  m.def(
      "acceptance_probing",
      [](const sim::Machine& machine, const std::string& artefacts, std::optional<double> mpe_form,
         std::optional<double> mpe_size, double lobing, double noise, std::uint64_t seed) {
        acceptance::ProbingOptions o;
        if (mpe_form) o.mpe_form = *mpe_form * 1e-3;
        if (mpe_size) o.mpe_size = *mpe_size * 1e-3;
        const auto setup = io::read_acceptance_setup(artefacts);
        auto r = std::make_shared<acceptance::ProbingResult>(
            acceptance::run_probing(setup, probe(machine, lobing, noise, seed), o));
        py::dict d;
        d["kind"] = "acceptance-probing";
        d["PForm_um"] = r->form * 1e3;
        d["PSize_um"] = r->size * 1e3;
        d["diameter_mm"] = r->diameter;
        d["centre"] = xyz(r->centre);
        d["form_verdict"] = r->form_verdict
                                ? py::object(py::str(acceptance::to_string(*r->form_verdict)))
                                : py::none();
        d["size_verdict"] = r->size_verdict
                                ? py::object(py::str(acceptance::to_string(*r->size_verdict)))
                                : py::none();
        d["points"] = Eigen::Matrix3Xd(r->points).transpose().eval();
        d["radial_um"] = Eigen::VectorXd(r->radial * 1e3);
        d["summary"] = r->summary();
        savable(d, [r](const std::string& path) { io::write_probing_result(path, *r); });
        return d;
      },
      py::arg("machine"), py::arg("artefacts"), py::arg("mpe_form") = py::none(),
      py::arg("mpe_size") = py::none(), py::arg("lobing") = 0.0, py::arg("noise") = 0.0,
      py::arg("seed") = 1,
      R"doc(The probing test of ISO 10360-5 (25 points on the reference sphere) on the virtual CMM of a
trueaxis.Machine, as 'trueaxis acceptance probing'. mpe_form, mpe_size, lobing, noise in µm.
Returns {'PForm_um', 'PSize_um', 'diameter_mm', 'centre', 'form_verdict', 'size_verdict',
'points' (25 × 3, mm), 'radial_um', 'summary'}; trueaxis.save() writes probing.json.)doc");
}

}  // namespace trueaxis::python
