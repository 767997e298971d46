// trueaxis CLI — 'certificate': one calibration certificate per visit, from the records, as HTML
// and (printed by headless Chromium) PDF.
#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdlib>
#include <filesystem>
#include <memory>

#include "commands.hpp"
#include "trueaxis/certificate/certificate.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/records/records.hpp"
#include "trueaxis/report/html.hpp"

namespace trueaxis::cli {
namespace {

struct CertificateArgs {
  std::string db, lab, output = "certificate.html", pdf;
  certificate::Options options;
  bool quiet = false;
};

// The first of Chromium's names on the PATH ("" when none is installed).
std::string find_chromium() {
  const char* path = std::getenv("PATH");
  if (path == nullptr) return "";
  for (const char* name :
       {"chromium", "chromium-browser", "google-chrome", "google-chrome-stable"}) {
    std::string dirs = path;
    std::size_t start = 0;
    while (start <= dirs.size()) {
      const std::size_t end = std::min(dirs.find(':', start), dirs.size());
      const std::string candidate = dirs.substr(start, end - start) + "/" + name;
      if (end > start && ::access(candidate.c_str(), X_OK) == 0) return candidate;
      start = end + 1;
    }
  }
  return "";
}

// Prints `html` (a file) to `pdf` with headless Chromium; returns why not ("" when printed).
std::string print_pdf(const std::string& chromium, const std::string& html,
                      const std::string& pdf) {
  const std::string url = "file://" + std::filesystem::absolute(html).string();
  const std::string out = "--print-to-pdf=" + std::filesystem::absolute(pdf).string();
  const std::string profile = "--user-data-dir=" + (std::filesystem::temp_directory_path() /
                                                    fmt::format("trueaxis-chromium-{}", ::getpid()))
                                                       .string();
  const pid_t child = ::fork();
  if (child < 0) return "cannot start Chromium (fork failed)";
  if (child == 0) {
    // Chromium's own chatter is not the user's business: the result is the PDF or our message.
    if (FILE* null = std::fopen("/dev/null", "w")) {
      ::dup2(::fileno(null), 1);
      ::dup2(::fileno(null), 2);
    }
    ::execl(chromium.c_str(), chromium.c_str(), "--headless", "--no-sandbox", "--disable-gpu",
            "--no-pdf-header-footer", "--virtual-time-budget=5000", profile.c_str(), out.c_str(),
            url.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  int status = 0;
  ::waitpid(child, &status, 0);
  std::error_code ec;
  std::filesystem::remove_all(profile.substr(profile.find('=') + 1), ec);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || !std::filesystem::exists(pdf) ||
      std::filesystem::file_size(pdf) == 0)
    return fmt::format("Chromium ({}) did not print it (exit {})", chromium,
                       WIFEXITED(status) ? WEXITSTATUS(status) : -1);
  return "";
}

int run_certificate(CertificateArgs& a) {
  const certificate::Lab lab = a.lab.empty() ? certificate::Lab{} : certificate::read_lab(a.lab);
  const records::Database db(records::database_path(a.db), records::Access::ReadOnly);
  const auto c = certificate::make(db, lab, a.options);
  report::write(a.output, c.html());
  if (!a.quiet) {
    const auto count = certificate::tally(c.lines);
    fmt::print("{}: {} figures ({} conform, {} do not, {} without a decision) -> {}\n", c.title,
               c.lines.size(), count.conform, count.fail, count.undecided, a.output);
    for (const auto& w : c.warnings) fmt::print("  note: {}\n", w);
  }
  if (a.pdf.empty()) return 0;
  const std::string chromium = find_chromium();
  if (chromium.empty()) {
    fmt::print(stderr,
               "trueaxis: no PDF: Chromium is not installed (Debian: apt-get install chromium); "
               "the certificate is in {} and prints from any browser\n",
               a.output);
    return 1;
  }
  if (const std::string why = print_pdf(chromium, a.output, a.pdf); !why.empty()) {
    fmt::print(stderr, "trueaxis: no PDF: {}; the certificate is in {}\n", why, a.output);
    return 1;
  }
  if (!a.quiet) fmt::print("  printed -> {}\n", a.pdf);
  return 0;
}

}  // namespace

std::vector<Command> add_certificate_command(CLI::App& app) {
  auto a = std::make_shared<CertificateArgs>();
  auto* c = app.add_subcommand(
      "certificate",
      "A calibration certificate for one visit, from the machine's records: the tests as found "
      "and as left, each figure with its expanded uncertainty and the decision against its "
      "limit (ISO 14253-1), the instruments and their calibration, the environment, the "
      "compensation, the ISO/TR 230-9 budget of laser tests, and the signature lines.\n"
      "Example: trueaxis certificate --machine VMC-3 --date 2026-11-29 --lab lab.json -o "
      "cert.html --pdf cert.pdf");
  c->add_option("--db", a->db,
                "the records: an SQLite file, or postgresql://[user@]host[:port]/dbname "
                "(default: $TRUEAXIS_DB, else trueaxis-records.db here)");
  c->add_option("--machine", a->options.machine, "the machine's id")->required();
  c->add_option("--date", a->options.date, "the visit's (first) day, ISO 8601")->required();
  c->add_option("--to", a->options.to, "the visit's last day, when it took several (ISO 8601)");
  c->add_option("--issued", a->options.issued, "the certificate's date (default: today)");
  c->add_option("--lab", a->lab,
                "the laboratory's JSON: its name, the customer, the machine's description, the "
                "instruments and their calibration, limits, decision rule, laser budget inputs, "
                "signatories (see the README)")
      ->check(existing_file());
  c->add_option("--output,-o", a->output, "the certificate, HTML")->capture_default_str();
  c->add_option("--pdf", a->pdf, "also print it to this PDF (headless Chromium)");
  c->add_flag("--quiet,-q", a->quiet, "print nothing on success");
  return {{c, [a] { return run_certificate(*a); }}};
}

}  // namespace trueaxis::cli
