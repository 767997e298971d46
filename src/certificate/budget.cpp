// The uncertainty of an ISO 230-2 laser positioning test (certificate.hpp): the contributions
// of ISO 230-2:2014 Annex A, combined as ISO/TR 230-9:2005 and the GUM (JCGM 100:2008, 5.1.2)
// do, and the decision rules of ISO 14253-1:2017 and ILAC-G8:09/2019.
#include <fmt/format.h>

#include <cmath>

#include "trueaxis/certificate/certificate.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::certificate {

void LaserInputs::validate() const {
  auto non_negative = [](double v, const char* what) {
    if (!(v >= 0) || !std::isfinite(v))
      throw Error(fmt::format("laser budget: {} must be a number >= 0", what));
  };
  non_negative(device_U_per_m, "device_U_per_m");
  non_negative(misalignment_mrad, "misalignment_mrad");
  non_negative(temperature_u_K, "temperature_u_K");
  non_negative(expansion_u_relative, "expansion_u_relative");
  non_negative(setup_u_um, "setup_u_um");
  if (!(expansion_coefficient > 0 && expansion_coefficient < 1e-4))
    throw Error("laser budget: expansion_coefficient must be in 1/K (steel: 11.5e-6)");
  if (temperature_C && !(*temperature_C > -50 && *temperature_C < 100))
    throw Error("laser budget: temperature_C must be in °C");
  if (eve_um) non_negative(*eve_um, "eve_um");
}

PositioningBudget positioning_budget(double length_mm, std::optional<double> temperature_C,
                                     const LaserInputs& in) {
  in.validate();
  if (!(length_mm > 0)) throw Error("positioning budget: the measured length must be > 0");
  PositioningBudget b;
  b.length_mm = length_mm;
  b.temperature_C = in.temperature_C ? in.temperature_C : temperature_C;
  const double L_m = length_mm * 1e-3;
  // The laser's calibration, stated expanded (k = 2) per metre: its standard u over L.
  b.contributions.push_back({"u_DEVICE",
                             fmt::format("the laser's calibration, {:g} µm/m (k = 2) over {:g} mm",
                                         in.device_U_per_m, length_mm),
                             in.device_U_per_m / 2 * L_m, false});
  // The beam at θ to the axis reads L·cos θ: short by L·θ²/2 at most, one-sided; a rectangular
  // distribution over [0, L·θ²/2] has u = L·θ²/2 / (2√3).
  const double theta = in.misalignment_mrad * 1e-3;
  b.contributions.push_back(
      {"u_MISALIGNMENT",
       fmt::format("beam to axis within {:g} mrad (cosine error, rectangular)",
                   in.misalignment_mrad),
       length_mm * 1e3 * theta * theta / 2 / (2 * std::sqrt(3.0)), false});
  // The machine's temperature, measured with u(T): its expansion corrected with that error.
  b.contributions.push_back(
      {"u_M",
       fmt::format("the machine's temperature measurement, u = {:g} K, α = {:g}/K",
                   in.temperature_u_K, in.expansion_coefficient),
       in.expansion_coefficient * length_mm * 1e3 * in.temperature_u_K, false});
  if (!b.temperature_C) {
    b.not_estimated =
        "the machine's temperature during the test is not stated (give it when adding the "
        "record, --temperature, or as the laboratory's laser.temperature_C)";
  } else {
    // The expansion coefficient known to u(α): the correction from T to 20 °C errs by
    // u(α)·|T − 20|·L.
    const double dT = std::abs(*b.temperature_C - 20);
    b.contributions.push_back(
        {"u_E",
         fmt::format("the expansion coefficient, u(α) = {:g} % of α, {:.2g} K from 20 °C",
                     100 * in.expansion_u_relative, dT),
         in.expansion_u_relative * in.expansion_coefficient * dT * length_mm * 1e3, false});
  }
  if (!in.eve_um) {
    if (!b.not_estimated.empty()) b.not_estimated += "; ";
    b.not_estimated +=
        "the environmental variation error E_VE of a drift test on this machine (ISO 230-3) is "
        "not stated (laser.eve_um)";
  } else {
    // E_VE, the drift seen over the test's duration, taken as rectangular over its full span.
    b.contributions.push_back(
        {"u_EVE", fmt::format("environmental variation, E_VE = {:g} µm (ISO 230-3)", *in.eve_um),
         *in.eve_um / (2 * std::sqrt(3.0)), true});
  }
  b.contributions.push_back({"u_SETUP", "the set-up (Abbe offsets, fixture)", in.setup_u_um, true});
  if (!b.not_estimated.empty()) return b;
  double all = 0, br = 0;
  for (const auto& c : b.contributions) {
    all += c.u_um * c.u_um;
    if (c.in_B_R) br += c.u_um * c.u_um;
  }
  b.U_EAM_um = 2 * std::sqrt(all);
  b.U_BR_um = 2 * std::sqrt(br);
  return b;
}

std::string decide(double value, std::optional<double> U, double limit, Rule rule) {
  if (rule == Rule::Simple) return value <= limit ? "conforms" : "does not conform";
  if (!U) return "no decision: no uncertainty stated";
  if (value + *U <= limit) return "conforms";
  if (value - *U > limit) return "does not conform";
  return "no decision: within U of the limit";
}

void Tally::add(const Line& l) {
  if (l.decision.rfind("conforms", 0) == 0)
    ++conform;
  else if (l.decision.rfind("does not conform", 0) == 0)
    ++fail;
  else if (l.limit)
    ++undecided;
}

Tally tally(const std::vector<Line>& lines) {
  Tally t;
  for (const auto& l : lines) t.add(l);
  return t;
}

void Options::validate() const {
  if (machine.empty()) throw Error("certificate: give the machine's id");
  (void)records::day_number(date);
  if (!to.empty() && records::day_number(to) < records::day_number(date))
    throw Error("certificate: the visit ends (--to) before it starts (--date)");
  if (!issued.empty()) (void)records::day_number(issued);
}

}  // namespace trueaxis::certificate
