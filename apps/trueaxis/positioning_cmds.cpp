// trueaxis CLI — positioning accuracy of a linear axis by ISO 230-2: 'positioning' and
// 'simulate positioning'.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>

#include "commands.hpp"
#include "trueaxis/compensation/table.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/compensation/controller.hpp"
#include "trueaxis/io/csv.hpp"
#include "trueaxis/io/positioning/positioning.hpp"
#include "trueaxis/io/positioning/renishaw.hpp"
#include "trueaxis/positioning/positioning.hpp"
#include "trueaxis/report/positioning.hpp"
#include "trueaxis/sim/machine.hpp"
#include "trueaxis/sim/positioning.hpp"

namespace trueaxis::cli {
namespace {

double parse_number(std::string_view s, const std::string& what) {
  while (!s.empty() && s.front() == ' ') s.remove_prefix(1);
  while (!s.empty() && s.back() == ' ') s.remove_suffix(1);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  double v = 0;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || r.ec != std::errc() || r.ptr != s.data() + s.size() || !std::isfinite(v))
    throw CLI::ValidationError(what, fmt::format("'{}' is not a number", s));
  return v;
}

std::vector<double> parse_targets(const std::string& s);

struct PositioningArgs {
  std::string input, log_targets, output = "positioning.json", standard = "iso230-2", report,
                                  run_directions = "order", before;
  positioning::LogOptions lo;
  double dwell_tolerance_um = 2;
  std::vector<std::string> tolerances;
  positioning::Options o;
  double expansion_ppm = 11.5;
  bool no_temperature = false, quiet = false;
};

int run_positioning(const PositioningArgs& a) {
  std::vector<std::pair<std::string, double>> tol;
  for (const auto& t : a.tolerances) {
    const auto eq = t.find('=');
    if (eq == std::string::npos)
      throw CLI::ValidationError("--tolerance", fmt::format("'{}': use NAME=µm, e.g. A=10", t));
    const std::string name = t.substr(0, eq);
    const auto& names = positioning::parameter_names();
    if (std::find(names.begin(), names.end(), name) == names.end()) {
      std::string known;
      for (const auto& n : names) known += (known.empty() ? "" : ", ") + n;
      throw CLI::ValidationError("--tolerance",
                                 fmt::format("unknown parameter '{}' (known: {})", name, known));
    }
    const double v = parse_number(std::string_view(t).substr(eq + 1), "--tolerance");
    if (!(v > 0)) throw CLI::ValidationError("--tolerance", fmt::format("{}: must be > 0 µm", t));
    tol.emplace_back(name, v * 1e-3);
  }
  const bool is_log = io::is_log_file(a.input);
  if (is_log && a.log_targets.empty())
    throw CLI::ValidationError(fmt::format(
        "{} is an interferometer log (time_s, reading_mm): it needs --targets (the positions "
        "the axis stopped at)",
        a.input));
  if (!is_log && !a.log_targets.empty())
    throw CLI::ValidationError(
        fmt::format("--targets belongs to an interferometer log; {} holds runs", a.input));
  io::PositioningRuns runs;
  std::vector<std::string> source_warnings;
  std::string source = a.input;
  if (is_log) {
    const std::string& log_file = a.input;
    positioning::LogOptions lo = a.lo;
    lo.dwell_tolerance = a.dwell_tolerance_um * 1e-3;
    const positioning::Log log = io::read_log(log_file);
    const std::vector<double> targets = parse_targets(a.log_targets);
    positioning::LogReadings found;
    try {
      found = positioning::readings_from_log(log, targets, lo);
    } catch (const Error& e) {
      throw Error(fmt::format("{}: {}", log_file, e.what()));
    }
    if (!a.quiet) {
      fmt::print("{}: {} stops, {} at targets", log_file, found.stops, found.readings.size());
      fmt::print("{}\n",
                 found.ignored.empty() ? "" : fmt::format(", {} not used:", found.ignored.size()));
      for (const auto& why : found.ignored) fmt::print("  {}\n", why);
    }
    if (found.readings.empty())
      throw Error(fmt::format("{}: no stop of {:g} s within {:g} µm lies at a target", log_file,
                              lo.dwell_time, a.dwell_tolerance_um));
    runs.readings = std::move(found.readings);
  } else if (io::is_rtl_file(a.input)) {
    io::RtlOptions ro;
    ro.directions = io::run_directions_from(a.run_directions);
    io::RtlFile rtl = io::read_rtl(a.input, ro);
    if (!a.quiet)
      fmt::print("{}: Renishaw .rtl, {} targets, {} runs, {} readings\n", a.input,
                 rtl.targets.size(), rtl.run_count, rtl.runs.readings.size());
    source_warnings = std::move(rtl.warnings);
    for (const auto& w : source_warnings)
      std::fprintf(stderr, "trueaxis positioning: warning: %s\n", w.c_str());
    runs = std::move(rtl.runs);
  } else {
    if (a.run_directions != "order")
      throw CLI::ValidationError("--run-directions belongs to a Renishaw .rtl input");
    runs = io::read_runs(a.input);
  }
  positioning::Options o = a.o;
  o.expansion_coefficient = a.expansion_ppm * 1e-6;
  o.correct_temperature = !a.no_temperature;
  if (runs.lines.size() == runs.readings.size())
    o.locate = [&](std::size_t k) { return fmt::format("{}:{}:1: ", a.input, runs.lines[k]); };
  positioning::Result r;
  try {
    r = positioning::evaluate(runs.readings, o);
  } catch (const Error& e) {
    // A message that names its place in the file (file:line:col) already names the file.
    const std::string what = e.what();
    throw Error(
        o.locate && what.rfind(a.input + ":", 0) == 0 ? what : fmt::format("{}: {}", source, what));
  }
  r.warnings.insert(r.warnings.begin(), source_warnings.begin(), source_warnings.end());
  const bool vdi = a.standard == "vdi3441";
  const auto verdicts = positioning::check(r, tol);
  const auto standard = vdi ? positioning::Standard::Vdi3441 : positioning::Standard::Iso230_2;
  io::write_positioning_result(a.output, r, standard, verdicts);
  // The same axis before its compensation: a result this command wrote earlier.
  std::optional<io::PositioningFile> before;
  if (!a.before.empty()) {
    before = io::read_positioning_result(a.before);
    const auto& b = before->result;
    if (b.targets.empty() || r.targets.empty() ||
        b.targets.back().position < r.targets.front().position ||
        r.targets.back().position < b.targets.front().position)
      throw Error(fmt::format(
          "{}: its targets ({:g} … {:g} mm) do not overlap this run's ({:g} … {:g} mm): not the "
          "same axis before compensation",
          a.before, b.targets.empty() ? NAN : b.targets.front().position,
          b.targets.empty() ? NAN : b.targets.back().position,
          r.targets.empty() ? NAN : r.targets.front().position,
          r.targets.empty() ? NAN : r.targets.back().position));
  }
  if (!a.report.empty()) {
    auto section =
        report::positioning_section("Positioning accuracy of a linear axis", r, standard, verdicts);
    if (before) report::add_before_after(section, before->result, r);
    report::write(a.report, report::render("trueaxis positioning report",
                                           {from_file(std::move(section), source)}, 4000,
                                           cli::report_meta()));
  }
  bool pass = true;
  std::string failed;
  for (const auto& v : verdicts) {
    if (v.pass) continue;
    pass = false;
    if (!v.not_judged.empty()) {
      failed = "not judged: " + v.not_judged;
      break;
    }
    failed += fmt::format("{}{} {} (tolerance {:g} µm)", failed.empty() ? "" : "; ", v.name,
                          std::isnan(v.value) ? std::string("is not defined by these runs")
                                              : fmt::format("= {:.2f} µm", v.value * 1e3),
                          v.limit * 1e3);
  }
  if (!a.quiet) {
    fmt::print("{}", r.summary(vdi));
    if (before)
      fmt::print(
          "  before compensation ({}): A {:.2f} -> {:.2f} µm, E {:.2f} -> {:.2f} µm, B "
          "mean {:.2f} -> {:.2f} µm\n",
          a.before, before->result.iso.A * 1e3, r.iso.A * 1e3, before->result.iso.E * 1e3,
          r.iso.E * 1e3, before->result.iso.B_mean * 1e3, r.iso.B_mean * 1e3);
    if (!verdicts.empty())
      fmt::print("  tolerances: {}\n", pass                     ? "all met"
                                       : !r.implausible.empty() ? "NOT JUDGED (see below)"
                                                                : "NOT MET");
    fmt::print("wrote {}{}\n", a.output, a.report.empty() ? "" : " and " + a.report);
  }
  if (!pass) {
    std::fprintf(stderr, "trueaxis positioning: %s%s\n",
                 r.implausible.empty() ? "out of tolerance: " : "", failed.c_str());
    return 1;
  }
  return 0;
}

// The numbers of `s` separated by `sep`.
std::vector<double> split_numbers(const std::string& s, char sep, const std::string& what) {
  std::vector<double> v;
  for (std::size_t b = 0;;) {
    const std::size_t e = s.find(sep, b);
    v.push_back(
        parse_number(std::string_view(s).substr(b, e == std::string::npos ? e : e - b), what));
    if (e == std::string::npos) return v;
    b = e + 1;
  }
}

// "0:50:800" (start:step:end, end included) or "0,50,120".
std::vector<double> parse_targets(const std::string& s) {
  if (s.find(':') == std::string::npos) return split_numbers(s, ',', "--targets");
  const std::vector<double> p = split_numbers(s, ':', "--targets");
  if (p.size() != 3 || !(p[1] > 0) || !(p[2] > p[0]))
    throw CLI::ValidationError("--targets",
                               "use START:STEP:END with STEP > 0 and END > START, e.g. 0:50:800");
  const double n = std::floor((p[2] - p[0]) / p[1] + 1e-9);
  if (n > 10000) throw CLI::ValidationError("--targets", "more than 10000 targets");
  std::vector<double> t;
  for (int i = 0; i <= static_cast<int>(n); ++i) t.push_back(p[0] + i * p[1]);
  return t;
}

struct SimArgs {
  MachineSource machine;
  std::string axis = "x", targets, output = "runs.csv", truth, temperature, compensation, log,
              comp_format = "linuxcnc";
  int comp_type = 1;
  io::FanucOptions fanuc;
  std::vector<double> at;
  sim::PositioningRunOptions o;
  double backlash_um = 0, noise_um = 0, drift_um = 0, growth_um_per_m = 0, expansion_ppm = 11.5;
  bool quiet = false;
};

int run_simulate(const SimArgs& a) {
  const sim::Machine m = a.machine.load();
  sim::PositioningRunOptions o = a.o;
  o.axis = a.axis == "x" ? 0 : a.axis == "y" ? 1 : 2;
  const auto& range = m.range[static_cast<std::size_t>(o.axis)];
  o.targets = a.targets.empty() ? parse_targets(fmt::format("{:g}:{:g}:{:g}", range[0],
                                                            (range[1] - range[0]) / 16, range[1]))
                                : parse_targets(a.targets);
  if (!a.at.empty()) {
    if (a.at.size() != 3) throw CLI::ValidationError("--at", "give three numbers x,y,z (mm)");
    for (int k = 0; k < 3; ++k)
      if (k != o.axis) o.at[k] = a.at[static_cast<std::size_t>(k)];
  }
  o.backlash = a.backlash_um * 1e-3;
  o.noise = a.noise_um * 1e-3;
  o.drift = a.drift_um * 1e-3;
  o.growth = a.growth_um_per_m * 1e-3;
  o.expansion_coefficient = a.expansion_ppm * 1e-6;
  if (!a.temperature.empty()) {
    const auto c = a.temperature.find(':');
    o.temperature_start =
        parse_number(std::string_view(a.temperature).substr(0, c), "--temperature");
    o.temperature_end =
        c == std::string::npos
            ? o.temperature_start
            : parse_number(std::string_view(a.temperature).substr(c + 1), "--temperature");
  }
  compensation::AxisTable table;
  if (!a.compensation.empty()) {
    if (a.comp_format == "sinumerik") {
      table = io::read_sinumerik(a.compensation);
    } else if (a.comp_format == "heidenhain") {
      table = io::read_heidenhain(a.compensation);
    } else if (a.comp_format == "fanuc") {
      io::FanucOptions fo = a.fanuc;
      if (std::isnan(fo.reference)) fo.reference = o.targets.front();
      table = io::read_fanuc(a.compensation, fo);
    } else {
      table = io::read_linuxcnc(a.compensation, a.comp_type);
    }
    o.compensation = [&table](double p, positioning::Direction d) {
      return table.correction(p, d);
    };
  }
  sim::PositioningRun run;
  if (a.log.empty()) {
    run = sim::simulate_positioning(m, o);
  } else {
    auto sl = sim::simulate_positioning_log(m, o);
    io::write_log(a.log, sl.log);
    run = std::move(sl.run);
  }
  if (io::has_rtl_name(a.output)) {
    std::string ax = a.axis;
    for (char& ch : ax) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
    // An .rtl file carries deviations with the laser software's material compensation applied
    // and no temperatures: correct them to 20 C as that software would, with the axis'
    // expansion coefficient about the laser's datum (the first target).
    std::vector<positioning::Reading> readings = run.readings;
    if (!std::isnan(o.temperature_start)) {
      positioning::Options eo;
      eo.expansion_coefficient = o.expansion_coefficient;
      eo.datum = o.targets.front();
      eo.allow_incomplete = true;
      readings = positioning::evaluate(run.readings, eo).readings;
    }
    io::write_rtl(a.output, readings,
                  {{"Machine", m.name.empty() ? "virtual machine" : m.name}, {"Axis", ax}});
  } else {
    io::write_runs(a.output, run.readings);
  }
  const std::string truth = a.truth.empty() ? truth_beside(a.output) : a.truth;
  const Eigen::VectorXd g = run.geometric * 1e3, up = run.up * 1e3, down = run.down * 1e3;
  io::write_csv(truth, {"target_mm", "geometric_um", "up_um", "down_um"},
                {&run.targets, &g, &up, &down});
  if (!a.quiet)
    fmt::print("simulated {} cycles over {} targets along {} of {}{}: wrote {} and {}\n", o.cycles,
               o.targets.size(), a.axis, m.name.empty() ? "the virtual machine" : m.name,
               a.compensation.empty() ? "" : " compensated by " + a.compensation, a.output, truth);
  return 0;
}

}  // namespace

