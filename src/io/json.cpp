#include "trueaxis/io/json.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <vector>

#include "fast_text.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::io {
namespace {

std::string line_col(std::string_view text, std::size_t byte) {
  std::size_t line = 1, col = 1;
  for (std::size_t i = 0; i < byte && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      col = 1;
    } else {
      ++col;
    }
  }
  return fmt::format("{}:{}", line, col);
}

// A char iterator that publishes how far the parser has read.
struct CountingIterator {
  using iterator_category = std::forward_iterator_tag;
  using value_type = char;
  using difference_type = std::ptrdiff_t;
  using pointer = const char*;
  using reference = const char&;
  const char* p = nullptr;
  const char** cursor = nullptr;
  reference operator*() const { return *p; }
  CountingIterator& operator++() {
    *cursor = ++p;
    return *this;
  }
  CountingIterator operator++(int) {
    CountingIterator t = *this;
    ++*this;
    return t;
  }
  bool operator==(const CountingIterator& o) const { return p == o.p; }
  bool operator!=(const CountingIterator& o) const { return p != o.p; }
};

// SAX pass that tracks the JSON pointer of every value and stops at the target (or remembers the
// deepest existing parent of the target).
class Locator : public nlohmann::json_sax<nlohmann::json> {
 public:
  Locator(const char* begin, const char** cursor, std::vector<std::string> target)
      : begin_(begin), cursor_(cursor), target_(std::move(target)) {}

  std::ptrdiff_t found = -1;  // byte offset of the best match
  std::size_t found_depth = 0;

  bool null() override { return value(); }
  bool boolean(bool) override { return value(); }
  bool number_integer(number_integer_t) override { return value(); }
  bool number_unsigned(number_unsigned_t) override { return value(); }
  bool number_float(number_float_t, const string_t&) override { return value(); }
  bool string(string_t&) override { return value(); }
  bool binary(binary_t&) override { return value(); }
  bool start_object(std::size_t) override {
    if (!value(true)) return false;
    stack_.push_back({false, 0, {}});
    return true;
  }
  bool key(string_t& k) override {
    stack_.back().key = k;
    prev_ = *cursor_;
    return true;
  }
  bool end_object() override { return end(); }
  bool start_array(std::size_t) override {
    if (!value(true)) return false;
    stack_.push_back({true, 0, {}});
    return true;
  }
  bool end_array() override { return end(); }
  bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) override {
    return false;
  }

 private:
  struct Frame {
    bool array;
    std::size_t index;
    std::string key;
  };
  bool end() {
    stack_.pop_back();
    advance_index();
    prev_ = *cursor_;
    return true;
  }
  void advance_index() {
    if (!stack_.empty() && stack_.back().array) ++stack_.back().index;
  }
  // A value starts: its token begins at the first character after the previous event that is
  // not white space or a separator.
  bool value(bool container = false) {
    const char* s = prev_ ? prev_ : begin_;
    while (*s == ' ' || *s == '\t' || *s == '\r' || *s == '\n' || *s == ',' || *s == ':') ++s;
    // Does the current path match a prefix of the target?
    std::size_t depth = 0;
    bool match = true;
    for (const Frame& f : stack_) {
      if (depth >= target_.size()) {
        match = false;
        break;
      }
      const std::string seg = f.array ? std::to_string(f.index) : f.key;
      if (seg != target_[depth]) {
        match = false;
        break;
      }
      ++depth;
    }
    if (match && (found < 0 || depth > found_depth)) {
      found = s - begin_;
      found_depth = depth;
    }
    if (match && depth == target_.size()) return false;  // exact hit: stop
    if (!container) advance_index();  // a container's index advances when it ends
    prev_ = *cursor_;
    return true;
  }

  const char* begin_;
  const char** cursor_;
  const char* prev_ = nullptr;
  std::vector<std::string> target_;
  std::vector<Frame> stack_;
};

