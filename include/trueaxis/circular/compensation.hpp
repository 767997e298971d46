// trueaxis::circular — what to give the controller after a circular test: backlash per axis and
// the squareness of the plane's two axes, from the diagnosis (circular.hpp).
//
// A controller's backlash compensation adds the value at each reversal of the axis (positive
// when the table falls short of the command after a reversal: LinuxCNC [JOINT_n] BACKLASH,
// HEIDENHAIN MP710.x / CfgAxisComp backLash, FANUC parameter 1851, Siemens MD32450 BACKLASH). A
// test run with a compensation already active measures what is left, so the value to enter is
// the active one plus the diagnosed backlash.
//
// Squareness S (rad, positive when the actual +a and +b make more than 90°) moves the tool by
// e_a = −S·b. A cross-axis table that adds c(b) = S·b to axis a's command removes it (zero at
// b = 0, the machine's datum); with a correction S₀ already active, the new slope is S₀ + S.
//
// A value is proposed only when the data resolve it: a cause the fit could not separate, or one
// smaller than twice its standard uncertainty, leaves the active value as it is, with the reason.
// Units: mm and rad.
#pragma once

#include <array>
#include <cmath>
#include <optional>
#include <string>

#include "trueaxis/circular/circular.hpp"

namespace trueaxis::circular {

struct CompensationOptions {
  std::array<double, 2> active_backlash{0, 0};  // mm, axes a, b: in force during the test
  double active_squareness = 0;                 // rad: the cross-axis slope in force
  double coverage = 2;    // a diagnosed value smaller than coverage·u is not proposed
  void validate() const;  // throws Error
};

struct CompensationValue {
  double active = 0;       // in force during the test
  double diagnosed = NAN;  // what the test found left (NaN: not resolved)
  std::optional<double> u;
  double value = 0;  // to enter: active + diagnosed when changed, else active
  bool changed = false;
  std::string reason;  // why not changed, when not
};

struct Compensation {
  Plane plane;
  std::array<CompensationValue, 2> backlash;  // mm, axes a, b
  CompensationValue squareness;               // rad, slope of a's correction over b
  std::string summary() const;                // µm and µm/m
};

// Throws Error for invalid options.
Compensation compensation_from(const Result& result, const CompensationOptions& options = {});

}  // namespace trueaxis::circular
