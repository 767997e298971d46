// trueaxis demo — every capability on the built-in virtual machine, in one HTML report.
#include <fmt/format.h>

#include <Eigen/QR>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <filesystem>

#include "commands.hpp"
#include "moody_data.hpp"
#include "trueaxis/ballgauge/ballgauge.hpp"
#include "trueaxis/ballgauge/lengths.hpp"
#include "trueaxis/ballgauge/parametric.hpp"
#include "trueaxis/circular/circular.hpp"
#include "trueaxis/circular/compensation.hpp"
#include "trueaxis/compensation/table.hpp"
#include "trueaxis/design/design.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/guideway/guideway.hpp"
#include "trueaxis/io/ballgauge/ballgauge.hpp"
#include "trueaxis/io/circular/circular.hpp"
#include "trueaxis/io/circular/compensation.hpp"
#include "trueaxis/io/compensation/controller.hpp"
#include "trueaxis/io/design/design.hpp"
#include "trueaxis/io/files.hpp"
#include "trueaxis/io/guideway/guideway.hpp"
#include "trueaxis/io/positioning/positioning.hpp"
#include "trueaxis/io/positioning/renishaw.hpp"
#include "trueaxis/io/scan/scan.hpp"
#include "trueaxis/io/separation/probes.hpp"
#include "trueaxis/io/sim/machine.hpp"
#include "trueaxis/io/surface/space.hpp"
#include "trueaxis/io/surface/surface.hpp"
#include "trueaxis/map/error_map.hpp"
#include "trueaxis/report/ballgauge.hpp"
#include "trueaxis/report/circular.hpp"
#include "trueaxis/report/guideway.hpp"
#include "trueaxis/report/html.hpp"
#include "trueaxis/report/positioning.hpp"
#include "trueaxis/report/scan.hpp"
#include "trueaxis/report/surface.hpp"
#include "trueaxis/scan/controller.hpp"
#include "trueaxis/separation/separation.hpp"
#include "trueaxis/sim/ballgauge.hpp"
#include "trueaxis/sim/circular.hpp"
#include "trueaxis/sim/guideway.hpp"
#include "trueaxis/sim/machine.hpp"
#include "trueaxis/sim/part.hpp"
#include "trueaxis/sim/positioning.hpp"
#include "trueaxis/sim/straightness.hpp"
#include "trueaxis/surface/space.hpp"

namespace trueaxis::cli {
namespace {

separation::ProbeData subset(const separation::ProbeData& d, int probes, bool angle) {
  separation::ProbeData s;
  s.x = d.x;
  s.readings = d.readings.leftCols(probes);
  s.offsets.assign(d.offsets.begin(), d.offsets.begin() + probes);
  if (angle) s.angle = d.angle;
  return s;
}

}  // namespace

int run_demo(const DemoOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  auto say = [&](const std::string& s) {
    if (!o.quiet)
      fmt::print("[{:5.2f}s] {}\n",
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), s);
  };
  const std::filesystem::path out(o.output);
  const std::filesystem::path dir =
      out.has_parent_path() ? out.parent_path() : std::filesystem::path(".");
  // The demo writes a folder of its own: it creates it (the one output that does) and says so.
  if (!std::filesystem::is_directory(dir)) {
    std::filesystem::create_directories(dir);
    say(fmt::format("created {}/ for the report and the files behind it", dir.string()));
  }

  // Scenario 1: straightness separation on a pitching carriage with four probes and a level.
  sim::StraightnessOptions so;
  so.stations = o.stations;
  so.step = 5;
  so.offsets = {0, 5, 10, 15};
  so.workpiece_amplitude = 4e-3;
  so.guide_amplitude = 3e-3;
  so.pitch_amplitude = 4e-6;
  so.noise = 0.02e-3;
  so.angle = true;
  so.angle_noise = 0.2e-6;
  so.seed = o.seed;
  const auto camp = sim::simulate_straightness(so);
  say(
      fmt::format("straightness: simulated a pitching carriage, {} stations x {} mm, 4 probes + "
                  "level, noise {} µm",
                  so.stations, so.step, so.noise * 1e3));
  io::write_probes((dir / "probes.csv").string(), camp.data);

  std::vector<report::Section> sections;
  report::Section intro;
  intro.title = "Straightness error separation";
  intro.intro_html =
      "<p>A virtual carriage pitches by a few µrad while four displacement probes (5 mm apart) and "
      "an electronic level read a workpiece. Each method recovers the workpiece profile and the "
      "guide's straightness; the dashed red curves are the simulator's truth in the same "
      "reference. "
      "The two-point method cannot see pitch, so it integrates it into the profiles; Mitsubishi's "
      "three-point method removes pitch but cannot tell a parabola in the guide from one in the "
      "workpiece (and its noise grows fastest); the least-squares solver uses all four probes and "
      "the level, recovers the curvature and has the smallest uncertainty.</p>";
  intro.table.push_back({"method", "data used", "max error workpiece (µm)", "max error guide (µm)",
                         "max u workpiece (µm)"});
  struct Run {
    const char* label;
    separation::Method m;
    int probes;
    bool angle;
  };
  double best_ew = INFINITY;  // the best method's largest workpiece error (µm)
  const Run runs[] = {{"two-point", separation::Method::TwoPoint, 2, false},
                      {"three-point (JPH0464003B2)", separation::Method::ThreePoint, 3, false},
                      {"least squares", separation::Method::Lsq, 4, true}};
  for (const Run& run : runs) {
    separation::Options opt;
    opt.method = run.m;
    opt.sigma = so.noise;
    opt.angle_sigma = so.angle_noise;
    const auto data = subset(camp.data, run.probes, run.angle);
    const auto r = separation::separate(data, opt);
    const auto t = camp.truth.like(r);
    const std::string file = fmt::format("result-{}.json", separation::to_string(run.m));
    io::write_result((dir / file).string(), r);
    const double ew = (r.workpiece.value - t.workpiece.value).cwiseAbs().maxCoeff() * 1e3;
    const double eg = (r.guide.value - t.guide.value).cwiseAbs().maxCoeff() * 1e3;
    intro.table.push_back({run.label,
                           fmt::format("{} probes{}", run.probes, run.angle ? " + level" : ""),
                           fmt::format("{:.3f}", ew), fmt::format("{:.3f}", eg),
                           r.workpiece.uncertainty.size()
                               ? fmt::format("{:.3f}", r.workpiece.uncertainty.maxCoeff() * 1e3)
                               : "-"});
    sections.push_back(report::separation_section(run.label, r, &t));
    sections.back().summary = fmt::format(
        "largest error against the truth: workpiece {:.3f} µm, guide {:.3f} µm{}", ew, eg,
        sections.back().warnings.empty() ? "" : "; not resolved by this probe layout");
    best_ew = std::min(best_ew, ew);
    say(fmt::format("straightness: {:<20} max error workpiece {:.3f} µm, guide {:.3f} µm -> {}",
                    run.label, ew, eg, file));
  }
  intro.summary = fmt::format(
      "three methods on one pitching carriage; the best recovers the workpiece to {:.3f} µm",
      best_ew);
  sections.insert(sections.begin(), intro);