// A SAX handler that accepts every event and stops at an error: the base of the passes below.
struct AcceptAll : nlohmann::json_sax<nlohmann::json> {
  bool null() override { return true; }
  bool boolean(bool) override { return true; }
  bool number_integer(number_integer_t) override { return true; }
  bool number_unsigned(number_unsigned_t) override { return true; }
  bool number_float(number_float_t, const string_t&) override { return true; }
  bool string(string_t&) override { return true; }
  bool binary(binary_t&) override { return true; }
  bool start_object(std::size_t) override { return true; }
  bool key(string_t&) override { return true; }
  bool end_object() override { return true; }
  bool start_array(std::size_t) override { return true; }
  bool end_array() override { return true; }
  bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) override {
    return false;
  }
};

// Where a SAX parse stops with an error (nlohmann's DOM parser reports a number too large for a
// double, '1e309', without a position).
struct ErrorPosition : AcceptAll {
  std::size_t byte = 0;
  std::string token;
  bool parse_error(std::size_t position, const std::string& last_token,
                   const nlohmann::detail::exception&) override {
    byte = position;
    token = last_token;
    return false;
  }
};

// Byte offset of the first key that repeats a key of its own object (SAX pass with a cursor; the
// error path only).
std::size_t second_key_position(const std::string& text) {
  struct Keys : AcceptAll {
    const char* begin;
    const char** cursor;
    std::vector<std::vector<std::string>> open;
    std::ptrdiff_t found = -1;
    bool start_object(std::size_t) override {
      open.emplace_back();
      return true;
    }
    bool key(string_t& k) override {
      auto& keys = open.back();
      if (std::find(keys.begin(), keys.end(), k) != keys.end()) {
        // The cursor is just past the key's closing quote: back to its opening one.
        const char* q = *cursor - 1;
        while (q > begin && *q != '"') --q;
        --q;
        while (q > begin && *q != '"') --q;
        found = q - begin;
        return false;
      }
      keys.push_back(k);
      return true;
    }
    bool end_object() override {
      open.pop_back();
      return true;
    }
  } keys;
  const char* cursor = text.data();
  keys.begin = text.data();
  keys.cursor = &cursor;
  CountingIterator first{text.data(), &cursor};
  CountingIterator last{text.data() + text.size(), &cursor};
  nlohmann::json::sax_parse(first, last, &keys);
  return keys.found < 0 ? 0 : static_cast<std::size_t>(keys.found);
}

// nlohmann's message with the input it quotes ("last read: '...'") cut to a few dozen
// characters: a malformed file must not be echoed whole.
// The JSON parser's message in words: what was found where, and what was expected there
// (nlohmann's "[json.exception.parse_error.101] parse error at line 1, column 7: syntax error
// while parsing value - invalid literal; last read: 'I'" becomes "'I' is not a JSON value").
std::string short_message(const std::string& what) {
  std::string m = what;
  if (const std::size_t colon = m.find(": ");
      m.rfind("[json.exception.", 0) == 0 && colon != std::string::npos)
    m = m.substr(colon + 2);
  if (const std::size_t dash = m.find(" - ");
      m.rfind("syntax error while parsing", 0) == 0 && dash != std::string::npos)
    m = m.substr(dash + 3);
  std::string read;
  const std::string key = "; last read: '";
  if (const std::size_t at = m.find(key); at != std::string::npos) {
    const std::size_t from = at + key.size();
    std::size_t to = m.find("'; ", from);
    if (to == std::string::npos) to = m.rfind('\'');
    if (to == std::string::npos || to < from) to = m.size();
    read = m.substr(from, to - from);
    m = m.substr(0, at) + (to + 1 < m.size() ? m.substr(to + 1) : "");
  }
  const auto replace = [&m](const std::string& from, const std::string& to) {
    if (const std::size_t at = m.find(from); at != std::string::npos)
      m.replace(at, from.size(), to);
  };
  replace("invalid literal",
          "not a JSON value (a number, \"text\", true, false, null, {...} or [...])");
  replace("unexpected end of input", "the text ends before the JSON does (a '}' or ']' missing?)");
  replace("unexpected string literal",
          "unexpected text in double quotes (a ',' missing before it?)");
  replace("; expected string literal", "; expected a key in double quotes");
  replace("expected '[', '{', or a literal", "expected a value");
  replace("invalid string: control character",
          "a line break or control character inside a string:");
  // The last token read: what stood where a value was expected ("tru" of '"a": tru}').
  if (const std::size_t cut = read.find_last_of("{[,: ");
      cut != std::string::npos && cut + 1 < read.size())
    read = read.substr(cut + 1);
  while (read.size() > 1 && (read.back() == '}' || read.back() == ']')) read.pop_back();
  if (!read.empty() && m.rfind("the text ends", 0) != 0)
    return fmt::format("'{}': {}", detail::quote_cut(read), m);
  return detail::quote_cut(m, 200);
}

}  // namespace

