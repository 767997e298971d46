// trueaxis::ippdme — the commands of I++ DME 1.4.3 (sections 6, 11 and 12 of the
// specification) and what arguments each takes: the checks a server makes on a command line
// that parsed, before it acts on it.
//
// Error numbers as the specification and NIST's reference parser assign them: 0507 an unknown
// command, 0001 an event command (AbortE, GetErrStatusE, GetPropE, OnMoveReportE) without an E
// tag or an ordinary one with an E tag, 0502 a wrong number or kind of arguments (or the same
// axis twice), 0509 a bad argument value (a string where a number belongs, a step width that is
// not positive, a property path that does not exist), 1007 a Euler angle theta outside 0..180°.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "trueaxis/ippdme/protocol.hpp"

namespace trueaxis::ippdme {

// Nothing, or what is wrong with the command (the column of the offending argument).
std::optional<SyntaxError> check(const Command& command);

// The commands known, in alphabetical order.
const std::vector<std::string_view>& command_names();

// True for the commands that go through the fast queue and must carry an E tag.
bool is_event_command(std::string_view name);

}  // namespace trueaxis::ippdme
