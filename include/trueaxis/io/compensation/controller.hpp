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
//
// HEIDENHAIN nonlinear axis error compensation (iTNC 530, TNC 640, MANUALplus 620 Technical
// Manuals, "Nonlinear axis error compensation"): a compensation value table *.COM in HEIDENHAIN's
// table format — "BEGIN NAME.COM MM", a header line of column names, one line per compensation
// point, "[END]". Columns: NR (0, 1, 2, ...), AXISPOS (the compensation point, mm from the
// machine datum, increasing), the compensated axis' column (named as in CfgAxes/axisList: the
// compensation value for traverse in the positive direction, mm, added to the position) and
// BACKLASH (how much the compensation for the negative direction differs, forward − reverse, mm:
// positive for lost motion, as HEIDENHAIN's backlash setting is positive when the table traverse
// falls short after a reversal). At most 256 points per table (the controller refuses more). The
// table is assigned to its axis in the *.CMA file.
//
// FANUC pitch error compensation (Series 0i/16i/18i/30i parameter manuals, parameters 3620-3624):
// compensation points at a fixed interval (No. 3624, mm) numbered so that point No. 3620 is the
// reference position; No. 3621 and 3622 are the farthest points in the negative and positive
// directions. The value at point n applies to the travel between points n−1 and n, and is
// incremental: the change of the compensation over that section, in detection units times the
// magnification (No. 3623, 1..100), a whole number in −128..127. The compensation is zero at the
// reference position (where the reference return sets the coordinates). It is one curve for both
// directions (the reversal goes to parameter 1851, backlash compensation). Written as FANUC tape
// data between '%' lines: the parameters as "N3620A1P40" (parameter, axis number, value) and the
// points as "N10033P2" (10000 + point number); comments in parentheses.
#pragma once

#include <limits>
#include <string>
#include <vector>

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

inline constexpr int kHeidenhainMaxPoints = 256;

struct HeidenhainOptions {
  std::string axis = "X";  // the compensated axis' column name (CfgAxes/axisList)
  std::string name;        // table name in the BEGIN line; empty: the output file's name
};
// Writes the table's own points (no resampling); returns the number of points. Throws Error for
// more than 256 points or a bad axis name.
int write_heidenhain(const std::string& path, const compensation::AxisTable& table,
                     const HeidenhainOptions& options = {});
// Reads a *.COM table back (values in mm; an INCH table is converted). `axis`: the column to read
// when the table has several axis columns (empty: the only one); receives the column read.
compensation::AxisTable parse_heidenhain(std::string text, const std::string& path,
                                         std::string* axis = nullptr);
compensation::AxisTable read_heidenhain(const std::string& path, std::string* axis = nullptr);

struct FanucOptions {
  int axis_number = 1;          // the axis' number in the parameters (A1 = first axis)
  std::string axis_name = "X";  // for the comment only
  double reference = std::numeric_limits<double>::quiet_NaN();  // mm, in the table's
                                                                // coordinates: the reference
                                                                // position; NaN: the lowest point
  double interval = std::numeric_limits<double>::quiet_NaN();   // mm (No. 3624); NaN: the mean
                                                                // spacing of the table's points
  int first_number = 0;                   // No. 3621: the farthest negative point's number
  int max_number = 1023;                  // the highest point number the control has
  int magnification = 0;                  // No. 3623, 1..100; 0: the smallest that fits the values
  double detection_unit = 1e-3;           // mm (IS-B: 0.001 mm)
  int min_value = -128, max_value = 127;  // range of one point's value (detection units)
  double max_feedrate =
      std::numeric_limits<double>::quiet_NaN();  // mm/min; if given, the
                                                 // interval must be at least max_feedrate / 7500
};

struct FanucTable {
  int reference_number = 0, negative_number = 0, positive_number = 0;  // 3620, 3621, 3622
  int magnification = 1;                                               // 3623
  double interval = 0;                                                 // mm, 3624
  std::vector<int> values;  // points negative_number..positive_number
};

// Resamples the table (forward column) onto the points and writes the file; returns what was
// written. Throws Error for a bidirectional table, a point number beyond max_number, an interval
// below max_feedrate / 7500, or a change between points that no magnification up to 100 fits.
FanucTable write_fanuc(const std::string& path, const compensation::AxisTable& table,
                       const FanucOptions& options = {});
// Reads such a file back: the absolute compensation (mm, zero at the reference position) at every
// point from the one before the farthest negative to the farthest positive. Uses the options'
// axis_number (which axis' parameters: A1, A2, ...), detection_unit (not in the file) and
// reference (where the reference position lies in the returned positions; NaN: at 0); the point
// values must lie in −128..127.
compensation::AxisTable parse_fanuc(std::string text, const std::string& path,
                                    const FanucOptions& options = {}, FanucTable* raw = nullptr);
compensation::AxisTable read_fanuc(const std::string& path, const FanucOptions& options = {},
                                   FanucTable* raw = nullptr);

}  // namespace trueaxis::io
