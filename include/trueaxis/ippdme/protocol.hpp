// trueaxis::ippdme — the lines of I++ DME (VDMA 8722), the protocol CMM software uses to drive a
// CMM controller: parsing and formatting of command and response lines by the grammar of the
// I++ DME specification 1.4.3, section 6.1.4.2. No I/O here.
//
// A command line is `Tag s Method`, e.g. `00010 GoTo(X(100), Y(150))`; a response line is
// `Tag s "&"`, `Tag s "%"`, `Tag s "#" s Data` or `Tag s "!" s Error(F1, F2, F3, Text)`. Tags are
// five characters: 00001–99999 for ordinary commands, E0001–E9999 for the fast queue, E0000 for
// the server's unsolicited events. Spaces are allowed only before or after a comma, around a
// left parenthesis and before a right one; the single spaces after the tag and around the
// response kind are required.
//
// Two things servers send that the grammar does not define are accepted: spaces at the end of
// a line, and AlignPart's and AlignTool's vectors as a parenthesised list with no name
// (`# (0.6, 0, 0.8)`, a Call with an empty name).
//
// Parsing keeps the number of optional spaces at every place they may stand, and each number's
// text as written, so that formatting a parsed line gives back the same characters. Values are
// nested: the arguments of the scan commands of version 1.5 and later (Format(X(), Y(), IJK()),
// Data(...)) parse as calls within calls.
//
// Syntax errors name the column (1-based) and carry the specification's error number as NIST's
// reference parser assigns it: 0001 illegal tag, 0002 no space at position 6, 0007 a character
// outside printable ASCII, 0509 bad number or string (no digits, more than 16 digits, two
// decimal points, an exponent of other than 1–3 digits; an unclosed or empty string), 0507
// characters after the command's end, 0502 incorrect arguments (anything else misplaced).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace trueaxis::ippdme {

// The longest line the specification allows, without its CR LF.
inline constexpr std::size_t kMaxLine = 65536;

struct Tag {
  bool event = false;  // E tag (fast queue, or E0000 for events)
  int number = 1;      // 1..99999, or 0..9999 for an E tag
  std::string text() const;
  bool operator==(const Tag&) const = default;
};

// One item of a line: a string, a number, a bare name (e.g. PartCsy), an event tag used as an
// argument (e.g. the tag of a daemon to stop), or a call: a name with arguments in parentheses
// (a method, a property such as Tool.GoToPar.Speed(100), or X(12.5) in data).
struct Value {
  enum class Kind { String, Number, Name, ETag, Call };
  Kind kind = Kind::Number;
  // String: the characters between the quotes. Number: as written (e.g. "+1.2E-3"). Name and
  // Call: the name, dotted for properties (Tool.PtMeasPar.Speed). ETag: e.g. "E0017".
  std::string text;
  std::vector<Value> args;  // of a call
  // Optional spaces of a call, for formatting it back as written: before "(", after "(", then
  // before and after each comma, and before ")".
  std::vector<std::uint16_t> spaces;
  std::uint32_t column = 0;  // where it starts in the parsed line (1-based; 0: built in code)

  double number() const;  // the value of a Number (precondition: kind == Number)
  bool is_call(std::string_view name) const { return kind == Kind::Call && text == name; }
};

struct Command {
  Tag tag;
  Value method;                // a Call whose name has no dots
  std::uint16_t trailing = 0;  // spaces after it (outside the grammar, tolerated and kept)
};

struct Response {
  enum class Kind : char { Ack = '&', Done = '%', Data = '#', Error = '!' };
  Tag tag;
  Kind kind = Kind::Ack;
  // Data: the items (all numbers; two strings; one method; or properties). Error: one call
  // Error(severity, number, cause, text).
  std::vector<Value> items;
  std::vector<std::uint16_t> spaces;  // before and after each comma between the items
  std::uint16_t trailing = 0;         // spaces at the end (outside the grammar, tolerated)
};

// What is wrong with a line.
struct SyntaxError {
  int error = 502;              // the specification's error number (see above)
  std::size_t column = 1;       // 1-based
  std::string what;             // one line
  std::string message() const;  // "column 12: ... (error 0509)"
};

template <class T>
struct Parsed {
  std::optional<T> value;
  SyntaxError error;  // when there is no value
  explicit operator bool() const { return value.has_value(); }
};

// The tag a line starts with (its first five characters), if they are one; E0000 included.
std::optional<Tag> parse_tag(std::string_view line);

// An I++ DME version as GetDMEVersion gives it ("1.4.3", or "1.4"), as one number that orders
// versions: 10000·major + 100·minor + patch (1.4.3: 10403). Nothing if it is not one.
std::optional<int> version_number(std::string_view version);

// `line` without its CR LF (a trailing CR is an error: the framing belongs to the transport).
Parsed<Command> parse_command(std::string_view line);
Parsed<Response> parse_response(std::string_view line);

// The line as the specification writes it, with the spaces and number texts kept from parsing
// (or none: values built in code format as `Name(a, b)`, a space after each comma).
std::string format(const Command& c);
std::string format(const Response& r);
std::string format(const Value& v);

// Values built in code.
Value number(double v);  // shortest text that reads back exactly
Value string(std::string s);
Value name(std::string s);
Value call(std::string name, std::vector<Value> args = {});

}  // namespace trueaxis::ippdme
