// trueaxis::io — JSON input files whose errors name file, line and column.
//
// nlohmann::json keeps no source positions. JsonFile parses the text once into a DOM; when a
// reader finds a structural problem (a missing key, a string where a number belongs) it asks for
// the position of that value by its JSON pointer, and JsonFile finds it with a second, SAX-only
// pass over the text (error path only, so the common path pays nothing).
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>

namespace trueaxis::io {

// Limits of what a JSON reader accepts: nesting depth, and the size of a number (subnormal
// numbers, below 2.2e-308, are refused too).
constexpr std::size_t kMaxJsonDepth = 64;
constexpr double kMaxJsonMagnitude = 1e12;

class JsonFile {
 public:
  using json = nlohmann::json;
  using pointer = nlohmann::json::json_pointer;

  // Reads and parses `path`. Throws Error "path:line:col: invalid JSON: ..." on syntax errors and
  // "path: cannot open ..." when unreadable.
  static JsonFile read(const std::string& path);
  // Parses `text`; `path` is used in messages only.
  static JsonFile parse(std::string text, std::string path);

  const json& root() const { return root_; }
  const std::string& path() const { return path_; }

  // "path:line:col: " of the value at `p` (the start of its token). If `p` does not exist, the
  // position of its deepest existing parent. "path: " if nothing can be located.
  std::string where(const pointer& p) const;
  // Throws Error(where(p) + what).
  [[noreturn]] void fail(const pointer& p, const std::string& what) const;

  // Typed access with located errors. `p` must point to a number (finite) / string / array /
  // object; otherwise fail() with a message naming the pointer and the expected type.
  double number(const pointer& p) const;
  std::string string(const pointer& p) const;
  const json& array(const pointer& p) const;
  const json& object(const pointer& p) const;
  // The array of numbers at `p`, each times `scale`; every element checked like number().
  Eigen::VectorXd numbers(const pointer& p, double scale = 1.0) const;
  bool has(const pointer& p) const { return root_.contains(p); }

 private:
  std::string path_, text_;
  json root_;
};

// Writes `j` (indented by one space, newline-terminated) to `path`. Throws Error naming the path
// if it cannot be written.
void write_json(const std::string& path, const nlohmann::ordered_json& j);

// "/a/b/3" -> "a.b[3]", the way users read paths in messages.
std::string dotted(const JsonFile::pointer& p);

}  // namespace trueaxis::io