  // Scenario 2: Moody's surface plate (1955), written out as his files and assembled like
  // 'trueaxis surface --moody DIR' would: the classic worksheet and the least-squares network.
  const std::filesystem::path moody_dir = dir / "moody";
  std::filesystem::create_directories(moody_dir);
  for (const auto& [name, text] : moody_files()) {
    io::write_text((moody_dir / std::string(name)).string(), text);
  }
  const auto moody_data = io::read_moody(moody_dir.string());
  const auto classic = surface::moody(moody_data);
  const auto moody_lsq = surface::moody(moody_data, true);
  io::write_surface((dir / "surface-moody.json").string(), classic);
  io::write_surface((dir / "surface-moody-lsq.json").string(), moody_lsq);
  say(fmt::format(
      "surface: Moody's plate, classic worksheet: flatness {:.3f} µm (min zone); least squares: "
      "closure RMS {:.3f} µm, max {:.3f} µm -> surface-moody*.json",
      classic.flatness_min_zone * 1e3, moody_lsq.closure_rms * 1e3, moody_lsq.closure_max * 1e3));
  sections.push_back(report::surface_section(
      "Error surface: Moody's surface plate (1955)", classic,
      "<p>J. C. Moody's 1955 Union Jack: eight autocollimator lines over a granite plate, one "
      "reading per 4-inch foot. The classic worksheet reproduces his published heights (the "
      "reproduction is checked against every one of them). Try <code>trueaxis surface --moody "
      "moody "
      "--method lsq -o s.json --report s.html</code> in the report's directory.</p>"));
  sections.push_back(report::surface_section(
      "The same lines, least squares", moody_lsq,
      "<p>All eight lines adjusted jointly: every crossing should agree, and the closure at the "
      "crossings measures how well the lines fit one surface (noise, drift, a plate that moved). "
      "The worksheet hides this: it forces the lines through its chosen points.</p>"));
  sections[sections.size() - 2].summary =
      fmt::format("flatness {:.2f} µm (minimum zone), Moody's published heights reproduced",
                  classic.flatness_min_zone * 1e3);
  sections.back().summary = fmt::format("closure at the crossings RMS {:.3f} µm, max {:.3f} µm",
                                        moody_lsq.closure_rms * 1e3, moody_lsq.closure_max * 1e3);

  // Scenario 3: the error space of a virtual bridge CMM, its compensation and LinuxCNC files.
  sim::MachineOptions mo;
  mo.seed = o.seed;
  const sim::Machine machine = sim::random_machine(mo);
  io::write_machine((dir / "machine.json").string(), machine);
  surface::SpacePlan plan;
  plan.spacing = o.spacing;
  plan.probe_noise = 0.02e-3;
  plan.laser_noise = 0.05e-3;
  plan.monte_carlo = o.repetitions;
  plan.seed = o.seed;
  const auto axes = surface::space_axes(machine, plan);
  say(
      fmt::format("space: measuring a {} x {} x {} grid on a virtual {} machine ({} repetitions "
                  "for the uncertainty)...",
                  axes[0].size(), axes[1].size(), axes[2].size(), machine.chain, plan.monte_carlo));
  const auto space = surface::measure_space(machine, plan);
  const auto check = surface::verify_compensation(machine, space.map, 1000, plan.seed);
  io::write_space((dir / "space.json").string(), space, plan, check);
  io::write_linuxcnc((dir / "x.comp").string(), space.map, 0,
                     {0, 0.5 * (axes[1][0] + axes[1][axes[1].size() - 1]),
                      0.5 * (axes[2][0] + axes[2][axes[2].size() - 1])},
                     1);
  say(fmt::format(
      "space: {} straightness + {} laser runs; map vs truth RMS {:.3f} µm; compensation at 1000 "
      "points: RMS {:.2f} -> {:.2f} µm (expected {:.2f}), x{:.1f} -> space.json, x.comp",
      space.straightness_runs, space.laser_runs, space.truth_rms * 1e3, check.before_rms * 1e3,
      check.after_rms * 1e3, check.predicted_rms * 1e3, check.improvement()));
  sections.push_back(
      report::space_section("Error space and compensation of a virtual CMM", space, &check));
  sections.back().summary = fmt::format(
      "21 errors mapped; compensated at 1000 points: RMS {:.2f} µm → {:.2f} µm (predicted {:.2f})",
      check.before_rms * 1e3, check.after_rms * 1e3, check.predicted_rms * 1e3);
  sections.back().intro_html =
      fmt::format(
          "<p>A virtual bridge CMM (chain {}; all 21 ISO 230-1 errors, below) is measured "
          "like a real one: three-point probe runs along every grid line with {} µm probe noise, "
          "separated and assembled into surfaces; laser positioning runs stack them and "
          "face diagonals fix the squareness. The map is then used to compensate 1000 random "
          "commands. Files: <code>machine.json</code>, <code>space.json</code>, "
          "<code>x.comp</code> (LinuxCNC). Try <code>trueaxis space --machine machine.json -o "
          "s.json --report s.html</code>.</p><pre>{}</pre>",
          report::escape(machine.chain), plan.probe_noise * 1e3,
          report::escape(machine.summary())) +
      sections.back().intro_html;