JsonFile JsonFile::parse(std::string text, std::string path) {
  JsonFile j;
  j.path_ = std::move(path);
  j.text_ = std::move(text);
  detail::normalize_text(j.text_);
  // Nesting deeper than any trueaxis file needs is refused before parsing (a file nested a
  // million levels deep would otherwise take the parser's time and memory).
  {
    std::size_t depth = 0;
    bool in_string = false;
    for (std::size_t i = 0; i < j.text_.size(); ++i) {
      const char c = j.text_[i];
      if (in_string) {
        if (c == '\\')
          ++i;
        else if (c == '"')
          in_string = false;
      } else if (c == '"') {
        in_string = true;
      } else if (c == '[' || c == '{') {
        if (++depth > kMaxJsonDepth)
          throw Error(fmt::format("{}:{}: nested more than {} levels deep", j.path_,
                                  line_col(j.text_, i), kMaxJsonDepth));
      } else if ((c == ']' || c == '}') && depth > 0) {
        --depth;
      }
    }
  }
  try {
    // Keys of every open object: a repeated key is refused (nlohmann keeps the last copy
    // silently, and a message about the value would point at the first).
    std::vector<std::vector<std::string>> open_keys;
    std::string duplicate;
    const nlohmann::json::parser_callback_t cb = [&](int, nlohmann::json::parse_event_t e,
                                                     nlohmann::json& parsed) {
      using E = nlohmann::json::parse_event_t;
      if (e == E::object_start) {
        open_keys.emplace_back();
      } else if (e == E::object_end) {
        if (!open_keys.empty()) open_keys.pop_back();
      } else if (e == E::key && !open_keys.empty() && duplicate.empty()) {
        const std::string& k = parsed.get_ref<const std::string&>();
        auto& keys = open_keys.back();
        if (std::find(keys.begin(), keys.end(), k) != keys.end())
          duplicate = k;
        else
          keys.push_back(k);
      }
      return true;
    };
    j.root_ = nlohmann::json::parse(j.text_, cb);
    if (!duplicate.empty()) {
      const std::size_t at = second_key_position(j.text_);
      throw Error(fmt::format("{}:{}: duplicated key '{}'", j.path_, line_col(j.text_, at),
                              detail::quote_cut(duplicate)));
    }
  } catch (const nlohmann::json::parse_error& e) {
    throw Error(fmt::format("{}:{}: invalid JSON: {}", j.path_,
                            line_col(j.text_, e.byte ? e.byte - 1 : 0), short_message(e.what())));
  } catch (const nlohmann::json::exception& e) {
    // A number beyond the range of a double ('1e309'): find it with a SAX pass.
    ErrorPosition pos;
    nlohmann::json::sax_parse(j.text_, &pos);
    const std::size_t at = pos.byte >= pos.token.size() ? pos.byte - pos.token.size() : 0;
    if (e.id == 406)
      throw Error(fmt::format("{}:{}: the number '{}' is out of range", j.path_,
                              line_col(j.text_, at), detail::quote_cut(pos.token)));
    throw Error(fmt::format("{}:{}: invalid JSON: {}", j.path_, line_col(j.text_, at),
                            short_message(e.what())));
  }
  return j;
}

JsonFile JsonFile::read(const std::string& path) {
  return parse(detail::read_text(path), path);
}

std::string JsonFile::where(const pointer& p) const {
  std::vector<std::string> target;
  for (pointer q = p; !q.empty(); q = q.parent_pointer()) target.insert(target.begin(), q.back());
  const char* cursor = text_.data();
  Locator loc(text_.data(), &cursor, target);
  CountingIterator first{text_.data(), &cursor};
  CountingIterator last{text_.data() + text_.size(), &cursor};
  nlohmann::json::sax_parse(first, last, &loc);
  if (loc.found < 0) return path_ + ": ";
  return fmt::format("{}:{}: ", path_, line_col(text_, static_cast<std::size_t>(loc.found)));
}

