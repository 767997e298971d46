// trueaxis CLI — the grammar every command shares: the command list (`trueaxis`, `trueaxis help`,
// `--help`), `--version` on every command, "did you mean" for a mistyped command or flag, and
// input files checked once the command line is read, so that a missing file is an error like
// every other ("trueaxis: error: …", exit 1) and not a usage mistake.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "commands.hpp"

namespace trueaxis::cli {
namespace {

// The inputs that were named but are missing, in the order met (filled while parsing).
std::vector<std::string>& missing_inputs() {
  static std::vector<std::string> m;
  return m;
}

// Each command's purpose in a line of a command list (its --help says the rest), by its path
// ("simulate part").
const std::map<std::string, std::string>& purposes() {
  static const std::map<std::string, std::string> p = {
      {"separate", "straightness of a workpiece and its guide from displacement probes"},
      {"surface", "flatness map of a surface plate from crossing straightness lines"},
      {"simulate", "data from a virtual machine, with the truth"},
      {"simulate straightness", "a carriage with probes over a workpiece"},
      {"simulate machine", "a machine with the 21 geometric errors (machine.json)"},
      {"simulate line", "a displacement-probe run along a line of a machine"},
      {"simulate guideway5d", "laser spots on the detectors of a guideway carriage"},
      {"simulate positioning", "laser positioning runs of an axis"},
      {"simulate ballgauge", "ball-gauge placements measured on a CMM with errors"},
      {"simulate part", "a part off its design, for scanning"},
      {"simulate circular", "a ballbar's circular test of two axes (ISO 230-4)"},
      {"machine", "query a machine description"},
      {"machine error", "the 21 error functions and the volumetric error at points"},
      {"space", "the volumetric error space of a machine from straightness and laser runs"},
      {"compensate", "commanded positions corrected with an error space"},
      {"export", "compensation tables for controllers, or an error space as CSV"},
      {"export linuxcnc", "LinuxCNC pitch-compensation table of a joint"},
      {"export sinumerik", "Sinumerik leadscrew-error compensation (part program)"},
      {"export heidenhain", "HEIDENHAIN nonlinear axis-error table (*.COM)"},
      {"export fanuc", "FANUC pitch-error compensation parameters"},
      {"export csv", "an error space on a grid as CSV"},
      {"guideway", "five motion errors of a guideway from laser spots on quadrant detectors"},
      {"positioning", "positioning accuracy of an axis by ISO 230-2 or VDI/DGQ 3441"},
      {"circular", "circular test of two axes with a ballbar (ISO 230-4), with its causes"},
      {"fit", "least-squares fit of a geometric element to points (ISO 10360-6)"},
      {"fit line", "a line through points"},
      {"fit plane", "a plane through points"},
      {"fit circle", "a circle through points"},
      {"fit sphere", "a sphere through points"},
      {"fit cylinder", "a cylinder through points"},
      {"fit cone", "a cone through points"},
      {"ballgauge", "CMM error map (and parametric model) from ball-gauge placements"},
      {"correct", "measured points corrected with an error map"},
      {"verify-lengths", "gauge-block check of a correction (ISO 10360-2 positions)"},
      {"design", "design data for scanning: sections of a STEP part and scanning paths"},
      {"scan", "error-tolerant scanning of a part along its design data"},
      {"serve", "the virtual CMM as an I++ DME server"},
      {"ipp", "I++ DME tools for CMM programs and servers"},
      {"ipp check", "check I++ DME programs, responses and logs against the specification"},
      {"ipp run", "run an I++ DME program on a server, compare with a recording"},
      {"acceptance", "CMM acceptance tests: E0, R0 (ISO 10360-2), PForm, PSize (ISO 10360-5)"},
      {"acceptance e0", "length measuring error E0 (or E150) and repeatability R0"},
      {"acceptance probing", "probing form and size errors on the reference sphere"},
      {"acceptance setup", "an artefact set-up that fits a machine's travel (or an offset stylus)"},
      {"record", "machine records: results with dates, states and figures (SQLite or PostgreSQL)"},
      {"record add", "store result files with their machine, date, state and instrument"},
      {"record machines", "the machines and their records' dates"},
      {"record list", "the records, one a line, with their headline figures"},
      {"record show", "one record in full, and the stored file"},
      {"record export", "the records as JSON or CSV"},
      {"record trend", "a figure's drift per year and the date it reaches its tolerance"},
      {"record due", "when each machine is next due, from its last visit and its trends"},
      {"record report", "every figure of one machine over time, with its drift, in HTML"},
      {"certificate", "a calibration certificate of one visit (HTML, PDF), from the records"},
      {"report", "an HTML report of any result file"},
      {"demo", "every capability on a virtual machine, with a report"},
      {"examples", "write the example inputs the README uses"},
      {"help", "the list of commands, or the help of one"},
  };
  return p;
}

// "simulate part" for the command `part` under `simulate`.
std::string path_of(const CLI::App& command) {
  std::string path = command.get_name();
  for (const CLI::App* a = command.get_parent(); a != nullptr && a->get_parent() != nullptr;
       a = a->get_parent())
    path = a->get_name() + " " + path;
  return path;
}

// A command's purpose on one line: from the table, else its description's first line.
std::string purpose(const CLI::App& command) {
  if (const auto it = purposes().find(path_of(command)); it != purposes().end()) return it->second;
  const std::string& d = command.get_description();
  return d.substr(0, d.find('\n'));
}

std::vector<const CLI::App*> subcommands_of(const CLI::App& app) {
  return app.get_subcommands([](const CLI::App*) { return true; });
}

// Levenshtein distance, for suggestions.
std::size_t edits(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diag = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

// The candidate nearest `word`, if near enough to be a slip (a third of its letters, at least 2).
std::string nearest(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t least = std::max<std::size_t>(2, word.size() / 3) + 1;
  for (const auto& c : candidates)
    if (const std::size_t d = edits(word, c); d < least) least = d, best = c;
  // A prefix of exactly one candidate ("--sig" for "--sigma") is a slip too.
  if (best.empty() && word.size() >= 3) {
    std::vector<std::string> starts;
    for (const auto& c : candidates)
      if (c.rfind(word, 0) == 0) starts.push_back(c);
    if (starts.size() == 1) best = starts.front();
  }
  return best;
}

// The command being run: the deepest subcommand the command line chose.
const CLI::App* chosen(const CLI::App& app) {
  for (const CLI::App* sub : subcommands_of(app))
    if (sub->parsed()) return chosen(*sub);
  return &app;
}

class Formatter : public CLI::Formatter {
 public:
  // A command in a list: its name and its purpose on one line (sub-commands named after it).
  std::string make_subcommand(const CLI::App* sub) const override {
    std::string out = fmt::format("  {:<17} {}\n", sub->get_name(), purpose(*sub));
    const auto subs = subcommands_of(*sub);
    if (!subs.empty()) {
      std::vector<std::string> names;
      for (const CLI::App* s : subs) names.push_back(s->get_name());
      out += fmt::format("  {:<17} {}\n", "", fmt::join(names, ", "));
    }
    return out;
  }
};

}  // namespace

void apply_grammar(CLI::App& app, const std::string& version) {
  app.formatter(std::make_shared<Formatter>());
  std::vector<CLI::App*> todo{&app};
  while (!todo.empty()) {
    CLI::App* a = todo.back();
    todo.pop_back();
    a->formatter(app.get_formatter());
    if (a != &app) a->set_version_flag("--version", version);
    for (CLI::App* s : a->get_subcommands([](const CLI::App*) { return true; })) todo.push_back(s);
  }
}

std::string command_list(const CLI::App& app) {
  std::string out = app.get_description() + "\n\nCommands:\n";
  for (const CLI::App* sub : subcommands_of(app)) out += Formatter().make_subcommand(sub);
  out +=
      "\n'trueaxis help COMMAND' (or 'trueaxis COMMAND --help') explains a command and its "
      "options.\n";
  return out;
}

std::string suggestion(const CLI::App& app, const CLI::ParseError& e) {
  const CLI::App* here = chosen(app);
  // The words the command line had that nothing took.
  std::vector<std::string> words;
  for (const CLI::App* a = here; a != nullptr; a = a->get_parent())
    for (const std::string& w : a->remaining()) words.push_back(w);
  if (words.empty() && dynamic_cast<const CLI::RequiredError*>(&e) == nullptr) return {};
  std::vector<std::string> flags, commands;
  for (const CLI::Option* o : here->get_options())
    for (const std::string& n : o->get_lnames()) flags.push_back("--" + n);
  for (const CLI::App* s : subcommands_of(*here)) commands.push_back(s->get_name());
  for (const std::string& w : words) {
    const bool flag = w.rfind("--", 0) == 0;
    const std::string name = flag ? w.substr(0, w.find('=')) : w;
    const std::string where = here == &app ? "trueaxis" : "'" + path_of(*here) + "'";
    if (const std::string n = nearest(name, flag ? flags : commands); !n.empty())
      return fmt::format("{} is not {} of {}; did you mean {}?", name,
                         flag ? "an option" : "a command", where, n);
    if (!flag && !commands.empty())
      return fmt::format("{} is not a command of {}; run 'trueaxis help{}' for the list", w, where,
                         here == &app ? "" : " " + path_of(*here));
  }
  return {};
}

CLI::Validator machine_axis() {
  return CLI::Validator(
      [](std::string& text) {
        if (text == "X" || text == "Y" || text == "Z") text = std::string(1, text[0] - 'X' + 'x');
        if (text == "x" || text == "y" || text == "z") return std::string();
        return fmt::format(
            "'{}' is not a machine axis: give x, y or z (a controller's own name for the axis, "
            "such as X1, goes in --axis-name where a table needs it)",
            text);
      },
      "x|y|z");
}

CLI::Validator existing_file() {
  return CLI::Validator(
      [](std::string& path) -> std::string {
        namespace fs = std::filesystem;
        std::error_code ec;
        if (fs::is_directory(path, ec))
          missing_inputs().push_back(fmt::format("{}: is a directory, not a file", path));
        else if (!fs::exists(path, ec))
          missing_inputs().push_back(fmt::format("{}: no such file", path));
        return {};
      },
      "FILE");
}

CLI::Validator existing_directory() {
  return CLI::Validator(
      [](std::string& path) -> std::string {
        namespace fs = std::filesystem;
        std::error_code ec;
        if (!fs::exists(path, ec))
          missing_inputs().push_back(fmt::format("{}: no such directory", path));
        else if (!fs::is_directory(path, ec))
          missing_inputs().push_back(fmt::format("{}: is a file, not a directory", path));
        return {};
      },
      "DIR");
}

report::Section from_file(report::Section section, const std::string& path) {
  std::string p = path;
  while (p.size() > 1 && p.back() == '/') p.pop_back();  // a directory: its own name ("plate")
  section.source = std::filesystem::path(p).filename().string();
  return section;
}

std::string missing_input() {
  return missing_inputs().empty() ? std::string() : missing_inputs().front();
}

}  // namespace trueaxis::cli
