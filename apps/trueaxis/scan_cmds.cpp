// trueaxis CLI — error-tolerant design-value scanning on the virtual CMM: 'scan'.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <memory>
#include <optional>
#include <tuple>

#include "commands.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/design/design.hpp"
#include "trueaxis/io/files.hpp"
#include "trueaxis/io/scan/scan.hpp"
#include "trueaxis/io/sim/machine.hpp"
#include "trueaxis/ippdme/remote_cmm.hpp"
#include "trueaxis/report/scan.hpp"
#include "trueaxis/scan/controller.hpp"

namespace trueaxis::cli {
namespace {

struct ScanArgs {
  std::string design, part, machine, cmm, output, points, log, corrected, truth, report,
      strategy = "error-tolerant";
  scan::ControllerOptions o;
  std::vector<double> part_origin;
  double probe_noise_um = 0, point_step = ippdme::RemoteCmmOptions{}.point_step;
  std::uint64_t seed = 1;
  bool passive = false, quiet = false;
};

int run_scan(ScanArgs& a) {
  a.o.strategy = scan::strategy_from_string(a.strategy);
  a.o.active = !a.passive;
  a.o.validate();
  const design::Design d = io::read_design(a.design);
  std::optional<sim::Part> part;
  if (!a.part.empty()) part = io::read_part(a.part);
  scan::VirtualCmmOptions vo;
  vo.probe.tip_radius = a.o.path.tip_radius;
  vo.probe.noise = a.probe_noise_um * 1e-3;
  vo.probe.seed = a.seed;
  vo.probe.range = std::max(1.0, 3 * a.o.path.pushing);
  if (!a.machine.empty()) vo.geometry = io::read_machine(a.machine);
  std::optional<Eigen::Vector3d> origin;
  if (!a.part_origin.empty())
    origin = Eigen::Vector3d(a.part_origin[0], a.part_origin[1], a.part_origin[2]);
  vo.part_origin = origin;
  // Start above the part's first section, clear of it.
  const Eigen::Vector3d home = scan::start_position(d, a.o);
  // The simulated part in process: the CMM itself, or (with --cmm) the truth to compare with.
  std::optional<scan::VirtualCmm> virt;
  if (part) virt.emplace(*part, vo, home);
  std::unique_ptr<ippdme::RemoteCmm> remote;
  if (!a.cmm.empty()) {
    ippdme::RemoteCmmOptions ro;
    std::tie(ro.client.host, ro.client.port) = parse_ipp_address(a.cmm);
    ro.part_origin = origin;
    ro.tip_radius = a.o.path.tip_radius;
    ro.point_step = a.point_step;
    remote = std::make_unique<ippdme::RemoteCmm>(ro);
    if (remote->scans_by_points() && !a.quiet)
      fmt::print(stderr,
                 "the server speaks I++ DME {}, which has no ScanOnCurve (1.4.2): scanning point "
                 "by point, a PtMeas every {:g} mm\n",
                 remote->version(), a.point_step);
  }
  scan::Machine& cmm = remote ? static_cast<scan::Machine&>(*remote) : *virt;
  const auto r =
      scan::scan(cmm, d, a.o, [&](std::size_t i, std::size_t n, const std::string& name) {
        if (!a.quiet) fmt::print(stderr, "scanning section {}/{} '{}' ...\n", i + 1, n, name);
      });
  io::ScanCmm rec{a.o.path.tip_radius, a.probe_noise_um, {}, {}};
  if (remote) {
    rec.machine = a.cmm;
    rec.part_origin = origin;
  } else if (vo.geometry) {
    rec.machine = vo.geometry->name.empty() ? a.machine : vo.geometry->name;
    rec.part_origin = virt->part_origin();
  }
  io::write_scan(a.output, r, a.o, rec);
  if (!a.points.empty()) io::write_scan_points(a.points, r);
  if (!a.log.empty()) io::write_scan_events(a.log, r);
  if (!a.corrected.empty()) io::write_design(a.corrected, r.design);
  double worst = 0;
  // Each measured point's distance from the simulated part (µm): for --truth and the report.
  std::vector<Eigen::VectorXd> truth_um;
  std::string out = "section,x,y,z,distance_um\n";
  for (std::size_t i = 0; i < r.sections.size(); ++i) {
    const auto& pts = r.sections[i].points;
    Eigen::VectorXd t(static_cast<Eigen::Index>(pts.size()));
    for (std::size_t k = 0; k < pts.size(); ++k) {
      const auto& p = pts[k];
      if (!virt) break;
      const double dist = virt->distance(r.planned.sections[i], p.surface);
      t[static_cast<Eigen::Index>(k)] = dist * 1e3;
      worst = std::max(worst, std::abs(dist));
      if (!a.truth.empty())
        out += fmt::format("{},{:.6f},{:.6f},{:.6f},{:.3f}\n", r.sections[i].name, p.surface.x(),
                           p.surface.y(), p.surface.z(), dist * 1e3);
    }
    truth_um.push_back(std::move(t));
  }
  if (!a.truth.empty()) {
    if (!virt) throw Error("--truth needs --part: the simulated part the points are compared with");
    io::write_text(a.truth, out);
  }
  if (!a.report.empty()) {
    // The simulated part's contour of each scanned section (matched by name).
    std::vector<Eigen::Matrix3Xd> true_part;
    for (const auto& ds : r.planned.sections) {
      true_part.emplace_back(3, 0);
      if (!part) continue;
      for (const auto& ps : part->design.sections)
        if (ps.name == ds.name || ds.name.rfind(ps.name + ":", 0) == 0)
          true_part.back() = ps.space_curve() ? sim::true_space_curve(*part, ps).points()
                                              : sim::true_contour(*part, ps).points();
    }
    report::write(
        a.report,
        report::render("trueaxis scanning report",
                       {from_file(report::scan_section("Error-tolerant scanning", r, r.planned,
                                                       a.o.tolerance, truth_um, true_part),
                                  a.design)},
                       4000, report_meta()));
  }
  if (!a.quiet) {
    if (remote)
      fmt::print(
          "scanned through the I++ DME server at {} ({} commands; times below are the "
          "wall-clock times this client saw, machine time only if the CMM runs in real "
          "time){}\n",
          a.cmm, remote->commands(),
          origin ? fmt::format("; part origin at ({:.1f}, {:.1f}, {:.1f}) mm", origin->x(),
                               origin->y(), origin->z())
                 : std::string());
    else if (vo.geometry)
      fmt::print(
          "CMM with the geometric errors of '{}'; part origin at ({:.1f}, {:.1f}, {:.1f}) mm in "
          "machine coordinates\n",
          rec.machine, rec.part_origin->x(), rec.part_origin->y(), rec.part_origin->z());
    for (const auto& s : r.sections) {
      std::string carried;
      for (const auto& c : s.corrections)
        if (!c.found_on.empty() && carried.find(c.found_on) == std::string::npos)
          carried += (carried.empty() ? " (and the part's move found on " : ", ") + c.found_on;
      if (!carried.empty()) carried += ")";
      fmt::print(
          "{}: {} — {} points, {} trajectory errors, {} corrections{}, {} autonomous scans, "
          "{:.1f} s\n",
          s.name,
          s.ok              ? "ok"
          : s.not_reachable ? "NOT REACHABLE: " + s.reason
                            : "ERROR: " + s.reason,
          s.points.size(), s.trajectory_errors,
          std::count_if(s.corrections.begin(), s.corrections.end(),
                        [](const auto& c) { return c.accepted && c.found_on.empty(); }),
          carried, s.autonomous_count, s.time.total);
    }
    fmt::print("{}\n", r.summary());
    if (!a.truth.empty())
      fmt::print("measured points against the simulated part: max |distance| {:.2f} µm -> {}\n",
                 worst * 1e3, a.truth);
    fmt::print("wrote {}{}\n", a.output, a.report.empty() ? "" : " and " + a.report);
  }
  for (const auto& s : r.sections)
    if (!s.ok) fmt::print(stderr, "trueaxis: error: section '{}': {}\n", s.name, s.reason);
  return r.ok() ? 0 : 1;
}

}  // namespace

std::vector<Command> add_scan_commands(CLI::App& app) {
  auto a = std::make_shared<ScanArgs>();
  auto* c = app.add_subcommand(
      "scan",
      "Scan a (simulated) part section by section along its design data on a servo-level "
      "virtual CMM. With the error-tolerant strategy a trajectory error leads to touch points "
      "and a geometric correction of the section's design data, or else to a slow autonomous "
      "scan that replaces them; then the section is rescanned along the design.\n"
      "Example: trueaxis scan --design design.json --part part.json -o scan.json --points "
      "points.csv --log events.csv --corrected-design design2.json");
  c->add_option("--design", a->design, "design.json of the part")
      ->required()
      ->check(cli::existing_file());
  c->add_option("--part", a->part,
                "part.json: the simulated real part (trueaxis simulate part); with --cmm only "
                "the truth that --truth and the report compare with")
      ->check(cli::existing_file());
  c->add_option("--machine", a->machine,
                "machine.json: the CMM's 21 geometric errors (trueaxis simulate machine); the "
                "measured points carry them, as on a real CMM")
      ->check(cli::existing_file());
  c->add_option("--part-origin", a->part_origin,
                "X,Y,Z: where the part's design origin sits in machine coordinates (mm; with "
                "--machine, default: the part centred in the travel; with --cmm, set as the "
                "server's part coordinate system, default: its current one)")
      ->delimiter(',')
      ->expected(3);
  c->add_option("--strategy", a->strategy,
                "error-tolerant (default), design (stop at a trajectory error) or autonomous "
                "(slow surface following only)")
      ->check(CLI::IsMember({"error-tolerant", "design", "autonomous"}))
      ->capture_default_str();
  c->add_option("--tolerance", a->o.tolerance, "trajectory-error tolerance |ΔL| (mm)")
      ->capture_default_str();
  c->add_option("--margin", a->o.margin,
                "how far off its design the part may stand (mm): free moves keep this far from "
                "the part's solid, and only stretches a part this far off cannot bring onto the "
                "stylus are scanned (default: the tolerance + 1 mm)");
  c->add_option("--guarded-speed", a->o.guarded_speed,
                "free moves within 2 mm beyond that margin go at most this fast (mm/s), so that "
                "the probe stops the machine on a part further off than the margin instead of a "
                "collision (default 0: the machine's; the virtual CMM's is 51 mm/s, and over "
                "--cmm nothing is slowed unless this is given)")
      ->capture_default_str();
  c->add_option("--max-autonomous", a->o.max_autonomous,
                "autonomous corrections allowed per section before it is given up")
      ->capture_default_str();
  c->add_option("--tip-radius", a->o.path.tip_radius, "stylus tip radius (mm)")
      ->capture_default_str();
  c->add_option("--pushing", a->o.path.pushing, "pushing amount held while scanning (mm)")
      ->capture_default_str();
  c->add_flag("--passive", a->passive, "passive design-value scanning (no pushing correction)");
  c->add_option("--cmm", a->cmm,
                "ipp://HOST:PORT: scan with the CMM behind this I++ DME server (e.g. trueaxis "
                "serve --part part.json) instead of the virtual CMM in process")
      ->excludes("--machine")
      ->excludes("--passive");
  c->add_option("--point-step", a->point_step,
                "with --cmm on a server older than I++ DME 1.4.2 (no ScanOnCurve): a point this "
                "far apart along the path (mm)")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 10.0));
  c->add_option("--probe-noise", a->probe_noise_um, "probe noise, standard deviation (µm)")
      ->capture_default_str();
  c->add_option("--seed", a->seed, "random seed of the probe noise")->capture_default_str();
  c->add_option("--output,-o", a->output, "scan.json to write")->required();
  c->add_option("--points", a->points, "points.csv: section,x,y,z,nx,ny,nz,t");
  c->add_option("--log", a->log, "events.csv: every decision of the flow");
  c->add_option("--corrected-design", a->corrected,
                "design.json after the corrections: the input for the next part of the batch");
  c->add_option("--truth", a->truth,
                "truth.csv: each measured point's distance from the simulated part (µm)");
  c->add_option("--report", a->report,
                "HTML report: status and machine time per section, ΔL along every scan with the "
                "tolerance, the measured contour against the design, every decision");
  add_meta_option(c);
  c->add_flag("--quiet,-q", a->quiet, "print nothing on success");
  return {{c, [a] {
             try {
               a->o.validate();
             } catch (const Error& e) {
               throw CLI::ValidationError(e.what());
             }
             if (a->part.empty() && a->cmm.empty())
               throw CLI::ValidationError(
                   "--part is needed (the simulated part), unless --cmm names a CMM to scan with");
             if (!a->part_origin.empty() && a->machine.empty() && a->cmm.empty())
               throw CLI::ValidationError("--part-origin needs --machine or --cmm");
             if (!a->cmm.empty() && a->probe_noise_um != 0)
               throw CLI::ValidationError(
                   "--probe-noise is the server's with --cmm (trueaxis serve --probe-noise)");
             return run_scan(*a);
           }}};
}

}  // namespace trueaxis::cli
