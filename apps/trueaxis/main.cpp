// trueaxis — command-line tool. A thin client of the library: parse options, read files, call
// the library, write files. Library errors (trueaxis::Error) become one line on stderr and exit
// code 1; command-line mistakes exit with code 2 (CLI11's).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <optional>

#include "commands.hpp"
#include "moody_data.hpp"
#include "trueaxis/acceptance/acceptance.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/acceptance/acceptance.hpp"
#include "trueaxis/io/csv.hpp"
#include "trueaxis/io/files.hpp"
#include "trueaxis/io/positioning/positioning.hpp"
#include "trueaxis/io/results.hpp"
#include "trueaxis/io/scan/scan.hpp"
#include "trueaxis/io/separation/probes.hpp"
#include "trueaxis/io/surface/surface.hpp"
#include "trueaxis/report/ballgauge.hpp"
#include "trueaxis/report/files.hpp"
#include "trueaxis/report/fit.hpp"
#include "trueaxis/report/guideway.hpp"
#include "trueaxis/report/html.hpp"
#include "trueaxis/report/positioning.hpp"
#include "trueaxis/report/scan.hpp"
#include "trueaxis/report/surface.hpp"
#include "trueaxis/separation/separation.hpp"
#include "trueaxis/sim/straightness.hpp"
#include "trueaxis/surface/surface.hpp"

using namespace trueaxis;

