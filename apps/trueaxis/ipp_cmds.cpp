// trueaxis CLI — I++ DME tools: 'ipp check' (validate program and session-log lines).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <fstream>
#include <iterator>
#include <memory>

#include "commands.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/ippdme/commands.hpp"
#include "trueaxis/ippdme/protocol.hpp"

namespace trueaxis::cli {
namespace {

struct IppCheckArgs {
  std::vector<std::string> files;
  bool quiet = false;
};

// A line is a response when its seventh character is a response kind (`00012 &`); else a
// command. NIST's test files put a "\\" line after each line and ":" lines at the end: skipped.
int run_ipp_check(const IppCheckArgs& a) {
  long lines = 0, commands = 0, responses = 0, bad = 0;
  for (const auto& path : a.files) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(path + ": cannot open the file");
    const std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    long number = 0;
    for (std::size_t at = 0; at < all.size();) {
      // On the wire lines end in CR LF; in a file LF alone will do.
      std::size_t end = all.find('\n', at);
      if (end == std::string::npos) end = all.size();
      std::string line = all.substr(at, end - at);
      if (!line.empty() && line.back() == '\r') line.pop_back();
      at = end + 1;
      ++number;
      if (line.empty() || line == "\\\\" || line[0] == ':') continue;
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
      ->check(CLI::ExistingFile);
  c->add_flag("--quiet,-q", a->quiet, "print only the bad lines");
  return {{c, [a] { return run_ipp_check(*a); }}};
}

}  // namespace trueaxis::cli
