// Certificates: the ISO 230-2 Annex A / ISO/TR 230-9 budget against the standard's equations
// worked by hand, the decision rules, the laboratory file and its errors, and a certificate
// made from a visit's records (as found, as left, an instrument out of calibration).
#include "trueaxis/certificate/certificate.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>

#include "../records/backends.hpp"
#include "../test_util.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/positioning/positioning.hpp"
#include "trueaxis/positioning/positioning.hpp"
#include "trueaxis/sim/machine.hpp"
#include "trueaxis/sim/positioning.hpp"

using namespace trueaxis;

namespace {

constexpr double kBudgetTolerance = 1e-12;  // µm: the same arithmetic, term by term

// An ISO 230-2 result of X on a random machine, written where the test wants it.
std::string laser_result(const std::string& name, double backlash_um, std::uint64_t seed) {
  sim::MachineOptions mo;
  mo.seed = 3;
  const auto m = sim::random_machine(mo);
  sim::PositioningRunOptions o;
  for (double p = 0; p <= 800; p += 100) o.targets.push_back(p);
  o.backlash = backlash_um * 1e-3;
  o.noise = 0.3e-3;
  o.seed = seed;
  const auto r = positioning::evaluate(sim::simulate_positioning(m, o).readings);
  const std::string path = test::temp_dir() + "/" + name;
  io::write_positioning_result(path, r, positioning::Standard::Iso230_2);
  return path;
}

}  // namespace

TEST(CertificateBudget, ContributionsAsTheStandardsWriteThem) {
  certificate::LaserInputs in;
  in.device_U_per_m = 1.0;
  in.misalignment_mrad = 0.2;
  in.temperature_u_K = 0.1;
  in.expansion_coefficient = 11.5e-6;
  in.expansion_u_relative = 0.1;
  in.eve_um = 2.0;
  in.setup_u_um = 0.3;
  const auto b = certificate::positioning_budget(800, 21.5, in);
  ASSERT_TRUE(b.not_estimated.empty()) << b.not_estimated;
  // By hand over L = 800 mm at 21.5 °C, in µm.
  const double device = 1.0 / 2 * 0.8;                                        // U/k per metre × L
  const double misalignment = 800e3 * 0.2e-3 * 0.2e-3 / 2 / std::sqrt(12.0);  // L·θ²/2, rect.
  const double m = 11.5e-6 * 800e3 * 0.1;                                     // α·L·u(T)
  const double e = 0.1 * 11.5e-6 * 1.5 * 800e3;  // u(α)·|T − 20|·L
  const double eve = 2.0 / std::sqrt(12.0);      // E_VE rectangular
  const double setup = 0.3;
  ASSERT_EQ(b.contributions.size(), 6u);
  const double expected[] = {device, misalignment, m, e, eve, setup};
  for (std::size_t i = 0; i < 6; ++i)
    EXPECT_NEAR(b.contributions[i].u_um, expected[i], kBudgetTolerance) << b.contributions[i].name;
  ASSERT_TRUE(b.U_EAM_um && b.U_BR_um);
  EXPECT_NEAR(*b.U_EAM_um,
              2 * std::sqrt(device * device + misalignment * misalignment + m * m + e * e +
                            eve * eve + setup * setup),
              kBudgetTolerance);
  EXPECT_NEAR(*b.U_BR_um, 2 * std::sqrt(eve * eve + setup * setup), kBudgetTolerance);
  // Without the machine's temperature or a drift test: no U, and why.
  const auto no_t = certificate::positioning_budget(800, std::nullopt, in);
  EXPECT_FALSE(no_t.U_EAM_um);
  EXPECT_NE(no_t.not_estimated.find("temperature"), std::string::npos);
  in.eve_um.reset();
  const auto no_eve = certificate::positioning_budget(800, 20.0, in);
  EXPECT_FALSE(no_eve.U_BR_um);
  EXPECT_NE(no_eve.not_estimated.find("ISO 230-3"), std::string::npos) << no_eve.not_estimated;
  in.device_U_per_m = -1;
  EXPECT_THROW(certificate::positioning_budget(800, 20.0, in), Error);
}