namespace {

struct SeparateArgs {
  std::string input, output, csv, report, method = "lsq", reference = "ls";
  std::vector<double> offsets;
  std::vector<std::string> probes;
  std::string angle;
  std::optional<double> zero_difference, sigma;
  double angle_sigma = 1.0, filter_cutoff = 0;
  bool invert = false, quiet = false;
};

int cmd_separate(const SeparateArgs& a) {
  io::ProbeReadOptions ro;
  ro.offsets = a.offsets;
  ro.probe_columns = a.probes;
  if (!a.angle.empty()) ro.angle_column = a.angle;
  ro.invert = a.invert;
  const separation::ProbeData data = io::read_probes(a.input, ro);
  separation::Options o;
  o.method = separation::method_from_string(a.method);
  o.reference = separation::reference_from_string(a.reference);
  if (a.zero_difference) o.zero_difference = *a.zero_difference * 1e-3;
  if (a.sigma) o.sigma = *a.sigma * 1e-3;
  o.angle_sigma = a.angle_sigma * 1e-6;
  o.filter_cutoff = a.filter_cutoff;
  const separation::Result r = separation::separate(data, o);
  io::write_result(a.output, r);
  if (!a.csv.empty()) io::write_result_csv(a.csv, r);
  if (!a.report.empty())
    report::write(a.report, report::render(
                                "trueaxis straightness report",
                                {cli::from_file(report::separation_section(
                                                    "Straightness of a workpiece and its guide", r),
                                                a.input)},
                                4000, cli::report_meta()));
  if (!a.quiet)
    fmt::print("{}wrote {}{}{}\n", r.summary(), a.output, a.csv.empty() ? "" : ", " + a.csv,
               a.report.empty() ? "" : ", " + a.report);
  for (const auto& w : r.warnings()) fmt::print(stderr, "trueaxis: warning: {}\n", w);
  return 0;
}

struct SimArgs {
  sim::StraightnessOptions o;
  double noise_um = 0, pitch_urad = 5, workpiece_um = 5, guide_um = 3, angle_noise_urad = 0;
  std::string output = "probes.csv", truth;  // truth: beside the output
  bool quiet = false;
};

int cmd_simulate_straightness(SimArgs a) {
  a.o.noise = a.noise_um * 1e-3;
  a.o.pitch_amplitude = a.pitch_urad * 1e-6;
  a.o.workpiece_amplitude = a.workpiece_um * 1e-3;
  a.o.guide_amplitude = a.guide_um * 1e-3;
  a.o.angle_noise = a.angle_noise_urad * 1e-6;
  if (a.truth.empty()) a.truth = cli::truth_beside(a.output);
  const auto c = sim::simulate_straightness(a.o);
  io::write_probes(a.output, c.data);
  const Eigen::VectorXd w = c.truth.workpiece * 1e3, g = c.truth.guide * 1e3,
                        t = c.truth.pitch * 1e6;
  io::write_csv(a.truth, {"x", "workpiece_um", "guide_um", "pitch_urad"}, {&c.truth.x, &w, &g, &t});
  if (!a.quiet)
    fmt::print("simulated {} stations, {} probes{}: wrote {} and {}\n", a.o.stations,
               a.o.offsets.size(), a.o.angle ? " + angle channel" : "", a.output, a.truth);
  return 0;
}

struct SurfaceArgs {
  std::string lines, moody, method, output, report;
  bool quiet = false;
};

int cmd_surface(const SurfaceArgs& a) {
  surface::Result r;
  if (!a.moody.empty()) {
    if (!a.method.empty() && a.method != "classic" && a.method != "lsq")
      throw Error(
          fmt::format("--moody takes --method classic (default) or lsq, not '{}'", a.method));
    r = surface::moody(io::read_moody(a.moody), a.method == "lsq");
  } else {
    if (a.method == "classic") throw Error("--method classic needs --moody DIR");
    surface::Options o;
    o.method = a.method == "boundary" ? surface::Method::Seed : surface::Method::Lsq;
    r = surface::build(io::read_lines(a.lines), o);
  }
  io::write_surface(a.output, r);
  if (!a.report.empty())
    report::write(a.report, report::render(
                                "trueaxis surface report",
                                {cli::from_file(report::surface_section("Flatness of a surface", r),
                                                a.moody.empty() ? a.lines : a.moody)},
                                4000, cli::report_meta()));
  if (!a.quiet)
    fmt::print("{}wrote {}{}\n", r.summary(), a.output,
               a.report.empty() ? "" : fmt::format(" and {}", a.report));
  return 0;
}

// Any result file trueaxis writes, by its "kind".
int cmd_report(const std::string& input, const std::string& output, bool quiet) {
  const report::FileReport r = report::file_report(input);
  report::write(output, report::render(r.title, {r.section}, 4000, cli::report_meta()));
  if (!quiet) fmt::print("wrote {} ({})\n", output, r.kind);
  return 0;
}

// Writes the README's example inputs and Moody's plate (as plate/) into `dir`, which must exist.
// Existing files are left alone unless `force`: the command refuses before writing anything.
int cmd_examples(const std::string& dir, bool force, bool quiet) {
  namespace fs = std::filesystem;
  const fs::path root(dir);
  if (!fs::is_directory(root))
    throw Error(fmt::format("{}: no such directory (create it first)", dir));
  std::vector<std::pair<fs::path, std::string_view>> files;
  for (const auto& [name, text] : cli::example_files()) files.emplace_back(root / name, text);
  for (const auto& [name, text] : cli::moody_files())
    files.emplace_back(root / "plate" / std::string(name), text);
  // The CMM acceptance set-up fits the volume of the machine 'simulate machine' makes.
  const fs::path setup = root / "acceptance.json";
  if (!force)
    for (const auto& path : [&] {
           std::vector<fs::path> all;
           for (const auto& f : files) all.push_back(f.first);
           all.push_back(setup);
           return all;
         }())
      if (fs::exists(path))
        throw Error(fmt::format("{}: exists; nothing was written (use --force to overwrite)",
                                path.string()));
  fs::create_directories(root / "plate");
  for (const auto& [path, text] : files) {
    io::write_text(path.string(), text);
  }
  sim::Machine volume;
  const sim::MachineOptions defaults;
  volume.range = defaults.range;
  volume.offset = defaults.offset;
  io::write_acceptance_setup(setup.string(),
                             acceptance::example_setup(acceptance::Volume::of(volume)));
  if (!quiet)
    fmt::print(
        "wrote the example inputs in {}: lines.json, plan.json, points.csv, commands.csv, "
        "layout.json, cylinder.csv, ipp_simple.stp, acceptance.json (CMM acceptance artefacts) "
        "and plate/ (Moody's 1955 surface plate)\n",
        dir);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "trueaxis: measure, separate, map and compensate the geometric errors of machine tools and "
      "CMMs.\n\nUnits in files: positions in mm, deviations in µm, angles in µrad.\n"
      "Start with 'trueaxis demo' to see every capability on a virtual machine."};
  app.require_subcommand(1);
  const std::string version = "trueaxis 0.1.0";
  app.set_version_flag("--version", version);

