// trueaxis CLI — five guideway errors from QPD laser spots: 'guideway'.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>

#include "commands.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/guideway/guideway.hpp"
#include "trueaxis/io/guideway.hpp"

namespace trueaxis::cli {
namespace {

struct GuidewayArgs {
  std::string layout, input, output;
  double sigma = 0;
  bool skip_bad = false, quiet = false;
};

int run_guideway(const GuidewayArgs& a) {
  const io::GuidewayLayout g = io::read_layout(a.layout);
  const io::Spots sp = io::read_spots(a.input, g, a.skip_bad);
  for (const auto& why : sp.skipped) std::fprintf(stderr, "skipped: %s\n", why.c_str());
  guideway::Options o;
  o.sigma = a.sigma * 1e-3;
  const guideway::Result r = guideway::solve(g.layout, sp.s, sp.spots, o);
  io::write_guideway_result(a.output, r);
  if (!r.layout.message.empty())
    std::fprintf(stderr, "trueaxis guideway: %s\n", r.layout.message.c_str());
  if (!a.quiet)
    fmt::print("{}wrote {}{}\n", r.summary(), a.output,
               sp.skipped.empty() ? "" : fmt::format(" ({} positions skipped)", sp.skipped.size()));
  return 0;
}

}  // namespace

std::vector<Command> add_guideway_commands(CLI::App& app) {
  auto a = std::make_shared<GuidewayArgs>();
  auto* c = app.add_subcommand(
      "guideway",
      "Five motion errors of a guideway (horizontal and vertical straightness, pitch, yaw, roll) "
      "from laser spots on quadrant detectors carried by the carriage.\nlayout.json: the "
      "detectors' positions on the carriage (mm; z along the travel, x horizontal, y vertical) "
      "and kinds (position, or angle behind a lens).\nspots.csv: column s (mm), then "
      "<name>_dx,<name>_dy (um) or <name>_i1..<name>_i4 (quadrant currents) per detector.\n"
      "Errors the layout cannot see (e.g. pitch and yaw when all detectors share one z) are "
      "reported as not observable, never as numbers.\nExample: trueaxis guideway --layout "
      "layout.json --input spots.csv --output result.json");
  c->add_option("--layout", a->layout, "layout JSON (detectors, optional qpd calibration)")
      ->required()
      ->check(CLI::ExistingFile);
  c->add_option("--input,-i", a->input, "spots CSV (s in mm; dx, dy in um or quadrant currents)")
      ->required()
      ->check(CLI::ExistingFile);
  c->add_option("--output,-o", a->output, "result JSON to write")->required();
  c->add_option("--sigma", a->sigma,
                "standard deviation of one spot reading (um) for the uncertainties (default: "
                "estimated from the residuals when the layout is redundant)");
  c->add_flag("--skip-bad", a->skip_bad,
              "drop positions with a lost or out-of-range spot instead of failing");
  c->add_flag("--quiet,-q", a->quiet, "print nothing on success");
  return {{c, [a] { return run_guideway(*a); }}};
}

}  // namespace trueaxis::cli
