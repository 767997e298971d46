// I++ DME lines: a recursive-descent parser of the specification's grammar (1.4.3, 6.1.4.2),
// keeping what formatting needs to give the line back as written.
#include "trueaxis/ippdme/protocol.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cstdlib>

namespace trueaxis::ippdme {
namespace {

constexpr int kIllegalTag = 1, kNoSpace = 2, kIllegalCharacter = 7, kIncorrectArguments = 502,
              kIllegalCommand = 507, kBadArgument = 509, kBadNumber = 509;
// Calls nest at most this deep (Format(X(), ...) is two): a guard against hostile input.
constexpr int kMaxDepth = 32;

bool alpha(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z');
}
bool digit(char c) {
  return c >= '0' && c <= '9';
}

// A readable name for a character in a message.
std::string shown(char c) {
  if (c >= 32 && c <= 126) return fmt::format("'{}'", c);
  return fmt::format("character {}", static_cast<int>(static_cast<unsigned char>(c)));
}

struct Failure {
  SyntaxError e;
};

class Reader {
 public:
  explicit Reader(std::string_view s, std::size_t from = 0) : s_(s), i_(from) {}
  // Responses: a parenthesised list with no name, as servers send AlignPart's and AlignTool's
  // vectors: (0.6, 0, 0.8).
  bool groups = false;

  [[noreturn]] void fail(int error, std::size_t at, std::string what) const {
    throw Failure{{error, at + 1, std::move(what)}};
  }
  bool end() const { return i_ >= s_.size(); }
  char peek() const { return end() ? '\0' : s_[i_]; }
  std::size_t pos() const { return i_; }

  // Optional spaces: how many.
  std::uint16_t spaces() {
    std::size_t n = 0;
    while (!end() && s_[i_] == ' ') ++i_, ++n;
    return static_cast<std::uint16_t>(std::min<std::size_t>(n, 65535));
  }

  Tag tag(bool allow_e0000) {
    if (s_.size() < 5) fail(kIllegalTag, 0, "a line starts with a five-character tag");
    Tag t;
    t.event = s_[0] == 'E';
    for (std::size_t k = t.event ? 1 : 0; k < 5; ++k)
      if (!digit(s_[k]))
        fail(kIllegalTag, k,
             fmt::format("illegal tag '{}': five digits, or E and four digits", s_.substr(0, 5)));
    int n = 0;
    std::from_chars(s_.data() + (t.event ? 1 : 0), s_.data() + 5, n);
    t.number = n;
    if (n == 0 && !t.event) fail(kIllegalTag, 0, "tag 00000 is not allowed (00001 to 99999)");
    if (n == 0 && t.event && !allow_e0000)
      fail(kIllegalTag, 0, "tag E0000 is the server's, for events (a client uses E0001 to E9999)");
    i_ = 5;
    if (peek() != ' ')
      fail(kNoSpace, 5,
           end() ? "the line ends after its tag" : "the tag must be followed by one space");
    ++i_;
    return t;
  }

  std::string basic_name() {
    const std::size_t a = i_;
    if (!alpha(peek()))
      fail(kIncorrectArguments, i_,
           end() ? "the line ends where a name should be"
                 : fmt::format("a name starts with a letter, not {}", shown(peek())));
    while (!end() && (alpha(s_[i_]) || digit(s_[i_]))) ++i_;
    return std::string(s_.substr(a, i_ - a));
  }

  std::string string_value() {
    const std::size_t a = i_;
    ++i_;  // the opening quote
    while (!end() && s_[i_] != '"') {
      if (s_[i_] < 32 || s_[i_] > 126)
        fail(kBadArgument, i_, fmt::format("{} in a string (only printable ASCII)", shown(s_[i_])));
      ++i_;
    }
    if (end()) fail(kBadArgument, a, "the string has no closing quote");
    if (i_ == a + 1) fail(kBadArgument, a, "an empty string (\"\") is not allowed");
    ++i_;
    return std::string(s_.substr(a + 1, i_ - a - 2));
  }

  std::string number_text() {
    const std::size_t a = i_;
    if (peek() == '+' || peek() == '-') ++i_;
    int digits = 0, points = 0;
    while (!end() && (digit(s_[i_]) || s_[i_] == '.')) {
      if (s_[i_] == '.') {
        if (++points > 1) fail(kBadNumber, i_, "a number with two decimal points");
      } else {
        ++digits;
      }
      ++i_;
    }
    if (digits == 0) fail(kBadNumber, a, "a number needs at least one digit");
    if (digits > 16) fail(kBadNumber, a, fmt::format("a number of {} digits (at most 16)", digits));
    if (peek() == 'E' || peek() == 'e') {
      const std::size_t e = i_++;
      if (peek() == '+' || peek() == '-') ++i_;
      int ed = 0;
      while (!end() && digit(s_[i_])) ++i_, ++ed;
      if (ed < 1 || ed > 3)
        fail(kBadNumber, e, "the exponent of a number must have one, two or three digits");
    }
    return std::string(s_.substr(a, i_ - a));
  }

