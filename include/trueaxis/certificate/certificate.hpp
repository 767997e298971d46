// trueaxis::certificate — one calibration certificate per visit to a machine, from its records:
// the machine, the tests as found and as left, each headline figure with its expanded
// uncertainty, its limit and the decision by the stated rule (ISO 14253-1:2017 by default), the
// instruments and their calibration, the environment, the compensation applied, and the
// signature lines. For ISO 230-2 positioning results, the uncertainty budget after ISO 230-2:2014
// Annex A and ISO/TR 230-9:2005, from inputs the laboratory states (with documented defaults).
//
// Units: lengths in µm unless named otherwise, temperatures in °C, dates ISO 8601.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "trueaxis/records/records.hpp"
#include "trueaxis/report/html.hpp"

namespace trueaxis::certificate {

// The inputs of the budget of an ISO 230-2 laser positioning test. Each has a default a
// workshop laser calibration would state; the environmental variation error has none: it comes
// from the drift test of ISO 230-3 on that machine, and without it no U is given.
struct LaserInputs {
  double device_U_per_m = 1.0;             // µm/m: the laser's calibration, with its air
                                           // compensation, expanded (k = 2), from its certificate
  double misalignment_mrad = 0.1;          // beam to axis (a cosine error L·θ²/2, one-sided)
  double temperature_u_K = 0.1;            // standard u of the machine's temperature measurement
  double expansion_coefficient = 11.5e-6;  // 1/K, the machine's scale (steel)
  double expansion_u_relative = 0.1;       // u(α)/α
  std::optional<double> temperature_C;     // the machine's temperature during the test (else
                                           // the record's temperature)
  std::optional<double> eve_um;            // E_VE of the drift test (ISO 230-3), µm
  double setup_u_um = 0;                   // standard u of the set-up (Abbe offsets, fixture)
  void validate() const;                   // throws Error
};

struct Contribution {
  std::string name;     // "u_DEVICE"
  std::string what;     // "the laser's calibration: 1 µm/m (k = 2) over 800 mm"
  double u_um = 0;      // standard uncertainty
  bool in_B_R = false;  // also in U(B) and U(R)
};

// The budget of one positioning result over its measured length: each contribution's standard
// uncertainty, U (k = 2) of E, A and M (every contribution) and of B and R (the environmental
// variation and the set-up: the length-proportional terms are common to the readings B and R
// compare, at one target minutes apart, and cancel). Null U with the reason when an input is
// missing (no temperature, no E_VE).
struct PositioningBudget {
  double length_mm = 0;
  std::optional<double> temperature_C;
  std::vector<Contribution> contributions;
  std::optional<double> U_EAM_um, U_BR_um;
  std::string not_estimated;
};
PositioningBudget positioning_budget(double length_mm, std::optional<double> temperature_C,
                                     const LaserInputs& inputs);

struct MachineInfo {
  std::string description, maker, model, serial, location;
};
struct Instrument {
  std::string id, description, serial, certificate, calibrated, due;  // dates ISO 8601
};

enum class Rule { Iso14253, Simple };

// What the laboratory states: read from a JSON file (read_lab). Every field is optional.
struct Lab {
  std::string name, address, accreditation;
  std::string certificate_number;  // "{machine}-{date}" when not given
  std::string customer, customer_address;
  std::map<std::string, MachineInfo> machines;  // by the records' machine id
  std::vector<Instrument> instruments;
  // Upper limits by figure: "A@X", "E0", "G_ccw@XY", or a name alone for every axis.
  std::map<std::string, double> limits;
  Rule rule = Rule::Iso14253;
  std::string compensation;  // what was adjusted or compensated between as found and as left
  std::string environment;   // free text (air conditioning, heat sources, ...)
  std::string performed_by, approved_by;
  LaserInputs laser;
};
// Throws Error naming the file, line and column of what it cannot read.
Lab read_lab(const std::string& path);
Lab parse_lab(const std::string& json, const std::string& name);

// One figure's line on the certificate.
struct Line {
  long long record = 0;
  std::string kind, state, figure, unit;  // figure with its axis: "A@X"
  double value = 0;
  std::optional<double> U;  // expanded, k = 2
  std::string U_source;     // "ISO/TR 230-9 budget", "the result's own", ...
  std::optional<double> limit;
  std::string decision;  // "conforms", "does not conform", "no decision: …"
};

// How many lines conform, do not, and have a limit but no decision (within U, or no U).
struct Tally {
  int conform = 0, fail = 0, undecided = 0;
  void add(const Line& line);
};
Tally tally(const std::vector<Line>& lines);

struct Options {
  std::string machine;
  std::string date, to;   // the visit: from `date` to `to` inclusive (`to` "": one day)
  std::string issued;     // the certificate's date ("": today)
  void validate() const;  // throws Error
};

struct Certificate {
  std::string title;
  report::Meta meta;
  std::vector<report::Section> sections;
  std::vector<Line> lines;
  std::vector<std::string> warnings;  // an instrument out of calibration, no records, ...
  std::string html() const;           // the printable document
};

// Throws Error when the machine has no record in the visit's dates.
Certificate make(const records::Database& db, const Lab& lab, const Options& options);

// The decision for an upper limit: ISO 14253-1 — conforms when value + U ≤ limit, does not
// conform when value − U > limit, else no decision (the value is within U of the limit; without
// U, no decision at all); simple acceptance (ILAC-G8:09/2019, 4.2.1) — value ≤ limit.
std::string decide(double value, std::optional<double> U, double limit, Rule rule);

}  // namespace trueaxis::certificate
