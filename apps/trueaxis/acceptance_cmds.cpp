// trueaxis CLI — CMM acceptance and reverification tests: 'acceptance e0' (ISO 10360-2) and
// 'acceptance probing' (ISO 10360-5).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <iostream>
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
  std::string artefacts, output, report, correction;
  std::string mpe, r0_mpe;
  std::vector<double> stylus_offset;  // mm: L, or X,Y,Z
  std::vector<std::string> positions;
  double mpe_form_um = 0, mpe_size_um = 0;
  double lobing_um = 0, noise_um = 0;
  std::uint64_t seed = 1;
  bool quiet = false, pause = false;
};

// --pause: asks the operator on stderr and waits for a line on stdin; "q" or the end of the input
// stops the run (an Error, so what was measured is kept). Returns the seconds waited.
double wait_for_operator(const std::string& ask, const std::string& stop) {
  fmt::print(stderr, "{} Press Enter when ready, or q and Enter to stop: ", ask);
  std::fflush(stderr);
  const auto t0 = std::chrono::steady_clock::now();
  std::string line;
  const bool got = static_cast<bool>(std::getline(std::cin, line));
  if (isatty(fileno(stdin)) == 0) fmt::print(stderr, "\n");  // a terminal echoes the Enter
  if (!got || line == "q" || line == "Q") throw Error("by the operator " + stop);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

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
    // E_L: the machine probes with the offset stylus, whose tip reaches another volume.
    if (!a.stylus_offset.empty())
      c->machine = acceptance::with_stylus(*c->machine, stylus_offset_of(a.stylus_offset));
    c->volume = acceptance::Volume::of(*c->machine);
  }
  if (a.cmm.empty()) {
    acceptance::VirtualProbeOptions p;
    p.lobing = a.lobing_um * 1e-3;
    p.noise = a.noise_um * 1e-3;
    p.seed = a.seed;
    c->touch = acceptance::virtual_touch(*c->machine, p);
    if (!a.correction.empty()) {
      // The controller's correction applied to every point read, as on the CMM it stands for.
      auto correct = load_correction(a.correction);
      c->touch = [raw = c->touch, correct](const Eigen::Vector3d& at, const Eigen::Vector3d& d) {
        return correct(raw(at, d));
      };
    }
    return c;
  }
  if (!a.correction.empty())
    throw CLI::ValidationError("--correction",
                               "is for the virtual CMM of --machine; a CMM over I++ DME applies "
                               "its own (trueaxis serve --correction)");
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
  if (!a.stylus_offset.empty()) o.stylus_offset = stylus_offset_of(a.stylus_offset);
  o.positions = a.positions;
  if (!o.stylus_offset && !o.positions.empty())
    throw CLI::ValidationError("--position",
                               "E0 is measured in every position of the set-up; --position "
                               "chooses them for E_L, with --stylus-offset");
  const auto setup = io::read_acceptance_setup(a.artefacts);
  const auto cmm = open_cmm(a, setup);
  Progress progress("measuring the lengths", a.quiet);
  o.progress = [&](std::size_t done, std::size_t total) {
    progress.update(static_cast<double>(done) / static_cast<double>(total));
  };
  if (a.pause)
    o.before_position = [&](const acceptance::Position& pos, std::size_t k, std::size_t n) {
      std::string blocks;
      for (const auto i : pos.placements)
        blocks += (blocks.empty() ? "" : ", ") + setup.placements[i].block;
      progress.exclude(wait_for_operator(
          fmt::format("Set up position {} of {}, '{}': {}.", k + 1, n, pos.name, blocks),
          fmt::format("before position '{}'", pos.name)));
    };
  const auto r = acceptance::run_e0(setup, cmm->volume, cmm->touch, o);
  progress.done();
  io::write_e0_result(a.output, r);
  if (!a.report.empty())
    report::write(
        a.report,
        report::render(
            "trueaxis CMM acceptance: length measuring error",
            {from_file(report::e0_section(
                           fmt::format("Length measuring error {} (ISO 10360-2)", r.name()), r),
                       a.artefacts)},
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
  if (a.pause && setup.sphere)
    wait_for_operator(
        fmt::format("Set up the reference sphere at ({:.1f}, {:.1f}, {:.1f}) mm.",
                    setup.sphere->centre.x(), setup.sphere->centre.y(), setup.sphere->centre.z()),
        "before the reference sphere");
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

struct SetupArgs {
  MachineSource machine;
  std::vector<double> stylus_offset;
  std::string output = "acceptance.json";
};

int run_setup(const SetupArgs& a) {
  sim::Machine m = a.machine.load();
  if (!a.stylus_offset.empty()) m = acceptance::with_stylus(m, stylus_offset_of(a.stylus_offset));
  const auto volume = acceptance::Volume::of(m);
  const auto setup = acceptance::example_setup(volume);
  io::write_acceptance_setup(a.output, setup);
  fmt::print(
      "{} gauge blocks in {} positions and a Ø{:g} mm reference sphere, in the volume ({:.0f}, "
      "{:.0f}, {:.0f}) … ({:.0f}, {:.0f}, {:.0f}) mm of the tip{} -> {}\n",
      setup.placements.size(), acceptance::lines(setup).size(), setup.sphere->diameter,
      volume.low.x(), volume.low.y(), volume.low.z(), volume.high.x(), volume.high.y(),
      volume.high.z(), a.stylus_offset.empty() ? "" : " with the offset stylus", a.output);
  return 0;
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
  c->add_option("--correction", a.correction,
                "map.json (ball-gauge grid map) or model.json (parametric model): the virtual CMM "
                "corrects every point it reads, as a controller with that error map would")
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
  c->add_flag("--pause", a.pause,
              "before each position (and the sphere) wait for the operator to set it up: Enter "
              "goes on, q stops (what was measured is kept); for a real CMM whose artefacts are "
              "moved by hand");
  c->add_flag("--quiet,-q", a.quiet, "print nothing when the test passes");
}

}  // namespace

Eigen::Vector3d stylus_offset_of(const std::vector<double>& v) {
  Eigen::Vector3d lateral;
  if (v.size() == 1)
    lateral = Eigen::Vector3d(v[0], 0, 0);
  else if (v.size() == 3)
    lateral = Eigen::Vector3d(v[0], v[1], v[2]);
  else
    throw CLI::ValidationError("--stylus-offset", "give L (mm, along +X) or X,Y,Z");
  try {
    acceptance::validate_stylus_offset(lateral);
  } catch (const Error& e) {
    throw CLI::ValidationError("--stylus-offset", e.what());
  }
  return lateral;
}

void add_stylus_offset_option(CLI::App* command, std::vector<double>& values,
                              const std::string& help) {
  command->add_option("--stylus-offset", values, help)->delimiter(',')->expected(1, 3);
}

std::vector<Command> add_acceptance_commands(CLI::App& app) {
  auto* group = app.add_subcommand(
      "acceptance",
      "CMM acceptance and reverification tests, on a CMM over I++ DME or the virtual CMM of a "
      "machine file: the length "
      "measuring error E0 (E150 with a stylus offset) and repeatability R0 (ISO 10360-2) and the "
      "probing errors PForm and "
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
  add_stylus_offset_option(
      ce, e->stylus_offset,
      "L or X,Y,Z (mm): E_L instead of E0, the stylus tip offset across the ram by L along +X "
      "(150: E150) or by (X, Y, 0); the virtual CMM of --machine probes with it, a CMM over I++ "
      "DME with the stylus it has (mount and qualify it first)");
  ce->add_option("--position", e->positions,
                 "E_L: a position to measure, by its name in the set-up (repeat the flag; "
                 "default: the first two space diagonals, ISO 10360-2 asks for two)");
  auto p = std::make_shared<AcceptanceArgs>();
  auto* cp = group->add_subcommand(
      "probing",
      "Probing errors PForm and PSize on the reference sphere: 25 points in the pattern of ISO "
      "10360-5.\nExample: trueaxis acceptance probing --machine machine.json --artefacts "
      "acceptance.json --mpe-form 1.8 --mpe-size 1.5 -o probing.json");
  add_common(cp, *p, "probing.json");
  cp->add_option("--mpe-form", p->mpe_form_um, "PForm,MPE (µm)");
  cp->add_option("--mpe-size", p->mpe_size_um, "PSize,MPE (µm)");
  auto s = std::make_shared<SetupArgs>();
  auto* cs = group->add_subcommand(
      "setup",
      "Writes an artefact set-up that fits a machine's travel: 35 gauge blocks in the 7 positions "
      "of ISO 10360-2 (the 4 space diagonals, along X, Y and Z) and a Ø25 mm reference sphere, "
      "for the stylus the machine file has, or an offset one.\nExample: trueaxis acceptance setup "
      "--machine machine.json --stylus-offset 150 -o acceptance150.json");
  s->machine.add_options(cs);
  add_stylus_offset_option(cs, s->stylus_offset,
                           "L or X,Y,Z (mm): fit the volume the tip reaches with a stylus offset "
                           "across the ram (as for 'acceptance e0 --stylus-offset')");
  cs->add_option("--output,-o", s->output, "the set-up JSON")->capture_default_str();
  return {{ce, [e] { return run_e0(*e); }},
          {cp, [p] { return run_probing(*p); }},
          {cs, [s] { return run_setup(*s); }}};
}

}  // namespace trueaxis::cli
