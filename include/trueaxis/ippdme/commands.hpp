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

// The predefined errors of the specification (section 8.2): default severity and text.
struct ErrorInfo {
  int severity = 0;
  std::string_view text;
};
std::optional<ErrorInfo> error_info(int number);

// Checks a response that parsed, by what it says of itself: an error's number, severity and
// text against the predefined list; data by their names (IsHomed(0|1), ErrStatus(0|1),
// CoordSystem(...), ChangeToolAction(Switch|Rotate|MoveAuto|MoveMan, X(), Y(), Z()), points
// and positions as X(), Y(), Z(), IJK(i, j, k), ... each once, properties by their paths, the
// events of E0000). Nothing, or what is wrong (error 0008, protocol error).
std::optional<SyntaxError> check(const Response& response);

}  // namespace trueaxis::ippdme
