// trueaxis CLI — CMM acceptance and reverification tests: 'acceptance e0' (ISO 10360-2) and
// 'acceptance probing' (ISO 10360-5).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <memory>
#include <optional>

#include "commands.hpp"
#include "progress.hpp"
#include "trueaxis/acceptance/acceptance.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/acceptance/acceptance.hpp"
#include "trueaxis/ippdme/acceptance.hpp"
#include "trueaxis/ippdme/remote_cmm.hpp"
#include "trueaxis/report/acceptance.hpp"
#include "trueaxis/sim/machine.hpp"

namespace trueaxis::cli {
namespace {

struct AcceptanceArgs {
  MachineSource machine;
  std::string cmm, log;
  std::vector<double> travel;
  double clearance = 5;
  std::string artefacts, output, report;
  std::string mpe, r0_mpe;
  double stylus_offset = 0;
  double mpe_form_um = 0, mpe_size_um = 0;
  double lobing_um = 0, noise_um = 0;
  std::uint64_t seed = 1;
  bool quiet = false;
};

// Where the test runs: the virtual CMM in process (--machine), or a CMM over I++ DME (--cmm),
// whose travel comes from --machine or --travel.
struct Cmm {
  acceptance::Volume volume;
  std::optional<sim::Machine> machine;
  std::unique_ptr<ippdme::RemoteCmm> remote;
  acceptance::Touch touch;
};

std::unique_ptr<Cmm> open_cmm(const AcceptanceArgs& a, const acceptance::Setup& setup) {
  auto c = std::make_unique<Cmm>();
  if (a.cmm.empty() || !a.machine.path.empty()) {
    c->machine = a.machine.load();
    c->volume = acceptance::Volume::of(*c->machine);
  }
  if (a.cmm.empty()) {
    acceptance::VirtualProbeOptions p;
    p.lobing = a.lobing_um * 1e-3;
    p.noise = a.noise_um * 1e-3;
    p.seed = a.seed;
    c->touch = acceptance::virtual_touch(*c->machine, p);
    return c;
  }
  if (!c->machine) {
    if (a.travel.size() != 6)
      throw CLI::ValidationError("--travel",
                                 "with --cmm give the travel: --travel X0,Y0,Z0,X1,Y1,Z1 (mm, tip "
                                 "centre) or --machine");
    c->volume.low = Eigen::Vector3d(a.travel[0], a.travel[1], a.travel[2]);
    c->volume.high = Eigen::Vector3d(a.travel[3], a.travel[4], a.travel[5]);
    if (!(c->volume.high.array() > c->volume.low.array()).all())
      throw CLI::ValidationError("--travel", "each high end must lie above its low end");
  }
  ippdme::RemoteCmmOptions ro;
  std::tie(ro.client.host, ro.client.port) = parse_ipp_address(a.cmm);
  ro.client.log = a.log;
  ro.tip_radius = 0;  // the server's tool
  c->remote = std::make_unique<ippdme::RemoteCmm>(ro);
  ippdme::AcceptanceProbingOptions po;
  po.clearance = a.clearance;
  c->touch = ippdme::acceptance_touch(*c->remote, setup, c->volume, po);
  return c;
}

int run_e0(const AcceptanceArgs& a) {
  acceptance::E0Options o;
  o.mpe = ballgauge::Mpe::parse(a.mpe);
  if (!a.r0_mpe.empty()) o.r0 = ballgauge::Mpe::parse(a.r0_mpe);
  if (a.stylus_offset > 0) o.stylus_offset = a.stylus_offset;
  const auto setup = io::read_acceptance_setup(a.artefacts);
  const auto cmm = open_cmm(a, setup);
  Progress progress("measuring the lengths", a.quiet);
  o.progress = [&](std::size_t done, std::size_t total) {
    progress.update(static_cast<double>(done) / static_cast<double>(total));
  };
  const auto r = acceptance::run_e0(setup, cmm->volume, cmm->touch, o);
  progress.done();
  io::write_e0_result(a.output, r);
  if (!a.report.empty())
    report::write(
        a.report,
        report::render(
            "trueaxis CMM acceptance: length measuring error",
            {from_file(report::e0_section("Length measuring error (ISO 10360-2)", r), a.artefacts)},
            4000, report_meta()));
  const bool pass = r.verdict == acceptance::Verdict::Conforms && r.r0_pass.value_or(true);
  if (!a.quiet || !pass) fmt::print("{} -> {}\n", r.summary(), a.output);
  if (!r.complete) {
    fmt::print(stderr, "trueaxis acceptance e0: stopped after {} lengths: {}\n", r.lengths.size(),
               r.stopped);
    return 1;
  }
  return pass ? 0 : 1;
}

int run_probing(const AcceptanceArgs& a) {
  acceptance::ProbingOptions o;
  if (a.mpe_form_um > 0) o.mpe_form = a.mpe_form_um * 1e-3;
  if (a.mpe_size_um > 0) o.mpe_size = a.mpe_size_um * 1e-3;
  const auto setup = io::read_acceptance_setup(a.artefacts);
  const auto cmm = open_cmm(a, setup);
  const auto r = acceptance::run_probing(setup, cmm->touch, o);
  io::write_probing_result(a.output, r);
  if (!a.report.empty())
    report::write(
        a.report,
        report::render("trueaxis CMM acceptance: probing errors",
                       {from_file(report::probing_section(
                                      "Probing errors on the reference sphere (ISO 10360-5)", r,
                                      setup.sphere->pole),
                                  a.artefacts)},
                       4000, report_meta()));
  const bool pass =
      r.form_verdict.value_or(acceptance::Verdict::Conforms) == acceptance::Verdict::Conforms &&
      r.size_verdict.value_or(acceptance::Verdict::Conforms) == acceptance::Verdict::Conforms;
  if (!a.quiet || !pass) fmt::print("{} -> {}\n", r.summary(), a.output);
  return pass ? 0 : 1;
}

void add_common(CLI::App* c, AcceptanceArgs& a, const char* output) {
  a.machine.add_options(c);
  c->add_option("--cmm", a.cmm,
                "ipp://HOST:PORT: run on a CMM over I++ DME (trueaxis serve --artefacts, or a real "
                "one) instead of the virtual CMM of --machine");
  c->add_option("--travel", a.travel,
                "with --cmm and no --machine: the travel X0,Y0,Z0,X1,Y1,Z1 (mm, tip centre)")
      ->delimiter(',');
  c->add_option("--clearance", a.clearance,
                "with --cmm: mm kept between the ball and any artefact on a free move")
      ->capture_default_str();
  c->add_option("--log", a.log, "with --cmm: every I++ DME line sent and received, timed");
  c->add_option("--artefacts", a.artefacts,
                "acceptance.json: the artefacts as set up, in the machine's coordinates "
                "(trueaxis examples writes one)")
      ->required()
      ->check(existing_file());
  c->add_option("--lobing", a.lobing_um,
                "the virtual probe's pre-travel variation (µm, three lobes about the stylus)")
      ->capture_default_str();
  c->add_option("--noise", a.noise_um, "the virtual probe's noise (µm, 1σ per point)")
      ->capture_default_str();
  c->add_option("--seed", a.seed, "seed of the probe's noise")->capture_default_str();
  a.output = output;
  c->add_option("--output,-o", a.output, "result JSON")->capture_default_str();
  c->add_option("--report", a.report, "HTML report: the figures, the verdict and its rule, plots");
  add_meta_option(c);
  c->add_flag("--quiet,-q", a.quiet, "print nothing when the test passes");
}

}  // namespace

std::vector<Command> add_acceptance_commands(CLI::App& app) {
  auto* group = app.add_subcommand(
      "acceptance",
      "CMM acceptance and reverification tests, on a CMM over I++ DME or the virtual CMM of a "
      "machine file: the length "
      "measuring error E0 and repeatability R0 (ISO 10360-2) and the probing errors PForm and "
      "PSize (ISO 10360-5), judged by ISO 14253-1 with the test's own uncertainty.\n"
      "Exit status 0 when conformance is proven, 1 otherwise.");
  group->require_subcommand(1);
  auto e = std::make_shared<AcceptanceArgs>();
  auto* ce = group->add_subcommand(
      "e0",
      "Length measuring error E0 (or E150 with a stylus offset): every calibrated length at each "
      "of its placements (7 positions, 5 lengths) probed on both faces, 3 times.\nExample: "
      "trueaxis acceptance e0 --machine machine.json --artefacts acceptance.json --mpe "
      "\"1.5+L/300\" -o e0.json");
  add_common(ce, *e, "e0.json");
  ce->add_option("--mpe", e->mpe, "E0,MPE in µm, L in mm: \"A\", \"A+L/K\" or \"A+L/K,B\"")
      ->required()
      ->check(mpe_text());
  ce->add_option("--r0-mpe", e->r0_mpe, "R0,MPE in µm (same form), when specified")
      ->check(mpe_text());
  ce->add_option("--stylus-offset", e->stylus_offset,
                 "mm: an E150 test with this stylus offset, recorded in the result");
  auto p = std::make_shared<AcceptanceArgs>();
  auto* cp = group->add_subcommand(
      "probing",
      "Probing errors PForm and PSize on the reference sphere: 25 points in the pattern of ISO "
      "10360-5.\nExample: trueaxis acceptance probing --machine machine.json --artefacts "
      "acceptance.json --mpe-form 1.8 --mpe-size 1.5 -o probing.json");
  add_common(cp, *p, "probing.json");
  cp->add_option("--mpe-form", p->mpe_form_um, "PForm,MPE (µm)");
  cp->add_option("--mpe-size", p->mpe_size_um, "PSize,MPE (µm)");
  return {{ce, [e] { return run_e0(*e); }}, {cp, [p] { return run_probing(*p); }}};
}

}  // namespace trueaxis::cli
