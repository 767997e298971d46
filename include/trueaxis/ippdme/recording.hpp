// trueaxis::ippdme — programs and recorded responses in the form of NIST's I++ DME test suite,
// and the comparison of two response streams by their structure.
//
// NIST's files put a line "\\" after each protocol line and end with ":" lines. A structure
// compares what a client can rely on, not values: per tag, in order, the kind of each line
// (&, #, !, %), the error number of an error and the number of items of a data line. Scan data
// (lines of bare numbers) count as one item "scan data" however many points and lines they are:
// how many points a scan gives depends on the part. Lines of E0000 (unsolicited events) and the
// data a daemon reports after its transaction completed (OnMoveReportE) depend on time and
// motion, and are left out.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace trueaxis::ippdme {

// The protocol lines of a file in NIST's form (or of a plain file: one line per line), without
// the "\\" and ":" lines, CR LF or LF. `numbers` (if given) receives each one's line number in
// the file (1-based), for messages.
std::vector<std::string> recorded_lines(std::string_view text,
                                        std::vector<long>* numbers = nullptr);

struct StructureDifference {
  std::string tag;       // e.g. "00010"
  std::string expected;  // the structure, e.g. "& #3 %" or "& !2500 %"; "-" when absent
  std::string got;
};

// The differences between two response streams (lines that do not parse count as "?").
std::vector<StructureDifference> compare_structure(const std::vector<std::string>& expected,
                                                   const std::vector<std::string>& got);

// The structure of one tag's lines in a stream, as compare_structure writes it.
std::string structure(const std::vector<std::string>& lines, const std::string& tag);

}  // namespace trueaxis::ippdme
