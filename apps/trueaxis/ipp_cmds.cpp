// trueaxis CLI — I++ DME: 'serve' (the virtual CMM as an I++ DME server), 'ipp run' (run a
// program against a server, compare with a recording) and 'ipp check' (validate lines).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <fstream>
#include <iterator>
#include <memory>
#include <thread>

#include "commands.hpp"
#include "trueaxis/acceptance/acceptance.hpp"
#include "trueaxis/ballgauge/lengths.hpp"
#include "trueaxis/ballgauge/parametric.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/acceptance/acceptance.hpp"
#include "trueaxis/io/ballgauge/ballgauge.hpp"
#include "trueaxis/io/design/design.hpp"
#include "trueaxis/io/json.hpp"
#include "trueaxis/io/sim/machine.hpp"
#include "trueaxis/io/surface/space.hpp"
#include "trueaxis/ippdme/client.hpp"
#include "trueaxis/ippdme/commands.hpp"
#include "trueaxis/ippdme/protocol.hpp"
#include "trueaxis/ippdme/recording.hpp"
#include "trueaxis/ippdme/server.hpp"
#include "trueaxis/scan/machine.hpp"

namespace trueaxis::cli {
namespace {

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open the file");
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

struct IppCheckArgs {
  std::vector<std::string> files;
  bool quiet = false;
};

// A line is a response when its seventh character is a response kind (`00012 &`); else a
// command. NIST's test files put a "\\" line after each line and ":" lines at the end: skipped.
int run_ipp_check(const IppCheckArgs& a) {
  long lines = 0, commands = 0, responses = 0, bad = 0;
  for (const auto& path : a.files) {
    std::vector<long> numbers;
    const auto file = ippdme::recorded_lines(slurp(path), &numbers);
    for (std::size_t k = 0; k < file.size(); ++k) {
      const std::string& line = file[k];
      const long number = numbers[k];
      ++lines;
      std::optional<ippdme::SyntaxError> e;
      const bool response =
          line.size() > 6 && std::string_view("&%#!").find(line[6]) != std::string_view::npos;
      if (response) {
        ++responses;
        const auto r = ippdme::parse_response(line);
        e = r ? ippdme::check(*r.value) : std::optional(r.error);
      } else {
        ++commands;
        const auto c = ippdme::parse_command(line);
        e = c ? ippdme::check(*c.value) : std::optional(c.error);
      }
      if (e) {
        ++bad;
        fmt::print("{}:{}:{}: error {:04d}: {}\n", path, number, e->column, e->error, e->what);
      }
    }
  }
  if (!a.quiet || bad)
    fmt::print("{} lines checked ({} commands, {} responses): {}\n", lines, commands, responses,
               bad ? fmt::format("{} with errors", bad) : std::string("all valid I++ DME"));
  return bad ? 1 : 0;
}

}  // namespace

std::pair<std::string, unsigned short> parse_ipp_address(const std::string& address) {
  try {
    return ippdme::parse_address(address);
  } catch (const Error& e) {
    throw CLI::ValidationError(e.what());
  }
}

// A controller's error correction from a ball-gauge grid map (held at its edges beyond them, as a
// controller holds its table's last values) or an identified model (outside its span, points
// are left as read).
std::function<Eigen::Vector3d(const Eigen::Vector3d&)> load_correction(const std::string& path) {
  const auto kind = io::JsonFile::read(path).root().value("kind", std::string());
  if (kind == "parametric model") {
    auto c = std::make_shared<ballgauge::Correction>(
        ballgauge::parametric_correction(io::read_parametric(path)));
    return [c](const Eigen::Vector3d& x) {
      try {
        return c->corrected(x);
      } catch (const Error&) {
        return x;
      }
    };
  }
  auto grid = std::make_shared<map::ErrorMap>(io::read_error_map(path));
  map::EvalOptions eo;
  eo.outside = map::Outside::Clamp;
  auto c = std::make_shared<ballgauge::Correction>(ballgauge::grid_correction(*grid, eo));
  return [c, grid](const Eigen::Vector3d& x) { return c->corrected(x); };
}

namespace {

struct ServeArgs {
  std::string host = "127.0.0.1", machine, part, log, balls, artefacts, correction;
  double lobing_um = 0;
  std::vector<double> stylus_offset;
  int port = 1294;
  std::vector<double> part_origin;
  double time_scale = 1, tip_radius = 1, probe_noise_um = 0;
  std::string dme_version = "1.4.3";
  std::uint64_t seed = 1;
  long sessions = 0;
  bool quiet = false;
};

std::atomic<bool> g_interrupted{false};

int run_serve(const ServeArgs& a) {
  ippdme::ServerOptions o;
  o.host = a.host;
  o.port = static_cast<unsigned short>(a.port);
  o.log = a.log;
  auto& e = o.engine;
  e.time_scale = a.time_scale;
  e.version = a.dme_version;
  e.cmm.probe.tip_radius = a.tip_radius;
  e.cmm.probe.noise = a.probe_noise_um * 1e-3;
  e.cmm.probe.seed = a.seed;
  if (!a.machine.empty()) {
    e.cmm.geometry = io::read_machine(a.machine);
    // An offset stylus (ISO 10360-2's E_L): the tip, and so the travel, moves with it.
    if (!a.stylus_offset.empty())
      e.cmm.geometry = acceptance::with_stylus(*e.cmm.geometry, stylus_offset_of(a.stylus_offset));
    const auto& g = *e.cmm.geometry;
    // Home: the back left top corner of the travel (tool point, machine coordinates).
    e.cmm.home = Eigen::Vector3d(g.range[0][0], g.range[1][1], g.range[2][1]) + g.offset;
  }
  if (!a.stylus_offset.empty() && !e.cmm.geometry)
    throw CLI::ValidationError("--stylus-offset",
                               "needs --machine: the offset is added to the machine's stylus");
  if (!a.part.empty()) {
    e.part = io::read_part(a.part);
    // Home above the part: the top of the travel.
    if (!e.cmm.geometry) e.cmm.home = Eigen::Vector3d(0, 0, e.cmm.travel[2][1]);
    if (!a.part_origin.empty()) {
      e.part_origin = Eigen::Vector3d(a.part_origin[0], a.part_origin[1], a.part_origin[2]);
    } else if (e.cmm.geometry) {
      // Where `trueaxis scan --machine` puts it: centred in the travel.
      scan::VirtualCmmOptions vo;
      vo.geometry = e.cmm.geometry;
      e.part_origin = scan::VirtualCmm(*e.part, vo).part_origin();
    }
  }
  if (!a.balls.empty()) {
    e.balls = io::read_balls(a.balls);
    // Home above the balls when no machine says where (with one, its top corner).
    if (!e.cmm.geometry) e.cmm.home = Eigen::Vector3d(0, 0, e.cmm.travel[2][1]);
  }
  bool sphere = false;
  if (!a.artefacts.empty()) {
    const auto setup = io::read_acceptance_setup(a.artefacts);
    e.boxes = acceptance::artefact_boxes(setup);
    if (setup.sphere) e.balls.push_back({setup.sphere->centre, setup.sphere->diameter / 2});
    sphere = setup.sphere.has_value();
  }
  e.cmm.probe.lobing = a.lobing_um * 1e-3;
  std::string corrected;
  if (!a.correction.empty()) {
    e.correction = load_correction(a.correction);
    corrected = fmt::format(", corrected by {}", a.correction);
  }
  ippdme::Server server(o);
  std::string world = e.part ? fmt::format("the part of {}", a.part) : std::string();
  if (!e.boxes.empty())
    world += fmt::format("{}{} gauge blocks{} of {} (a position at a time)",
                         world.empty() ? "" : " and ", e.boxes.size(),
                         sphere ? " and the reference sphere" : "", a.artefacts);
  if (!a.balls.empty())
    world += fmt::format("{}{} balls of {}", world.empty() ? "" : " and ", e.balls.size(), a.balls);
  fmt::print("trueaxis serve: I++ DME 1.4.3 on {}:{}, {}{}{}; Ctrl-C stops\n", a.host,
             server.port(), world.empty() ? std::string("the nominal world") : world,
             e.cmm.geometry ? fmt::format(" on the machine of {}", a.machine) : std::string(),
             corrected);
  if (e.part)
    fmt::print(
        "the part's design origin is at ({:.3f}, {:.3f}, {:.3f}) mm in machine "
        "coordinates (trueaxis scan --cmm ... --part-origin {:.3f},{:.3f},{:.3f})\n",
        e.part_origin.x(), e.part_origin.y(), e.part_origin.z(), e.part_origin.x(),
        e.part_origin.y(), e.part_origin.z());
  std::fflush(stdout);
  std::signal(SIGINT, [](int) { g_interrupted = true; });
  std::signal(SIGTERM, [](int) { g_interrupted = true; });
  std::atomic<bool> done{false};
  std::thread watch([&] {
    while (!done) {
      if (g_interrupted ||
          (a.sessions > 0 && static_cast<long>(server.sessions_served()) >= a.sessions &&
           !server.session_active()))
        server.stop();
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  });
  server.run();
  done = true;
  watch.join();
  if (!a.quiet)
    fmt::print("trueaxis serve: stopped after {} session(s)\n", server.sessions_served());
  return 0;
}

struct RunArgs {
  std::string program, host = "127.0.0.1", log, expect;
  int port = 1294;
  double timeout = 120;
  bool quiet = false;
};

int run_ipp_run(const RunArgs& a) {
  std::vector<long> numbers;
  const auto program = ippdme::recorded_lines(slurp(a.program), &numbers);
  std::vector<std::string> expected;
  if (!a.expect.empty()) expected = ippdme::recorded_lines(slurp(a.expect));
  ippdme::ClientOptions co;
  co.host = a.host;
  co.port = static_cast<unsigned short>(a.port);
  co.timeout = a.timeout;
  co.log = a.log;
  ippdme::Client client(co);
  for (std::size_t i = 0; i < program.size(); ++i) {
    const std::string& line = program[i];
    // A bad line is sent as it is (the server's answer is part of the test), and named here.
    const auto parsed = ippdme::parse_command(line);
    const auto bad = parsed ? ippdme::check(*parsed.value) : std::optional(parsed.error);
    if (bad)
      fmt::print(stderr, "{}:{}:{}: error {:04d}: {} (sent as it is)\n", a.program, numbers[i],
                 bad->column, bad->error, bad->what);
    client.send_line(line);
    // The next command goes when this one completed; an AbortE goes at once, while it runs.
    if (i + 1 < program.size() && program[i + 1].find("AbortE") != std::string::npos) continue;
    if (const auto tag = ippdme::parse_tag(line); tag && !(tag->event && tag->number == 0))
      client.wait(*tag);
  }
  // What came back, in order; then what differs from the recording.
  const auto got = client.received();
  if (!a.quiet)
    for (const auto& l : got) fmt::print("{}\n", l);
  if (a.expect.empty()) return 0;
  const auto d = ippdme::compare_structure(expected, got);
  for (const auto& x : d)
    fmt::print("{}: tag {}: expected [{}], got [{}]\n", a.expect, x.tag, x.expected, x.got);
  fmt::print("{} lines sent, {} received; {}\n", program.size(), got.size(),
             d.empty() ? fmt::format("the structure matches {}", a.expect)
                       : fmt::format("{} tag(s) differ from {}", d.size(), a.expect));
  return d.empty() ? 0 : 1;
}

}  // namespace

std::vector<Command> add_serve_command(CLI::App& app) {
  auto a = std::make_shared<ServeArgs>();
  auto* c = app.add_subcommand(
      "serve",
      "Serve the virtual CMM over I++ DME (VDMA 8722), the protocol CMM software uses to drive "
      "CMM controllers: measuring software or 'trueaxis ipp run' connects over TCP and moves, "
      "probes and scans it. One session at a time. Without --part each probing meets the "
      "surface its command describes (a plane through a PtMeas point, the circle of a "
      "ScanOnCircle); with --part the simulated part's sections, with --balls the balls of a "
      "gauge.\n"
      "Example: trueaxis serve --machine machine.json --part part.json --log session.log");
  c->add_option("--host", a->host, "address to listen on")->capture_default_str();
  c->add_option("--port", a->port, "TCP port (0: any free one, printed)")
      ->capture_default_str()
      ->check(CLI::Range(0, 65535));
  c->add_option("--machine", a->machine,
                "machine.json: the CMM's 21 geometric errors and travel (trueaxis simulate "
                "machine); the measured points carry them")
      ->check(cli::existing_file());
  c->add_option("--part", a->part, "part.json: the simulated part (trueaxis simulate part)")
      ->check(cli::existing_file());
  c->add_option("--balls", a->balls,
                "balls.csv: balls standing in the machine (x,y,z,diameter in mm, machine "
                "coordinates), e.g. a ball gauge (trueaxis simulate ballgauge --balls)")
      ->check(cli::existing_file());
  c->add_option("--artefacts", a->artefacts,
                "acceptance.json: gauge blocks (a position at a time: the one a PtMeas aims at) "
                "and the reference sphere, for 'trueaxis acceptance --cmm'")
      ->check(existing_file());
  c->add_option("--correction", a->correction,
                "map.json (ball-gauge grid map) or model.json (parametric model): corrects every "
                "point reported and every position commanded, as a controller's error map")
      ->check(existing_file());
  c->add_option("--lobing", a->lobing_um,
                "single points: the probe's pre-travel variation (µm, three lobes)")
      ->capture_default_str();
  add_stylus_offset_option(
      c, a->stylus_offset,
      "L or X,Y,Z (mm), with --machine: Probe1 is a stylus offset across the ram by L along +X or "
      "by (X, Y, 0), as for ISO 10360-2's E150 (the carriages' rotations then move the tip by "
      "their angle times the offset)");
  c->add_option("--part-origin", a->part_origin,
                "X,Y,Z: the part's design origin in machine coordinates (mm; default: the "
                "machine origin, or centred in the travel with --machine)")
      ->expected(3)
      ->delimiter(',');
  c->add_option("--time-scale", a->time_scale,
                "wall-clock seconds per machine second: 1 real time, 0 as fast as it computes")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 100.0));
  c->add_option("--tip-radius", a->tip_radius, "stylus tip radius of Probe1 (mm)")
      ->capture_default_str()
      ->check(CLI::Range(0.05, 50.0));
  c->add_option("--dme-version", a->dme_version,
                "the I++ DME version served: 1.4.1 refuses what 1.4.2 added (ScanOnCurve, "
                "Tool.ScanPar, Tool.AvrRadius), to try a client against an older controller")
      ->capture_default_str()
      ->check(CLI::IsMember({"1.4.1", "1.4.2", "1.4.3"}));
  c->add_option("--probe-noise", a->probe_noise_um, "probe noise, standard deviation (µm)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 100.0));
  c->add_option("--seed", a->seed, "random seed of the probe noise")->capture_default_str();
  c->add_option("--log", a->log, "session log: every line received and sent, with the time");
  c->add_option("--sessions", a->sessions, "stop after this many sessions (0: serve until Ctrl-C)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  c->add_flag("--quiet,-q", a->quiet, "print only the listening line");
  return {{c, [a] { return run_serve(*a); }}};
}

std::vector<Command> add_ipp_commands(CLI::App& app) {
  auto* ipp = app.add_subcommand(
      "ipp", "I++ DME (VDMA 8722), the protocol CMM software uses to drive CMM controllers");
  ipp->require_subcommand(1);
  auto a = std::make_shared<IppCheckArgs>();
  auto* c = ipp->add_subcommand(
      "check",
      "Check I++ DME lines (command programs, server responses, session logs) against the "
      "grammar and the commands of the I++ DME 1.4.3 specification. Prints file:line:column, "
      "the specification's error number and the reason for every bad line; exit 1 if any.\n"
      "Example: trueaxis ipp check session.prg session.res");
  c->add_option("files", a->files, "files of lines, one command or response per line (CR LF)")
      ->required()
      ->check(cli::existing_file());
  c->add_flag("--quiet,-q", a->quiet, "print only the bad lines");
  auto r = std::make_shared<RunArgs>();
  auto* run = ipp->add_subcommand(
      "run",
      "Run an I++ DME program (one command per line, as NIST's test programs) against a server "
      "and print every response. With --expect, compare the responses' structure (tags, "
      "kinds, error numbers, numbers of data items; scan data as a whole) with a recorded "
      "file; exit 1 if they differ.\n"
      "Example: trueaxis ipp run PtMeas.prg --port 1294 --expect PtMeas.res");
  run->add_option("program", r->program, "the program: command lines (CR LF or LF)")
      ->required()
      ->check(cli::existing_file());
  run->add_option("--host", r->host, "the server's address")->capture_default_str();
  run->add_option("--port", r->port, "the server's TCP port")
      ->capture_default_str()
      ->check(CLI::Range(1, 65535));
  run->add_option("--expect", r->expect, "a recording (.res) to compare the structure with")
      ->check(cli::existing_file());
  run->add_option("--log", r->log, "session log: every line sent and received, with the time");
  run->add_option("--timeout", r->timeout, "seconds to wait for any one response")
      ->capture_default_str()
      ->check(positive_number());
  run->add_flag("--quiet,-q", r->quiet, "print only the comparison");
  return {{c, [a] { return run_ipp_check(*a); }}, {run, [r] { return run_ipp_run(*r); }}};
}

}  // namespace trueaxis::cli
