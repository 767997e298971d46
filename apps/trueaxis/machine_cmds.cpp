// trueaxis CLI — the virtual machine: 'simulate machine', 'simulate line', 'machine error'.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <memory>

#include "commands.hpp"
#include "trueaxis/ballgauge/lengths.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/csv.hpp"
#include "trueaxis/io/separation/probes.hpp"
#include "trueaxis/io/sim/machine.hpp"
#include "trueaxis/sim/machine.hpp"

namespace trueaxis::cli {

namespace {
std::vector<std::string>& meta_args() {
  static std::vector<std::string> args;
  return args;
}
}  // namespace

void add_meta_option(CLI::App* command) {
  command
      ->add_option("--meta", meta_args(),
                   "key=value for the report's header, repeatable (e.g. --meta \"machine=Prismo "
                   "7\" --meta operator=Kim --meta \"temperature=20.1 C\")")
      ->check([](const std::string& kv) {
        const auto eq = kv.find('=');
        return eq == std::string::npos || eq == 0 ? std::string("--meta takes key=value")
                                                  : std::string();
      });
}

std::vector<std::pair<std::string, std::string>> report_meta() {
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& kv : meta_args()) {
    const auto eq = kv.find('=');
    out.emplace_back(kv.substr(0, eq), kv.substr(eq + 1));
  }
  return out;
}

CLI::Validator positive_number() {
  return CLI::Validator(
      [](std::string& text) {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0' || !(v > 0) || !std::isfinite(v))
          return fmt::format("must be a positive number, not '{}'", text);
        return std::string();
      },
      "POSITIVE");
}

CLI::Validator mpe_text() {
  return CLI::Validator(
      [](std::string& text) {
        try {
          ballgauge::Mpe::parse(text);
        } catch (const Error& e) {
          return std::string(e.what());
        }
        return std::string();
      },
      "MPE");
}

std::string truth_beside(const std::string& output) {
  const std::filesystem::path p(output);
  return (p.parent_path() / (p.stem().string() + "-truth.csv")).string();
}

void MachineSource::add_options(CLI::App* c) {
  c->add_option("--machine", path, "machine JSON (default: a random machine from --machine-seed)")
      ->check(cli::existing_file());
  c->add_option("--machine-seed", seed, "seed of the random machine")->capture_default_str();
}

sim::Machine MachineSource::load() const {
  if (!path.empty()) return io::read_machine(path);
  sim::MachineOptions o;
  o.seed = seed;
  return sim::random_machine(o);
}