std::vector<Command> add_positioning_commands(CLI::App& app, CLI::App& simulate) {
  auto sa = std::make_shared<SimArgs>();
  auto* sc = simulate.add_subcommand(
      "positioning",
      "Virtual laser-interferometer runs on one axis of a virtual machine, in the standard test "
      "cycle of ISO 230-2 (targets up, then down, every cycle), with backlash, drift, thermal "
      "growth and noise. Writes the runs CSV that 'trueaxis positioning' reads and the truth "
      "(target_mm, geometric_um: the machine's error from the first target; up_um, down_um: the "
      "noise-free mean deviation of each direction at 20 °C).\nExample: trueaxis simulate "
      "positioning --axis x --targets 0:50:800 --cycles 5 --backlash 3 --noise 0.5 -o runs.csv");
  sa->machine.add_options(sc);
  sc->add_option("--axis", sa->axis, "the axis under test")
      ->transform(cli::machine_axis())
      ->capture_default_str();
  sc->add_option("--targets", sa->targets,
                 "target positions, mm: START:STEP:END or a list 0,55,103 (default: 17 over the "
                 "axis range)");
  sc->add_option("--cycles", sa->o.cycles, "cycles (ISO 230-2: 5)")->capture_default_str();
  sc->add_option("--at", sa->at, "the other axes' coordinates x,y,z, mm (default: mid-range)")
      ->delimiter(',');
  sc->add_option("--backlash", sa->backlash_um, "lost motion on reversal, µm")
      ->capture_default_str();
  sc->add_option("--noise", sa->noise_um, "reading noise, µm (standard deviation)")
      ->capture_default_str();
  sc->add_option("--drift", sa->drift_um, "zero drift over the whole test, µm")
      ->capture_default_str();
  sc->add_option("--growth", sa->growth_um_per_m,
                 "thermal growth of the axis reached at the end of the test, µm per metre "
                 "(not in the readings' temperatures)")
      ->capture_default_str();
  sc->add_option("--temperature", sa->temperature,
                 "material temperature T0:T1, C, ramping over the test: the axis expands with it "
                 "and the readings carry it (material_temp_c)");
  sc->add_option("--expansion", sa->expansion_ppm, "expansion coefficient of the axis, ppm/K")
      ->capture_default_str();
  sc->add_option("--compensation", sa->compensation,
                 "run the axis compensated by this table (LinuxCNC: forward or reverse trim by "
                 "the direction of approach; interpolated linearly)")
      ->check(cli::existing_file());
  sc->add_option("--comp-format", sa->comp_format,
                 "the table's format: linuxcnc (COMP_FILE), sinumerik (LEC part program), "
                 "heidenhain (*.COM table) or fanuc (pitch error data)")
      ->check(CLI::IsMember({"linuxcnc", "sinumerik", "heidenhain", "fanuc"}))
      ->capture_default_str();
  sc->add_option("--comp-reference", sa->fanuc.reference,
                 "a FANUC table's reference position on the axis, mm (default: the first "
                 "target, where 'export fanuc' puts it by default)");
  sc->add_option("--comp-axis-number", sa->fanuc.axis_number,
                 "which axis' parameters of a FANUC file to read (A1, A2, ...)")
      ->capture_default_str();
  sc->add_option("--comp-detection-unit", sa->fanuc.detection_unit,
                 "a FANUC axis' detection unit, mm")
      ->capture_default_str();
  sc->add_option("--comp-type", sa->comp_type, "a LinuxCNC table's COMP_FILE_TYPE (0 or 1)")
      ->check(CLI::IsMember({0, 1}))
      ->capture_default_str();
  sc->add_option("--log", sa->log,
                 "also write the runs as an interferometer log (time_s, reading_mm; 10 samples "
                 "per second, 1000 mm/min, 3 s stops, 5 mm overrun)");
  sc->add_option("--seed", sa->o.seed, "seed of the noise")->capture_default_str();
  sc->add_option("--output,-o", sa->output,
                 "runs CSV to write (a name ending in .rtl: Renishaw's .rtl text file)")
      ->capture_default_str();
  sc->add_option("--truth", sa->truth, "truth CSV; default: the output's name with -truth");
  sc->add_flag("--quiet,-q", sa->quiet, "print nothing on success");

  auto a = std::make_shared<PositioningArgs>();
  auto* c = app.add_subcommand(
      "positioning",
      "Accuracy and repeatability of positioning of a linear axis from bidirectional laser runs, "
      "by ISO 230-2:2014 (A, E, M, R, B and their one-direction forms) or VDI/DGQ 3441 (P, Pa, "
      "Ps, U).\nruns.csv: target_mm,cycle,direction,deviation_um (direction '+' for an approach "
      "moving in +, '-' for one moving in -; deviation = actual - target), optional "
      "material_temp_c (then deviations are corrected to 20 °C for the axis' expansion) and "
      "air_temp_c (recorded). Rows in any order. Renishaw's .rtl files are read too (each "
      "run's direction from the order it lists its targets, or --run-directions).\nParameters the "
      "runs cannot define (one "
      "direction only, a single cycle) are written as null and named, never guessed.\nExit "
      "status 1 when a parameter exceeds its --tolerance (the result is still written).\n"
      "Example: trueaxis positioning --input runs.csv --tolerance A=12,R=4 --output "
      "positioning.json");
  c->add_option("--input,-i", a->input,
                "runs CSV, a Renishaw .rtl file (laser software's export: targets in mm, "
                "deviations in µm), or an interferometer log (time_s, reading_mm: the readings "
                "are the stops at --targets, found by dwell)")
      ->required()
      ->check(cli::existing_file());
  c->add_option("--run-directions", a->run_directions,
                "with an .rtl file: how its runs went. order: from the order each run lists its "
                "targets (default); +-: odd runs '+', even '-'; -+; + or -: all one way")
      ->check(CLI::IsMember({"order", "+-", "-+", "+", "-"}))
      ->capture_default_str();
  c->add_option("--targets", a->log_targets,
                "with an interferometer log: where the axis stopped, START:STEP:END or a list, "
                "mm");
  c->add_option("--dwell", a->lo.dwell_time, "with a log: the shortest stop, s")
      ->capture_default_str();
  c->add_option("--dwell-tolerance", a->dwell_tolerance_um,
                "with a log: the reading's range during a stop, µm")
      ->capture_default_str();
  c->add_option("--capture", a->lo.capture,
                "with a log: a stop this close to a target is at it, mm (default: a quarter of "
                "the target spacing, at most 0.5)");
  c->add_option("--output,-o", a->output, "result JSON (µm)")->capture_default_str();
  c->add_option("--report", a->report,
                "HTML report: the standard's plot (mean deviations with +-2s), every reading, "
                "the parameters and tolerances");
  add_meta_option(c);
  c->add_option("--before", a->before,
                "the result JSON of the same axis before its compensation (this command's "
                "--output then): printed and drawn with this run on one plot")
      ->check(cli::existing_file());
  c->add_option("--standard", a->standard, "iso230-2 (ISO 230-2:2014) or vdi3441 (VDI/DGQ 3441)")
      ->check(CLI::IsMember({"iso230-2", "vdi3441"}))
      ->capture_default_str();
  c->add_option("--tolerance", a->tolerances,
                "NAME=µm, e.g. A=12,R=4,B=3: check parameters (A, A_up, A_down, E, E_up, E_down, "
                "M, R, R_up, R_down, B, B_mean, P, Pa, Ps, U)")
      ->delimiter(',');
  c->add_option("--expansion", a->expansion_ppm,
                "expansion coefficient of the axis for the correction to 20 °C, ppm/K (steel "
                "11.5, cast iron 10.5, aluminium 23)")
      ->capture_default_str();
  c->add_option("--datum", a->o.datum,
                "position where the laser was zeroed, mm (the expansion correction is zero "
                "there; default: the lowest target)");
  c->add_flag("--no-temperature-correction", a->no_temperature,
              "keep the deviations as read although material temperatures are given");
  c->add_flag("--allow-incomplete", a->o.allow_incomplete,
              "evaluate targets that miss readings in some cycles with the readings they have");
  c->add_option("--target-tolerance", a->o.target_tolerance,
                "readings whose targets differ by less than this are one target, mm")
      ->capture_default_str();
  c->add_flag("--quiet,-q", a->quiet, "print nothing on success");

  return {{sc, [sa] { return run_simulate(*sa); }}, {c, [a] { return run_positioning(*a); }}};
}

}  // namespace trueaxis::cli