  // Scenario 4: the five errors of the machine's X carriage from three QPDs.
  guideway::Layout layout;
  layout.detectors = {{"a", guideway::Kind::Position, {-60, 0, 0}, 0},
                      {"b", guideway::Kind::Position, {60, 0, 150}, 0},
                      {"c", guideway::Kind::Position, {0, 80, 300}, 0}};
  sim::GuidewayOptions go;
  go.axis = 0;
  go.positions = 401;
  go.noise = 0.1e-3;
  go.pointing_noise = 0.1e-3;
  go.seed = o.seed;
  const auto carriage = sim::simulate_guideway(machine, layout, go);
  io::write_layout((dir / "layout.json").string(), layout);
  io::write_spots((dir / "spots.csv").string(), layout, carriage.s, carriage.spots);
  guideway::Options gopt;
  gopt.sigma = std::hypot(go.noise, go.pointing_noise);
  const auto g = guideway::solve(layout, carriage.s, carriage.spots, gopt);
  double worst_z = 0;  // largest |error| / u over errors and positions
  for (std::size_t j = 0; j < guideway::kErrors; ++j)
    worst_z = std::max(worst_z,
                       (g.value[j] - carriage.truth[j]).cwiseAbs().maxCoeff() / g.uncertainty[j]);
  // The same carriage with every detector in one cross-section.
  guideway::Layout flat = layout;
  for (auto& d : flat.detectors) d.position.z() = 0;
  const auto carriage_flat = sim::simulate_guideway(machine, flat, go);
  const auto gflat = guideway::solve(flat, carriage_flat.s, carriage_flat.spots, gopt);
  say(fmt::format(
      "guideway: X carriage, 3 QPDs, {} positions: largest |error|/u {:.1f}; all detectors at "
      "z = 0: {} -> layout.json, spots.csv",
      go.positions, worst_z,
      gflat.layout.message.substr(0, gflat.layout.message.find(" (singular"))));
  auto gs =
      report::guideway_section("Five guideway errors from three laser spots", g, &carriage.truth);
  gs.intro_html =
      fmt::format(
          "<p>The X carriage of the same virtual machine carries three quadrant detectors "
          "(a, b, c at z = 0, 150 and 300 mm) through three laser beams fixed to the bed; "
          "{:.1f} µm reading noise and {:.1f} µm beam jitter. Horizontal and vertical "
          "straightness, pitch, yaw and roll come from one least-squares solve per position "
          "(the 6 × 5 operator factored once). The dashed red curves are the machine's own "
          "errors; bands are ±2u. Try <code>trueaxis guideway --layout "
          "layout.json --input spots.csv -o g.json --report g.html</code>.</p>",
          go.noise * 1e3, go.pointing_noise * 1e3) +
      gs.intro_html;
  gs.summary = fmt::format(
      "five errors at {} positions; the largest deviation from the truth is {:.1f} standard "
      "uncertainties over {} values",
      go.positions, worst_z, 5 * go.positions);
  sections.push_back(std::move(gs));
  // The same carriage with a layout that cannot see everything: its own section, so that each
  // table and text speaks of one layout.
  auto gfs = report::guideway_section(
      "The same carriage with every detector at z = 0: what such a layout cannot see", gflat,
      &carriage_flat.truth);
  gfs.intro_html =
      "<p>The three detectors moved into one cross-section (z = 0): the layout analysis finds "
      "which errors the readings no longer determine and reports them as not observable instead "
      "of inventing them.</p>" +
      gfs.intro_html;
  gfs.summary = fmt::format(
      "{} of the five errors not observable, and reported so",
      5 - std::count(gflat.layout.observable.begin(), gflat.layout.observable.end(), true));
  sections.push_back(std::move(gfs));

