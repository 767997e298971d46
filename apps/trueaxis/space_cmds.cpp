// trueaxis CLI — error space and compensation: 'space', 'compensate', 'export
// linuxcnc|sinumerik|heidenhain|fanuc|csv'.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <memory>

#include "commands.hpp"
#include "progress.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/compensation/controller.hpp"
#include "trueaxis/io/csv.hpp"
#include "trueaxis/io/positioning/positioning.hpp"
#include "trueaxis/io/sim/machine.hpp"
#include "trueaxis/io/surface/space.hpp"
#include "trueaxis/map/error_map.hpp"
#include "trueaxis/report/surface.hpp"
#include "trueaxis/surface/space.hpp"

namespace trueaxis::cli {
namespace {

struct SpaceArgs {
  std::string machine, plan, output, csv, report;
  long verify = 1000;
  bool quiet = false;
};

int run_space(const SpaceArgs& a) {
  const sim::Machine m = io::read_machine(a.machine);
  const surface::SpacePlan plan = a.plan.empty() ? surface::SpacePlan{} : io::read_plan(a.plan);
  const auto t0 = std::chrono::steady_clock::now();
  if (!a.quiet) {
    const auto axes = surface::space_axes(m, plan);
    fmt::print("measuring the error space on a {} x {} x {} grid{}...\n", axes[0].size(),
               axes[1].size(), axes[2].size(),
               plan.monte_carlo >= 2
                   ? fmt::format(" ({} repetitions for the uncertainty)", plan.monte_carlo)
                   : "");
    std::fflush(stdout);
  }
  Progress progress("measuring", a.quiet);
  const surface::SpaceResult s =
      surface::measure_space(m, plan, [&](double f) { progress.update(f); });
  progress.done();
  std::optional<surface::Verification> v;
  if (a.verify > 0) v = surface::verify_compensation(m, s.map, a.verify, plan.seed);
  io::write_space(a.output, s, plan, v);
  if (!a.csv.empty()) io::write_map_csv(a.csv, s.map);
  if (!a.report.empty())
    report::write(
        a.report,
        report::render("trueaxis error space report",
                       {report::space_section("Error space of a machine", s, v ? &*v : nullptr)},
                       4000, cli::report_meta()));
  if (!a.quiet) {
    fmt::print("{}", s.summary());
    if (v) {
      fmt::print(
          "  compensation check at {} random points (rigid-body part removed):\n"
          "    before: RMS {:.3f} µm, max {:.3f} µm\n    after:  RMS {:.3f} µm, max {:.3f} µm "
          "(improvement x{:.1f})\n",
          v->points, v->before_rms * 1e3, v->before_max * 1e3, v->after_rms * 1e3,
          v->after_max * 1e3, v->improvement());
      if (v->uncertainty_known)
        fmt::print(
            "    expected after: RMS {:.3f} µm = interpolation {:.3f} (+) map uncertainty {:.3f}\n",
            v->predicted_rms * 1e3, v->interpolation_rms * 1e3, v->uncertainty_rms * 1e3);
      else
        fmt::print(
            "    expected after: at least RMS {:.3f} µm (interpolation; the map's uncertainty was "
            "not computed)\n",
            v->interpolation_rms * 1e3);
    }
    fmt::print("wrote {}{}{} in {:.1f} s\n", a.output, a.csv.empty() ? "" : ", " + a.csv,
               a.report.empty() ? "" : ", " + a.report,
               std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  for (const auto& w : surface::space_warnings(s, v ? &*v : nullptr))
    fmt::print(stderr, "trueaxis: warning: {}\n", w);
  return 0;
}

struct CompensateArgs {
  std::string space, input, output, interpolation = "linear";
  int iterations = 2;
  bool clamp = false, quiet = false;
};

int run_compensate(const CompensateArgs& a) {
  const map::ErrorMap m = io::read_error_map(a.space);
  Eigen::Matrix3Xd p = io::read_points(a.input);
  if (!a.clamp) refuse_outside(m, p, a.input);
  map::CompensateOptions o;
  o.eval.interpolation = map::interpolation_from_string(a.interpolation);
  o.eval.outside = a.clamp ? map::Outside::Clamp : map::Outside::Refuse;
  o.iterations = a.iterations;
  try {
    map::compensate(m, p, o);
  } catch (const Error& e) {
    throw Error(fmt::format("{}: {}", a.input, e.what()));
  }
  io::write_points(a.output, p);
  if (!a.quiet && a.output != "-")
    fmt::print("compensated {} commands ({} interpolation, {} iterations): wrote {}\n", p.cols(),
               a.interpolation, a.iterations, a.output);
  return 0;
}

// The grid line of an export: --at x,y,z (the axis' own coordinate is ignored), by default the
// line through the grid's centre.
Eigen::Vector3d line_at(const map::ErrorMap& m, const std::vector<double>& given) {
  if (!given.empty()) {
    if (given.size() != 3) throw Error("--at needs x,y,z (the axis' own coordinate is ignored)");
    return {given[0], given[1], given[2]};
  }
  return compensation::grid_centre(m);
}

struct ExportArgs {
  std::string space, positioning, output, axis = "x";
  std::vector<double> at;
  int type = 1;
  bool unidirectional = false, quiet = false;
};

int run_export_linuxcnc(const ExportArgs& a) {
  if (a.space.empty() == a.positioning.empty())
    throw CLI::ValidationError("give --space FILE or --positioning FILE (one of them)");
  if (!a.positioning.empty()) {
    if (!a.at.empty()) throw CLI::ValidationError("--at belongs to --space");
    const io::PositioningFile f = io::read_positioning_result(a.positioning);
    compensation::AxisTable t;
    try {
      t = compensation::from_positioning(f.result, !a.unidirectional);
    } catch (const Error& e) {
      throw Error(fmt::format("{}: {}", a.positioning, e.what()));
    }
    const int n = io::write_linuxcnc(a.output, t, a.type);
    if (!a.quiet)
      fmt::print(
          "wrote {} ({} points, type {}: {}, {}). In the INI file: [JOINT_n] COMP_FILE = {}, "
          "COMP_FILE_TYPE = {}{}\n",
          a.output, n, a.type, a.type == 0 ? "actual positions" : "trims",
          t.bidirectional() ? "forward and reverse differ by the measured reversal"
                            : "the same in both directions",
          a.output, a.type,
          t.bidirectional() ? " and BACKLASH = 0 (the table holds the reversal)" : "");
    return 0;
  }
  if (a.unidirectional) throw CLI::ValidationError("--unidirectional belongs to --positioning");
  const map::ErrorMap m = io::read_error_map(a.space);
  const int axis = a.axis == "x" ? 0 : a.axis == "y" ? 1 : 2;
  const int n = io::write_linuxcnc(a.output, m, axis, line_at(m, a.at), a.type);
  if (!a.quiet)
    fmt::print(
        "wrote {} ({} points, type {}: {}). In the INI file: [JOINT_n] COMP_FILE = {} and "
        "COMP_FILE_TYPE = {}\n",
        a.output, n, a.type, a.type == 0 ? "actual positions" : "trims", a.output, a.type);
  return 0;
}

// --axis of every export: which machine axis the table is for.
constexpr const char* kTableAxis =
    "the machine axis the table is for: with --space, the grid line along it through --at; with "
    "--positioning, the axis the result is of (it names the axis on the control by default)";

// The control's name of a machine axis when --axis-name is not given: X, Y, Z (and X1, Y1, Z1
// for a Sinumerik).
std::string control_name(const std::string& given, const std::string& axis,
                         const std::string& suffix = "") {
  if (!given.empty()) return given;
  return std::string(1, static_cast<char>(axis[0] - 'x' + 'X')) + suffix;
}

struct SinumerikArgs {
  std::string positioning, space, output, line_axis = "x", axis_name;
  std::vector<double> at;
  io::SinumerikOptions o;
  bool quiet = false;
};

int run_export_sinumerik(SinumerikArgs a) {
  a.o.axis = control_name(a.axis_name, a.line_axis, "1");
  if (a.space.empty() == a.positioning.empty())
    throw CLI::ValidationError("give --space FILE or --positioning FILE (one of them)");
  compensation::AxisTable t;
  io::PositioningFile f;
  if (!a.positioning.empty()) {
    if (!a.at.empty()) throw CLI::ValidationError("--at belongs to --space");
    f = io::read_positioning_result(a.positioning);
    try {
      t = compensation::from_positioning(f.result, false);
    } catch (const Error& e) {
      throw Error(fmt::format("{}: {}", a.positioning, e.what()));
    }
  } else {
    const map::ErrorMap m = io::read_error_map(a.space);
    const int axis = a.line_axis == "x" ? 0 : a.line_axis == "y" ? 1 : 2;
    t = compensation::from_map(m, axis, line_at(m, a.at));
  }
  const int n = io::write_sinumerik(a.output, t, a.o);
  if (!a.quiet) {
    fmt::print("wrote {} ({} points, {}, measuring system {})\n", a.output, n, a.o.axis,
               a.o.encoder);
    const double b = f.result.iso.B_mean;
    if (!std::isnan(b))
      fmt::print(
          "mean reversal {:.4f} mm: set MD32450 $MA_BACKLASH[{}] to {:.4f} (lost motion is "
          "positive there; the LEC table holds the mean of both directions)\n",
          b, a.o.encoder, -b);
    fmt::print(
        "MD38000 $MA_MM_ENC_COMP_MAX_POINTS must be at least {}; MD32700 $MA_ENC_COMP_ENABLE[{}] "
        "= 1 activates it once the axis is referenced\n",
        n, a.o.encoder);
  }
  return 0;
}

// The table of --positioning (bidirectional unless asked otherwise) or of --space's grid line.
compensation::AxisTable table_from(const std::string& positioning, const std::string& space,
                                   const std::string& line_axis, const std::vector<double>& at,
                                   bool bidirectional, io::PositioningFile* file) {
  if (space.empty() == positioning.empty())
    throw CLI::ValidationError("give --space FILE or --positioning FILE (one of them)");
  if (!positioning.empty()) {
    if (!at.empty()) throw CLI::ValidationError("--at belongs to --space");
    *file = io::read_positioning_result(positioning);
    try {
      return compensation::from_positioning(file->result, bidirectional);
    } catch (const Error& e) {
      throw Error(fmt::format("{}: {}", positioning, e.what()));
    }
  }
  const map::ErrorMap m = io::read_error_map(space);
  const int axis = line_axis == "x" ? 0 : line_axis == "y" ? 1 : 2;
  return compensation::from_map(m, axis, line_at(m, at));
}

struct HeidenhainArgs {
  std::string positioning, space, output, line_axis = "x", axis_name;
  std::vector<double> at;
  io::HeidenhainOptions o;
  bool unidirectional = false, quiet = false;
};

int run_export_heidenhain(HeidenhainArgs a) {
  a.o.axis = control_name(a.axis_name, a.line_axis);
  if (a.unidirectional && a.positioning.empty())
    throw CLI::ValidationError("--unidirectional belongs to --positioning");
  io::PositioningFile f;
  const compensation::AxisTable t =
      table_from(a.positioning, a.space, a.line_axis, a.at, !a.unidirectional, &f);
  const int n = io::write_heidenhain(a.output, t, a.o);
  if (!a.quiet)
    fmt::print(
        "wrote {} ({} points; column {}: the compensation for traverse in +, mm; BACKLASH: {}). "
        "Enter the table in the {} column of the *.CMA file and activate its line{}\n",
        a.output, n, a.o.axis,
        t.bidirectional() ? "forward - reverse, the measured reversal at each point"
                          : "0, the same in both directions",
        a.o.axis, t.bidirectional() ? "; the axis' own backlash setting must then be 0" : "");
  return 0;
}

struct FanucArgs {
  std::string positioning, space, output, line_axis = "x", axis_name;
  std::vector<double> at;
  io::FanucOptions o;
  bool quiet = false;
};

int run_export_fanuc(FanucArgs a) {
  a.o.axis_name = control_name(a.axis_name, a.line_axis);
  io::PositioningFile f;
  const compensation::AxisTable t =
      table_from(a.positioning, a.space, a.line_axis, a.at, false, &f);
  const io::FanucTable ft = io::write_fanuc(a.output, t, a.o);
  if (!a.quiet) {
    const double ref = std::isnan(a.o.reference) ? t.position.front() : a.o.reference;
    fmt::print(
        "wrote {}: axis {} ({}), points {} to {}, reference position ({:g} mm of the table) at "
        "point {}, interval {:g} mm, magnification {}\n"
        "parameters: 3620 = {}, 3621 = {}, 3622 = {}, 3623 = {}, 3624 = {:g}\n",
        a.output, a.o.axis_number, a.o.axis_name, ft.negative_number, ft.positive_number, ref,
        ft.reference_number, ft.interval, ft.magnification, ft.reference_number, ft.negative_number,
        ft.positive_number, ft.magnification, ft.interval);
    const double b = f.result.iso.B_mean;
    if (!std::isnan(b))
      fmt::print(
          "mean reversal {:.4f} mm: set parameter 1851 (backlash compensation) of axis {} to {} "
          "detection units (the table holds the mean of both directions)\n",
          b, a.o.axis_number, std::lround(-b / a.o.detection_unit));
    fmt::print(
        "the compensation is zero at the reference position: reference the axis (G28) after "
        "loading, and turn the control off and on after changing 3620 to 3624\n");
  }
  return 0;
}

}  // namespace

std::vector<Command> add_space_commands(CLI::App& app) {
  std::vector<Command> out;
  auto sa = std::make_shared<SpaceArgs>();
  auto* c = app.add_subcommand(
      "space",
      "Measure the error space of a (virtual) machine: straightness runs with displacement "
      "probes -> separated lines -> surfaces on stacked planes, laser positioning runs to stack "
      "them, face diagonals for squareness. Writes the error-vector grid with its uncertainty "
      "and checks compensation at random points.\nExample: trueaxis space --machine "
      "machine.json --plan plan.json -o space.json");
  c->add_option("--machine", sa->machine, "machine JSON ('trueaxis simulate machine')")
      ->required()
      ->check(cli::existing_file());
  c->add_option("--plan", sa->plan,
                "plan JSON: spacing (mm), probes, probe_noise_um, laser_noise_um, profile_um, "
                "diagonals, monte_carlo, seed (default: 50 mm grid over the whole range, "
                "noise-free)")
      ->check(cli::existing_file());
  c->add_option("--output,-o", sa->output, "space JSON to write")->required();
  c->add_option("--csv", sa->csv, "also write the grid as a CSV table");
  add_meta_option(c);
  c->add_option("--report", sa->report,
                "also write an HTML report (distorted planes, level surfaces, uncertainty, "
                "before/after compensation)");
  c->add_option("--verify", sa->verify,
                "random points for the compensation check on the machine (0: none)")
      ->capture_default_str();
  c->add_flag("--quiet,-q", sa->quiet, "print nothing on success");
  out.push_back({c, [sa] { return run_space(*sa); }});

  auto ca = std::make_shared<CompensateArgs>();
  c = app.add_subcommand(
      "compensate",
      "Correct commanded positions with an error space so the machine lands where wanted: "
      "c' = c - e(c'), iterated.\ncommands.csv: header row with columns x,y,z (mm); the output "
      "has the corrected x,y,z.\nExample: trueaxis compensate --space space.json --input "
      "commands.csv --output corrected.csv");
  c->add_option("--space", ca->space, "space JSON ('trueaxis space')")
      ->required()
      ->check(cli::existing_file());
  c->add_option("--input,-i", ca->input, "commands CSV (x,y,z in mm)")
      ->required()
      ->check(cli::existing_file());
  c->add_option("--output,-o", ca->output, "corrected CSV to write ('-': standard output)")
      ->required();
  c->add_option("--interpolation", ca->interpolation, "linear (trilinear) or cubic")
      ->check(CLI::IsMember({"linear", "cubic"}))
      ->capture_default_str();
  c->add_option("--iterations", ca->iterations, "fixed-point iterations (1 or more)")
      ->capture_default_str();
  c->add_flag("--clamp", ca->clamp,
              "hold the edge value for commands outside the grid (default: refuse them)");
  c->add_flag("--quiet,-q", ca->quiet, "print nothing on success");
  out.push_back({c, [ca] { return run_compensate(*ca); }});

  auto* ex = app.add_subcommand(
      "export",
      "Compensation tables for controllers (LinuxCNC, Sinumerik, HEIDENHAIN, FANUC) from a "
      "positioning result or an error space, or an error space as CSV");
  ex->require_subcommand(1);
  auto ea = std::make_shared<ExportArgs>();
  c = ex->add_subcommand(
      "linuxcnc",
      "LinuxCNC per-joint compensation file: lines 'nominal forward reverse' along one axis, "
      "from an error space (the grid line through --at) or from a positioning result (forward "
      "and reverse differ by the measured reversal; --unidirectional for one table for both "
      "directions).\n"
      "Examples: trueaxis export linuxcnc --space space.json --axis x --output x.comp\n"
      "          trueaxis export linuxcnc --positioning positioning.json --output x.comp");
  c->add_option("--space", ea->space, "space JSON")->check(cli::existing_file());
  c->add_option("--positioning", ea->positioning, "positioning JSON ('trueaxis positioning')")
      ->check(cli::existing_file());
  c->add_flag("--unidirectional", ea->unidirectional,
              "with --positioning: the bidirectional mean in both columns (leaves the reversal "
              "to the controller's backlash setting)");
  c->add_option("--axis", ea->axis, kTableAxis)
      ->transform(cli::machine_axis())
      ->capture_default_str();
  c->add_option("--at", ea->at,
                "the line's other coordinates x,y,z in mm (default: the grid's centre)")
      ->delimiter(',');
  c->add_option("--type", ea->type,
                "COMP_FILE_TYPE: 0 = actual positions, 1 = trims (nominal - actual)")
      ->check(CLI::IsMember({0, 1}))
      ->capture_default_str();
  c->add_option("--output,-o", ea->output, "compensation file to write")->required();
  c->add_flag("--quiet,-q", ea->quiet, "print nothing on success");
  out.push_back({c, [ea] { return run_export_linuxcnc(*ea); }});

  auto sn = std::make_shared<SinumerikArgs>();
  c = ex->add_subcommand(
      "sinumerik",
      "Siemens Sinumerik leadscrew error compensation (LEC) as a part program: "
      "$AA_ENC_COMP[e,N,AX] values (mm, the measured error: a positive value moves the axis in "
      "the negative direction) at equidistant points, with _STEP, _MIN, _MAX and "
      "_IS_MODULO = 0, from a positioning result or an error space. One curve for both "
      "directions (the bidirectional mean); the mean reversal is printed for MD32450 "
      "BACKLASH.\n"
      "Example: trueaxis export sinumerik --positioning positioning.json --axis x -o x_lec.mpf");
  c->add_option("--positioning", sn->positioning, "positioning JSON ('trueaxis positioning')")
      ->check(cli::existing_file());
  c->add_option("--space", sn->space,
                "or a space JSON: the error along the grid line of --axis through --at")
      ->check(cli::existing_file());
  c->add_option("--axis", sn->line_axis, kTableAxis)
      ->transform(cli::machine_axis())
      ->capture_default_str();
  c->add_option("--at", sn->at, "with --space: the line's other coordinates x,y,z, mm")
      ->delimiter(',');
  c->add_option("--axis-name", sn->axis_name,
                "the axis' name on the control ($AA_ENC_COMP[e,N,name]; default: --axis as X1, Y1 "
                "or Z1)");
  c->add_option("--encoder", sn->o.encoder, "measuring system (0: first, 1: second)")
      ->check(CLI::IsMember({0, 1}))
      ->capture_default_str();
  c->add_option("--step", sn->o.step,
                "distance between interpolation points, mm (default: the mean target spacing); "
                "the table is interpolated linearly onto them");
  c->add_option("--max-points", sn->o.max_points,
                "MD38000 $MA_MM_ENC_COMP_MAX_POINTS as set on the machine")
      ->capture_default_str();
  c->add_option("--output,-o", sn->output, "part program to write")->required();
  c->add_flag("--quiet,-q", sn->quiet, "print nothing on success");
  out.push_back({c, [sn] { return run_export_sinumerik(*sn); }});

  auto hh = std::make_shared<HeidenhainArgs>();
  c = ex->add_subcommand(
      "heidenhain",
      "HEIDENHAIN nonlinear axis error compensation: a compensation value table (*.COM: NR, "
      "AXISPOS in mm from the machine datum, the axis' column with the compensation for "
      "traverse in +, mm, and BACKLASH = forward - reverse, positive for lost motion), at most "
      "256 points, from a positioning result (both directions; --unidirectional for the mean) or "
      "an error space.\n"
      "Example: trueaxis export heidenhain --positioning positioning.json --axis x -o X.COM");
  c->add_option("--positioning", hh->positioning, "positioning JSON ('trueaxis positioning')")
      ->check(cli::existing_file());
  c->add_option("--space", hh->space,
                "or a space JSON: the error along the grid line of --axis through --at")
      ->check(cli::existing_file());
  c->add_option("--axis", hh->line_axis, kTableAxis)
      ->transform(cli::machine_axis())
      ->capture_default_str();
  c->add_option("--at", hh->at, "with --space: the line's other coordinates x,y,z, mm")
      ->delimiter(',');
  c->add_flag("--unidirectional", hh->unidirectional,
              "with --positioning: the bidirectional mean, BACKLASH 0 (the reversal left to the "
              "axis' backlash setting)");
  c->add_option("--axis-name", hh->axis_name,
                "the axis' column name (as in CfgAxes/axisList; default: --axis as X, Y or Z)");
  c->add_option("--name", hh->o.name, "table name in the BEGIN line (default: the file's name)");
  c->add_option("--output,-o", hh->output, "table to write (*.COM)")->required();
  c->add_flag("--quiet,-q", hh->quiet, "print nothing on success");
  out.push_back({c, [hh] { return run_export_heidenhain(*hh); }});

  auto fa = std::make_shared<FanucArgs>();
  c = ex->add_subcommand(
      "fanuc",
      "FANUC pitch error compensation: the parameters 3620 (reference point number), 3621/3622 "
      "(farthest points), 3623 (magnification), 3624 (interval, mm) and the incremental value of "
      "every point (N10000 + point, detection units, -128..127), as FANUC tape data. One curve "
      "for both directions, zero at the reference position; the mean reversal is printed for "
      "parameter 1851.\n"
      "Example: trueaxis export fanuc --positioning positioning.json --axis-number 1 "
      "--reference 800 -o x-pitch.txt");
  c->add_option("--positioning", fa->positioning, "positioning JSON ('trueaxis positioning')")
      ->check(cli::existing_file());
  c->add_option("--space", fa->space,
                "or a space JSON: the error along the grid line of --axis through --at")
      ->check(cli::existing_file());
  c->add_option("--axis", fa->line_axis, kTableAxis)
      ->transform(cli::machine_axis())
      ->capture_default_str();
  c->add_option("--at", fa->at, "with --space: the line's other coordinates x,y,z, mm")
      ->delimiter(',');
  c->add_option("--axis-number", fa->o.axis_number, "the axis' number in the parameters (A1...)")
      ->check(CLI::Range(1, 32))
      ->capture_default_str();
  c->add_option("--axis-name", fa->axis_name,
                "the axis' name on the control, for the file's comment (default: --axis as X, Y "
                "or Z)");
  c->add_option("--reference", fa->o.reference,
                "where the reference position lies, mm in the table's coordinates (default: the "
                "lowest point)");
  c->add_option("--interval", fa->o.interval,
                "distance between points, mm (default: the mean target spacing); the table is "
                "interpolated linearly onto them");
  c->add_option("--first-number", fa->o.first_number,
                "the farthest negative point's number (3621); other axes' points must not overlap")
      ->capture_default_str();
  c->add_option("--max-number", fa->o.max_number, "the control's highest point number")
      ->capture_default_str();
  c->add_option("--magnification", fa->o.magnification,
                "parameter 3623, 1..100 (default 0: the smallest that fits)")
      ->check(CLI::Range(0, 100))
      ->capture_default_str();
  c->add_option("--detection-unit", fa->o.detection_unit,
                "the axis' detection unit, mm (IS-B: 0.001)")
      ->capture_default_str();
  c->add_option("--max-feedrate", fa->o.max_feedrate,
                "the axis' maximum feedrate, mm/min: the interval must be at least this / 7500");
  c->add_option("--output,-o", fa->output, "file to write")->required();
  c->add_flag("--quiet,-q", fa->quiet, "print nothing on success");
  out.push_back({c, [fa] { return run_export_fanuc(*fa); }});

  auto csv_space = std::make_shared<std::string>(), csv_out = std::make_shared<std::string>();
  c = ex->add_subcommand("csv",
                         "Generic error-map table: x,y,z (mm), ex,ey,ez and uncertainties (µm)");
  c->add_option("--space", *csv_space, "space JSON")->required()->check(cli::existing_file());
  c->add_option("--output,-o", *csv_out, "CSV to write")->required();
  out.push_back({c, [csv_space, csv_out] {
                   io::write_map_csv(*csv_out, io::read_error_map(*csv_space));
                   return 0;
                 }});
  return out;
}

}  // namespace trueaxis::cli