  // separate --------------------------------------------------------------------------------
  SeparateArgs sa;
  auto* sep = app.add_subcommand(
      "separate",
      "Separate a workpiece profile from the guide's straightness (and pitch) using displacement "
      "probes on a moving carriage.\n\nprobes.csv: header row; column 'x' (mm, equal steps), then "
      "one "
      "column per probe (µm) in the order of --offsets.\nExample: trueaxis separate --input "
      "probes.csv "
      "--method three-point --output result.json");
  sep->add_option("--input,-i", sa.input, "probes CSV (x in mm, one column of µm per probe)")
      ->required()
      ->check(cli::existing_file());
  sep->add_option("--method,-m", sa.method,
                  "two-point: probes at 0,h (no pitch); three-point: with pitch, probes at 0,h,2h "
                  "(Mitsubishi JPH0464003B2); "
                  "lsq: least squares, any whole-step offsets, optional angle channel")
      ->check(CLI::IsMember({"two-point", "three-point", "lsq"}))
      ->capture_default_str();
  sep->add_option("--offsets", sa.offsets,
                  "probe offsets from the first probe, mm (default 0,h,2h,...)")
      ->delimiter(',');
  sep->add_option("--probes", sa.probes,
                  "names of the probe columns, in the order of --offsets (default: every column "
                  "after x except the angle column)")
      ->delimiter(',');
  sep->add_option("--angle", sa.angle,
                  "name of a pitch column (µrad) from an autocollimator or level (lsq)");
  sep->add_option(
      "--zero-difference", sa.zero_difference,
      "known zero difference of a three-probe layout, µm (o_A - 2 o_B + o_C for equal spacing); "
      "removes the parabola ambiguity");
  sep->add_flag("--invert", sa.invert, "negate probe readings (probes that read the gap)");
  sep->add_option("--reference", sa.reference,
                  "ls: residuals from least-squares lines; patent: the numbers of JPH0464003B2 "
                  "(three-point); "
                  "min-zone: relative to minimum-zone lines")
      ->check(CLI::IsMember({"ls", "patent", "min-zone"}))
      ->capture_default_str();
  sep->add_option("--sigma", sa.sigma,
                  "probe noise, µm (standard deviation) for the uncertainties; "
                  "default: estimated from the residuals when the data are redundant");
  sep->add_option("--angle-sigma", sa.angle_sigma, "angle channel noise, µrad")
      ->capture_default_str();
  sep->add_option("--filter-cutoff", sa.filter_cutoff,
                  "apply an ISO 16610-21 Gaussian filter with this cut-off, mm");
  sep->add_option("--output,-o", sa.output, "result JSON")->required();
  sep->add_option("--csv", sa.csv, "also write the profiles as CSV");
  sep->add_option("--report", sa.report, "also write an HTML report (profiles with their bands)");
  cli::add_meta_option(sep);
  sep->add_flag("--quiet,-q", sa.quiet, "print nothing on success");

  // surface ----------------------------------------------------------------------------------
  SurfaceArgs sf;
  auto* surf = app.add_subcommand(
      "surface",
      "Assemble an error surface (flatness map) from straightness lines that cross each other.\n\n"
      "Each line's heights are known only up to an offset and a tilt; the lines are fitted "
      "together where they cross.\nExamples:\n  trueaxis surface --lines lines.json --method lsq "
      "-o surface.json\n  trueaxis surface --moody plate/ -o surface.json   (Union Jack, Moody "
      "1955)");
  auto* sf_in = surf->add_option("--lines", sf.lines,
                                 "lines.json: lines with start, direction, spacing and heights "
                                 "(µm), slopes (µrad) or 'from' a separate result")
                    ->check(cli::existing_file());
  surf->add_option("--moody", sf.moody,
                   "directory with Moody's eight line files (arc-seconds) and Config.txt")
      ->check(cli::existing_directory())
      ->excludes(sf_in);
  surf->add_option(
          "--method", sf.method,
          "with --lines: lsq (default; all lines jointly, closure at every crossing) or "
          "boundary (x lines hung on two boundary y lines); with --moody: classic (default, "
          "Moody's worksheet) or lsq")
      ->check(CLI::IsMember({"lsq", "boundary", "classic"}));
  surf->add_option("--output,-o", sf.output, "surface JSON to write")->required();
  cli::add_meta_option(surf);
  surf->add_option("--report", sf.report,
                   "also write an HTML report (heat map of the heights, closure at the crossings)");
  surf->add_flag("--quiet,-q", sf.quiet, "print nothing on success");

