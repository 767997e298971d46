// Machine records over time: the virtual machine drifting (its X scale error growing linearly
// with time), tested by laser every three months; the history's fitted drift and due date
// against the drift the simulation put in. And `record due`: the last visit plus the interval,
// brought forward by a trend, overdue when past.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "../test_util.hpp"
#include "backends.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/positioning/positioning.hpp"
#include "trueaxis/positioning/positioning.hpp"
#include "trueaxis/records/records.hpp"
#include "trueaxis/sim/machine.hpp"
#include "trueaxis/sim/positioning.hpp"

using namespace trueaxis;

namespace {

constexpr double kDaysPerYear = 365.2425;
constexpr double kScaleError = 20e-3;        // mm per metre at the first visit, uncompensated
constexpr double kScaleDriftPerYear = 4e-3;  // mm per metre per year: the X scale creeping
constexpr double kLaserNoise = 0.2e-3;       // mm, each reading

// The machine `years` after the first visit: a scale error on X (on top of the random
// machine's own positioning error and bow) that grows by the drift, in the direction the
// machine's error already has from end to end. The mean deviations then rise monotonically
// along the axis and E, their range, grows linearly with time.
sim::Machine drifted(const sim::Machine& m0, double years) {
  sim::Machine m = m0;
  auto& f = m.errors[0][0];
  const double sign = f(800) >= f(0) ? 1.0 : -1.0;
  f.polynomial.resize(std::max<std::size_t>(f.polynomial.size(), 2), 0.0);
  f.polynomial[1] += sign * (kScaleError + kScaleDriftPerYear * years);
  return m;
}

// E (µm) of an ISO 230-2 run on X of `m`: noise-free (the truth) or with the laser's noise.
double positioning_E(const sim::Machine& m, double noise, std::uint64_t seed,
                     const std::string& write_to = "") {
  sim::PositioningRunOptions o;
  o.axis = 0;
  for (double p = 0; p <= 800; p += 80) o.targets.push_back(p);
  o.cycles = 5;
  o.noise = noise;
  o.seed = seed;
  const auto run = sim::simulate_positioning(m, o);
  const auto r = positioning::evaluate(run.readings);
  if (!write_to.empty()) io::write_positioning_result(write_to, r, positioning::Standard::Iso230_2);
  return r.iso.E * 1e3;
}

}  // namespace

