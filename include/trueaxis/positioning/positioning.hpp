// trueaxis::positioning — accuracy and repeatability of positioning of a numerically controlled
// linear axis from bidirectional laser runs, by ISO 230-2:2014 and by VDI/DGQ 3441:1977.
//
// Data. The axis approaches m target positions P_i (mm), each in both directions, over n cycles:
// ↑ ("+", "up") is an approach moving in the positive direction, ↓ ("-", "down") one moving in
// the negative direction. Each approach gives one positional deviation x_ij = actual − target
// (mm in the library; the laser's reading minus the commanded position).
//
// ISO 230-2:2014 (clause 3), per target i and direction (↑ shown; ↓ alike):
//     x̄_i↑ = Σ_j x_ij↑ / n                       mean unidirectional positional deviation
//     s_i↑ = sqrt(Σ_j (x_ij↑ − x̄_i↑)² / (n − 1))  estimator of the standard uncertainty
//     R_i↑ = 4·s_i↑                                unidirectional repeatability
//     x̄_i  = (x̄_i↑ + x̄_i↓) / 2                   mean bidirectional positional deviation
//     B_i  = x̄_i↑ − x̄_i↓                         reversal value
//     R_i  = max(2s_i↑ + 2s_i↓ + |B_i|, R_i↑, R_i↓) bidirectional repeatability
// and for the axis:
//     B = max |B_i|,  B̄ = Σ B_i / m               reversal value, mean reversal value
//     R↑ = max R_i↑,  R↓ = max R_i↓,  R = max R_i  repeatability of positioning
//     E↑ = max x̄_i↑ − min x̄_i↑ (E↓ alike)        unidirectional systematic positional deviation
//     E  = max(x̄_i↑, x̄_i↓) − min(x̄_i↑, x̄_i↓)    bidirectional systematic positional deviation
//     M  = max x̄_i − min x̄_i                      range of mean bidirectional deviation
//     A↑ = max(x̄_i↑ + 2s_i↑) − min(x̄_i↑ − 2s_i↑) (A↓ alike)   unidirectional accuracy
//     A  = max over both directions of (x̄ + 2s) − min over both of (x̄ − 2s)   accuracy
//
// VDI/DGQ 3441:1977, per target: reversal span U_j = |x̄_j↑ − x̄_j↓|, positional scatter
// Ps_j = 6·(s_j↑ + s_j↓)/2, mean position x̄_j = (x̄_j↑ + x̄_j↓)/2; for the axis: positional
// deviation Pa = max x̄_j − min x̄_j, U = max U_j (and its mean Ū), Ps = max Ps_j (and its mean),
// positional uncertainty P = max(x̄_j + (U_j + Ps_j)/2) − min(x̄_j − (U_j + Ps_j)/2).
//
// What is still defined with imperfect data. With one direction only, the unidirectional
// parameters of that direction are evaluated and every bidirectional one (B, B̄, R, E, M, A and
// the VDI set) is NaN ("not defined"). With fewer than two readings of a target in a direction
// its s, and so R and A, are NaN. Incomplete cycles (a target missing a reading in one cycle)
// are refused unless Options::allow_incomplete, which evaluates each target with the readings it
// has and says so in the warnings.
//
// Temperature. If the readings carry the machine's (material) temperature T, each deviation is
// corrected to the reference temperature (20 °C, ISO 1) for the nominal expansion of the axis:
// x ← x − α·(T − 20 °C)·(P − P₀), with α the axis' expansion coefficient and P₀ the laser's datum
// (default: the lowest target). This is the "material compensation" of laser software; the air
// temperature (wavelength compensation) is the laser's own business and is only recorded.
#pragma once

#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace trueaxis::positioning {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

enum class Direction { Up, Down };  // Up: approach moving in +; Down: moving in −

struct Reading {
  double target = 0;  // mm, commanded target position
  int cycle = 1;      // 1-based cycle number
  Direction direction = Direction::Up;
  double deviation = 0;                // mm, actual − target
  double material_temperature = kNaN;  // °C, NaN when not measured
  double air_temperature = kNaN;       // °C, NaN when not measured
};

struct Options {
  // Readings whose targets differ by less than this are the same target (mm).
  double target_tolerance = 1e-4;
  // Linear expansion coefficient of the axis for the correction to 20 °C (1/K; steel 11.5e-6).
  double expansion_coefficient = 11.5e-6;
  double reference_temperature = 20;  // °C
  double datum = kNaN;              // mm, laser datum P₀ of the expansion correction; NaN: lowest
  bool correct_temperature = true;  // apply the correction when material temperatures are given
  bool allow_incomplete = false;    // evaluate targets with missing readings (see above)
  // Where reading k (0-based, input order) is, "file:line:col: ", for messages that name a
  // reading; empty: messages count readings from 1 instead.
  std::function<std::string(std::size_t)> locate;
  void validate() const;  // throws Error
};

// Per-target statistics (mm). NaN marks what is not defined (see above).
struct Target {
  double position = 0;
  int n_up = 0, n_down = 0;                 // readings per direction
  double mean_up = kNaN, mean_down = kNaN;  // x̄_i↑, x̄_i↓
  double s_up = kNaN, s_down = kNaN;        // s_i↑, s_i↓
  double mean = kNaN;                       // x̄_i
  double B = kNaN;                          // B_i
  double R_up = kNaN, R_down = kNaN, R = kNaN;
  double U = kNaN, Ps = kNaN;  // VDI/DGQ 3441
};

