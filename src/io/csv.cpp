#include "trueaxis/io/csv.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>

#include "trueaxis/error.hpp"

namespace trueaxis::io {
namespace {

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r';
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

bool blank(std::string_view line) {
  return trim(line).empty();
}

}  // namespace

CsvTable CsvTable::read(const std::string& path) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) throw Error(fmt::format("{}: cannot open file for reading", path));
  std::string text;
  char buf[1 << 16];
  std::size_t got;
  while ((got = std::fread(buf, 1, sizeof buf, f.get())) > 0) text.append(buf, got);
  if (std::ferror(f.get())) throw Error(fmt::format("{}: read error", path));
  return parse(std::move(text), path);
}

CsvTable CsvTable::parse(std::string text, std::string path) {
  CsvTable t;
  t.path_ = std::move(path);
  t.text_ = std::move(text);
  const std::string_view all(t.text_);
  std::size_t pos = 0, line = 0;
  auto next_line = [&](std::string_view& out, std::size_t& start) {
    if (pos >= all.size()) return false;
    start = pos;
    const std::size_t nl = all.find('\n', pos);
    const std::size_t end = nl == std::string_view::npos ? all.size() : nl;
    out = all.substr(pos, end - pos);
    pos = nl == std::string_view::npos ? all.size() : nl + 1;
    ++line;
    return true;
  };

  std::string_view l;
  std::size_t start = 0;
  bool have_header = false;
  while (next_line(l, start)) {
    if (blank(l)) continue;
    have_header = true;
    break;
  }
  if (!have_header) throw Error(fmt::format("{}:1:1: empty file: expected a header row", t.path_));
  t.header_start_ = start;
  t.header_line_ = line;
  {
    std::size_t f0 = 0;
    while (true) {
      const std::size_t comma = l.find(',', f0);
      const std::string_view field =
          trim(l.substr(f0, comma == std::string_view::npos ? std::string_view::npos : comma - f0));
      const int col = static_cast<int>(t.header_.size());
      if (field.empty())
        throw Error(
            fmt::format("{}:{}:{}: empty column name (column {})", t.path_, line, f0 + 1, col + 1));
      for (const auto& h : t.header_)
        if (h == field)
          throw Error(
              fmt::format("{}:{}:{}: duplicated column name '{}'", t.path_, line, f0 + 1, field));
      t.header_.emplace_back(field);
      if (comma == std::string_view::npos) break;
      f0 = comma + 1;
    }
  }
  const std::size_t ncol = t.header_.size();
  // Estimate rows from the byte count to avoid repeated reallocation.
  const std::size_t guess = all.size() / std::max<std::size_t>(1, l.size() + 1) + 16;
  std::vector<std::vector<double>> cols(ncol);
  for (auto& c : cols) c.reserve(guess);
  t.line_start_.reserve(guess);
  t.line_no_.reserve(guess);

  while (next_line(l, start)) {
    if (blank(l)) continue;
    std::size_t f0 = 0;
    for (std::size_t c = 0; c < ncol; ++c) {
      if (f0 > l.size())
        throw Error(fmt::format("{}:{}:{}: missing field for column '{}' ({} expected, {} found)",
                                t.path_, line, l.size() + 1, t.header_[c], ncol, c));
      std::size_t comma = l.find(',', f0);
      if (comma == std::string_view::npos) comma = l.size();
      const char* b = l.data() + f0;
      const char* e = l.data() + comma;
      while (b < e && is_space(*b)) ++b;
      while (e > b && is_space(e[-1])) --e;
      const std::size_t colno = static_cast<std::size_t>(b - l.data()) + 1;
      if (b == e)
        throw Error(fmt::format("{}:{}:{}: empty field in column '{}'", t.path_, line, f0 + 1,
                                t.header_[c]));
      if (*b == '+') ++b;  // from_chars rejects a leading '+'
      double v = 0;
      const auto r = std::from_chars(b, e, v);
      if (r.ec == std::errc::result_out_of_range) {
        throw Error(fmt::format("{}:{}:{}: number out of range in column '{}'", t.path_, line,
                                colno, t.header_[c]));
      }
      if (r.ec != std::errc() || r.ptr != e)
        throw Error(fmt::format(
            "{}:{}:{}: '{}' is not a number (column '{}')", t.path_, line, colno,
            std::string_view(l.data() + colno - 1, e - (l.data() + colno - 1)), t.header_[c]));
      if (!std::isfinite(v))
        throw Error(fmt::format("{}:{}:{}: {} is not allowed (column '{}')", t.path_, line, colno,
                                std::isnan(v) ? "NaN" : "Inf", t.header_[c]));
      cols[c].push_back(v);
      f0 = comma + 1;
    }
    if (f0 <= l.size())
      throw Error(fmt::format("{}:{}:{}: extra field: the header has {} columns", t.path_, line,
                              f0 + 1, ncol));
    t.line_start_.push_back(start);
    t.line_no_.push_back(line);
  }
  t.rows_ = t.line_no_.size();
  t.columns_.resize(ncol);
  for (std::size_t c = 0; c < ncol; ++c)
    t.columns_[c] = Eigen::Map<const Eigen::VectorXd>(cols[c].data(),
                                                      static_cast<Eigen::Index>(cols[c].size()));
  return t;
}

