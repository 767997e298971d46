// trueaxis demo — the machine records scenario: three visits to the demo machine over two years,
// each tested by laser as found, adjusted and compensated, tested as left; its backlash trend and
// the certificate of the last visit.
#include <fmt/format.h>

#include <algorithm>
#include <filesystem>

#include "commands.hpp"
#include "trueaxis/certificate/certificate.hpp"
#include "trueaxis/io/positioning/positioning.hpp"
#include "trueaxis/positioning/positioning.hpp"
#include "trueaxis/records/records.hpp"
#include "trueaxis/report/records.hpp"
#include "trueaxis/sim/positioning.hpp"

namespace trueaxis::cli {
namespace {

constexpr double kDaysPerYearDemo = 365.2425;

// The demo's laboratory: who calibrates, what with, and the limits the customer set.
constexpr const char* kDemoLab = R"lab({
  "name": "trueaxis demo laboratory (a simulation)",
  "certificate_number": "DEMO-2027-01",
  "customer": "the demo workshop",
  "machines": {"DEMO-VMC": {"description": "the demo's virtual machine", "serial": "simulated"}},
  "instruments": [{"id": "laser-1", "description": "laser interferometer (simulated)",
                   "certificate": "simulated", "calibrated": "2026-06-01", "due": "2027-06-01"}],
  "limits": {"A@X": 25, "B@X": 6},
  "compensation": "X: backlash adjusted, pitch error compensation table loaded from the as-found run",
  "environment": "simulated: 20.5 °C throughout",
  "performed_by": "demo operator", "approved_by": "demo reviewer",
  "laser": {"eve_um": 1.0, "temperature_C": 20.5}
})lab";

}  // namespace

report::Section demo_records(const sim::Machine& machine, const std::string& dir,
                             std::uint64_t seed,
                             const std::function<void(const std::string&)>& say) {
  const std::string db_path = dir + "/records.db";
  std::filesystem::remove(db_path);
  records::Database db(db_path);
  const char* dates[] = {"2025-01-15", "2026-01-14", "2027-01-13"};
  const long long day0 = records::day_number(dates[0]);
  for (int v = 0; v < 3; ++v) {
    const double years =
        static_cast<double>(records::day_number(dates[v]) - day0) / kDaysPerYearDemo;
    // The ball screw wears: the backlash grows 1.6 µm a year from 2 µm, whatever was adjusted.
    sim::PositioningRunOptions o;
    o.axis = 0;
    for (double p = machine.range[0][0]; p <= machine.range[0][1] + 1e-9; p += 50)
      o.targets.push_back(p);
    o.cycles = 5;
    o.noise = 0.3e-3;
    o.backlash = (2.0 + 1.6 * years) * 1e-3;
    o.seed = seed + static_cast<std::uint64_t>(10 * v);
    const auto found = positioning::evaluate(sim::simulate_positioning(machine, o).readings);
    const std::string found_file = fmt::format("{}/visit{}-as-found.json", dir, v + 1);
    io::write_positioning_result(found_file, found, positioning::Standard::Iso230_2);
    // Adjusted: the backlash taken up to 1 µm, and a pitch error table of the as-found
    // bidirectional mean deviations (interpolated between the targets) loaded: the same
    // correction whichever the direction, as the backlash is the adjustment's business.
    std::vector<double> at, y;
    for (const auto& t : found.targets) {
      at.push_back(t.position);
      y.push_back(t.mean);
    }
    o.backlash = 1.0e-3;
    o.compensation = [at, y](double p, positioning::Direction) {
      const auto k = std::clamp<std::size_t>(
          static_cast<std::size_t>(std::upper_bound(at.begin(), at.end(), p) - at.begin()), 1,
          at.size() - 1);
      const double s = (p - at[k - 1]) / (at[k] - at[k - 1]);
      return -((1 - s) * y[k - 1] + s * y[k]);
    };
    o.seed += 1;
    const auto left = positioning::evaluate(sim::simulate_positioning(machine, o).readings);
    const std::string left_file = fmt::format("{}/visit{}-as-left.json", dir, v + 1);
    io::write_positioning_result(left_file, left, positioning::Standard::Iso230_2);
    records::AddOptions a;
    a.machine = "DEMO-VMC";
    a.date = dates[v];
    a.axis = "x";
    a.operator_name = "demo operator";
    a.instrument = "laser-1";
    a.temperature = 20.5;
    a.note = "simulated";
    a.new_machine = v == 0;
    a.state = records::State::AsFound;
    db.add(found_file, a);
    a.new_machine = false;
    a.state = records::State::AsLeft;
    db.add(left_file, a);
  }
  // The as-found backlash is what wears: its trend, and when it reaches the customer's 6 µm.
  records::TrendOptions to;
  to.tolerance = 6;
  to.use = records::TrendOptions::Use::AsFound;
  const records::Trend trend = db.trend("DEMO-VMC", "B", "X", to);
  const std::string lab_file = dir + "/lab.json";
  {
    std::FILE* f = std::fopen(lab_file.c_str(), "w");
    if (f != nullptr) {
      std::fputs(kDemoLab, f);
      std::fclose(f);
    }
  }
  const auto lab = certificate::parse_lab(kDemoLab, "lab.json");
  certificate::Options co;
  co.machine = "DEMO-VMC";
  co.date = dates[2];
  co.issued = dates[2];
  const auto cert = certificate::make(db, lab, co);
  report::write(dir + "/certificate.html", cert.html());
  say(fmt::format(
      "records: 3 visits over two years, as found and as left -> records.db; backlash B {}; the "
      "last visit's certificate -> certificate.html",
      trend.drift_per_year
          ? fmt::format("drifts {:.2f} ± {:.2f} µm/year{}", *trend.drift_per_year,
                        trend.u_drift.value_or(0),
                        trend.due ? ", reaches 6 µm on " + *trend.due : std::string())
          : std::string("not resolved")));
  auto s = report::trend_section(trend, "DEMO-VMC", to.tolerance);
  s.title = "Machine records: the backlash of X over three visits (a simulation)";
  s.intro_html =
      "<p>The demo machine, visited once a year: X tested by laser (ISO 230-2) as found, the "
      "backlash adjusted and a pitch compensation table loaded, tested again as left, every "
      "result stored in <code>records.db</code>. The ball screw wears between visits; the "
      "as-found reversal value B shows it, and its trend says when it will reach the customer's "
      "6 µm. The last visit's certificate, with the ISO/TR 230-9 budget and the ISO 14253-1 "
      "decisions, is <a href=\"certificate.html\">certificate.html</a>. Try <code>trueaxis "
      "record list --db records.db</code>, <code>trueaxis record due --db records.db --limit "
      "B@X=6</code>, <code>trueaxis certificate --db records.db --machine DEMO-VMC --date "
      "2027-01-13 --lab lab.json --pdf certificate.pdf</code>.</p>" +
      s.intro_html;
  return s;
}

}  // namespace trueaxis::cli