// Twenty-four machines, each tested ten times over 27 months: the fitted drift of E lies within
// 2u of the simulated one, and the date E reaches its limit within 2u of the true date, as often
// as the estimates' stated uncertainty says (Student's t with 8 degrees of freedom: 92 %).
TEST(RecordsDrift, TheFittedDriftAndDueDateHoldTheSimulatedOnesWithinTheirUncertainty) {
  const std::string path = test::fresh_records("sqlite", "drift");
  records::Database db(path);
  constexpr int kMachines = 24, kVisits = 10;
  const long long day0 = records::day_number("2024-02-01");
  int drift_in_2u = 0, due_in_2u = 0;
  for (int k = 0; k < kMachines; ++k) {
    sim::MachineOptions mo;
    mo.seed = 500 + static_cast<std::uint64_t>(k);
    const auto m0 = sim::random_machine(mo);
    records::AddOptions a;
    a.machine = fmt::format("VM-{}", k);
    a.axis = "x";
    a.new_machine = true;
    std::vector<double> years, truth;
    for (int v = 0; v < kVisits; ++v) {
      const long long day = day0 + v * 91 + (v * 37 % 11) - 5;  // every three months, give or take
      const double t = static_cast<double>(day - day0) / kDaysPerYear;
      const auto m = drifted(m0, t);
      const std::string file = test::temp_dir() + fmt::format("/pos-{}-{}.json", k, v);
      positioning_E(m, kLaserNoise, 1000 + static_cast<std::uint64_t>(k * kVisits + v), file);
      a.date = records::date_of_day(day);
      db.add(file, a);
      a.new_machine = false;
      years.push_back(t);
      truth.push_back(positioning_E(m, 0, 1));
    }
    // E of noisy readings is biased upwards (the range of noisy means is wider than that of the
    // true ones) by an amount the drift does not change: the figure the records hold, and the
    // limit applies to, is that measured E. Its bias, by Monte Carlo at the first visit:
    double bias = 0;
    constexpr int kDraws = 30;
    for (int d = 0; d < kDraws; ++d)
      bias += positioning_E(drifted(m0, 0), kLaserNoise, 90000 + static_cast<std::uint64_t>(d));
    bias = bias / kDraws - truth.front();
    for (auto& e : truth) e += bias;
    // The simulated drift: the noise-free E's own line (exactly straight while the scale term
    // sets the range of the mean deviations).
    const auto n = static_cast<double>(kVisits);
    double st = 0, sy = 0, stt = 0, sty = 0;
    for (int v = 0; v < kVisits; ++v) {
      st += years[static_cast<std::size_t>(v)];
      sy += truth[static_cast<std::size_t>(v)];
      stt += years[static_cast<std::size_t>(v)] * years[static_cast<std::size_t>(v)];
      sty += years[static_cast<std::size_t>(v)] * truth[static_cast<std::size_t>(v)];
    }
    const double slope = (n * sty - st * sy) / (n * stt - st * st), icpt = (sy - slope * st) / n;
    for (int v = 0; v < kVisits; ++v)
      ASSERT_NEAR(icpt + slope * years[static_cast<std::size_t>(v)],
                  truth[static_cast<std::size_t>(v)], 0.05)
          << "the simulated E is not a straight line in time on machine " << k;
    // A limit the truth reaches a year after the last visit.
    const double limit = icpt + slope * (years.back() + 1);
    records::TrendOptions to;
    to.tolerance = limit;
    const auto t = db.trend(a.machine, "E", "X", to);
    ASSERT_TRUE(t.drift_per_year && t.u_drift && t.due) << t.summary();
    EXPECT_EQ(t.unit, "µm");
    EXPECT_LT(std::abs(*t.drift_per_year - slope), 5 * *t.u_drift) << t.summary();
    drift_in_2u += std::abs(*t.drift_per_year - slope) <= 2 * *t.u_drift;
    const double true_due = static_cast<double>(day0) + (limit - icpt) / slope * kDaysPerYear;
    due_in_2u += std::abs(static_cast<double>(records::day_number(*t.due)) - true_due) <=
                 2 * *t.u_due_days + 1;
  }
  // 92 % expected: at least 20 of 24 (fewer has a chance of about 2 % when the u are right).
  EXPECT_GE(drift_in_2u, 20) << drift_in_2u;
  EXPECT_GE(due_in_2u, 20) << due_in_2u;
}

TEST(RecordsDue, MonthsLimitsAndTheirRefusals) {
  EXPECT_EQ(records::add_months("2026-01-31", 1), "2026-02-28");
  EXPECT_EQ(records::add_months("2028-01-31", 1), "2028-02-29");
  EXPECT_EQ(records::add_months("2026-11-29", 12), "2027-11-29");
  EXPECT_EQ(records::add_months("2026-11-29", 14), "2028-01-29");
  const auto l = records::Limit::parse("A@x=25");
  EXPECT_EQ(l.figure, "A");
  EXPECT_EQ(l.axis, "X");
  EXPECT_EQ(l.value, 25);
  EXPECT_EQ(records::Limit::parse("E0=3.5").axis, "");
  for (const char* bad : {"A", "=3", "A=", "A=3x", "A=nan"})
    EXPECT_THROW(records::Limit::parse(bad), Error) << bad;
  records::DueOptions o;
  o.interval_months = 0;
  EXPECT_THROW(o.validate(), Error);
  o.interval_months = 12;
  o.today = "tomorrow";
  EXPECT_THROW(o.validate(), Error);
}