  // simulate ---------------------------------------------------------------------------------
  auto* simc = app.add_subcommand(
      "simulate", "Generate data from a virtual machine (with the truth, to check methods)");
  simc->require_subcommand(1);
  SimArgs ma;
  auto* simst = simc->add_subcommand(
      "straightness",
      "A seeded virtual carriage with probes over a workpiece: writes probes.csv and "
      "probes-truth.csv");
  simst->add_option("--stations", ma.o.stations, "number of stops")->capture_default_str();
  simst->add_option("--step", ma.o.step, "distance between stops, mm")->capture_default_str();
  simst->add_option("--offsets", ma.o.offsets, "probe offsets from the first probe, mm")
      ->delimiter(',')
      ->capture_default_str();
  simst->add_option("--noise", ma.noise_um, "probe noise, µm (standard deviation)")
      ->capture_default_str();
  simst->add_option("--pitch", ma.pitch_urad, "pitch error amplitude, µrad (0: no pitch)")
      ->capture_default_str();
  simst->add_option("--workpiece", ma.workpiece_um, "workpiece form error amplitude, µm")
      ->capture_default_str();
  simst->add_option("--guide", ma.guide_um, "guide straightness amplitude, µm")
      ->capture_default_str();
  simst->add_flag("--angle", ma.o.angle, "add a pitch (angle) channel, column 'angle' in µrad");
  simst->add_option("--angle-noise", ma.angle_noise_urad, "angle channel noise, µrad")
      ->capture_default_str();
  simst->add_option("--seed", ma.o.seed, "random seed (same seed, same data)")
      ->capture_default_str();
  simst->add_option("--output,-o", ma.output, "probes CSV to write")->capture_default_str();
  simst->add_option("--truth", ma.truth,
                    "truth CSV to write (x, workpiece_um, guide_um, pitch_urad); default: the "
                    "output's name with -truth");
  simst->add_flag("--quiet,-q", ma.quiet, "print nothing on success");

  std::vector<cli::Command> machine_cmds = cli::add_machine_commands(app, *simc);
  for (auto& c : cli::add_space_commands(app)) machine_cmds.push_back(std::move(c));
  for (auto& c : cli::add_guideway_commands(app, *simc)) machine_cmds.push_back(std::move(c));
  for (auto& c : cli::add_positioning_commands(app, *simc)) machine_cmds.push_back(std::move(c));
  for (auto& c : cli::add_circular_commands(app, *simc)) machine_cmds.push_back(std::move(c));
  for (auto& c : cli::add_fit_commands(app)) machine_cmds.push_back(std::move(c));
  for (auto& c : cli::add_ballgauge_commands(app, *simc)) machine_cmds.push_back(std::move(c));
  for (auto& c : cli::add_design_commands(app, *simc)) machine_cmds.push_back(std::move(c));
  for (auto& c : cli::add_scan_commands(app)) machine_cmds.push_back(std::move(c));
  for (auto& c : cli::add_serve_command(app)) machine_cmds.push_back(std::move(c));
  for (auto& c : cli::add_ipp_commands(app)) machine_cmds.push_back(std::move(c));
  for (auto& c : cli::add_acceptance_commands(app)) machine_cmds.push_back(std::move(c));
  for (auto& c : cli::add_record_commands(app)) machine_cmds.push_back(std::move(c));
  for (auto& c : cli::add_certificate_command(app)) machine_cmds.push_back(std::move(c));

  // report -----------------------------------------------------------------------------------
  std::string rin, rout = "report.html";
  bool rquiet = false;
  auto* rep = app.add_subcommand(
      "report", "Write an HTML report (interactive plots, works offline) of a result JSON");
  rep->add_option(
         "result", rin,
         "any result JSON trueaxis writes (separate, surface, space, guideway, positioning, "
         "circular, ballgauge, verify-lengths, fit, scan)")
      ->required()
      ->check(cli::existing_file());
  rep->add_option("--output,-o", rout, "HTML file to write")->capture_default_str();
  rep->add_flag("--quiet,-q", rquiet, "print nothing on success");
  cli::add_meta_option(rep);