  // Positioning of the X axis by ISO 230-2: laser runs in the standard test cycle on the same
  // machine, with backlash, a warming axis and noise; evaluated with the temperature correction.
  {
    sim::PositioningRunOptions po;
    po.axis = 0;
    for (int i = 0; i <= 16; ++i) po.targets.push_back(machine.range[0][0] + 50.0 * i);
    po.backlash = 3e-3;
    po.noise = 0.3e-3;
    po.temperature_start = 20.6;
    po.temperature_end = 21.4;
    po.seed = o.seed;
    const auto run = sim::simulate_positioning(machine, po);
    io::write_runs((dir / "runs.csv").string(), run.readings);
    const auto pr = positioning::evaluate(run.readings);
    double hi = -INFINITY, lo = INFINITY;
    for (Eigen::Index i = 0; i < run.up.size(); ++i) {
      hi = std::max({hi, run.up[i], run.down[i]});
      lo = std::min({lo, run.up[i], run.down[i]});
    }
    // Renishaw's software writes deviations with its material compensation applied: the
    // evaluation's readings, corrected to 20 °C.
    io::write_rtl((dir / "runs.rtl").string(), pr.readings, {{"Axis", "X"}});
    say(
        fmt::format("positioning: X, 17 targets x 5 cycles, ISO 230-2: A {:.2f} µm, E {:.2f} µm "
                    "(noise-free truth {:.2f}), B mean {:.2f} µm (backlash 3) -> runs.csv, "
                    "runs.rtl",
                    pr.iso.A * 1e3, pr.iso.E * 1e3, (hi - lo) * 1e3, pr.iso.B_mean * 1e3));
    // Compensation tables for the controllers, and the axis rerun with the HEIDENHAIN one (both
    // directions) to show what it removes.
    const auto both = compensation::from_positioning(pr, true);
    const auto mean = compensation::from_positioning(pr, false);
    io::write_linuxcnc((dir / "x-positioning.comp").string(), both, 1);
    io::write_heidenhain((dir / "X.COM").string(), both);
    io::write_fanuc((dir / "x-pitch.txt").string(), mean);
    io::SinumerikOptions so;
    io::write_sinumerik((dir / "x_lec.mpf").string(), mean, so);
    sim::PositioningRunOptions pc = po;
    pc.seed = po.seed + 1;
    const auto com = io::read_heidenhain((dir / "X.COM").string());
    pc.compensation = [&com](double p, positioning::Direction d) { return com.correction(p, d); };
    const auto after = positioning::evaluate(sim::simulate_positioning(machine, pc).readings);
    say(fmt::format(
        "positioning: compensated with X.COM (HEIDENHAIN), a new run: A {:.2f} -> {:.2f} µm, E "
        "{:.2f} -> {:.2f} µm, B mean {:.2f} -> {:.2f} µm (tables: x-positioning.comp, X.COM, "
        "x-pitch.txt, x_lec.mpf)",
        pr.iso.A * 1e3, after.iso.A * 1e3, pr.iso.E * 1e3, after.iso.E * 1e3, pr.iso.B_mean * 1e3,
        after.iso.B_mean * 1e3));
    auto ps = report::positioning_section("Positioning accuracy of the X axis (ISO 230-2)", pr,
                                          positioning::Standard::Iso230_2);
    ps.intro_html =
        fmt::format(
            "<p>A laser interferometer along X of the same virtual machine: 17 targets, 5 "
            "bidirectional cycles in the standard test cycle, 3 µm of backlash, {:.1f} µm reading "
            "noise, and an axis warming from {:.1f} to {:.1f} °C whose expansion the evaluation "
            "corrects to 20 °C. The noise-free truth gives E = {:.2f} µm and B̄ = −3 µm; the "
            "evaluation finds E = {:.2f} µm and B̄ = {:.2f} µm. Try <code>trueaxis positioning "
            "--input runs.csv --tolerance A=20,R=6 --report positioning.html</code> (or "
            "<code>--input runs.rtl</code>, the same runs as Renishaw's .rtl file).</p>"
            "<p>Compensation tables from this result: LinuxCNC (<code>x-positioning.comp</code>) "
            "and HEIDENHAIN (<code>X.COM</code>) carry both directions, Sinumerik LEC "
            "(<code>x_lec.mpf</code>) and FANUC pitch error data (<code>x-pitch.txt</code>) the "
            "mean of both. The axis was compensated with <code>X.COM</code> and measured "
            "again (<code>trueaxis positioning --input after.csv --before positioning.json</code> "
            "compares two runs so).</p>",
            po.noise * 1e3, po.temperature_start, po.temperature_end, (hi - lo) * 1e3,
            pr.iso.E * 1e3, pr.iso.B_mean * 1e3) +
        ps.intro_html;
    report::add_before_after(ps, pr, after);
    ps.summary = fmt::format("A {:.2f} µm, E {:.2f} µm; compensated with X.COM: A {:.2f} µm",
                             pr.iso.A * 1e3, pr.iso.E * 1e3, after.iso.A * 1e3);
    sections.push_back(std::move(ps));
  }