// ISO 230-2:2014 parameters of the axis (mm); NaN when not defined.
struct IsoParameters {
  double A = kNaN, A_up = kNaN, A_down = kNaN;
  double E = kNaN, E_up = kNaN, E_down = kNaN;
  double M = kNaN;
  double R = kNaN, R_up = kNaN, R_down = kNaN;
  double B = kNaN, B_mean = kNaN;
};

// VDI/DGQ 3441:1977 parameters of the axis (mm); NaN when not defined.
struct VdiParameters {
  double P = kNaN, Pa = kNaN, Ps = kNaN, Ps_mean = kNaN, U = kNaN, U_mean = kNaN;
};

struct Result {
  std::vector<Target> targets;  // ascending position
  int cycles = 0;               // distinct cycle numbers in the data
  bool has_up = false, has_down = false;
  IsoParameters iso;
  VdiParameters vdi;
  // Temperatures seen (°C, NaN when absent) and the largest expansion correction applied (mm).
  double material_min = kNaN, material_max = kNaN, air_min = kNaN, air_max = kNaN;
  bool temperature_corrected = false;
  double expansion_coefficient = kNaN;  // 1/K, when corrected
  double datum = kNaN;                  // mm, when corrected
  double reference_temperature = kNaN;  // °C, when corrected
  double max_correction = 0;
  // The readings as evaluated, in the order of the input: deviations corrected to the reference
  // temperature when temperature_corrected (mm).
  std::vector<Reading> readings;
  // Departures from the standard's test conditions and what could not be evaluated, in words.
  std::vector<std::string> warnings;
  // Non-empty when the data look like a unit mix-up (targets spanning under 5 mm, deviations
  // varying by less than 0.05 µm along the axis): what looks wrong and which unit the data look
  // like. Also the first warning; no tolerance is judged on such data.
  std::string implausible;

  // A few lines for the terminal: the ISO 230-2 (or VDI 3441) parameters in µm.
  std::string summary(bool vdi = false) const;
};

enum class Standard { Iso230_2, Vdi3441 };

// The parameter names a tolerance can be given for: A, A_up, A_down, E, E_up, E_down, M, R,
// R_up, R_down, B, B_mean (ISO 230-2) and P, Pa, Ps, U (VDI/DGQ 3441).
const std::vector<std::string>& parameter_names();
// The value of a parameter by name (mm; NaN when not defined). Throws Error for unknown names.
double parameter(const Result& result, const std::string& name);

// A parameter checked against its tolerance (mm). A parameter that is not defined fails: a
// tolerance that cannot be checked is not met.
struct Verdict {
  std::string name;
  double value = kNaN, limit = 0;
  bool pass = false;
  std::string not_judged;  // why the tolerance was not judged (Result::implausible), or empty
};
// Checks |value| <= limit for each (name, limit) pair; throws Error for unknown names or limits
// that are not finite and positive. On implausible data nothing passes: each verdict says why
// it was not judged.
std::vector<Verdict> check(const Result& result,
                           const std::vector<std::pair<std::string, double>>& tolerances);

// Evaluates the runs. Throws Error on readings that cannot be evaluated: none at all, non-finite
// values, cycle numbers below 1, the same target, cycle and direction twice, material
// temperatures on some readings only, or missing readings without allow_incomplete (the message
// names the first missing target, cycle and direction).
Result evaluate(const std::vector<Reading>& readings, const Options& options = {});

// A plain interferometer log: the laser's reading (the actual position of the axis, mm) sampled
// over time while the machine runs its test cycle, stopping (dwelling) at each target.
struct Log {
  std::vector<double> time;     // s, strictly increasing
  std::vector<double> reading;  // mm
};

struct LogOptions {
  double dwell_time = 1.0;        // s: a stop must last this long to count
  double dwell_tolerance = 2e-3;  // mm: the reading's range during a stop
  double capture = kNaN;          // mm: a stop this close to a target is at it; NaN: a quarter of
                                  // the smallest target spacing, at most 0.5 mm
  void validate() const;          // throws Error
};

struct LogReadings {
  std::vector<Reading> readings;     // one per stop at a target, in time order
  int stops = 0;                     // stops found
  std::vector<std::string> ignored;  // stops not used, with the time and why
};

// Target detection by dwell. A stop is a maximal run of samples whose readings stay within
// dwell_tolerance for at least dwell_time; its value is the mean of the second half of its
// samples (the settled part). A stop within
// `capture` of a target is a reading at that target with deviation value − target; its direction
// is that of the motion into it (the last sample before the stop that is farther than
// 10 × dwell_tolerance from its value lies below it: '+', above: '-'), so an overrun before a
// reversal is recognised. Stops elsewhere (home, the overrun) and a stop at the start of the log
// (no motion into it) are listed in `ignored`. The k-th stop at a target in one direction is
// cycle k. Throws Error when `targets` is not strictly increasing or the log is malformed.
LogReadings readings_from_log(const Log& log, const std::vector<double>& targets,
                              const LogOptions& options = {});

}  // namespace trueaxis::positioning
