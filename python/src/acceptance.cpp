// Python bindings for the CMM acceptance tests (ISO 10360-2 and -5): trueaxis.acceptance_e0,
// trueaxis.acceptance_probing and trueaxis.acceptance_setup, with the command line's units.
#include "trueaxis/acceptance/acceptance.hpp"

#include <fmt/format.h>
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <memory>
#include <optional>
#include <variant>

#include "bindings.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/acceptance/acceptance.hpp"
#include "trueaxis/ippdme/acceptance.hpp"
#include "trueaxis/ippdme/client.hpp"
#include "trueaxis/ippdme/remote_cmm.hpp"
#include "trueaxis/sim/machine.hpp"

namespace py = pybind11;

namespace trueaxis::python {
namespace {

using Offset = std::optional<std::variant<double, std::vector<double>>>;

// A stylus offset given as L (mm, along +X) or [x, y, z].
std::optional<Eigen::Vector3d> lateral(const Offset& o) {
  if (!o) return std::nullopt;
  Eigen::Vector3d v;
  if (const double* l = std::get_if<double>(&*o)) {
    v = Eigen::Vector3d(*l, 0, 0);
  } else {
    const auto& xyz = std::get<std::vector<double>>(*o);
    if (xyz.size() != 3) throw Error("stylus_offset: L (mm, along +X) or [x, y, z]");
    v = Eigen::Vector3d(xyz[0], xyz[1], xyz[2]);
  }
  acceptance::validate_stylus_offset(v);
  return v;
}

// Where the test runs: the virtual CMM of `machine` in process, or a CMM over I++ DME (`cmm`,
// ipp://HOST:PORT) whose travel is `machine`'s or `travel` [x0, y0, z0, x1, y1, z1].
struct Runner {
  acceptance::Volume volume;
  std::unique_ptr<ippdme::RemoteCmm> remote;
  acceptance::Touch touch;
};

std::unique_ptr<Runner> runner(const std::optional<sim::Machine>& machine,
                               const std::optional<std::string>& cmm,
                               const std::optional<std::vector<double>>& travel, double clearance,
                               const std::string& log, const std::optional<Eigen::Vector3d>& offset,
                               const acceptance::Setup& setup, double lobing, double noise,
                               std::uint64_t seed) {
  auto r = std::make_unique<Runner>();
  std::optional<sim::Machine> m = machine;
  if (m && offset) m = acceptance::with_stylus(*m, *offset);
  if (m) r->volume = acceptance::Volume::of(*m);
  if (!cmm) {
    if (!m) throw Error("give the machine (a trueaxis.Machine), or cmm='ipp://HOST:PORT'");
    acceptance::VirtualProbeOptions o;
    o.lobing = lobing * 1e-3;
    o.noise = noise * 1e-3;
    o.seed = seed;
    r->touch = acceptance::virtual_touch(*m, o);
    return r;
  }
  if (!m) {
    if (!travel || travel->size() != 6)
      throw Error("with cmm= give the machine or travel=[x0, y0, z0, x1, y1, z1] (mm, tip centre)");
    r->volume.low = Eigen::Vector3d((*travel)[0], (*travel)[1], (*travel)[2]);
    r->volume.high = Eigen::Vector3d((*travel)[3], (*travel)[4], (*travel)[5]);
    if (!(r->volume.high.array() > r->volume.low.array()).all())
      throw Error("travel: each high end must lie above its low end");
  }
  ippdme::RemoteCmmOptions ro;
  std::tie(ro.client.host, ro.client.port) = ippdme::parse_address(*cmm);
  ro.client.log = log;
  ro.tip_radius = 0;  // the server's tool
  r->remote = std::make_unique<ippdme::RemoteCmm>(ro);
  ippdme::AcceptanceProbingOptions po;
  po.clearance = clearance;
  r->touch = ippdme::acceptance_touch(*r->remote, setup, r->volume, po);
  return r;
}

py::list xyz(const Eigen::Vector3d& v) {
  return py::cast(std::vector<double>{v.x(), v.y(), v.z()});
}

}  // namespace

void bind_acceptance(py::module_& m) {
  m.def(
      "acceptance_setup",
      [](const sim::Machine& machine, const std::string& path, const Offset& stylus_offset) {
        const auto offset = lateral(stylus_offset);
        io::write_acceptance_setup(
            path, acceptance::example_setup(acceptance::Volume::of(
                      offset ? acceptance::with_stylus(machine, *offset) : machine)));
        return path;
      },
      py::arg("machine"), py::arg("path"), py::arg("stylus_offset") = py::none(),
      R"doc(Writes an ISO 10360-2 and -5 artefact set-up (acceptance.json) that fits the travel of a
trueaxis.Machine: 35 gauge blocks in the 7 positions (the 4 space diagonals, along X, Y and Z) and a
Ø25 mm reference sphere, as 'trueaxis examples' writes for the default machine; with stylus_offset
(mm: L along +X, or [x, y, 0]) in the volume that stylus reaches. Returns the path.)doc");

  m.def(
      "acceptance_e0",
      [](const std::optional<sim::Machine>& machine, const std::string& artefacts,
         const std::string& mpe, const std::optional<std::string>& r0_mpe,
         const Offset& stylus_offset, const std::vector<std::string>& positions, double lobing,
         double noise, std::uint64_t seed, const std::optional<std::string>& cmm,
         const std::optional<std::vector<double>>& travel, double clearance,
         const std::string& log) {
        acceptance::E0Options o;
        o.mpe = ballgauge::Mpe::parse(mpe);
        if (r0_mpe) o.r0 = ballgauge::Mpe::parse(*r0_mpe);
        o.stylus_offset = lateral(stylus_offset);
        o.positions = positions;
        const auto setup = io::read_acceptance_setup(artefacts);
        const auto run = runner(machine, cmm, travel, clearance, log, o.stylus_offset, setup,
                                lobing, noise, seed);
        std::shared_ptr<acceptance::E0Result> r;
        {
          py::gil_scoped_release unlocked;  // a run over I++ DME takes machine time
          r = std::make_shared<acceptance::E0Result>(
              acceptance::run_e0(setup, run->volume, run->touch, o));
        }
        py::dict d;
        d["kind"] = "acceptance-e0";
        d["test"] = r->name();
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
      py::arg("stylus_offset") = py::none(), py::arg("positions") = std::vector<std::string>{},
      py::arg("lobing") = 0.0, py::arg("noise") = 0.0, py::arg("seed") = 1, py::kw_only(),
      py::arg("cmm") = py::none(), py::arg("travel") = py::none(), py::arg("clearance") = 5.0,
      py::arg("log") = "",
      R"doc(The length measuring error test of ISO 10360-2 on the virtual CMM of a trueaxis.Machine,
or on a CMM over I++ DME (cmm='ipp://HOST:PORT'; its travel from the machine, or
travel=[x0, y0, z0, x1, y1, z1] in mm; clearance: mm kept from every artefact on a free move;
log: a file of every I++ line), as 'trueaxis acceptance e0'. artefacts: acceptance.json's path;
mpe: "A+L/K" (µm, L in mm); stylus_offset: E_L instead of E0 (mm: L along +X, or [x, y, 0];
150: E150), measured in `positions` (names; default the first two space diagonals); lobing,
noise: the virtual probe's (µm). Returns {'E0_max_um', 'R0_max_um', 'verdict'
('conforms', 'does not conform', 'not proven': ISO 14253-1 with the test's U), 'pass', 'rule',
'complete', 'lengths': [{'position', 'block', 'repetition', 'nominal_mm', 'measured_mm',
'error_um', 'mpe_um', 'U_um', 'endpoints'}], 'r0', 'summary'}; trueaxis.save() writes e0.json.)doc");

  m.def(
      "acceptance_probing",
      [](const std::optional<sim::Machine>& machine, const std::string& artefacts,
         std::optional<double> mpe_form, std::optional<double> mpe_size, double lobing,
         double noise, std::uint64_t seed, const std::optional<std::string>& cmm,
         const std::optional<std::vector<double>>& travel, double clearance,
         const std::string& log) {
        acceptance::ProbingOptions o;
        if (mpe_form) o.mpe_form = *mpe_form * 1e-3;
        if (mpe_size) o.mpe_size = *mpe_size * 1e-3;
        const auto setup = io::read_acceptance_setup(artefacts);
        const auto run =
            runner(machine, cmm, travel, clearance, log, std::nullopt, setup, lobing, noise, seed);
        std::shared_ptr<acceptance::ProbingResult> r;
        {
          py::gil_scoped_release unlocked;
          r = std::make_shared<acceptance::ProbingResult>(
              acceptance::run_probing(setup, run->touch, o));
        }
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
      py::arg("seed") = 1, py::kw_only(), py::arg("cmm") = py::none(),
      py::arg("travel") = py::none(), py::arg("clearance") = 5.0, py::arg("log") = "",
      R"doc(The probing test of ISO 10360-5 (25 points on the reference sphere) on the virtual CMM of a
trueaxis.Machine, or over I++ DME (cmm=, travel=, clearance=, log= as for acceptance_e0), as
'trueaxis acceptance probing'. mpe_form, mpe_size, lobing, noise in µm.
Returns {'PForm_um', 'PSize_um', 'diameter_mm', 'centre', 'form_verdict', 'size_verdict',
'points' (25 × 3, mm), 'radial_um', 'summary'}; trueaxis.save() writes probing.json.)doc");
}

}  // namespace trueaxis::python
