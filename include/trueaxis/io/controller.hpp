// trueaxis::io — compensation tables in the formats of machine-tool controllers.
//
// LinuxCNC ([JOINT_n] COMP_FILE, COMP_FILE_TYPE; LinuxCNC's INI documentation and its
// usrmotLoadComp): one line "nominal forward reverse" per node, nominals strictly increasing, at
// most 256 lines per joint, machine units (mm here). Type 0: the actual positions reached when
// commanding the nominal moving forward (+) and in reverse (−); type 1: the trims
// nominal − actual, which LinuxCNC adds to the command. LinuxCNC stops reading at the first line
// that is not three numbers, so nothing else (no header, no comment) is written, and the reader
// refuses any such line (file:line:col) instead of dropping the rest silently. Its own BACKLASH
// must then be 0: the reverse column already holds the reversal.
//
// Siemens Sinumerik leadscrew/measuring-system error compensation (LEC; SINUMERIK 840D sl
// Function Manual Extended Functions, K3 "Interpolatory compensation"): a part program
// %_N_AX_EEC_INI with CHANDATA(1), one $AA_ENC_COMP[e,N,AX]=value (mm) per interpolation point
// N = 0..k, equidistant from $AA_ENC_COMP_MIN with $AA_ENC_COMP_STEP to $AA_ENC_COMP_MAX,
// $AA_ENC_COMP_IS_MODULO = 0, M17. A positive value moves the axis in the negative direction, so
// the value is the measured error (the negated correction). The table is one curve for both
// directions: a bidirectional table is refused (the reversal goes to MD32450 BACKLASH). The
// number of points is limited by MD38000 $MA_MM_ENC_COMP_MAX_POINTS (the writer's max_points).
#pragma once

#include <limits>
#include <string>

#include "trueaxis/compensation/table.hpp"

namespace trueaxis::io {

inline constexpr int kLinuxCncMaxPoints = 256;

// Writes the table; returns the number of lines. Throws Error when it exceeds LinuxCNC's limit
// or the type is not 0 or 1.
int write_linuxcnc(const std::string& path, const compensation::AxisTable& table, int type);
compensation::AxisTable read_linuxcnc(const std::string& path, int type);
compensation::AxisTable parse_linuxcnc(std::string text, const std::string& path, int type);

struct SinumerikOptions {
  std::string axis = "X1";                                 // machine axis name
  int encoder = 0;                                         // measuring system: 0 or 1
  double step = std::numeric_limits<double>::quiet_NaN();  // mm; NaN: the mean target spacing
  int max_points = 5000;                                   // MD38000 as configured on the machine
};
// Resamples the table linearly onto the equidistant points and writes the part program; returns
// the number of points. Throws Error for a bidirectional table, a step that is not positive, or
// more points than max_points.
int write_sinumerik(const std::string& path, const compensation::AxisTable& table,
                    const SinumerikOptions& options = {});
// Reads such a program back (forward == reverse == −value); `axis` receives the axis name.
compensation::AxisTable parse_sinumerik(std::string text, const std::string& path,
                                        std::string* axis = nullptr);
compensation::AxisTable read_sinumerik(const std::string& path, std::string* axis = nullptr);

}  // namespace trueaxis::io