  // demo -------------------------------------------------------------------------------------
  cli::DemoOptions da;
  auto* demo = app.add_subcommand(
      "demo", "Run every capability on the built-in virtual machine and write an HTML report");
  demo->add_option("--output,-o", da.output, "HTML report to write")->capture_default_str();
  cli::add_meta_option(demo);
  demo->add_option("--seed", da.seed, "random seed of the virtual machine")->capture_default_str();
  demo->add_option("--stations", da.stations, "stations of the straightness campaign")
      ->capture_default_str();
  demo->add_option("--spacing", da.spacing, "grid step of the error space (mm)")
      ->capture_default_str();
  demo->add_option("--repetitions", da.repetitions,
                   "Monte Carlo repetitions for the error space's uncertainty (0: none)")
      ->capture_default_str();
  demo->add_flag("--quiet,-q", da.quiet, "print only errors");

  // examples ---------------------------------------------------------------------------------
  std::string ex_dir = ".";
  bool ex_force = false, ex_quiet = false;
  auto* examples = app.add_subcommand(
      "examples",
      "Write the example inputs that the README's examples use (lines.json, plan.json, "
      "points.csv, commands.csv, layout.json, cylinder.csv, NIST's I++ test part ipp_simple.stp "
      "and Moody's plate in plate/)");
  examples->add_option("--output,-o", ex_dir, "directory to write them in")->capture_default_str();
  examples->add_flag("--force", ex_force, "overwrite files that exist");
  examples->add_flag("--quiet,-q", ex_quiet, "print nothing on success");

  // help -------------------------------------------------------------------------------------
  std::vector<std::string> help_topic;
  auto* help = app.add_subcommand("help",
                                  "Show the help of trueaxis or of one command "
                                  "(trueaxis help separate, trueaxis help simulate line)");
  help->add_option("command", help_topic, "the command (and sub-command) to explain");

  cli::apply_grammar(app, version);
  if (argc == 1) {
    std::fputs(cli::command_list(app).c_str(), stdout);
    return 0;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version exit 0; every command-line mistake exits 2, whatever CLI11's own code.
    if (e.get_exit_code() == 0) return app.exit(e);
    const std::string hint = cli::suggestion(app, e);
    if (!hint.empty()) {
      std::fprintf(stderr, "trueaxis: %s\nRun with --help for more information.\n", hint.c_str());
      return 2;
    }
    const int rc = app.exit(e);
    return rc == 0 ? 0 : 2;
  }
  if (const std::string m = cli::missing_input(); !m.empty()) {
    std::fprintf(stderr, "trueaxis: error: %s\n", m.c_str());
    return 1;
  }
  if (help->parsed() && help_topic.empty()) {
    std::fputs(cli::command_list(app).c_str(), stdout);
    return 0;
  }
  if (help->parsed()) {
    const CLI::App* topic = &app;
    for (const std::string& word : help_topic) {
      const CLI::App* next = nullptr;
      for (const CLI::App* sub : topic->get_subcommands([](const CLI::App*) { return true; }))
        if (sub->get_name() == word) next = sub;
      if (next == nullptr) {
        std::fprintf(stderr, "trueaxis help: no command '%s'%s; run 'trueaxis help' for the list\n",
                     word.c_str(),
                     topic == &app ? "" : (" under '" + topic->get_name() + "'").c_str());
        return 2;
      }
      topic = next;
    }
    std::fputs(topic->help().c_str(), stdout);
    return 0;
  }
  if (surf->parsed() && sf.lines.empty() && sf.moody.empty()) {
    std::fprintf(stderr,
                 "trueaxis surface: give --lines FILE or --moody DIR\nRun with --help for more "
                 "information.\n");
    return 2;
  }
  try {
    if (sep->parsed()) return cmd_separate(sa);
    if (simst->parsed()) return cmd_simulate_straightness(ma);
    for (const auto& c : machine_cmds)
      if (c.app->parsed()) return c.run();
    if (surf->parsed()) return cmd_surface(sf);
    if (rep->parsed()) return cmd_report(rin, rout, rquiet);
    if (demo->parsed()) return cli::run_demo(da);
    if (examples->parsed()) return cmd_examples(ex_dir, ex_force, ex_quiet);
  } catch (const Error& e) {
    std::fprintf(stderr, "trueaxis: error: %s\n", e.what());
    return 1;
  } catch (const CLI::Error& e) {
    // Usage mistakes found once the options are combined (a command's own checks).
    std::fprintf(stderr, "trueaxis: %s\nRun with --help for more information.\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "trueaxis: internal error: %s\n", e.what());
    return 3;
  }
  return 0;
}