  // Argument :== String | Number | Property | ETag | BasicName, and calls within calls.
  Value value(int depth) {
    const std::size_t at = i_;
    Value v = value_at(depth);
    v.column = static_cast<std::uint32_t>(at + 1);
    return v;
  }

  Value value_at(int depth) {
    Value v;
    const char c = peek();
    if (c == '"') {
      v.kind = Value::Kind::String;
      v.text = string_value();
    } else if (c == '(' && groups) {
      v = call_rest("", 0, depth, i_);
    } else if (digit(c) || c == '+' || c == '-' || c == '.') {
      v.kind = Value::Kind::Number;
      v.text = number_text();
    } else if (alpha(c)) {
      const std::size_t a = i_;
      std::string name = basic_name();
      while (peek() == '.') {
        ++i_;
        name.push_back('.');
        name.append(basic_name());
      }
      const std::size_t after = i_;
      const std::uint16_t before = spaces();
      if (peek() == '(') {
        v = call_rest(std::move(name), before, depth, a);
      } else {
        i_ = after;  // the spaces belong to the separator that follows
        if (name.find('.') != std::string::npos)
          fail(kIncorrectArguments, a,
               fmt::format("the property '{}' needs parentheses: {}()", name, name));
        const bool etag = name.size() == 5 && name[0] == 'E' &&
                          name.find_first_not_of("0123456789", 1) == std::string::npos;
        v.kind = etag ? Value::Kind::ETag : Value::Kind::Name;
        v.text = std::move(name);
      }
    } else {
      fail(kIncorrectArguments, i_,
           end() ? "the line ends where a value should be"
                 : fmt::format("{} cannot start a value", shown(c)));
    }
    return v;
  }

  // After the name and its spaces: "(" args ")".
  Value call_rest(std::string name, std::uint16_t before, int depth, std::size_t at) {
    if (depth >= kMaxDepth)
      fail(kIncorrectArguments, at, fmt::format("calls nested deeper than {}", kMaxDepth));
    Value v;
    v.kind = Value::Kind::Call;
    v.text = std::move(name);
    ++i_;  // "("
    v.spaces.push_back(before);
    v.spaces.push_back(spaces());
    if (peek() == ')') {
      ++i_;
      v.spaces.push_back(0);
      return v;
    }
    for (;;) {
      v.args.push_back(value(depth + 1));
      const std::uint16_t sp = spaces();
      if (peek() == ',') {
        ++i_;
        v.spaces.push_back(sp);
        v.spaces.push_back(spaces());
        continue;
      }
      if (peek() == ')') {
        ++i_;
        v.spaces.push_back(sp);
        return v;
      }
      after_item(sp, v.args.back());
    }
  }

  // What follows an item is not a comma or ")": say why in the words that fit.
  [[noreturn]] void after_item(std::uint16_t sp, const Value& item) const {
    if (end()) fail(kIncorrectArguments, i_, "the line ends before the closing ')'");
    if (sp > 0 && item.kind == Value::Kind::Number)
      fail(kIncorrectArguments, i_ - sp,
           fmt::format("a space inside or after the number '{}' before {}", item.text,
                       shown(peek())));
    if (sp > 0 && item.kind == Value::Kind::Call)
      fail(kIncorrectArguments, i_ - sp,
           fmt::format("a space after ')' before {}: expected ',' or ')'", shown(peek())));
    fail(kIncorrectArguments, i_, fmt::format("expected ',' or ')', found {}", shown(peek())));
  }

  void skip(char c) {
    if (peek() != c) fail(kIncorrectArguments, i_, fmt::format("expected '{}'", c));
    ++i_;
  }

  void expect_end() const {
    if (!end())
      fail(kIllegalCommand, i_,
           fmt::format("{} after the end of the line's content", shown(s_[i_])));
  }

