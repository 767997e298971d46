// trueaxis CLI — circular tests with a ballbar (ISO 230-4): 'circular' and 'simulate circular'.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>

#include "commands.hpp"
#include "trueaxis/circular/circular.hpp"
#include "trueaxis/circular/compensation.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/circular/circular.hpp"
#include "trueaxis/io/circular/compensation.hpp"
#include "trueaxis/report/circular.hpp"
#include "trueaxis/sim/circular.hpp"
#include "trueaxis/sim/machine.hpp"

namespace trueaxis::cli {
namespace {

constexpr double kCircularDegree = 3.14159265358979323846 / 180;

struct CircularArgs {
  std::string input, output = "circular.json", report, plane = "XY";
  circular::Options o;
  double spike_decay_deg = 0;
  std::vector<double> pitch;
  std::vector<std::string> tolerances;
  std::string compensation, before;
  std::vector<double> active_backlash_um, travel;
  double active_squareness_um_per_m = 0;
  double start_angle_deg = 0;
  std::string order = "ccw,cw";
  CLI::Option *feed_given = nullptr, *radius_given = nullptr;
  bool quiet = false;
};

int run_circular(const CircularArgs& a) {
  std::vector<std::pair<std::string, double>> tol;
  for (const auto& t : a.tolerances) {
    const auto eq = t.find('=');
    const std::string name = t.substr(0, eq);
    if (eq == std::string::npos || (name != "G" && name != "H"))
      throw CLI::ValidationError("--tolerance", fmt::format("'{}': use G=µm and/or H=µm", t));
    double v = 0;
    try {
      std::size_t used = 0;
      v = std::stod(t.substr(eq + 1), &used);
      if (used != t.size() - eq - 1) throw std::invalid_argument(t);
    } catch (const std::exception&) {
      throw CLI::ValidationError("--tolerance", fmt::format("'{}': not a number of µm", t));
    }
    if (!(v > 0)) throw CLI::ValidationError("--tolerance", fmt::format("{}: must be > 0 µm", t));
    tol.emplace_back(name, v * 1e-3);
  }
  circular::Options o = a.o;
  o.plane = circular::Plane::parse(a.plane);
  o.spike_decay = a.spike_decay_deg * kCircularDegree;
  if (!a.pitch.empty()) {
    if (a.pitch.size() != 2) throw CLI::ValidationError("--pitch", "give A,B (mm; 0: none)");
    o.pitch_a = a.pitch[0];
    o.pitch_b = a.pitch[1];
  }
  // A time series is turned into angles with the feed and radius the user states (not defaults).
  io::TimeSeriesOptions series;
  series.feed = a.feed_given->count() ? o.feed : NAN;
  series.radius = a.radius_given->count() ? o.radius : NAN;
  series.start_angle = a.start_angle_deg * kCircularDegree;
  series.order = io::TimeSeriesOptions::order_of(a.order);
  const circular::Trace trace = io::read_trace(a.input, &series);
  circular::Result r;
  try {
    r = circular::evaluate(trace, o);
  } catch (const Error& e) {
    const std::string what = e.what();
    throw Error(what.rfind(a.input + ":", 0) == 0 ? what : a.input + ": " + what);
  }
  io::write_circular_result(a.output, r, &trace);
  io::CircularFile before;
  if (!a.before.empty()) {
    before = io::read_circular_result(a.before);
    if (before.result.plane.name() != r.plane.name() ||
        std::abs(before.result.radius - r.radius) > 1e-9 * r.radius)
      throw Error(fmt::format("{}: a test in {} of radius {:g} mm; this one is in {} of {:g} mm",
                              a.before, before.result.plane.name(), before.result.radius,
                              r.plane.name(), r.radius));
    if (before.trace.angle.size() == 0)
      throw Error(a.before + ": holds no trace to draw (write it with this version)");
  }
  std::optional<circular::Compensation> comp;
  io::CompensationFiles files;
  if (!a.compensation.empty()) {
    circular::CompensationOptions co;
    if (!a.active_backlash_um.empty()) {
      if (a.active_backlash_um.size() != 2)
        throw CLI::ValidationError("--active-backlash", "give A,B (µm) for the plane's two axes");
      co.active_backlash = {a.active_backlash_um[0] * 1e-3, a.active_backlash_um[1] * 1e-3};
    }
    co.active_squareness = a.active_squareness_um_per_m * 1e-6;
    io::CompensationFilesOptions fo;
    if (!a.travel.empty()) {
      if (a.travel.size() != 2 || !(a.travel[1] > a.travel[0]))
        throw CLI::ValidationError("--travel", "give LOW,HIGH (mm) of the plane's second axis");
      fo.travel = std::array<double, 2>{a.travel[0], a.travel[1]};
    }
    comp = circular::compensation_from(r, co);
    files = io::write_compensation_files(a.compensation, *comp, fo);
  }
  if (!a.report.empty()) {
    report::Section section = report::circular_section(
        fmt::format("Circular test in {} (ISO 230-4)", o.plane.name()), r, trace,
        a.before.empty() ? report::CircularBefore{}
                         : report::CircularBefore{&before.result, &before.trace});
    if (comp) {
      std::vector<std::vector<std::string>> rows{{"file", "controller", "what"}};
      for (const auto& w : files.written)
        rows.push_back({std::filesystem::path(w.path).filename().string(), w.controller, w.what});
      for (const auto& n : files.not_written)
        rows.push_back({"not written", n.controller, n.what + ": " + n.reason});
      report::add_compensation(section, *comp, rows);
    }
    report::write(a.report,
                  report::render("trueaxis circular test report",
                                 {from_file(std::move(section), a.input)}, 4000, report_meta()));
  }
  std::string failed;
  for (const auto& [name, limit] : tol) {
    const double value = name == "G" ? std::max(r.ccw.G, r.cw.G) : (r.H ? *r.H : std::nan(""));
    if (std::isnan(value))
      failed += fmt::format("{}H is not defined by one direction", failed.empty() ? "" : "; ");
    else if (value > limit)
      failed += fmt::format("{}{} = {:.2f} µm (tolerance {:g} µm)", failed.empty() ? "" : "; ",
                            name, value * 1e3, limit * 1e3);
  }
  if (!a.quiet) {
    fmt::print("{}", r.summary());
    if (!a.before.empty())
      fmt::print("  before ({}): G {:.2f} µm, H {}\n", a.before,
                 std::max(before.result.ccw.G, before.result.cw.G) * 1e3,
                 before.result.H ? fmt::format("{:.2f} µm", *before.result.H * 1e3)
                                 : std::string("not defined"));
    if (!tol.empty()) fmt::print("  tolerances: {}\n", failed.empty() ? "all met" : "NOT MET");
    if (comp) {
      fmt::print("{}", comp->summary());
      for (const auto& w : files.written)
        fmt::print("  wrote {} ({}: {}; read back and checked)\n", w.path, w.controller, w.what);
      for (const auto& n : files.not_written)
        fmt::print("  not written for {}: {} ({})\n", n.controller, n.what, n.reason);
      fmt::print("  wrote {}\n", files.json_path);
    }
    fmt::print("wrote {}{}\n", a.output, a.report.empty() ? "" : " and " + a.report);
  }
  if (!failed.empty()) {
    std::fprintf(stderr, "trueaxis circular: tolerance not met: %s\n", failed.c_str());
    return 1;
  }
  return 0;
}

struct CircularSimArgs {
  MachineSource machine;
  std::string plane = "XY", output = "trace.csv", truth, servo, directions = "both", compensation;
  std::vector<double> centre, pivot_offset_um;
  double arc_deg = 360, overshoot_deg = 180, noise_um = 0, length_error_um = 0, drift_um = 0;
  sim::CircularOptions o;
  bool quiet = false;
};

int run_simulate_circular(const CircularSimArgs& a) {
  const sim::Machine m = a.machine.load();
  sim::CircularOptions o = a.o;
  o.plane = circular::Plane::parse(a.plane);
  if (!a.centre.empty()) {
    if (a.centre.size() != 3) throw CLI::ValidationError("--centre", "give X,Y,Z (mm)");
    o.centre = {a.centre[0], a.centre[1], a.centre[2]};
  }
  if (!a.pivot_offset_um.empty()) {
    if (a.pivot_offset_um.size() != 3)
      throw CLI::ValidationError("--pivot-offset", "give X,Y,Z (µm)");
    o.pivot_offset =
        Eigen::Vector3d(a.pivot_offset_um[0], a.pivot_offset_um[1], a.pivot_offset_um[2]) * 1e-3;
  }
  o.arc = a.arc_deg * kCircularDegree;
  o.overshoot = a.overshoot_deg * kCircularDegree;
  o.noise = a.noise_um * 1e-3;
  o.length_error = a.length_error_um * 1e-3;
  o.drift = a.drift_um * 1e-3;
  o.ccw = a.directions != "cw";
  o.cw = a.directions != "ccw";
  if (!a.servo.empty()) o.servo = io::read_servo(a.servo);
  if (!a.compensation.empty()) {
    io::read_compensation_json(a.compensation).apply(o);
  }
  const auto run = sim::simulate_circular(m, o);
  io::write_trace(a.output, run.trace);
  const std::string truth = a.truth.empty() ? truth_beside(a.output) : a.truth;
  const std::string truth_json = truth.size() > 4 && truth.substr(truth.size() - 4) == ".csv"
                                     ? truth.substr(0, truth.size() - 4) + ".json"
                                     : truth;
  io::write_circular_truth(truth_json, sim::circular_truth(m, o), o.plane);
  if (!a.quiet)
    fmt::print(
        "simulated a circular test in {} of {} (radius {:g} mm, feed {:g} mm/min, {} "
        "samples): wrote {} and {}\n",
        o.plane.name(),
        a.machine.path.empty() ? fmt::format("the random machine of seed {}", a.machine.seed)
                               : a.machine.path,
        o.radius, o.feed, run.trace.angle.size(), a.output, truth_json);
  return 0;
}

}  // namespace

std::vector<Command> add_circular_commands(CLI::App& app, CLI::App& simulate) {
  auto sa = std::make_shared<CircularSimArgs>();
  auto* sc = simulate.add_subcommand(
      "circular",
      "A circular test with a telescoping ballbar on the virtual machine (ISO 230-4): the two "
      "axes of a plane contour a circle under their position loops (lag, backlash, reversal "
      "spikes, cyclic error per axis, from --servo) with the machine's geometric errors; the "
      "ballbar reads the tool's distance from its pivot. Writes the trace 'trueaxis circular' "
      "reads, and the truth it should find.\nservo.json: {\"X\": {\"gain_per_s\": 30, "
      "\"backlash_um\": 3, \"spike_um\": 4, \"spike_decay_deg\": 5, \"cyclic_um\": 0.5, "
      "\"pitch_mm\": 10}, \"Y\": {...}}.\nExample: trueaxis simulate circular --machine "
      "machine.json --plane XY --radius 100 --feed 1000 --servo servo.json --noise 0.1 -o "
      "trace.csv");
  sa->machine.add_options(sc);
  sc->add_option("--plane", sa->plane, "XY, YZ or ZX")
      ->check(CLI::IsMember({"XY", "YZ", "ZX"}, CLI::ignore_case))
      ->capture_default_str();
  sc->add_option("--radius", sa->o.radius, "mm (the ballbar's calibrated length)")
      ->capture_default_str();
  sc->add_option("--feed", sa->o.feed, "mm/min")->capture_default_str();
  sc->add_option("--centre", sa->centre, "the circle's centre X,Y,Z (mm; default: mid-range)")
      ->delimiter(',');
  sc->add_option("--arc", sa->arc_deg, "data arc, degrees")->capture_default_str();
  sc->add_option("--overshoot", sa->overshoot_deg,
                 "feed-in and feed-out arcs together, degrees (half before, half after)")
      ->capture_default_str();
  sc->add_option("--directions", sa->directions, "both (ccw, then cw), ccw or cw")
      ->check(CLI::IsMember({"both", "ccw", "cw"}))
      ->capture_default_str();
  sc->add_option("--servo", sa->servo, "servo.json: per axis gain, backlash, spikes, cyclic error")
      ->check(existing_file());
  sc->add_option("--pivot-offset", sa->pivot_offset_um, "the pivot's set-up offset X,Y,Z (µm)")
      ->delimiter(',');
  sc->add_option("--length-error", sa->length_error_um, "the ballbar's calibration error, µm")
      ->capture_default_str();
  sc->add_option("--drift", sa->drift_um, "the ballbar's length drift over each run, µm")
      ->capture_default_str();
  sc->add_option("--compensation", sa->compensation,
                 "compensation.json from 'trueaxis circular --compensation': run the test with "
                 "that backlash and squareness compensation loaded in the controller")
      ->check(existing_file());
  sc->add_option("--noise", sa->noise_um, "reading noise, µm (standard deviation)")
      ->capture_default_str();
  sc->add_option("--sample-rate", sa->o.sample_rate, "Hz")->capture_default_str();
  sc->add_option("--seed", sa->o.seed, "seed of the noise")->capture_default_str();
  sc->add_option("--output,-o", sa->output, "trace CSV to write")->capture_default_str();
  sc->add_option("--truth", sa->truth,
                 "truth JSON (what the diagnosis should find); default: the output's name with "
                 "-truth.json");
  sc->add_flag("--quiet,-q", sa->quiet, "print nothing on success");

  auto a = std::make_shared<CircularArgs>();
  auto* c = app.add_subcommand(
      "circular",
      "A circular test with a telescoping ballbar (ISO 230-4): the circular deviation G per "
      "direction, the radial deviation F and the circular hysteresis H, and the trace explained "
      "by its causes (centre offset, squareness, scale and servo lag mismatch, backlash, reversal "
      "spikes, straightness, cyclic error), each with its uncertainty and share of G.\ntrace.csv: "
      "direction (ccw or cw), angle_deg (from the plane's first axis towards its second), "
      "deviation_um (the reading less the calibrated length); or a raw time series t_s, "
      "deviation_um with --feed, --radius, --start-angle and --order.\nExit status 1 when G or H "
      "exceeds "
      "its --tolerance (the result is still written).\nExample: trueaxis circular --input "
      "trace.csv --plane XY --radius 100 --feed 1000 -o circular.json --report circular.html");
  c->add_option("--input,-i", a->input, "trace CSV")->required()->check(existing_file());
  c->add_option("--plane", a->plane, "XY, YZ or ZX")
      ->check(CLI::IsMember({"XY", "YZ", "ZX"}, CLI::ignore_case))
      ->capture_default_str();
  a->radius_given = c->add_option("--radius", a->o.radius, "mm (the ballbar's calibrated length)")
                        ->capture_default_str();
  a->feed_given =
      c->add_option("--feed", a->o.feed, "mm/min (for the lag mismatch)")->capture_default_str();
  c->add_option("--start-angle", a->start_angle_deg,
                "a time series: the angle (degrees) of each run's first sample")
      ->capture_default_str();
  c->add_option("--order", a->order,
                "a time series: the runs' directions in time order (ccw,cw; cw,ccw; ccw; cw)")
      ->check(CLI::IsMember({"ccw,cw", "cw,ccw", "ccw", "cw"}))
      ->capture_default_str();
  c->add_option("--spike-decay", a->spike_decay_deg,
                "reversal spikes' decay, degrees of the circle (0: found from the data)")
      ->capture_default_str();
  c->add_option("--pitch", a->pitch, "ball screw pitches A,B (mm) to fit cyclic errors of")
      ->delimiter(',');
  c->add_option("--tolerance", a->tolerances, "G=µm and/or H=µm: check them")->delimiter(',');
  c->add_option("--compensation", a->compensation,
                "folder to write the backlash and squareness compensation to, for LinuxCNC, "
                "HEIDENHAIN, FANUC and Siemens (each file read back and checked), with "
                "compensation.json");
  c->add_option("--active-backlash", a->active_backlash_um,
                "A,B: the backlash compensation (µm) active during the test; the new values add "
                "what the test found")
      ->delimiter(',');
  c->add_option("--active-squareness", a->active_squareness_um_per_m,
                "the squareness compensation (µm/m) active during the test")
      ->capture_default_str();
  c->add_option("--travel", a->travel,
                "LOW,HIGH: the plane's second axis' travel (mm), the span of the squareness "
                "tables (without it no table is written)")
      ->delimiter(',');
  c->add_option("--before", a->before,
                "circular.json of the same test before a compensation: drawn on the same polar "
                "plot, its G and H beside the new ones")
      ->check(existing_file());
  c->add_option("--output,-o", a->output, "result JSON")->capture_default_str();
  c->add_option("--report", a->report,
                "HTML report: the polar plot, the figures, the diagnosis, the trace and its fit");
  add_meta_option(c);
  c->add_flag("--quiet,-q", a->quiet, "print nothing on success");
  return {{sc, [sa] { return run_simulate_circular(*sa); }}, {c, [a] { return run_circular(*a); }}};
}

}  // namespace trueaxis::cli
