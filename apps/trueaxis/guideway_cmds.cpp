// trueaxis CLI — five guideway errors from QPD laser spots: 'guideway'.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <memory>

#include "commands.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/guideway/guideway.hpp"
#include "trueaxis/io/csv.hpp"
#include "trueaxis/io/guideway/guideway.hpp"
#include "trueaxis/io/sim/machine.hpp"
#include "trueaxis/report/guideway.hpp"
#include "trueaxis/sim/guideway.hpp"

namespace trueaxis::cli {
namespace {

struct GuidewayArgs {
  std::string layout, input, output, report, axis;
  double sigma = 0;
  bool skip_bad = false, quiet = false;
};

int run_guideway(const GuidewayArgs& a) {
  const io::GuidewayLayout g = io::read_layout(a.layout);
  const io::Spots sp = io::read_spots(a.input, g, a.skip_bad);
  for (const auto& why : sp.skipped) std::fprintf(stderr, "skipped: %s\n", why.c_str());
  guideway::Options o;
  o.sigma = a.sigma * 1e-3;
  guideway::Result r = guideway::solve(g.layout, sp.s, sp.spots, o);
  if (!a.axis.empty()) r.axis = a.axis[0] - 'x';
  io::write_guideway_result(a.output, r);
  if (!a.report.empty())
    report::write(
        a.report,
        report::render(
            "trueaxis guideway report",
            {from_file(report::guideway_section("Five motion errors of a guideway", r), a.input)},
            4000, cli::report_meta()));
  if (!r.layout.message.empty())
    std::fprintf(stderr, "trueaxis guideway: %s\n", r.layout.message.c_str());
  if (!a.quiet)
    fmt::print("{}wrote {}{}\n", r.summary(), a.output,
               sp.skipped.empty() ? "" : fmt::format(" ({} positions skipped)", sp.skipped.size()));
  return 0;
}

struct SimArgs {
  MachineSource machine;
  std::string layout, output = "spots.csv", truth, axis = "x";  // truth: beside the output
  sim::GuidewayOptions o;
  double noise_um = 0, pointing_um = 0, angle_urad = 0, quant_um = 0;
  bool quiet = false;
};

int run_simulate(const SimArgs& a) {
  const sim::Machine m = a.machine.load();
  const io::GuidewayLayout g = io::read_layout(a.layout);
  sim::GuidewayOptions o = a.o;
  o.axis = a.axis == "x" ? 0 : a.axis == "y" ? 1 : 2;
  o.noise = a.noise_um * 1e-3;
  o.pointing_noise = a.pointing_um * 1e-3;
  o.angle_noise = a.angle_urad * 1e-6;
  o.quantisation = a.quant_um * 1e-3;
  const auto c = sim::simulate_guideway(m, g.layout, o);
  if (o.currents) {
    std::vector<std::string> header{"s"};
    std::vector<Eigen::VectorXd> cols;
    for (std::size_t i = 0; i < g.layout.detectors.size(); ++i)
      for (int q = 0; q < 4; ++q) {
        header.push_back(fmt::format("{}_i{}", g.layout.detectors[i].name, q + 1));
        cols.push_back(c.currents.col(4 * static_cast<Eigen::Index>(i) + q));
      }
    std::vector<const Eigen::VectorXd*> ptrs{&c.s};
    for (const auto& v : cols) ptrs.push_back(&v);
    io::write_csv(a.output, header, ptrs);
  } else {
    io::write_spots(a.output, g.layout, c.s, c.spots);
  }
  const std::string truth = a.truth.empty() ? truth_beside(a.output) : a.truth;
  const Eigen::VectorXd t[5] = {c.truth[0] * 1e3, c.truth[1] * 1e3, c.truth[2] * 1e6,
                                c.truth[3] * 1e6, c.truth[4] * 1e6};
  io::write_csv(truth, {"s", "horizontal_um", "vertical_um", "pitch_urad", "yaw_urad", "roll_urad"},
                {&c.s, &t[0], &t[1], &t[2], &t[3], &t[4]});
  if (!a.quiet) {
    fmt::print("simulated {} positions along {} of {} with {} detectors{}: wrote {} and {}\n",
               o.positions, a.axis, m.name, g.layout.detectors.size(),
               o.exact ? " (exact geometry)" : "", a.output, truth);
    if (o.currents)
      fmt::print(
          "quadrant currents of a Gaussian spot (1/e2 radius {} mm): near the centre the layout "
          "needs \"qpd\": {{\"gain_um\": {:.6g}}}; farther out, a calibration table\n",
          o.spot_radius, o.spot_radius * std::sqrt(M_PI) / (2 * std::sqrt(2.0)) * 1e3);
  }
  return 0;
}

}  // namespace

std::vector<Command> add_guideway_commands(CLI::App& app, CLI::App& simulate) {
  auto sa = std::make_shared<SimArgs>();
  auto* sc = simulate.add_subcommand(
      "guideway5d",
      "A virtual guideway carriage: one axis of a virtual machine carries the layout's "
      "detectors through laser beams fixed to the bed. Writes the spots CSV that 'trueaxis "
      "guideway' reads and the truth (the axis' own straightness, pitch, yaw and roll).\n"
      "Example: trueaxis simulate guideway5d --layout layout.json --axis x --noise 0.2 -o "
      "spots.csv --truth spots-truth.csv");
  sc->add_option("--layout", sa->layout, "layout JSON (detectors on the carriage)")
      ->required()
      ->check(cli::existing_file());
  sa->machine.add_options(sc);
  sc->add_option("--axis", sa->axis, "the machine axis the carriage rides")
      ->transform(cli::machine_axis())
      ->capture_default_str();
  sc->add_option("--stations,--positions", sa->o.positions,
                 "stops over the axis range (--stations, as for the other simulations)")
      ->capture_default_str();
  sc->add_option("--noise", sa->noise_um, "spot reading noise, µm")->capture_default_str();
  sc->add_option("--pointing-noise", sa->pointing_um, "beam pointing jitter, µm")
      ->capture_default_str();
  sc->add_option("--angle-noise", sa->angle_urad, "angle detector noise, µrad")
      ->capture_default_str();
  sc->add_option("--quantisation", sa->quant_um, "reading resolution, µm (0: none)")
      ->capture_default_str();
  sc->add_flag("--exact", sa->o.exact,
               "exact spot geometry (rotated detector planes) instead of the small-angle model");
  sc->add_flag("--currents", sa->o.currents,
               "write quadrant currents <name>_i1..i4 of a Gaussian spot instead of dx, dy");
  sc->add_option("--spot-radius", sa->o.spot_radius, "Gaussian spot 1/e2 radius, mm")
      ->capture_default_str();
  sc->add_option("--current-noise", sa->o.current_noise, "relative noise of each current")
      ->capture_default_str();
  sc->add_option("--seed", sa->o.seed, "seed of the noise")->capture_default_str();
  sc->add_option("--output,-o", sa->output, "spots CSV to write")->capture_default_str();
  sc->add_option("--truth", sa->truth,
                 "truth CSV (s, horizontal_um, vertical_um, pitch_urad, yaw_urad, roll_urad); "
                 "default: the output's name with -truth");
  sc->add_flag("--quiet,-q", sa->quiet, "print nothing on success");

  auto a = std::make_shared<GuidewayArgs>();
  auto* c = app.add_subcommand(
      "guideway",
      "Five motion errors of a guideway (horizontal and vertical straightness, pitch, yaw, roll) "
      "from laser spots on quadrant detectors carried by the carriage.\nlayout.json: the "
      "detectors' positions on the carriage (mm; z along the travel, x horizontal, y vertical) "
      "and kinds (position, or angle behind a lens).\nspots.csv: column s (mm), then "
      "<name>_dx,<name>_dy (µm) or <name>_i1..<name>_i4 (quadrant currents) per detector.\n"
      "Errors the layout cannot see (e.g. pitch and yaw when all detectors share one z) are "
      "reported as not observable, never as numbers.\nExample: trueaxis guideway --layout "
      "layout.json --input spots.csv --axis x --output result.json");
  c->add_option("--layout", a->layout, "layout JSON (detectors, optional qpd calibration)")
      ->required()
      ->check(cli::existing_file());
  c->add_option("--input,-i", a->input, "spots CSV (s in mm; dx, dy in µm or quadrant currents)")
      ->required()
      ->check(cli::existing_file());
  c->add_option("--output,-o", a->output, "result JSON to write")->required();
  c->add_option("--axis", a->axis,
                "the machine axis the carriage rides (x, y or z): its errors are then named as "
                "ISO 230-1 names them (for X: EYX, EZX horizontal and vertical straightness, EBX "
                "pitch, ECX yaw, EAX roll), with the carriage frame on X as (Y, Z, X), on Y as "
                "(-X, Z, Y), on Z as (X, Y, Z); without it, a stand-alone carriage's own names")
      ->transform(cli::machine_axis());
  c->add_option("--sigma", a->sigma,
                "standard deviation of one spot reading (µm) for the uncertainties (default: "
                "estimated from the residuals when the layout is redundant)");
  c->add_option("--report", a->report, "also write an HTML report (one plot per error)");
  add_meta_option(c);
  c->add_flag("--skip-bad", a->skip_bad,
              "drop positions with a lost or out-of-range spot instead of failing");
  c->add_flag("--quiet,-q", a->quiet, "print nothing on success");
  return {{c, [a] { return run_guideway(*a); }}, {sc, [sa] { return run_simulate(*sa); }}};
}

}  // namespace trueaxis::cli