  // Scenario: a circular test of X and Y with a ballbar (ISO 230-4), its causes diagnosed.
  {
    say("circular: a ballbar test of X and Y, R 100 mm at 1000 mm/min, both directions...");
    sim::CircularOptions co;
    co.radius = 100;
    co.feed = 1000;
    co.servo[0].gain = 40;
    co.servo[1].gain = 36;
    co.servo[0].backlash = 3e-3;
    co.servo[1].backlash = 5e-3;
    co.servo[1].spike = 3e-3;
    co.servo[1].spike_decay = 5 * M_PI / 180;
    co.pivot_offset = Eigen::Vector3d(0.006, -0.004, 0);
    co.noise = 0.1e-3;
    co.sample_rate = 25;  // Hz: the report draws every sample, and stays small
    co.seed = o.seed;
    const auto run = sim::simulate_circular(machine, co);
    io::write_trace((dir / "circular.csv").string(), run.trace);
    circular::Options opt;
    opt.radius = co.radius;
    opt.feed = co.feed;
    const auto cr = circular::evaluate(run.trace, opt);
    io::write_circular_result((dir / "circular.json").string(), cr, &run.trace);
    const auto truth = sim::circular_truth(machine, co);
    auto value = [&](const std::string& key) -> double {
      for (const auto& c : cr.causes)
        if (c.key == key) return c.value;
      return NAN;
    };
    say(
        fmt::format("circular: G {:.2f} / {:.2f} µm (ccw / cw), H {:.2f} µm; backlash X {:.2f}, Y "
                    "{:.2f} µm (set 3, 5); lag mismatch {:.2f} ms (set {:.2f}) -> circular.csv, "
                    "circular.json",
                    cr.ccw.G * 1e3, cr.cw.G * 1e3, cr.H ? *cr.H * 1e3 : NAN, value("backlash.X"),
                    value("backlash.Y"), value("lag_mismatch"), truth.lag_mismatch * 1e3));
    // What to give the controller: backlash and squareness, written for the four controllers
    // and read back; the test rerun with them loaded.
    io::CompensationFilesOptions fo;
    fo.travel = std::array<double, 2>{machine.range[1][0], machine.range[1][1]};
    const auto comp = circular::compensation_from(cr);
    const auto files =
        io::write_compensation_files((dir / "circular-compensation").string(), comp, fo);
    sim::CircularOptions co_after = co;
    io::read_compensation_json(files.json_path).apply(co_after);
    const auto run_after = sim::simulate_circular(machine, co_after);
    const auto cr_after = circular::evaluate(run_after.trace, opt);
    say(fmt::format(
        "circular: compensated (backlash X {:.2f}, Y {:.2f} µm, squareness {:.1f} µm/m; files "
        "for 4 controllers read back) and rerun: G {:.2f} -> {:.2f} µm; what is left is the "
        "servo lag mismatch -> circular-compensation/",
        comp.backlash[0].value * 1e3, comp.backlash[1].value * 1e3, comp.squareness.value * 1e6,
        std::max(cr.ccw.G, cr.cw.G) * 1e3, std::max(cr_after.ccw.G, cr_after.cw.G) * 1e3));
    auto cs = report::circular_section("Circular test of X and Y with a ballbar (ISO 230-4)", cr,
                                       run.trace);
    std::vector<std::vector<std::string>> rows{{"file", "controller", "what"}};
    for (const auto& w : files.written)
      rows.push_back({std::filesystem::path(w.path).filename().string(), w.controller, w.what});
    for (const auto& n : files.not_written)
      rows.push_back({"not written", n.controller, n.what + ": " + n.reason});
    cs.intro_html =
        fmt::format(
            "<p>A telescoping ballbar on the same virtual machine: X and Y contour a 100 mm circle "
            "at 1000 mm/min under position loops of 40 and 36 /s (a lag mismatch of {:.2f} ms), "
            "with 3 and 5 µm of backlash, a 3 µm reversal spike on Y, the machine's own "
            "geometric errors (squareness {:.1f} µm/m, scale mismatch {:.1f} µm/m over ±R), the "
            "pivot set 6 µm and −4 µm off and 0.1 µm of reading noise. The diagnosis below is "
            "found from the trace alone. The backlash and squareness it finds are written for "
            "four controllers (each file read back), loaded in the virtual controller, and the "
            "test rerun: the second polar plot shows both runs. What is left is mostly the servo "
            "lag mismatch, which is tuned in the drives, not compensated. Try <code>trueaxis "
            "circular --input circular.csv --compensation comp --travel 0,600 --report "
            "c.html</code>.</p>",
            truth.lag_mismatch * 1e3, truth.squareness * 1e6, truth.scale_mismatch * 1e6) +
        cs.intro_html;
    report::add_compensation(cs, comp, rows);
    {  // G before and after on one polar plot: the rerun's section, its polar plot only.
      auto after = report::circular_section("", cr_after, run_after.trace,
                                            report::CircularBefore{&cr, &run.trace});
      after.planes.front().title = fmt::format(
          "before (dashed) and after the compensation: G {:.2f} → {:.2f} µm; {}",
          std::max(cr.ccw.G, cr.cw.G) * 1e3, std::max(cr_after.ccw.G, cr_after.cw.G) * 1e3,
          after.planes.front().title.substr(after.planes.front().title.find("deviations")));
      cs.planes.push_back(std::move(after.planes.front()));
    }
    sections.push_back(std::move(cs));
  }