 private:
  std::string_view s_;
  std::size_t i_ = 0;
};

void check_line(std::string_view line) {
  if (line.size() > kMaxLine)
    throw Failure{{kIncorrectArguments, kMaxLine + 1,
                   fmt::format("the line has {} characters (at most {})", line.size(), kMaxLine)}};
  for (std::size_t k = 0; k < line.size(); ++k)
    if (line[k] < 32 || line[k] > 126)
      throw Failure{
          {kIllegalCharacter, k + 1,
           fmt::format("{}: only printable ASCII in a line (CR LF end it)", shown(line[k]))}};
}

void format_to(std::string& out, const Value& v) {
  switch (v.kind) {
    case Value::Kind::String:
      out += '"';
      out += v.text;
      out += '"';
      return;
    case Value::Kind::Number:
    case Value::Kind::Name:
    case Value::Kind::ETag:
      out += v.text;
      return;
    case Value::Kind::Call:
      break;
  }
  // Spaces as parsed, or the usual ones (none but one after each comma) for built values.
  const bool kept = v.spaces.size() == (v.args.empty() ? 3 : 2 * v.args.size() + 1);
  auto sp = [&](std::size_t k, int usual) {
    out.append(kept ? v.spaces[k] : static_cast<std::size_t>(usual), ' ');
  };
  out += v.text;
  sp(0, 0);
  out += '(';
  sp(1, 0);
  for (std::size_t a = 0; a < v.args.size(); ++a) {
    format_to(out, v.args[a]);
    if (a + 1 < v.args.size()) {
      sp(2 + 2 * a, 0);
      out += ',';
      sp(3 + 2 * a, 1);
    }
  }
  sp(v.args.empty() ? 2 : 2 * v.args.size(), 0);
  out += ')';
}

// DataData :== NumData | PropData | Method | PropertyList; servers also send one string alone
// (a tool's name from EnumTools), so strings are accepted in any number.
void check_data(const Response& r, const Reader& rd, std::size_t at) {
  bool numbers = true, strings = true, calls = true;
  for (const auto& v : r.items) {
    numbers = numbers && v.kind == Value::Kind::Number;
    strings = strings && v.kind == Value::Kind::String;
    calls = calls && v.kind == Value::Kind::Call;
  }
  if (numbers || strings || calls) return;
  rd.fail(kIncorrectArguments, at,
          "data must be numbers, strings, one method or properties, not a mixture");
}

void check_error(const Response& r, const Reader& rd, std::size_t at) {
  if (r.items.size() != 1 || !r.items[0].is_call("Error"))
    rd.fail(kIncorrectArguments, at, "an error response is Error(severity, number, cause, text)");
  const auto& a = r.items[0].args;
  if (a.size() != 4)
    rd.fail(kIncorrectArguments, at,
            fmt::format("Error(...) has 4 arguments (severity, number, cause, text), not {}",
                        a.size()));
  if (a[0].kind != Value::Kind::Number || a[0].text.size() != 1 || !digit(a[0].text[0]))
    rd.fail(kIncorrectArguments, at, "the severity of an error is one digit (0 to 9)");
  if (a[1].kind != Value::Kind::Number || a[1].text.size() != 4 ||
      a[1].text.find_first_not_of("0123456789") != std::string::npos)
    rd.fail(kIncorrectArguments, at, "the error number is four digits, e.g. 0512");
  if (a[2].kind != Value::Kind::String || a[3].kind != Value::Kind::String)
    rd.fail(kIncorrectArguments, at, "the cause and the text of an error are strings");
}

}  // namespace

std::string Tag::text() const {
  return event ? fmt::format("E{:04d}", number) : fmt::format("{:05d}", number);
}

double Value::number() const {
  // The grammar's numbers are what strtod reads (this library never changes the C locale);
  // beyond double's range they read as ±inf or 0.
  return std::strtod(text.c_str(), nullptr);
}

std::optional<int> version_number(std::string_view version) {
  int part[3] = {0, 0, 0};
  const char* p = version.data();
  const char* end = p + version.size();
  for (int i = 0; i < 3; ++i) {
    const auto [next, ec] = std::from_chars(p, end, part[i]);
    if (ec != std::errc() || part[i] < 0 || part[i] > 99) return std::nullopt;
    p = next;
    if (p == end)
      return i >= 1 ? std::optional<int>(10000 * part[0] + 100 * part[1] + part[2]) : std::nullopt;
    if (*p++ != '.' || i == 2) return std::nullopt;
  }
  return std::nullopt;
}

std::optional<Tag> parse_tag(std::string_view line) {
  if (line.size() < 5) return std::nullopt;
  Tag t;
  t.event = line[0] == 'E';
  for (std::size_t k = t.event ? 1 : 0; k < 5; ++k)
    if (line[k] < '0' || line[k] > '9') return std::nullopt;
  std::from_chars(line.data() + (t.event ? 1 : 0), line.data() + 5, t.number);
  if (t.number == 0 && !t.event) return std::nullopt;
  return t;
}

std::string SyntaxError::message() const {
  return fmt::format("column {}: {} (error {:04d})", column, what, error);
}

Parsed<Command> parse_command(std::string_view line) {
  Parsed<Command> out;
  try {
    check_line(line);
    Reader rd(line);
    Command c;
    c.tag = rd.tag(false);
    const std::size_t at = rd.pos();
    std::string name = rd.basic_name();
    if (rd.peek() == '.') rd.fail(kIncorrectArguments, rd.pos(), "a command's name has no dots");
    const std::uint16_t before = rd.spaces();
    if (rd.peek() != '(')
      rd.fail(kIncorrectArguments, rd.pos(),
              fmt::format("the command '{}' needs its parentheses: {}()", name, name));
    c.method = rd.call_rest(std::move(name), before, 0, at);
    c.method.column = static_cast<std::uint32_t>(at + 1);
    c.trailing = rd.spaces();
    rd.expect_end();
    out.value = std::move(c);
  } catch (const Failure& f) {
    out.error = f.e;
  }
  return out;
}

Parsed<Response> parse_response(std::string_view line) {
  Parsed<Response> out;
  try {
    check_line(line);
    Reader rd(line);
    Response r;
    r.tag = rd.tag(true);
    const std::size_t at = rd.pos();
    const char k = rd.peek();
    if (k != '&' && k != '%' && k != '#' && k != '!')
      rd.fail(kIncorrectArguments, at,
              rd.end() ? "the line ends where '&', '%', '#' or '!' should be"
                       : fmt::format("a response is '&', '%', '#' or '!', not {}", shown(k)));
    r.kind = static_cast<Response::Kind>(k);
    if (k == '&' || k == '%') {
      if (line.size() > at + 1)
        rd.fail(kIncorrectArguments, at + 1,
                fmt::format("nothing may follow '{}' (found {})", k, shown(line[at + 1])));
      out.value = std::move(r);
      return out;
    }
    if (line.size() < at + 2 || line[at + 1] != ' ')
      rd.fail(
          kIncorrectArguments, at + 1,
          fmt::format("'{}' is followed by one space and the {}", k, k == '#' ? "data" : "error"));
    if (line.size() > at + 2 && line[at + 2] == ' ')
      rd.fail(kIncorrectArguments, at + 2, fmt::format("one space after '{}', not more", k));
    // The items: values separated by commas, to the end of the line.
    Reader body(line, at + 2);
    body.groups = true;
    Response got = std::move(r);
    if (body.end()) body.fail(kIncorrectArguments, body.pos(), "the response has no data");
    for (;;) {
      got.items.push_back(body.value(0));
      const std::uint16_t sp = body.spaces();
      if (body.end()) {
        got.trailing = sp;
        break;
      }
      if (body.peek() != ',') {
        if (sp > 0 && got.items.back().kind == Value::Kind::Number)
          body.fail(kIncorrectArguments, body.pos() - sp,
                    fmt::format("a space inside or after the number '{}'", got.items.back().text));
        body.fail(kIncorrectArguments, body.pos(),
                  fmt::format("expected ',' between data items, found {}", shown(body.peek())));
      }
      got.spaces.push_back(sp);
      body.skip(',');
      got.spaces.push_back(body.spaces());
    }
    if (got.kind == Response::Kind::Data)
      check_data(got, rd, at + 2);
    else
      check_error(got, rd, at + 2);
    out.value = std::move(got);
  } catch (const Failure& f) {
    out.error = f.e;
  }
  return out;
}

std::string format(const Value& v) {
  std::string out;
  format_to(out, v);
  return out;
}

std::string format(const Command& c) {
  std::string out = c.tag.text() + ' ';
  format_to(out, c.method);
  out.append(c.trailing, ' ');
  return out;
}

std::string format(const Response& r) {
  std::string out = r.tag.text() + ' ';
  out += static_cast<char>(r.kind);
  if (r.kind == Response::Kind::Ack || r.kind == Response::Kind::Done) return out;
  out += ' ';
  const bool kept = r.spaces.size() == 2 * (r.items.empty() ? 0 : r.items.size() - 1);
  for (std::size_t a = 0; a < r.items.size(); ++a) {
    format_to(out, r.items[a]);
    if (a + 1 < r.items.size()) {
      out.append(kept ? r.spaces[2 * a] : 0, ' ');
      out += ',';
      out.append(kept ? r.spaces[2 * a + 1] : 1, ' ');
    }
  }
  out.append(r.trailing, ' ');
  return out;
}

Value number(double v) {
  Value out;
  out.kind = Value::Kind::Number;
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.text.assign(buf, r.ptr);
  return out;
}

Value string(std::string s) {
  Value out;
  out.kind = Value::Kind::String;
  out.text = std::move(s);
  return out;
}

Value name(std::string s) {
  Value out;
  out.kind = Value::Kind::Name;
  out.text = std::move(s);
  return out;
}

Value call(std::string n, std::vector<Value> args) {
  Value out;
  out.kind = Value::Kind::Call;
  out.text = std::move(n);
  out.args = std::move(args);
  return out;
}

}  // namespace trueaxis::ippdme
