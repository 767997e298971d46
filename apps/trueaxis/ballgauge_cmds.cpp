// trueaxis CLI — CMM error map from ball gauges: 'ballgauge', 'correct', 'simulate ballgauge'.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <Eigen/Geometry>
#include <cmath>
#include <memory>
#include <optional>

#include "commands.hpp"
#include "progress.hpp"
#include "trueaxis/ballgauge/ballgauge.hpp"
#include "trueaxis/ballgauge/lengths.hpp"
#include "trueaxis/ballgauge/parametric.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/ballgauge/ballgauge.hpp"
#include "trueaxis/io/csv.hpp"
#include "trueaxis/io/sim/machine.hpp"
#include "trueaxis/io/surface/space.hpp"
#include "trueaxis/ippdme/ballgauge.hpp"
#include "trueaxis/ippdme/remote_cmm.hpp"
#include "trueaxis/map/error_map.hpp"
#include "trueaxis/report/ballgauge.hpp"
#include "trueaxis/sim/ballgauge.hpp"

namespace trueaxis::cli {

// Before correcting: the first point outside the map is refused at its place in the input file
// (file:line:col, counted as the file counts), unless --clamp.
void refuse_outside(const map::ErrorMap& m, const Eigen::Matrix3Xd& p, const std::string& input,
                    double tolerance) {
  for (Eigen::Index i = 0; i < p.cols(); ++i)
    if (!m.contains(p.col(i), tolerance)) {
      io::CsvTable t = io::CsvTable::read(input);
      const int x = t.require("x", io::Unit::Millimetre);
      throw Error(fmt::format("{}point {} {}", t.where(static_cast<long>(i), x), i + 1,
                              m.outside_message(p.col(i))));
    }
}

namespace {

struct CalArgs {
  std::string gauge, measurements, output, parametric, report;
  ballgauge::Options o;
  ballgauge::ParametricOptions po;
  std::vector<double> stylus;
  bool quiet = false;
};

int run_calibrate(const CalArgs& a) {
  const auto g = io::read_gauge(a.gauge);
  const auto p = io::read_measurements(a.measurements, &g);
  ballgauge::Result r;
  try {
    r = ballgauge::calibrate(g, p, a.o);
  } catch (const Error& e) {
    throw Error(fmt::format("{}: {}", a.measurements, e.what()));
  }
  io::write_ballgauge_map(a.output, r);
  if (!a.quiet) fmt::print("{}wrote {}\n", r.summary(), a.output);
  for (const auto& pl : r.placements)
    for (const auto& d : pl.dropped)
      fmt::print(stderr, "trueaxis: warning: {}: {}: {}\n", a.measurements, pl.name, d);
  std::optional<ballgauge::ParametricResult> pr;
  if (!a.parametric.empty()) {
    ballgauge::ParametricOptions po = a.po;
    po.outlier_tolerance = a.o.outlier_tolerance;
    po.drop_outliers = a.o.drop_outliers;
    if (a.stylus.size() != 3) throw Error("--stylus-offset needs x,y,z (mm)");
    po.offset = Eigen::Vector3d(a.stylus[0], a.stylus[1], a.stylus[2]);
    try {
      pr = ballgauge::identify(g, p, po);
    } catch (const Error& e) {
      throw Error(fmt::format("{}: {}", a.measurements, e.what()));
    }
    io::write_parametric(a.parametric, *pr);
    if (!a.quiet) fmt::print("{}wrote {}\n", pr->summary(), a.parametric);
  }
  if (!a.report.empty()) {
    report::write(
        a.report,
        report::render(
            "trueaxis ball-gauge map",
            {from_file(report::ballgauge_section("CMM error map from ball-gauge placements", r,
                                                 pr ? &*pr : nullptr),
                       a.measurements)},
            4000, cli::report_meta()));
    if (!a.quiet) fmt::print("wrote {}\n", a.report);
  }
  if (!r.grid && r.frames > 1)
    fmt::print(stderr,
               "trueaxis ballgauge: the {} aligned placements map in {} separate frames, so "
               "map.json holds their points but no common grid for 'trueaxis correct'{}\n",
               r.frames, r.frames,
               a.parametric.empty()
                   ? "; --parametric model.json --stylus-offset x,y,z joins them in the 21-error "
                     "model"
                   : fmt::format(": use the 21-error model ({})", a.parametric));
  else if (!r.grid)
    std::fprintf(stderr,
                 "trueaxis ballgauge: the mapped points do not form a full lattice; map.json has "
                 "the points but no grid, so 'trueaxis correct' cannot use it\n");
  return 0;
}

struct CorrectArgs {
  std::string map, input, output;
  bool clamp = false, quiet = false;
};

int run_correct(const CorrectArgs& a) {
  const map::ErrorMap m = io::read_error_map(a.map);
  Eigen::Matrix3Xd p = io::read_points(a.input);
  if (!a.clamp) refuse_outside(m, p, a.input);
  map::EvalOptions o;
  o.outside = a.clamp ? map::Outside::Clamp : map::Outside::Refuse;
  try {
    map::correct(m, p, o);
  } catch (const Error& e) {
    throw Error(fmt::format("{}: {}", a.input, e.what()));
  }
  io::write_points(a.output, p);
  if (!a.quiet && a.output != "-")
    fmt::print("corrected {} points (X = x - error(x), {}): wrote {}\n", p.cols(),
               m.plane >= 0 ? "bilinear on the plate's plane" : "trilinear", a.output);
  return 0;
}

struct VerifyArgs {
  std::string map, model, input, output, report, mpe;
  ballgauge::LengthOptions o;
  bool clamp = false, quiet = false;
};

int run_verify(const VerifyArgs& a) {
  if (a.map.empty() && a.model.empty())
    throw Error("verify-lengths needs --map (grid correction) or --model (parametric), or both");
  const auto lengths = io::read_lengths(a.input);
  std::vector<ballgauge::Correction> corrections;
  std::optional<map::ErrorMap> grid;
  if (!a.map.empty()) {
    grid = io::read_error_map(a.map);
    map::EvalOptions eo;
    eo.outside = a.clamp ? map::Outside::Clamp : map::Outside::Refuse;
    corrections.push_back(ballgauge::grid_correction(*grid, eo));
  }
  if (!a.model.empty())
    corrections.push_back(ballgauge::parametric_correction(io::read_parametric(a.model)));
  // A length the verification refuses is named by the file's line and the column of the end
  // at fault (its x), reading the file again on that error path only.
  ballgauge::LengthOptions o = a.o;
  o.locate = [&](std::size_t index, int end) {
    auto table = io::CsvTable::read(a.input);
    const int col = table.find(end == 2 ? "x2" : "x1", io::Unit::Millimetre);
    return index < table.rows() && col >= 0 ? table.where(static_cast<long>(index), col)
                                            : a.input + ": ";
  };
  std::vector<ballgauge::LengthVerification> results;
  for (const auto& c : corrections) results.push_back(ballgauge::verify_lengths(lengths, c, o));
  std::optional<ballgauge::Mpe> mpe;
  if (!a.mpe.empty()) mpe = ballgauge::Mpe::parse(a.mpe);
  io::write_length_verification(a.output, results, mpe ? &*mpe : nullptr);
  if (!a.quiet) {
    for (const auto& r : results) fmt::print("{}", r.summary());
    fmt::print("wrote {}\n", a.output);
  }
  if (mpe) {
    const auto say = [&](const std::string& name, const std::vector<ballgauge::LengthRow>& rows,
                         bool after) {
      const auto c = ballgauge::check_mpe(rows, *mpe, after);
      if (!a.quiet)
        fmt::print("E0 {} against MPE {} µm: {} ({} of {} beyond, worst {:.0f} % of MPE)\n", name,
                   mpe->text, c.pass() ? "PASS" : "FAIL", c.failed, c.lengths, 100 * c.worst_ratio);
    };
    say("before correction", results.front().rows, false);
    for (const auto& r : results) say("after the " + r.correction + " correction", r.rows, true);
  }
  if (!a.report.empty()) {
    report::write(
        a.report,
        report::render(
            "trueaxis length verification",
            {from_file(report::lengths_section("Gauge-block verification (ISO 10360-2 positions)",
                                               results, mpe ? &*mpe : nullptr),
                       a.input)},
            4000, cli::report_meta()));
    if (!a.quiet) fmt::print("wrote {}\n", a.report);
  }
  return 0;
}

struct SimArgs {
  MachineSource machine;
  std::string gauge = "gauge.json", measurements = "measurements.json",
              truth = "ballgauge-truth.csv";
  std::string alignment = "321", lengths, balls, cmm, plate;
  const CLI::Option* tip_radius_given = nullptr;  // --tip-radius, when given
  int sections = 3, repeats = 3;
  double pitch = 100;
  double length_noise_um = -1;
  std::vector<double> origin{150, 120, 60};
  double misalignment_urad = 4000, noise_um = 0;
  sim::BallGaugeOptions o;
  bool quiet = false;
};

int run_simulate(const SimArgs& a) {
  std::pair<std::string, unsigned short> address;
  if (!a.cmm.empty()) address = parse_ipp_address(a.cmm);  // a usage error before any work
  const sim::Machine m = a.machine.load();
  if (a.origin.size() != 3) throw Error("--origin needs x,y,z (mm)");
  sim::BallGaugeSetup setup;
  if (!a.plate.empty()) sim::parse_plate(a.plate, setup);  // checked by --plate's validator
  setup.pitch = a.pitch;
  setup.placements = a.sections;
  setup.origin = {a.origin[0], a.origin[1], a.origin[2]};
  setup.misalignment = a.misalignment_urad * 1e-6;
  setup.least_squares = a.alignment == "ls";
  // On a CMM over I++ DME the server's stylus probes every placement from above.
  setup.from_above = !a.cmm.empty();
  const sim::BallGaugeLayout layout = sim::ballgauge_setup(m, setup);
  const ballgauge::Gauge& g = layout.gauge;
  const std::vector<sim::GaugePose>& poses = layout.poses;
  const std::string& what = layout.description;
  sim::BallGaugeOptions o = a.o;
  o.noise = a.noise_um * 1e-3;
  if (!a.balls.empty()) {
    io::write_balls(a.balls, sim::gauge_balls(g, poses));
    if (!a.quiet)
      fmt::print("wrote {}: where the gauge's balls stand (trueaxis serve --balls {})\n", a.balls,
                 a.balls);
  }
  sim::BallGaugeCampaign c;
  long commands = 0;
  if (a.cmm.empty()) {
    c = sim::simulate_ballgauge(m, g, poses, o);
  } else {
    // Measured on the CMM: PtMeas on every ball where the poses put it, with the CMM's probe.
    ippdme::RemoteCmmOptions ro;
    std::tie(ro.client.host, ro.client.port) = address;
    // The server's tip radius, unless one is given (a server before I++ DME 1.4.2 cannot say).
    ro.tip_radius = a.tip_radius_given && a.tip_radius_given->count() ? o.tip_radius : 0;
    ippdme::RemoteCmm cmm(ro);
    o.tip_radius = cmm.tip_radius();
    const double total =
        static_cast<double>(o.points_per_ball) * static_cast<double>(g.balls.size() * poses.size());
    double done = 0;
    cli::Progress progress("probing the gauge", a.quiet);
    auto probe = ippdme::ball_probe(cmm, sim::gauge_balls(g, poses));
    c = sim::measure_ballgauge(g, poses, o,
                               [&](const Eigen::Vector3d& X, double reach, const Eigen::Vector3d& d,
                                   const std::string& w) {
                                 const Eigen::Vector3d p = probe(X, reach, d, w);
                                 progress.update(++done / total);
                                 return p;
                               });
    progress.done();
    commands = cmm.commands();
  }
  io::write_gauge(a.gauge, g);
  io::write_measurements(a.measurements, c.placements);
  // Truth: every probed ball's true centre and the machine's error there.
  const sim::BallGaugeTruth truth = sim::ballgauge_truth(m, c);
  std::vector<Eigen::VectorXd> vc(8);
  vc[0] = Eigen::Map<const Eigen::VectorXi>(truth.placement.data(),
                                            static_cast<Eigen::Index>(truth.placement.size()))
              .cast<double>();
  vc[1] = Eigen::Map<const Eigen::VectorXi>(truth.ball.data(),
                                            static_cast<Eigen::Index>(truth.ball.size()))
              .cast<double>();
  for (int k = 0; k < 3; ++k) {
    vc[static_cast<std::size_t>(2 + k)] = truth.centre.row(k).transpose();
    vc[static_cast<std::size_t>(5 + k)] = truth.error.row(k).transpose() * 1e3;
  }
  io::write_csv(a.truth, {"placement", "ball", "x", "y", "z", "ex_um", "ey_um", "ez_um"},
                {&vc[0], &vc[1], &vc[2], &vc[3], &vc[4], &vc[5], &vc[6], &vc[7]});
  if (!a.cmm.empty()) {
    if (!a.quiet)
      fmt::print(
          "measured {} placements of {} through the I++ DME server at {} ({} "
          "points per ball, tip radius {} mm, {} commands): wrote {} and {}; {} holds where "
          "the balls should be and the errors of {} there (the truth if the server runs that "
          "machine)\n",
          c.placements.size(), what, a.cmm, o.points_per_ball, o.tip_radius, commands, a.gauge,
          a.measurements, a.truth,
          a.machine.path.empty() ? fmt::format("the random machine of seed {}", a.machine.seed)
                                 : a.machine.path);
    return 0;
  }
  if (!a.lengths.empty()) {
    // Gauge blocks in the box of the mapped ball centres (ISO 10360-2 style, held out), probed
    // with the machine's stylus within the span of axis positions the campaign covered (where
    // a model identified from it holds; placements probed with other styli cover other spans).
    sim::GaugeBlockOptions go = sim::held_out_blocks(m, c);
    go.repeats = a.repeats;
    go.tip_radius = o.tip_radius;
    go.noise = (a.length_noise_um >= 0 ? a.length_noise_um : a.noise_um) * 1e-3;
    go.seed = o.seed + 1000;
    const auto gb = sim::simulate_gauge_blocks(m, go);
    io::write_lengths(a.lengths, gb.lengths);
    if (!a.quiet)
      fmt::print("simulated {} gauge-block measurements in ISO 10360-2's 7 positions: wrote {}\n",
                 gb.lengths.size(), a.lengths);
  }
  if (!a.quiet)
    fmt::print(
        "simulated {} placements of {} ({} points per ball, noise {} "
        "µm): wrote {}, {} and {}\n",
        c.placements.size(), what, o.points_per_ball, a.noise_um, a.gauge, a.measurements, a.truth);
  return 0;
}

}  // namespace

std::vector<Command> add_ballgauge_commands(CLI::App& app, CLI::App& simulate) {
  std::vector<Command> out;
  auto ca = std::make_shared<CalArgs>();
  auto* c = app.add_subcommand(
      "ballgauge",
      "CMM error-vector map from ball-gauge placements (Oya et al. 1988): ball centres by sphere "
      "fit, the first placement aligned 3-2-1, later ones stitched to the map by least squares "
      "over shared balls.\nExample: trueaxis ballgauge --gauge gauge.json --measurements "
      "measurements.json --output map.json");
  c->add_option("--gauge", ca->gauge, "gauge JSON (ball_diameter, ball centres in the gauge frame)")
      ->required()
      ->check(cli::existing_file());
  c->add_option("--measurements", ca->measurements,
                "measurements JSON (placements: alignment, tip_radius, probed points per ball)")
      ->required()
      ->check(cli::existing_file());
  c->add_option("--output,-o", ca->output, "map JSON to write")->required();
  c->add_option("--match-tolerance", ca->o.match_tolerance,
                "mm: a ball is shared with the map when its centre is this close to a mapped one")
      ->capture_default_str();
  c->add_option("--min-points", ca->o.min_points, "fewest probed points accepted per ball")
      ->capture_default_str();
  c->add_option("--plane-band", ca->o.plane_band,
                "mm: a plate's map (all balls in one plane) is used this far either side of its "
                "plane")
      ->check(positive_number())
      ->capture_default_str();
  c->add_option("--outlier-tolerance", ca->o.outlier_tolerance,
                "mm: a probed point this far off the sphere through the ball's other points "
                "(which fit within it) is a wrong touch, and refused")
      ->capture_default_str();
  c->add_flag("--drop-outliers", ca->o.drop_outliers,
              "leave wrong touches out (each one named on stderr) instead of refusing the file");
  c->add_option("--report", ca->report, "HTML report to write (error-vector field)");
  add_meta_option(c);
  auto* par = c->add_option("--parametric", ca->parametric,
                            "also identify the 21 rigid-body errors (polynomials per axis) and "
                            "write them as a machine JSON with their covariance");
  c->add_option("--stylus-offset", ca->stylus,
                "stylus tip offset from the ram's reference point x,y,z (mm), as in machine.json")
      ->delimiter(',')
      ->expected(3)
      ->needs(par);
  par->needs("--stylus-offset");
  c->add_option("--degree", ca->po.degree, "polynomial degree of each error function")
      ->capture_default_str();
  c->add_option("--chain", ca->po.chain, "kinematic chain, workpiece to tool (FYXZ: bridge CMM)")
      ->capture_default_str();
  c->add_flag("--quiet,-q", ca->quiet, "print nothing on success");
  out.push_back({c, [ca] { return run_calibrate(*ca); }});

  auto cr = std::make_shared<CorrectArgs>();
  c = app.add_subcommand(
      "correct",
      "Correct measured points with an error map: X = x - error(x), trilinear.\npoints.csv: "
      "columns x,y,z (mm).\nExample: trueaxis correct --map map.json --input points.csv --output "
      "corrected.csv");
  c->add_option("--map", cr->map, "map JSON with a grid ('trueaxis ballgauge' or 'space')")
      ->required()
      ->check(cli::existing_file());
  c->add_option("--input,-i", cr->input, "points CSV (x,y,z in mm)")
      ->required()
      ->check(cli::existing_file());
  c->add_option("--output,-o", cr->output, "corrected CSV ('-': standard output)")->required();
  c->add_flag("--clamp", cr->clamp,
              "hold the edge value for points outside the grid (default: refuse them)");
  c->add_flag("--quiet,-q", cr->quiet, "print nothing on success");
  out.push_back({c, [cr] { return run_correct(*cr); }});

  auto va = std::make_shared<VerifyArgs>();
  c = app.add_subcommand(
      "verify-lengths",
      "Gauge-block check of a correction (ISO 10360-2 positions, as in Oya et al. 1988): length "
      "errors before and after correction, range and RMS, and the level the repeatability "
      "predicts.\nlengths.csv: columns x1,y1,z1,x2,y2,z2 (measured end points, mm), nominal "
      "(mm).\nExample: trueaxis verify-lengths --map map.json --input lengths.csv --output "
      "verify.json --report verify.html");
  c->add_option("--map", va->map, "map JSON with a grid ('trueaxis ballgauge')")
      ->check(cli::existing_file());
  c->add_option("--model", va->model,
                "parametric model JSON ('trueaxis ballgauge --parametric'); with --map, both "
                "are compared")
      ->check(cli::existing_file());
  c->add_option("--input,-i", va->input, "lengths CSV")->required()->check(cli::existing_file());
  c->add_option("--output,-o", va->output, "verification JSON to write")->required();
  c->add_option("--report", va->report,
                "HTML report to write (length errors against nominal length)");
  add_meta_option(c);
  c->add_option("--mpe", va->mpe,
                "E0 check against a maximum permissible error A+L/K (µm, L in mm; e.g. "
                "\"1.5+L/300\", or \"1.5+L/300,4\" capped at 4 µm): PASS/FAIL and the envelope in "
                "the report")
      ->check(mpe_text());
  c->add_option("--repeat-tolerance", va->o.repeat_tolerance,
                "mm: rows with the same nominal and both ends this close are repeats")
      ->capture_default_str();
  c->add_flag("--clamp", va->clamp, "hold the grid's edge value outside it (default: refuse)");
  c->add_flag("--quiet,-q", va->quiet, "print nothing on success");
  out.push_back({c, [va] { return run_verify(*va); }});

  auto sa = std::make_shared<SimArgs>();
  c = simulate.add_subcommand(
      "ballgauge",
      "A ball gauge probed on a virtual CMM: a 5 x 4 x 2 frame at 80 mm pitch, stacked in "
      "sections (Oya et al.'s layout), each ball probed at points spread over its upper "
      "hemisphere.\nExample: trueaxis simulate ballgauge --machine machine.json --noise 0.5");
  sa->machine.add_options(c);
  auto* sections =
      c->add_option("--sections", sa->sections, "placements stacked in z")->capture_default_str();
  auto* plate = c->add_option(
      "--plate", sa->plate,
      "a ball plate of ROWSxCOLUMNS balls instead of the frame (e.g. 5x5), measured in the "
      "campaign that identifies the 21 errors: flat near the bottom and near the top of the "
      "volume, upright along X and along Y, each placement aligned by itself");
  plate->check([](const std::string& t) {
    sim::BallGaugeSetup probe;
    return sim::parse_plate(t, probe)
               ? std::string()
               : fmt::format("--plate {}: give ROWSxCOLUMNS, e.g. 5x5 (2 to 100 each)", t);
  });
  c->add_option("--pitch", sa->pitch, "ball plate pitch, mm")
      ->needs(plate)
      ->check(positive_number())
      ->capture_default_str();
  plate->excludes(sections);
  c->add_option("--alignment", sa->alignment,
                "the first placement's alignment: 321 (3-2-1 on balls 0, 1, 2) or ls (least "
                "squares over all its balls)")
      ->check(CLI::IsMember({"321", "ls"}))
      ->capture_default_str();
  c->add_option("--origin", sa->origin, "true position of ball 0 in the first placement x,y,z (mm)")
      ->delimiter(',')
      ->capture_default_str();
  c->add_option("--misalignment", sa->misalignment_urad, "gauge rotation against the axes, µrad")
      ->capture_default_str();
  c->add_option("--points", sa->o.points_per_ball, "probed points per ball")->capture_default_str();
  sa->tip_radius_given =
      c->add_option("--tip-radius", sa->o.tip_radius,
                    "stylus tip radius, mm (with --cmm: the server's unless given here, which a "
                    "server before I++ DME 1.4.2 needs)")
          ->capture_default_str();
  c->add_option("--noise", sa->noise_um, "probing noise per coordinate, µm")->capture_default_str();
  c->add_option("--seed", sa->o.seed, "seed of the noise")->capture_default_str();
  c->add_option("--gauge", sa->gauge, "gauge JSON to write")->capture_default_str();
  c->add_option("--output,-o,--measurements", sa->measurements, "measurements JSON to write")
      ->capture_default_str();
  c->add_option("--truth", sa->truth, "truth CSV to write (true centres, machine error)")
      ->capture_default_str();
  c->add_option("--lengths", sa->lengths,
                "also write gauge-block measurements (7 positions in the mapped box) to this CSV");
  c->add_option("--repeats", sa->repeats, "repeats of every gauge-block length")
      ->capture_default_str();
  c->add_option("--length-noise", sa->length_noise_um,
                "probing noise of the gauge-block measurements, µm (default: --noise)");
  c->add_option("--balls", sa->balls,
                "also write where the gauge's balls stand over all its placements (true "
                "centres, diameter) to this CSV, for trueaxis serve --balls");
  c->add_option("--cmm", sa->cmm,
                "measure the gauge on a CMM over I++ DME instead (ipp://HOST:PORT, e.g. trueaxis "
                "serve --machine machine.json --balls balls.csv): PtMeas on each ball where the "
                "placements put it, with the CMM's probe and its noise")
      ->excludes("--noise")
      ->excludes("--seed")
      ->excludes("--lengths");
  c->add_flag("--quiet,-q", sa->quiet, "print nothing on success");
  out.push_back({c, [sa] { return run_simulate(*sa); }});
  return out;
}

}  // namespace trueaxis::cli
