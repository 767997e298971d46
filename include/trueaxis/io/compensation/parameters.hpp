// trueaxis::io — backlash compensation parameters and a cross-axis (squareness) table, in the
// forms of four machine-tool controllers. Machine axes X, Y, Z are taken to be the controller's
// first three axes in that order (LinuxCNC joints 0, 1, 2 with trivial kinematics; HEIDENHAIN
// axis index 0, 1, 2; FANUC axis numbers 1, 2, 3; Siemens machine axes AX1, AX2, AX3). Values in
// mm; a positive backlash is added at a reversal of a table that falls short of the command.
//
// Backlash:
// - LinuxCNC (INI file documentation, [JOINT_n] section): "BACKLASH = value", machine units,
//   >= 0. Written as an INI fragment of [JOINT_n] sections; '#' lines are comments.
// - HEIDENHAIN (iTNC 530 Technical Manual, 6.4.1 "Backlash compensation"): MP710.x, −1 … +1 mm,
//   x the axis index (on a TNC 640 or 620 the same value is CfgAxisComp backLash of the axis).
//   Written as a list "MP710.x: value" to be entered; ';' lines are comments.
// - FANUC (parameter manuals, No. 1851 "backlash compensating value"): per axis, in detection
//   units, −9999 … 9999. Written as tape data between '%' lines, "N1851A<axis>P<value>", comments
//   in parentheses; the value is rounded to the detection unit.
// - Siemens (SINUMERIK 840D sl, K3 "Backlash compensation"): MD32450 $MA_BACKLASH[0,AX<n>] (mm,
//   first measuring system), written as machine-data lines of an INI program ending in M17;
//   ';' starts a comment.
//
// Cross-axis table (Siemens sag and angularity compensation, K3 "Interpolatory compensation"):
// %_N_NC_CEC_INI, CHANDATA(1), $AN_CEC[t,N] = the correction (mm) added to the output axis at the
// input axis' interpolation point N = 0…k, $AN_CEC_INPUT_AXIS[t]=(AX<i>),
// $AN_CEC_OUTPUT_AXIS[t]=(AX<o>), $AN_CEC_STEP/MIN/MAX[t] (mm), $AN_CEC_DIRECTION[t]=0 (both
// directions), $AN_CEC_MULT_BY_TABLE[t]=0, $AN_CEC_IS_MODULO[t]=0, M17. The number of points is
// limited by MD18342 $MN_MM_CEC_MAX_POINTS[t].
//
// Every reader names file:line:col for what it cannot take.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace trueaxis::io {

using AxisValues = std::array<std::optional<double>, 3>;  // mm per machine axis X, Y, Z

// `comment`: lines written at the top as the format's comments (what the values come from).
// Each writer throws Error for a value outside the parameter's range, or no value at all.
void write_linuxcnc_backlash(const std::string& path, const AxisValues& backlash,
                             const std::vector<std::string>& comment = {});
AxisValues parse_linuxcnc_backlash(std::string text, const std::string& path);

void write_heidenhain_backlash(const std::string& path, const AxisValues& backlash,
                               const std::vector<std::string>& comment = {});
AxisValues parse_heidenhain_backlash(std::string text, const std::string& path);

// Returns what was written (each value rounded to the detection unit, mm).
AxisValues write_fanuc_backlash(const std::string& path, const AxisValues& backlash,
                                double detection_unit = 1e-3,
                                const std::vector<std::string>& comment = {});
AxisValues parse_fanuc_backlash(std::string text, const std::string& path,
                                double detection_unit = 1e-3);

void write_sinumerik_backlash(const std::string& path, const AxisValues& backlash,
                              const std::vector<std::string>& comment = {});
AxisValues parse_sinumerik_backlash(std::string text, const std::string& path);

// One cross-axis table: the correction added to `output` at equidistant positions of `input`.
struct CrossTable {
  int table = 0;                           // t, 0…
  int input = 1;                           // machine axis 0..2 whose position the table follows
  int output = 0;                          // machine axis 0..2 the correction is added to
  double min = 0;                          // mm, the input's first interpolation point
  double step = 1;                         // mm, > 0
  std::vector<double> values;              // mm, at min + N·step; at least two
  double at(double input_position) const;  // linear between points, the end value beyond
};
void write_sinumerik_cec(const std::string& path, const CrossTable& table,
                         const std::vector<std::string>& comment = {});
CrossTable parse_sinumerik_cec(std::string text, const std::string& path);

// Each reads its file and calls the parser above.
AxisValues read_linuxcnc_backlash(const std::string& path);
AxisValues read_heidenhain_backlash(const std::string& path);
AxisValues read_fanuc_backlash(const std::string& path, double detection_unit = 1e-3);
AxisValues read_sinumerik_backlash(const std::string& path);
CrossTable read_sinumerik_cec(const std::string& path);

}  // namespace trueaxis::io
