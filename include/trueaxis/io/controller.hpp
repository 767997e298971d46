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
#pragma once

#include <string>

#include "trueaxis/compensation/table.hpp"

namespace trueaxis::io {

inline constexpr int kLinuxCncMaxPoints = 256;

// Writes the table; returns the number of lines. Throws Error when it exceeds LinuxCNC's limit
// or the type is not 0 or 1.
int write_linuxcnc(const std::string& path, const compensation::AxisTable& table, int type);
compensation::AxisTable read_linuxcnc(const std::string& path, int type);
compensation::AxisTable parse_linuxcnc(std::string text, const std::string& path, int type);

}  // namespace trueaxis::io