  // Scenario 5: the CMM's error-vector map from a ball gauge (Oya, Hokari, Tamura 1988), checked
  // with gauge blocks.
  say("ballgauge: probing a 5 x 4 x 2 ball frame in 3 stacked placements (0.5 µm noise)...");
  const auto bgauge = sim::frame_gauge();
  auto poses = sim::stacked_poses(
      bgauge, 3, {150, 120, 60},
      Eigen::AngleAxisd(0.004, Eigen::Vector3d(0.2, -0.1, 1).normalized()).toRotationMatrix());
  poses.front().alignment = ballgauge::Alignment::LeastSquares;
  sim::BallGaugeOptions bo;
  bo.noise = 0.5e-3;
  bo.seed = o.seed;
  const auto balls = sim::simulate_ballgauge(machine, bgauge, poses, bo);
  const auto bmap = ballgauge::calibrate(bgauge, balls.placements);
  ballgauge::ParametricOptions po;
  po.offset = machine.offset;
  const auto model = ballgauge::identify(bgauge, balls.placements, po);
  sim::GaugeBlockOptions gbo;
  balls.bounds(gbo.lo, gbo.hi);
  gbo.noise = 0.5e-3;
  gbo.seed = o.seed + 1000;
  const auto gblocks = sim::simulate_gauge_blocks(machine, gbo);
  const std::vector<ballgauge::LengthVerification> checks{
      ballgauge::verify_lengths(gblocks.lengths, ballgauge::grid_correction(*bmap.grid)),
      ballgauge::verify_lengths(gblocks.lengths, ballgauge::parametric_correction(model))};
  io::write_gauge((dir / "gauge.json").string(), bgauge);
  io::write_measurements((dir / "measurements.json").string(), balls.placements);
  io::write_ballgauge_map((dir / "map.json").string(), bmap);
  io::write_parametric((dir / "model.json").string(), model);
  io::write_lengths((dir / "lengths.csv").string(), gblocks.lengths);
  // The E0 specification of a mid-range bridge CMM of this size: the check before and after
  // correction.
  const auto mpe = ballgauge::Mpe::parse("2.5+L/300");
  io::write_length_verification((dir / "verify.json").string(), checks, &mpe);
  say(fmt::format(
      "ballgauge: {} mapped points; {} gauge-block lengths: before {:+.1f} ... {:+.1f} µm, "
      "after the grid {:+.1f} ... {:+.1f} µm (RMS {:.2f}, expected {:.2f}), after the parametric "
      "model {:+.1f} ... {:+.1f} µm (RMS {:.2f}, expected {:.2f}) -> map.json, model.json, "
      "lengths.csv, verify.json",
      bmap.points.size(), gblocks.lengths.size(), checks[0].before.min * 1e3,
      checks[0].before.max * 1e3, checks[0].after.min * 1e3, checks[0].after.max * 1e3,
      checks[0].after.rms * 1e3, checks[0].predicted_after * 1e3, checks[1].after.min * 1e3,
      checks[1].after.max * 1e3, checks[1].after.rms * 1e3, checks[1].predicted_after * 1e3));
  auto bs =
      report::ballgauge_section("CMM error map from a ball gauge (Oya et al. 1988)", bmap, &model);
  bs.intro_html =
      "<p>The same virtual CMM measures a 5 × 4 × 2 frame of 25 mm balls at 80 mm pitch in "
      "three placements stacked in z (as Oya et al.'s four sections, 320 × 240 × 240 mm), 10 "
      "probed "
      "points per ball with 0.5 µm noise. The first placement is aligned by least squares, the "
      "others are stitched over their 20 shared balls. The same data also give the 21 "
      "rigid-body errors as cubic polynomials (the parametric model, <code>model.json</code>, a "
      "machine file). Try <code>trueaxis ballgauge --gauge gauge.json --measurements "
      "measurements.json -o m.json --parametric p.json --stylus-offset 0,0,-100 --report "
      "m.html</code>.</p>" +
      bs.intro_html;
  bs.summary = fmt::format(
      "{} points mapped; gauge-block errors RMS {:.2f} µm before, {:.2f} µm after the grid, {:.2f} "
      "µm after the parametric model",
      bmap.points.size(), checks[0].before.rms * 1e3, checks[0].after.rms * 1e3,
      checks[1].after.rms * 1e3);
  sections.push_back(std::move(bs));
  {
    // The parametric model's 21 errors against the virtual machine's own: what a simulation can
    // show and a real CMM cannot.
    report::Section es;
    es.title = "The 21 rigid-body errors from the ball gauge, against the machine's truth";
    es.references = {report::refs::kIso230, report::refs::kGum};
    const auto diff = report::add_error_functions(es, model, machine);
    es.intro_html =
        "<p>The parametric model identified from the ball-gauge data above (cubic polynomials, "
        "<code>model.json</code>) beside the error functions this virtual machine was built "
        "with. Ball-gauge data fix no function's constant (the placements' poses absorb it) and "
        "no straightness slope (it is squareness, and a rotation of the whole map): both are "
        "taken out of the two curves alike, and the squareness errors are compared as ISO 230-1 "
        "defines them. The machine's errors are not cubic, so the model misses their short "
        "waves; the gauge-block check below shows what that costs in measured lengths. An error "
        "that does not move this stylus tip is not determined by the data, and is drawn only as "
        "the truth.</p>";
    es.summary = fmt::format(
        "the error functions within {:.2g} µm and {:.2g} µrad of the truth over the mapped span, "
        "squareness within {:.2g} µrad",
        diff.translation * 1e3, diff.rotation * 1e6, diff.squareness * 1e6);
    sections.push_back(std::move(es));
  }
  auto ls =
      report::lengths_section("Gauge-block verification (ISO 10360-2 positions)", checks, &mpe);
  ls.intro_html +=
      "<p>Held-out gauge blocks in the ISO 10360-2 positions (x, y, z and the four space "
      "diagonals of the mapped box), five lengths each, three repeats, measured on the same "
      "machine with 0.5 µm probing noise. Try <code>trueaxis verify-lengths --map map.json "
      "--model model.json -i lengths.csv -o v.json --report v.html</code>.</p>";
  {
    // The verdicts in words, from the numbers: what the correction achieved, and, for a
    // correction that still fails, why (a noise floor no map removes).
    const auto e0_before = ballgauge::check_mpe(checks[0].rows, mpe, false);
    std::string words = fmt::format(
        "<p>Against the MPE {} µm, before correction the CMM {} E0 ({} of {} lengths beyond the "
        "MPE, the worst at {:.0f} % of it).",
        report::escape(mpe.text), e0_before.pass() ? "passes" : "fails", e0_before.failed,
        e0_before.lengths, 100 * e0_before.worst_ratio);
    std::vector<std::string> verdicts;
    for (const auto& c : checks) {
      const auto e0 = ballgauge::check_mpe(c.rows, mpe, true);
      const double floor_um = 2 * std::hypot(c.repeatability, c.correction_u_rms) * 1e3;
      if (e0.pass())
        words += fmt::format(
            " Corrected with the {}, it passes: the worst length at {:.0f} % of "
            "the MPE.",
            c.correction == "grid" ? "grid map" : "parametric model", 100 * e0.worst_ratio);
      else {
        double shortest = INFINITY;
        for (const auto& row : c.rows) shortest = std::min(shortest, row.nominal);
        const double mpe_short = mpe.at(shortest);
        words += fmt::format(
            " Corrected with the {}, {} of {} lengths still exceed it (worst {:.0f} %). Its "
            "expected scatter is ±{:.1f} µm (2σ: repeats {:.2f} µm ⊕ the correction's own "
            "uncertainty {:.2f} µm) against an MPE of {:.1f} µm at {:g} mm: {}.",
            c.correction == "grid" ? "grid map" : "parametric model", e0.failed, e0.lengths,
            100 * e0.worst_ratio, floor_um, c.repeatability * 1e3, c.correction_u_rms * 1e3,
            mpe_short, shortest,
            floor_um >= 0.7 * mpe_short
                ? "with scatter this close to the MPE some lengths fail by chance, whatever the "
                  "map"
                : "more than that scatter explains; the correction leaves a systematic error");
      }
      verdicts.push_back(fmt::format("{} {}", c.correction == "grid" ? "grid" : "parametric",
                                     e0.pass() ? "PASS" : "FAIL"));
    }
    ls.intro_html += words + "</p>";
    ls.summary = fmt::format("E0 against {} µm: before correction {}; after: {}", mpe.text,
                             e0_before.pass() ? "PASS" : "FAIL", fmt::join(verdicts, ", "));
  }
  sections.push_back(std::move(ls));