void JsonFile::fail(const pointer& p, const std::string& what) const {
  throw Error(where(p) + what);
}

double JsonFile::number(const pointer& p) const {
  if (!root_.contains(p)) fail(p, fmt::format("'{}' is missing", dotted(p)));
  const json& v = root_.at(p);
  if (!v.is_number()) fail(p, fmt::format("'{}' must be a number", dotted(p)));
  const double x = v.get<double>();
  if (!std::isfinite(x)) fail(p, fmt::format("'{}' is not finite", dotted(p)));
  // No length (mm, µm), angle (µrad) or count in a trueaxis file comes near these bounds; a value
  // beyond them is a typo or corruption, and would turn into inf or NaN downstream.
  if (std::abs(x) > kMaxJsonMagnitude)
    fail(p, fmt::format("'{}' = {:g} is out of range (its size must be below {:g})", dotted(p), x,
                        kMaxJsonMagnitude));
  if (std::fpclassify(x) == FP_SUBNORMAL)
    fail(p, fmt::format("'{}' = {:g} is too small to mean anything (write 0 if it is zero)",
                        dotted(p), x));
  return x;
}

std::string JsonFile::string(const pointer& p) const {
  if (!root_.contains(p)) fail(p, fmt::format("'{}' is missing", dotted(p)));
  const json& v = root_.at(p);
  if (!v.is_string()) fail(p, fmt::format("'{}' must be a string", dotted(p)));
  return v.get<std::string>();
}

const nlohmann::json& JsonFile::array(const pointer& p) const {
  if (!root_.contains(p)) fail(p, fmt::format("'{}' is missing", dotted(p)));
  const json& v = root_.at(p);
  if (!v.is_array()) fail(p, fmt::format("'{}' must be an array", dotted(p)));
  return v;
}

const nlohmann::json& JsonFile::object(const pointer& p) const {
  if (!root_.contains(p))
    fail(p, fmt::format("'{}' is missing", p.empty() ? "(top level)" : dotted(p)));
  const json& v = root_.at(p);
  if (!v.is_object())
    fail(p, fmt::format("'{}' must be an object", p.empty() ? "(top level)" : dotted(p)));
  return v;
}

Eigen::VectorXd JsonFile::numbers(const pointer& p, double scale) const {
  const json& a = array(p);
  Eigen::VectorXd v(static_cast<Eigen::Index>(a.size()));
  for (std::size_t i = 0; i < a.size(); ++i)
    v[static_cast<Eigen::Index>(i)] = number(p / i) * scale;
  return v;
}

namespace {
// The JSON pointer of the first number that is not finite (nlohmann would write it as null).
std::string first_non_finite(const nlohmann::ordered_json& j, const std::string& at) {
  if (j.is_number_float() && !std::isfinite(j.get<double>())) return at.empty() ? "/" : at;
  if (j.is_object())
    for (const auto& [k, v] : j.items())
      if (auto w = first_non_finite(v, at + "/" + k); !w.empty()) return w;
  if (j.is_array())
    for (std::size_t i = 0; i < j.size(); ++i)
      if (auto w = first_non_finite(j[i], at + "/" + std::to_string(i)); !w.empty()) return w;
  return "";
}
}  // namespace

void write_json(const std::string& path, const nlohmann::ordered_json& j) {
  // Never a non-finite number in a result: refuse (nothing is written) instead of a null.
  if (const std::string w = first_non_finite(j, ""); !w.empty())
    throw Error(
        fmt::format("{}: the computed value at {} is not finite: the input is beyond "
                    "what these methods can handle; nothing was written",
                    path, w));
  detail::OutFile out(path);
  out.write(j.dump(1));
  out.write("\n");
  out.close();
}

std::string dotted(const JsonFile::pointer& p) {
  std::vector<std::string> segs;
  for (JsonFile::pointer q = p; !q.empty(); q = q.parent_pointer())
    segs.insert(segs.begin(), q.back());
  std::string s;
  for (const auto& seg : segs) {
    const bool index = !seg.empty() && seg.find_first_not_of("0123456789") == std::string::npos;
    if (index)
      s += "[" + seg + "]";
    else
      s += (s.empty() ? "" : ".") + seg;
  }
  return s;
}

}  // namespace trueaxis::io