TEST(CertificateBudget, DecisionRules) {
  using certificate::Rule;
  EXPECT_EQ(certificate::decide(8, 1.5, 10, Rule::Iso14253), "conforms");
  EXPECT_EQ(certificate::decide(9, 1.5, 10, Rule::Iso14253), "no decision: within U of the limit");
  EXPECT_EQ(certificate::decide(11, 1.5, 10, Rule::Iso14253), "no decision: within U of the limit");
  EXPECT_EQ(certificate::decide(12, 1.5, 10, Rule::Iso14253), "does not conform");
  EXPECT_EQ(certificate::decide(8, std::nullopt, 10, Rule::Iso14253),
            "no decision: no uncertainty stated");
  EXPECT_EQ(certificate::decide(9.9, 5, 10, Rule::Simple), "conforms");
  EXPECT_EQ(certificate::decide(10.1, std::nullopt, 10, Rule::Simple), "does not conform");
}

TEST(CertificateLab, ReadAndItsErrorsLocated) {
  const auto lab = certificate::parse_lab(R"({
  "name": "Calibration Lab", "certificate_number": "C-17",
  "machines": {"VMC-3": {"maker": "Acme", "model": "V8", "serial": "123"}},
  "instruments": [{"id": "XL-80", "description": "laser", "calibrated": "2025-01-10", "due": "2026-01-10"}],
  "limits": {"A@x": 20, "E0": 3.5}, "decision_rule": "simple",
  "laser": {"eve_um": 1.2, "device_U_per_m": 0.5}
})",
                                          "lab.json");
  EXPECT_EQ(lab.name, "Calibration Lab");
  EXPECT_EQ(lab.machines.at("VMC-3").model, "V8");
  EXPECT_EQ(lab.limits.at("A@X"), 20);
  EXPECT_EQ(lab.limits.at("E0"), 3.5);
  EXPECT_EQ(lab.rule, certificate::Rule::Simple);
  EXPECT_EQ(*lab.laser.eve_um, 1.2);
  EXPECT_EQ(lab.laser.device_U_per_m, 0.5);
  EXPECT_EQ(lab.laser.misalignment_mrad, 0.1);  // the documented default
  const std::pair<const char*, const char*> bad[] = {
      {"{\"nmae\": \"x\"}", "lab.json:1:10: unknown key 'nmae'"},
      {"{\"instruments\": [{\"id\": \"a\", \"due\": \"soon\"}]}", "not an ISO 8601 date"},
      {"{\"instruments\": [{\"description\": \"a\"}]}", "lab.json:1:18:"},
      {"{\"decision_rule\": \"lenient\"}", "\"ISO 14253-1\" or \"simple\""},
      {"{\"limits\": {\"A\": \"20\"}}", "lab.json:1:18: 'limits.A' must be a number"},
      {"{\"laser\": {\"eve_um\": -1}}", "eve_um must be a number >= 0"},
      {"{\"laser\": {\"expansion_coefficient\": 11.5}}", "1/K"},
      {"[1, 2]", "lab.json"},
      {"{\"name\": ", "lab.json:1:10"},
  };
  for (const auto& item : bad) {
    const std::string text = item.first, want = item.second;
    const std::string e = test::error_of([&] { certificate::parse_lab(text, "lab.json"); });
    EXPECT_NE(e.find(want), std::string::npos) << text << " -> " << e;
  }
  EXPECT_NE(test::error_of([] { certificate::read_lab("/no/such/lab.json"); }).find("cannot open"),
            std::string::npos);
}