namespace {

Eigen::Vector3d vec3(const std::vector<double>& v, const char* what) {
  if (v.size() != 3) throw Error(fmt::format("{} needs three numbers x,y,z", what));
  return {v[0], v[1], v[2]};
}

struct SimMachineArgs {
  sim::MachineOptions o;
  std::vector<double> x{0, 800}, y{0, 600}, z{0, 500}, offset{0, 0, -100};
  double straightness_um = 3, angular_urad = 10, positioning_um_per_m = 10, squareness_urad = 20,
         lead_um = 0;
  std::string output = "machine.json";
  bool quiet = false;
};

int run_simulate_machine(SimMachineArgs a) {
  const std::vector<double>* r[3] = {&a.x, &a.y, &a.z};
  for (int k = 0; k < 3; ++k) {
    if (r[k]->size() != 2) throw Error("each range needs two numbers min,max (mm)");
    a.o.range[static_cast<std::size_t>(k)] = {(*r[k])[0], (*r[k])[1]};
  }
  a.o.offset = vec3(a.offset, "--offset");
  a.o.straightness = a.straightness_um * 1e-3;
  a.o.angular = a.angular_urad * 1e-6;
  a.o.positioning = a.positioning_um_per_m * 1e-6;
  a.o.squareness = a.squareness_urad * 1e-6;
  a.o.lead_amplitude = a.lead_um * 1e-3;
  const sim::Machine m = sim::random_machine(a.o);
  io::write_machine(a.output, m);
  if (!a.quiet) fmt::print("{}wrote {}\n", m.summary(), a.output);
  return 0;
}

struct SimLineArgs {
  std::string machine, output = "line.csv", truth;  // truth: beside the output
  sim::ProbeRunOptions o;
  std::vector<double> start, direction{1, 0, 0}, sensing{0, 0, 1};
  std::optional<long> stations;
  double noise_um = 0, profile_um = 2, angle_noise_urad = 0;
  bool quiet = false;
};

int run_simulate_line(SimLineArgs a) {
  const sim::Machine m = io::read_machine(a.machine);
  a.o.start = a.start.empty() ? Eigen::Vector3d(m.range[0][0], m.range[1][0], m.range[2][0])
                              : vec3(a.start, "--start");
  a.o.direction = vec3(a.direction, "--direction");
  a.o.sensing = vec3(a.sensing, "--sensing");
  if (a.o.direction.norm() == 0) throw Error("--direction must not be zero");
  if (a.stations) {
    a.o.stations = *a.stations;
  } else {
    // As many stops as fit in the machine's range from the start along the direction.
    const Eigen::Vector3d d = a.o.direction.normalized();
    double t_max = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k) {
      const auto& r = m.range[static_cast<std::size_t>(k)];
      if (std::abs(d[k]) < 1e-15) continue;
      const double lim = d[k] > 0 ? (r[1] - a.o.start[k]) / d[k] : (r[0] - a.o.start[k]) / d[k];
      t_max = std::min(t_max, lim);
    }
    if (!(t_max >= 0) || !(a.o.step > 0))
      throw Error("the start is outside the machine's range or the step is not positive");
    a.o.stations = static_cast<long>(std::floor(t_max / a.o.step + 1e-9)) + 1;
  }
  a.o.noise = a.noise_um * 1e-3;
  a.o.profile_amplitude = a.profile_um * 1e-3;
  a.o.angle_noise = a.angle_noise_urad * 1e-6;
  if (a.truth.empty()) a.truth = truth_beside(a.output);
  const auto run = sim::simulate_probe_run(m, a.o);
  io::write_probes(a.output, run.data);
  const auto& T = run.truth;
  const Eigen::VectorXd w = T.workpiece * 1e3, g = T.guide * 1e3, t = T.pitch * 1e6;
  io::write_csv(a.truth, {"x", "workpiece_um", "guide_um", "pitch_urad"}, {&T.x, &w, &g, &t});
  if (!a.quiet)
    fmt::print(
        "simulated a {}-probe run of {} stops, {} mm apart, from ({}, {}, {}) mm{}: wrote {} and "
        "{}\n",
        a.o.offsets.size(), a.o.stations, a.o.step, a.o.start.x(), a.o.start.y(), a.o.start.z(),
        a.o.angle ? " with an angle channel" : "", a.output, a.truth);
  return 0;
}

struct MachineErrorArgs {
  std::string machine, points, output;
};

int run_machine_error(const MachineErrorArgs& a) {
  const sim::Machine m = io::read_machine(a.machine);
  const Eigen::Matrix3Xd p = io::read_points(a.points, &m);
  const Eigen::Matrix3Xd e = m.errors_at(p) * 1e3;
  const Eigen::VectorXd x = p.row(0).transpose(), y = p.row(1).transpose(),
                        z = p.row(2).transpose(), ex = e.row(0).transpose(),
                        ey = e.row(1).transpose(), ez = e.row(2).transpose();
  io::write_csv(a.output.empty() ? "-" : a.output, {"x", "y", "z", "ex", "ey", "ez"},
                {&x, &y, &z, &ex, &ey, &ez});
  return 0;
}

}  // namespace