  // Scenario: the CMM accepted by ISO 10360-2 and -5, failing, mapped and corrected.
  sections.push_back(demo_acceptance(machine, dir.string(), o.seed, say));

  // Scenario: the machine's records over three visits, its trend and a certificate.
  sections.push_back(demo_records(machine, dir.string(), o.seed, say));

  // Scenario 6: error-tolerant scanning of NIST's I++ test part, from its STEP file, on the same
  // CMM (its geometric errors included). Two parts of a batch that sit 1.8 mm off in the fixture
  // and carry a 2 mm bump the design does not have.
  for (const auto& [name, text] : example_files())
    if (name == "ipp_simple.stp") io::write_text((dir / "ipp_simple.stp").string(), text);
  const design::Design part_design =
      design::from_step((dir / "ipp_simple.stp").string(),
                        {{"mid", {Eigen::Vector3d(0, 0, 37.5), Eigen::Vector3d::UnitZ()}}});
  io::write_design((dir / "design.json").string(), part_design);
  sim::PartDeviation pdev;
  pdev.translation = Eigen::Vector3d(1.8, -1.1, 0);
  pdev.rotation_deg = Eigen::Vector3d(0, 0, 0.3);
  pdev.bumps = {{"mid.1", 150, 2.0, 30}};
  pdev.noise = 0.002;
  scan::VirtualCmmOptions vo;
  vo.probe.noise = 0.5e-3;
  vo.probe.seed = o.seed;
  vo.geometry = machine;
  scan::ControllerOptions sco;
  scan::ControllerOptions auto_only = sco;
  auto_only.strategy = scan::Strategy::Autonomous;
  design::Design batch_design = part_design;
  std::vector<double> tolerant_s, autonomous_s;
  std::vector<std::array<double, 4>> form_um;  // RMS raw, corrected; max raw, corrected
  for (std::uint64_t k = 1; k <= 2; ++k) {
    sim::Part part{part_design, pdev};
    part.deviation.seed = o.seed + k;
    io::write_part((dir / fmt::format("part{}.json", k)).string(), part);
    const design::Design used = batch_design;
    const Eigen::Vector3d home = scan::start_position(used, sco);
    scan::VirtualCmm cmm(part, vo, home);
    const auto r = scan::scan(cmm, used, sco);
    scan::VirtualCmm cmm_auto(part, vo, home);
    autonomous_s.push_back(scan::scan(cmm_auto, part_design, auto_only).time.total);
    tolerant_s.push_back(r.time.total);
    io::write_scan((dir / fmt::format("scan{}.json", k)).string(), r, sco,
                   {sco.path.tip_radius, vo.probe.noise * 1e3, machine.name, cmm.part_origin()});
    std::vector<sim::Contour> truth;
    for (const auto& s : part.design.sections) truth.push_back(sim::true_contour(part, s));
    std::vector<Eigen::VectorXd> truth_um;
    std::vector<Eigen::Matrix3Xd> true_part;
    // Each point's distance from the true part (µm) as measured, for the report; and the form
    // the points show of the part, before and after correcting them with the error map measured
    // above: the map's error at the machine command each point was read at (the stylus centre,
    // tip radius less pushing inside the surface point along its normal). A CMM's error map,
    // like any measurement of a part, is defined up to a rigid datum, so both are compared after
    // the best-fit translation and rotation in the section plane (a datum alignment).
    const map::Interpolator emap(space.map, {map::Interpolation::Linear, map::Outside::Clamp});
    std::array<std::vector<double>, 2> dist;  // raw, corrected
    std::array<std::vector<Eigen::Vector3d>, 2> where;
    std::vector<Eigen::Vector3d> normals;
    double worst = 0;
    for (std::size_t i = 0; i < r.sections.size(); ++i) {
      Eigen::VectorXd t(static_cast<Eigen::Index>(r.sections[i].points.size()));
      for (std::size_t j = 0; j < r.sections[i].points.size(); ++j) {
        const auto& pt = r.sections[i].points[j];
        const auto& plane = r.planned.sections[i].plane;
        t[static_cast<Eigen::Index>(j)] = cmm.distance(plane, pt.surface) * 1e3;
        const Eigen::Vector3d command = pt.surface +
                                        (sco.path.tip_radius - sco.path.pushing) * pt.normal +
                                        cmm.part_origin() - machine.offset;
        const Eigen::Vector3d fixed = pt.surface + emap(command);
        dist[0].push_back(cmm.distance(plane, pt.surface));
        dist[1].push_back(cmm.distance(plane, fixed));
        where[0].push_back(pt.surface);
        where[1].push_back(fixed);
        normals.push_back(pt.normal);
      }
      if (t.size()) worst = std::max(worst, t.cwiseAbs().maxCoeff());
      truth_um.push_back(std::move(t));
      // The true contour this section's points lie on (a section of the corrected design data
      // may be a stretch of a contour, under another name).
      const sim::Contour* on = nullptr;
      double best = INFINITY;
      for (const auto& c : truth) {
        double sum = 0;
        for (const auto& pt : r.sections[i].points) sum += std::abs(c.nearest(pt.surface).distance);
        if (sum < best) best = sum, on = &c;
      }
      if (on) true_part.push_back(on->points());
    }
    // Gauss–Newton on the exact distances, linearised with the measured normals.
    std::array<double, 2> form{}, form_max{};  // RMS and max distance after the alignment (µm)
    const auto n = static_cast<Eigen::Index>(normals.size());
    const Eigen::Vector3d centre(50, 50, 25);
    for (std::size_t v = 0; v < 2; ++v) {
      Eigen::Vector3d t = Eigen::Vector3d::Zero();
      double angle = 0;
      Eigen::VectorXd d(n);
      for (int iter = 0; iter < 4; ++iter) {
        const Eigen::Matrix3d R =
            Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()).toRotationMatrix();
        Eigen::MatrixXd A(n, 3);
        std::size_t k = 0;
        for (std::size_t i = 0; i < r.sections.size(); ++i)
          for (std::size_t j = 0; j < r.sections[i].points.size(); ++j, ++k) {
            const Eigen::Vector3d p = centre + R * (where[v][k] - centre) + t;
            const Eigen::Vector3d& nn = normals[k];
            const auto kk = static_cast<Eigen::Index>(k);
            d[kk] = cmm.distance(r.planned.sections[i].plane, p);
            A.row(kk) << nn.x(), nn.y(), nn.dot(Eigen::Vector3d::UnitZ().cross(p - centre));
          }
        const Eigen::Vector3d x = A.colPivHouseholderQr().solve(-d);
        t += Eigen::Vector3d(x[0], x[1], 0);
        angle += x[2];
      }
      form[v] = std::sqrt(d.squaredNorm() / static_cast<double>(n)) * 1e3;
      form_max[v] = d.cwiseAbs().maxCoeff() * 1e3;
    }
    int errors = 0;
    for (const auto& sec : r.sections) errors += sec.trajectory_errors;
    say(fmt::format(
        "scan: part {} of the batch: {}; {} trajectory errors; machine time {:.1f} s "
        "(autonomous scanning alone: {:.1f} s); points within {:.1f} µm of the true part, "
        "RMS {:.2f} µm after datum alignment, {:.2f} µm corrected with the error map -> "
        "scan{}.json",
        k, r.ok() ? "all sections scanned" : "FAILED", errors, r.time.total, autonomous_s.back(),
        worst, form[0], form[1], k));
    form_um.push_back({form[0], form[1], form_max[0], form_max[1]});
    auto ss = report::scan_section(fmt::format("Error-tolerant scanning, part {} of a batch{}", k,
                                               k == 1 ? "" : ", with the corrected design data"),
                                   r, r.planned, sco.tolerance, truth_um, true_part);
    if (k == 1)
      ss.intro_html =
          fmt::format(
              "<p>NIST's I++ DME test part (<code>ipp_simple.stp</code>, a 100 × 100 × 50 mm "
              "block with a Ø50 mm hole 25 mm deep) is cut half-way down the hole, at z = 37.5 mm, "
              "into "
              "two contours: the square and "
              "the hole. The parts of this batch sit 1.8 mm off and turned 0.3° in their "
              "fixture, and carry a 2 mm bump on the outline; they are scanned on the same "
              "virtual CMM as above (geometric errors, {:g} µm probe noise, 1 kHz servo). A "
              "plain design-value scan fails; the translation and rotation are found from "
              "touch points, and the bump, which no global correction explains, is scanned "
              "autonomously once and written into the design data. Try <code>trueaxis scan "
              "--design design.json --part part1.json --machine machine.json -o s.json "
              "--corrected-design d2.json --report s.html</code>.</p>",
              vo.probe.noise * 1e3) +
          ss.intro_html;
    else
      ss.intro_html =
          "<p>The next part of the batch, scanned with the design data the first part left "
          "(<code>scan1.json</code>'s corrected design): design-value scanning only.</p>" +
          ss.intro_html;
    ss.summary = fmt::format(
        "{}; {} trajectory error{}; machine time {:.1f} s (autonomous scanning: {:.1f} s)",
        r.ok() ? "every section scanned" : "not every section scanned", errors,
        errors == 1 ? "" : "s", r.time.total, autonomous_s.back());
    sections.push_back(std::move(ss));
    batch_design = r.design;
  }
  io::write_design((dir / "design-corrected.json").string(), batch_design);
  sections.back().intro_html += fmt::format(
      "<p>Machine time for these two parts: {:.1f} s error-tolerant against {:.1f} s scanning "
      "autonomously (the slow surface-following scan a CMM falls back to); every further part "
      "of the batch costs {:.1f} s instead of {:.1f} s.</p>",
      tolerant_s[0] + tolerant_s[1], autonomous_s[0] + autonomous_s[1], tolerant_s[1],
      autonomous_s[1]);
  sections.back().intro_html += fmt::format(
      "<p>The measured points carry the CMM's own geometric errors (the last column of the "
      "tables: distance from the simulated true part, most of it a shift of where the part "
      "sits, which a datum alignment removes). After a best-fit translation and rotation in "
      "the plane, the points lie at RMS {:.2f} µm (max {:.1f}) from the true part in part 1 "
      "and {:.2f} µm (max {:.1f}) in part 2. Corrected first with the error map measured "
      "above (each point moved by the map's error at the machine position it was read at): "
      "RMS {:.2f} µm (max {:.1f}) and {:.2f} µm (max {:.1f}), against {:g} µm of probe "
      "noise.</p>",
      form_um[0][0], form_um[0][2], form_um[1][0], form_um[1][2], form_um[0][1], form_um[0][3],
      form_um[1][1], form_um[1][3], vo.probe.noise * 1e3);

  report::write(o.output, report::render("trueaxis demo", sections, 4000, cli::report_meta()));
  say(fmt::format("wrote {}", o.output));
  return 0;
}

}  // namespace trueaxis::cli