// A visit: X measured as found (backlash 6 µm) and as left (1 µm) with a laser whose
// calibration ran out before the visit; the figures, their U from the budget, the decisions.
TEST(Certificate, AVisitAsFoundAndAsLeft) {
  const std::string path = test::fresh_records("sqlite", "certificate");
  records::Database db(path);
  records::AddOptions a;
  a.machine = "VMC-3";
  a.date = "2026-03-02";
  a.axis = "x";
  a.state = records::State::AsFound;
  a.operator_name = "K. Tanaka";
  a.instrument = "XL-80";
  a.temperature = 21.0;
  a.new_machine = true;
  db.add(laser_result("found.json", 6, 1), a);
  a.new_machine = false;
  a.state = records::State::AsLeft;
  a.date = "2026-03-03";
  db.add(laser_result("left.json", 1, 2), a);
  a.date = "2026-06-01";  // another visit
  db.add(laser_result("later.json", 2, 3), a);
  certificate::Lab lab = certificate::parse_lab(R"({
  "name": "Calibration Lab", "machines": {"VMC-3": {"model": "V8"}},
  "instruments": [{"id": "XL-80", "description": "laser interferometer", "due": "2026-03-01"}],
  "limits": {"B@X": 4, "A": 30}, "compensation": "backlash compensation of X set to 5 µm",
  "laser": {"eve_um": 1.0}})",
                                                "lab.json");
  certificate::Options o;
  o.machine = "VMC-3";
  o.date = "2026-03-02";
  o.to = "2026-03-03";
  o.issued = "2026-03-04";
  const auto c = certificate::make(db, lab, o);
  EXPECT_EQ(c.title, "Calibration certificate VMC-3-2026-03-02");
  ASSERT_EQ(c.lines.size(), 10u);  // A, B, E, M, R twice; not the later visit's
  const auto budget = certificate::positioning_budget(800, 21.0, lab.laser);
  for (const auto& l : c.lines) {
    ASSERT_TRUE(l.U) << l.figure;
    const bool br = l.figure.rfind("B", 0) == 0 || l.figure.rfind("R", 0) == 0;
    EXPECT_NEAR(*l.U, br ? *budget.U_BR_um : *budget.U_EAM_um, 1e-12) << l.figure;
    if (l.figure == "B@X") {
      EXPECT_EQ(*l.limit, 4);
      EXPECT_EQ(l.decision, certificate::decide(l.value, l.U, 4, certificate::Rule::Iso14253));
      EXPECT_EQ(l.decision, l.state == "as-found" ? "does not conform" : "conforms")
          << l.value << " ± " << *l.U;
    }
    if (l.figure == "A@X") {
      EXPECT_EQ(*l.limit, 30);
    }
    if (l.figure == "E@X") {
      EXPECT_FALSE(l.limit);
      EXPECT_EQ(l.decision, "no limit stated");
    }
  }
  const auto warned = [&](const std::string& what) {
    return std::any_of(c.warnings.begin(), c.warnings.end(),
                       [&](const std::string& w) { return w.find(what) != std::string::npos; });
  };
  EXPECT_TRUE(warned("'XL-80' was due for calibration on 2026-03-01")) << c.warnings.size();
  EXPECT_FALSE(warned("compensated between them"));  // the lab said what it did
  const std::string html = c.html();
  for (const char* want :
       {"Results as found", "Results as left", "Uncertainty of positioning on X", "u_EVE",
        "backlash compensation of X set to 5 µm", "approved by", "ISO 14253-1", "K. Tanaka"})
    EXPECT_NE(html.find(want), std::string::npos) << want;
  // No records in the dates: refused, with the dates the machine has.
  o.date = "2025-01-01";
  o.to = "";
  const std::string e = test::error_of([&] { certificate::make(db, lab, o); });
  EXPECT_NE(e.find("its records run from 2026-03-02 to 2026-06-01"), std::string::npos) << e;
  o.to = "2024-01-01";
  EXPECT_THROW(certificate::make(db, lab, o), Error);
}