std::vector<Command> add_machine_commands(CLI::App& app, CLI::App& simulate) {
  std::vector<Command> out;

  auto sm = std::make_shared<SimMachineArgs>();
  auto* c = simulate.add_subcommand(
      "machine",
      "A seeded random 3-axis machine with realistic errors (21 rigid-body errors, ISO 230-1): "
      "writes machine.json, which you can edit.\nExample: trueaxis simulate machine --seed 3 -o "
      "machine.json");
  c->add_option("--seed", sm->o.seed, "random seed (same seed, same machine)")
      ->capture_default_str();
  c->add_option("--chain", sm->o.chain,
                "kinematic chain from workpiece to tool, F = frame: FYXZ (bridge CMM), FXYZ, "
                "XFYZ, ...")
      ->capture_default_str();
  c->add_option("--x", sm->x, "x range min,max (mm)")->delimiter(',')->capture_default_str();
  c->add_option("--y", sm->y, "y range min,max (mm)")->delimiter(',')->capture_default_str();
  c->add_option("--z", sm->z, "z range min,max (mm)")->delimiter(',')->capture_default_str();
  c->add_option("--offset", sm->offset, "stylus/tool offset from the Z carriage, x,y,z (mm)")
      ->delimiter(',')
      ->capture_default_str();
  c->add_option("--straightness", sm->straightness_um, "straightness scale, µm over 500 mm")
      ->capture_default_str();
  c->add_option("--angular", sm->angular_urad, "roll/pitch/yaw scale, µrad")->capture_default_str();
  c->add_option("--positioning", sm->positioning_um_per_m, "positioning scale error, µm/m")
      ->capture_default_str();
  c->add_option("--squareness", sm->squareness_urad, "squareness standard deviation, µrad")
      ->capture_default_str();
  c->add_option("--lead-screw", sm->lead_um,
                "amplitude of a periodic lead-screw term in positioning, µm (0: none)")
      ->capture_default_str();
  c->add_option("--lead", sm->o.lead, "lead-screw period, mm")->capture_default_str();
  c->add_option("--output,-o", sm->output, "machine JSON to write")->capture_default_str();
  c->add_flag("--quiet,-q", sm->quiet, "print nothing on success");
  out.push_back({c, [sm] { return run_simulate_machine(*sm); }});

  auto sl = std::make_shared<SimLineArgs>();
  c = simulate.add_subcommand(
      "line",
      "A virtual displacement-probe run on a machine: the probes ride on the tool along a line "
      "and read a straightedge with its own unknown profile. Writes the probes.csv that "
      "'trueaxis separate' reads, and the truth.\nExample: trueaxis simulate line --machine "
      "machine.json --start 0,300,250 --direction 1,0,0 --sensing 0,0,1 --step 20 --offsets "
      "0,20,40");
  c->add_option("--machine", sl->machine, "machine JSON ('trueaxis simulate machine')")
      ->required()
      ->check(cli::existing_file());
  c->add_option("--start", sl->start, "command of the first stop x,y,z (mm; default: range start)")
      ->delimiter(',');
  c->add_option("--direction", sl->direction, "direction of motion x,y,z")
      ->delimiter(',')
      ->capture_default_str();
  c->add_option("--sensing", sl->sensing, "direction the probes measure in x,y,z (across motion)")
      ->delimiter(',')
      ->capture_default_str();
  c->add_option("--step", sl->o.step, "distance between stops, mm")->capture_default_str();
  c->add_option("--stations", sl->stations, "number of stops (default: as many as fit)");
  c->add_option("--offsets", sl->o.offsets, "probe offsets along the motion, mm (whole steps)")
      ->delimiter(',')
      ->capture_default_str();
  c->add_option("--noise", sl->noise_um, "probe noise, µm")->capture_default_str();
  c->add_option("--profile", sl->profile_um, "straightedge form error scale, µm")
      ->capture_default_str();
  c->add_flag(
      "--angle", sl->o.angle,
      "add an angle channel (autocollimator/level on the carriage), column 'angle' in µrad");
  c->add_option("--angle-noise", sl->angle_noise_urad, "angle channel noise, µrad")
      ->capture_default_str();
  c->add_option("--seed", sl->o.seed, "random seed")->capture_default_str();
  c->add_option("--output,-o", sl->output, "probes CSV to write")->capture_default_str();
  c->add_option("--truth", sl->truth,
                "truth CSV (x, workpiece_um = straightedge, guide_um = machine error along the "
                "sensing direction, pitch_urad); default: the output's name with -truth");
  c->add_flag("--quiet,-q", sl->quiet, "print nothing on success");
  out.push_back({c, [sl] { return run_simulate_line(*sl); }});

  auto* mach = app.add_subcommand("machine", "Query a virtual machine description");
  mach->require_subcommand(1);
  auto me = std::make_shared<MachineErrorArgs>();
  c = mach->add_subcommand(
      "error",
      "The machine's true error vector (actual - nominal tool point) at given commanded "
      "positions.\npoints.csv: header row with columns x,y,z (mm). Output columns x,y,z (mm) and "
      "ex,ey,ez (µm).\nExample: trueaxis machine error --machine machine.json --input points.csv "
      "-o errors.csv\n(or, shorter: trueaxis machine error machine.json points.csv)");
  c->add_option("machine,--machine", me->machine, "machine JSON")
      ->required()
      ->check(cli::existing_file());
  c->add_option("points,--input,-i", me->points, "CSV with columns x,y,z (mm)")
      ->required()
      ->check(cli::existing_file());
  c->add_option("--output,-o", me->output, "CSV to write (default: standard output)");
  out.push_back({c, [me] { return run_machine_error(*me); }});
  return out;
}

}  // namespace trueaxis::cli