// Three machines: one drifting (its trend sets the date, before the interval's), one steady
// (the interval sets it), one last seen long ago (overdue), one already over its limit.
TEST(RecordsDue, TheIntervalOrAnEarlierTrendSetsEachMachinesDate) {
  const std::string path = test::fresh_records("sqlite", "due");
  records::Database db(path);
  sim::MachineOptions mo;
  mo.seed = 77;
  const auto m0 = sim::random_machine(mo);
  const long long day0 = records::day_number("2025-01-10");
  auto visit = [&](const std::string& id, const sim::Machine& m, long long day, int seed) {
    records::AddOptions a;
    a.machine = id;
    a.axis = std::string(1, 'X');  // not = "X": GCC 12 warns falsely (-Wrestrict) once inlined
    a.date = records::date_of_day(day);
    const auto known = db.machines();
    a.new_machine =
        std::none_of(known.begin(), known.end(), [&](const auto& s) { return s.id == id; });
    const std::string file = test::temp_dir() + fmt::format("/due-{}-{}.json", id, seed);
    positioning_E(m, kLaserNoise, static_cast<std::uint64_t>(seed), file);
    db.add(file, a);
  };
  double last_E = 0;
  for (int v = 0; v < 6; ++v) {
    const long long day = day0 + v * 91;
    visit("DRIFTING", drifted(m0, v * 91 / kDaysPerYear), day, 10 + v);
    visit("STEADY", m0, day, 20 + v);
    last_E = positioning_E(drifted(m0, v * 91 / kDaysPerYear), 0, 1);
  }
  visit("OLD", m0, records::day_number("2022-03-15"), 30);
  const std::string last = records::date_of_day(day0 + 5 * 91);
  records::DueOptions o;
  o.interval_months = 12;
  o.today = records::date_of_day(day0 + 5 * 91 + 30);
  // The drifting machine's E reaches this a few months after its last visit.
  const double drift_per_year = 1e3 * kScaleDriftPerYear * 0.8;  // µm/year over 800 mm
  o.limits.push_back(records::Limit::parse(fmt::format("E@X={:.4f}", last_E + drift_per_year / 3)));
  auto due = records::due_dates(db, o);
  ASSERT_EQ(due.size(), 3u);
  EXPECT_EQ(due[0].machine, "OLD");  // soonest first
  EXPECT_TRUE(due[0].overdue);
  EXPECT_EQ(due[0].due, "2023-03-15");
  EXPECT_EQ(due[1].machine, "DRIFTING");
  ASSERT_TRUE(due[1].u_days);
  EXPECT_NE(due[1].because.find("E@X reaches"), std::string::npos) << due[1].because;
  const long long d = records::day_number(due[1].due), l = records::day_number(last);
  EXPECT_GT(d, l);
  EXPECT_LT(d, l + 365 / 2);  // about four months after, well before the interval
  EXPECT_EQ(due[2].machine, "STEADY");
  EXPECT_EQ(due[2].due, records::add_months(last, 12));
  EXPECT_FALSE(due[2].u_days);
  ASSERT_EQ(due[2].notes.size(), 1u);  // its flat trend gave no date: said, not hidden
  EXPECT_NE(due[2].notes[0].find("does not stand out"), std::string::npos) << due[2].notes[0];
  // A limit the last value already exceeds: due at that visit, whatever the trend.
  o.limits = {records::Limit::parse("E=0.01")};
  o.machine = "STEADY";
  due = records::due_dates(db, o);
  ASSERT_EQ(due.size(), 1u);
  EXPECT_EQ(due[0].due, last);
  EXPECT_TRUE(due[0].overdue);
  EXPECT_NE(due[0].because.find("over its limit"), std::string::npos) << due[0].because;
  // Over the limit as found but adjusted under it as left: not due at that visit.
  sim::Machine flat = m0;
  flat.errors[0][0] = {};  // its X positioning error compensated
  for (int v = 0; v < 2; ++v) {
    records::AddOptions a;
    a.machine = "ADJUSTED";
    a.axis = "X";
    a.date = records::date_of_day(day0 + v * 91);
    a.new_machine = v == 0;
    for (const auto state : {records::State::AsFound, records::State::AsLeft}) {
      a.state = state;
      const std::string file =
          test::temp_dir() + fmt::format("/due-adjusted-{}-{}.json", v, records::to_string(state));
      positioning_E(state == records::State::AsFound ? drifted(m0, 0) : flat, kLaserNoise,
                    static_cast<std::uint64_t>(50 + 2 * v + (state == records::State::AsLeft)),
                    file);
      db.add(file, a);
      a.new_machine = false;
    }
  }
  const double found_E = positioning_E(drifted(m0, 0), 0, 1), left_E = positioning_E(flat, 0, 1);
  ASSERT_GT(found_E, left_E + 5);
  o.limits = {records::Limit::parse(fmt::format("E@X={:.3f}", (found_E + left_E) / 2))};
  o.machine = "ADJUSTED";
  due = records::due_dates(db, o);
  ASSERT_EQ(due.size(), 1u);
  EXPECT_EQ(due[0].due, records::add_months(records::date_of_day(day0 + 91), 12)) << due[0].because;
  const auto j = nlohmann::json::parse(records::to_json(due));
  EXPECT_EQ(j["kind"], "due");
  EXPECT_TRUE(j["machines"][0]["u_days"].is_null());
}
