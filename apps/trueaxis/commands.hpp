// trueaxis CLI — shared declarations between the command files.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace CLI {
class App;
class ParseError;
class Validator;
}  // namespace CLI

namespace trueaxis::sim {
struct Machine;
}
namespace trueaxis::map {
struct ErrorMap;
}
#include <Eigen/Core>
#include <utility>

#include "trueaxis/report/html.hpp"

namespace trueaxis::cli {

// The virtual machine of a simulation: --machine FILE, or a random one from --machine-seed.
struct MachineSource {
  std::string path;
  std::uint64_t seed = 1;
  void add_options(CLI::App* command);
  sim::Machine load() const;
};

struct DemoOptions {
  std::string output = "demo-report/index.html";
  unsigned long seed = 7;
  long stations = 250;
  double spacing = 50;   // mm, grid of the error space
  int repetitions = 10;  // Monte Carlo repetitions for the space's uncertainty
  bool quiet = false;
};

// A registered subcommand and what to run when it was chosen.
struct Command {
  CLI::App* app;
  std::function<int()> run;
};

// --meta key=value (repeatable) on a command that writes a report: what the report is about
// (machine, instrument, operator, temperature, ...), shown in its header.
void add_meta_option(CLI::App* command);
// The pairs given, in order.
std::vector<std::pair<std::string, std::string>> report_meta();

// The section of a report made from `path`: `section` with the file's name as its source.
report::Section from_file(report::Section section, const std::string& path);

// Refuses the first point outside the map at its place in the input CSV (file:line:col, the
// point counted from 1), naming --clamp. Used before correcting or compensating.
void refuse_outside(const map::ErrorMap& map, const Eigen::Matrix3Xd& points,
                    const std::string& input, double tolerance = 1e-9);

// "ipp://HOST:PORT" (an I++ DME server) as host and port; throws CLI::ValidationError (exit 2)
// naming the expected form.
std::pair<std::string, unsigned short> parse_ipp_address(const std::string& address);

// Accepts a positive finite number; otherwise "must be a positive number, not '-1'" (CLI11's own
// PositiveNumber names a range up to 1.8e308).
CLI::Validator positive_number();

// Accepts an MPE as ballgauge::Mpe::parse reads it ("A", "A+L/K", "A+L/K,B"); otherwise its
// message (exit 2).
CLI::Validator mpe_text();

// The default truth file of a simulation: the output's name with "-truth.csv" (probes.csv ->
// probes-truth.csv), so that simulations never overwrite each other's truth.
std::string truth_beside(const std::string& output);

// 'simulate machine', 'simulate line' (under `simulate`) and 'machine error' (under `app`).
std::vector<Command> add_machine_commands(CLI::App& app, CLI::App& simulate);
// 'space', 'compensate', 'export linuxcnc', 'export csv'.
std::vector<Command> add_space_commands(CLI::App& app);

// 'guideway' and 'simulate guideway5d' (under `simulate`).
std::vector<Command> add_guideway_commands(CLI::App& app, CLI::App& simulate);

// 'fit line|plane|circle|sphere|cylinder|cone'.
std::vector<Command> add_fit_commands(CLI::App& app);

// 'ballgauge', 'correct' and 'simulate ballgauge' (under `simulate`).
std::vector<Command> add_ballgauge_commands(CLI::App& app, CLI::App& simulate);

// 'design' (STEP sections or design.json -> design.json and scanning paths) and 'simulate part'.
std::vector<Command> add_design_commands(CLI::App& app, CLI::App& simulate);

// 'scan' (error-tolerant design-value scanning on the virtual CMM).
std::vector<Command> add_scan_commands(CLI::App& app);

// 'positioning' (ISO 230-2 / VDI 3441) and 'simulate positioning' (under `simulate`).
std::vector<Command> add_positioning_commands(CLI::App& app, CLI::App& simulate);

// 'circular' (ISO 230-4, a ballbar) and 'simulate circular' (under `simulate`).
std::vector<Command> add_circular_commands(CLI::App& app, CLI::App& simulate);

// ipp check (ipp_cmds.cpp).
std::vector<Command> add_ipp_commands(CLI::App& app);
// The demo's CMM acceptance scenario (demo_acceptance.cpp): writes acceptance.json, e0-before.json,
// e0.json and probing.json into `dir`; returns its report section.
report::Section demo_acceptance(const sim::Machine& machine, const std::string& dir,
                                std::uint64_t seed,
                                const std::function<void(const std::string&)>& say);
// The demo's records scenario (demo_records.cpp): three visits over two years in records.db,
// the backlash trend (its report section) and certificate.html of the last visit.
report::Section demo_records(const sim::Machine& machine, const std::string& dir,
                             std::uint64_t seed,
                             const std::function<void(const std::string&)>& say);
// --correction's file: a ball-gauge grid map (map.json, held at its edges) or an identified
// model (model.json, points outside its span left as read), as a CMM controller applies it to
// every point it reads (ipp_cmds.cpp).
std::function<Eigen::Vector3d(const Eigen::Vector3d&)> load_correction(const std::string& path);
// --stylus-offset's values (mm): L alone (along +X) or X,Y,Z, the stylus tip's offset across
// the ram of ISO 10360-2's E_L test. Throws CLI::ValidationError naming the flag.
Eigen::Vector3d stylus_offset_of(const std::vector<double>& values);
// Adds --stylus-offset (1 or 3 numbers, comma-separated) to `command`, with `help`.
void add_stylus_offset_option(CLI::App* command, std::vector<double>& values,
                              const std::string& help);
// 'acceptance e0', 'acceptance probing'.
std::vector<Command> add_acceptance_commands(CLI::App& app);
std::vector<Command> add_serve_command(CLI::App& app);
// 'record add|machines|list|show|export' (record_cmds.cpp).
std::vector<Command> add_record_commands(CLI::App& app);
// 'certificate' (certificate_cmds.cpp).
std::vector<Command> add_certificate_command(CLI::App& app);

// The grammar every command shares (grammar.cpp). apply_grammar: once every command is added,
// the help lists commands one per line with their purpose, and every command takes --version.
void apply_grammar(CLI::App& app, const std::string& version);
// What `trueaxis` alone and `trueaxis help` print: every command on one line with its purpose.
std::string command_list(const CLI::App& app);
// After a failed parse: "did you mean --sigma?" for a word the command line had that nothing
// took, near a flag or command of the command being run ("" when none is near).
std::string suggestion(const CLI::App& app, const CLI::ParseError& e);
// Input files and directories: checked as the command line is read, reported after it (so a
// missing input is an error like every other, exit 1, not a usage mistake): missing_input() is
// the first problem met ("design.json: no such file"), or "".
CLI::Validator existing_file();
CLI::Validator existing_directory();
// --axis everywhere: a machine axis, x, y or z (X, Y, Z taken as the same); the controller's own
// name for an axis is --axis-name.
CLI::Validator machine_axis();
std::string missing_input();

// Runs every demo scenario and writes the HTML report. Returns the process exit code.
int run_demo(const DemoOptions& options);

}  // namespace trueaxis::cli