int CsvTable::find(std::string_view name) const {
  for (std::size_t i = 0; i < header_.size(); ++i)
    if (header_[i] == name) return static_cast<int>(i);
  return -1;
}

int CsvTable::require(std::string_view name) const {
  const int c = find(name);
  if (c < 0) {
    std::string have;
    for (const auto& h : header_) have += (have.empty() ? "" : ", ") + h;
    throw Error(fmt::format("{}:{}:1: missing column '{}' (header has: {})", path_, header_line_,
                            name, have));
  }
  return c;
}

std::string CsvTable::where(long row, int col) const {
  const std::size_t start = row < 0 ? header_start_ : line_start_.at(static_cast<std::size_t>(row));
  const std::size_t lineno = row < 0 ? header_line_ : line_no_.at(static_cast<std::size_t>(row));
  // Walk to the start of field `col`, skipping padding, to give the exact character column.
  std::size_t p = start;
  for (int c = 0; c < col && p < text_.size() && text_[p] != '\n'; ++p)
    if (text_[p] == ',') ++c;
  while (p < text_.size() && (text_[p] == ' ' || text_[p] == '\t')) ++p;
  return fmt::format("{}:{}:{}: ", path_, lineno, p - start + 1);
}

void write_csv(const std::string& path, const std::vector<std::string>& header,
               const std::vector<const Eigen::VectorXd*>& columns) {
  if (header.size() != columns.size()) throw Error("write_csv: header and columns differ in size");
  const Eigen::Index n = columns.empty() ? 0 : columns.front()->size();
  for (const auto* c : columns)
    if (c->size() != n) throw Error("write_csv: columns differ in length");
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "wb"), &std::fclose);
  if (!f) throw Error(fmt::format("{}: cannot open file for writing", path));
  fmt::memory_buffer buf;
  for (std::size_t c = 0; c < header.size(); ++c) {
    if (c) buf.push_back(',');
    fmt::format_to(std::back_inserter(buf), "{}", header[c]);
  }
  buf.push_back('\n');
  for (Eigen::Index r = 0; r < n; ++r) {
    for (std::size_t c = 0; c < columns.size(); ++c) {
      if (c) buf.push_back(',');
      fmt::format_to(std::back_inserter(buf), "{}", (*columns[c])[r]);
    }
    buf.push_back('\n');
    if (buf.size() > (1u << 20)) {
      std::fwrite(buf.data(), 1, buf.size(), f.get());
      buf.clear();
    }
  }
  if (std::fwrite(buf.data(), 1, buf.size(), f.get()) != buf.size() || std::fflush(f.get()) != 0)
    throw Error(fmt::format("{}: write error", path));
}

}  // namespace trueaxis::io
