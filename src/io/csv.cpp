#include "trueaxis/io/csv.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>

#include "../common/memory.hpp"
#include "fast_text.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::io {
namespace {

constexpr double kMaxCsvMagnitude = 1e12;

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r';
}

std::string_view trim_spaces(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

bool blank(std::string_view line) {
  return trim_spaces(line).empty();
}

}  // namespace

CsvTable CsvTable::read(const std::string& path) {
  detail::Text text = detail::Text::read(path);
  const std::string_view view = text.view();
  return parse_text(std::move(text).owner(), view, path);
}

namespace {

// One contiguous range of whole lines, parsed independently. Errors are kept, not thrown, so the
// earliest one in the file can be reported with its absolute line number.
struct Chunk {
  std::vector<double> values;  // row-major, ncol per row
  std::size_t lines = 0;       // newlines seen (blank lines included)
  std::size_t rows = 0;
  bool failed = false;
  std::size_t fail_line = 0;  // 0-based line within the chunk
  std::size_t fail_col = 0;   // 1-based character column
  std::string fail_what;
};

// One plain data row from `p` (at a line's start): ncol numbers separated by commas, each padded
// with spaces at most, then the line's end. Appends them and returns the start of the next line,
// or returns nullptr, appending nothing, for anything else (a blank line, a malformed or
// out-of-range field), which the careful path below then reads and reports. It reads each field
// as the careful path does (from_chars after an optional '+'); it only skips the searches for
// the line's end and each comma, which cost more than the numbers on short fields.
const char* plain_row(const char* p, const char* end, std::size_t ncol, std::vector<double>& out) {
  const std::size_t size0 = out.size();
  auto reject = [&]() -> const char* {
    out.resize(size0);
    return nullptr;
  };
  for (std::size_t c = 0; c < ncol; ++c) {
    while (p < end && is_space(*p)) ++p;
    const char* num = p < end && *p == '+' ? p + 1 : p;
    double v = 0;
    const auto r = std::from_chars(num, end, v);
    if (r.ec != std::errc() || !std::isfinite(v) || std::abs(v) > kMaxCsvMagnitude) return reject();
    p = r.ptr;
    while (p < end && is_space(*p)) ++p;
    if (c + 1 < ncol) {
      if (p == end || *p != ',') return reject();
      ++p;
    }
    out.push_back(v);
  }
  if (p == end) return p;
  return *p == '\n' ? p + 1 : reject();
}

// `original`: the same bytes as the file has them (a dialect's text, converted, has the same length
// and positions), for quoting a field in a message as the user wrote it.
void parse_chunk(std::string_view text, std::string_view original,
                 const std::vector<std::string>& header, Chunk& out) {
  const std::size_t ncol = header.size();
  out.values.reserve(text.size() / (ncol * 8 + 1) * ncol + ncol);
  trueaxis::detail::advise_huge_pages(out.values.data(), out.values.capacity() * sizeof(double));
  std::size_t pos = 0;
  auto fail = [&](std::size_t col, std::string what) {
    out.failed = true;
    out.fail_line = out.lines;
    out.fail_col = col;
    out.fail_what = std::move(what);
  };
  const char* const text_end = text.data() + text.size();
  while (pos < text.size()) {
    if (const char* next = plain_row(text.data() + pos, text_end, ncol, out.values)) {
      pos = static_cast<std::size_t>(next - text.data());
      ++out.rows;
      ++out.lines;
      continue;
    }
    const std::size_t nl = text.find('\n', pos);
    const std::size_t end = nl == std::string_view::npos ? text.size() : nl;
    const std::string_view l = text.substr(pos, end - pos);
    pos = nl == std::string_view::npos ? text.size() : nl + 1;
    if (blank(l)) {
      ++out.lines;
      continue;
    }
    std::size_t f0 = 0;
    for (std::size_t c = 0; c < ncol; ++c) {
      if (f0 > l.size())
        return fail(l.size() + 1,
                    fmt::format("missing field for column '{}' ({} expected, {} found)", header[c],
                                ncol, c));
      std::size_t comma = l.find(',', f0);
      if (comma == std::string_view::npos) comma = l.size();
      const char* b = l.data() + f0;
      const char* e = l.data() + comma;
      while (b < e && is_space(*b)) ++b;
      while (e > b && is_space(e[-1])) --e;
      const std::size_t colno = static_cast<std::size_t>(b - l.data()) + 1;
      if (b == e) return fail(f0 + 1, fmt::format("empty field in column '{}'", header[c]));
      const char* num = *b == '+' ? b + 1 : b;  // from_chars rejects a leading '+'
      double v = 0;
      const auto r = std::from_chars(num, e, v);
      if (r.ec == std::errc::result_out_of_range)
        return fail(colno, fmt::format("number out of range in column '{}'", header[c]));
      if (r.ec != std::errc() || r.ptr != e)
        return fail(
            colno,
            fmt::format("'{}' is not a number (column '{}')",
                        detail::quote_cut(original.substr(static_cast<std::size_t>(b - text.data()),
                                                          static_cast<std::size_t>(e - b))),
                        header[c]));
      if (!std::isfinite(v))
        return fail(colno, fmt::format("{} is not allowed (column '{}')",
                                       std::isnan(v) ? "NaN" : "Inf", header[c]));
      // No position (mm), deviation (µm), angle (µrad) or current in a trueaxis table comes near
      // this; beyond it a value is corruption, and would come out as inf or NaN downstream.
      if (std::abs(v) > kMaxCsvMagnitude)
        return fail(colno, fmt::format("{:g} is out of range in column '{}' (its size must be "
                                       "below {:g})",
                                       v, header[c], kMaxCsvMagnitude));
      out.values.push_back(v);
      f0 = comma + 1;
    }
    if (f0 <= l.size())
      return fail(f0 + 1, fmt::format("extra field: the header has {} columns", ncol));
    ++out.rows;
    ++out.lines;
  }
}

// A header name as a spreadsheet on Windows may write it: a lone Latin-1 / Windows-1252 'µ'
// (byte 0xB5) becomes UTF-8 "µ".
std::string header_name(std::string_view field) {
  std::string out;
  for (std::size_t i = 0; i < field.size(); ++i) {
    const auto c = static_cast<unsigned char>(field[i]);
    const bool after_c2 = i > 0 && static_cast<unsigned char>(field[i - 1]) == 0xC2;
    if (c == 0xB5 && !after_c2)
      out += "\xC2\xB5";  // UTF-8 µ
    else
      out += field[i];
  }
  return out;
}

}  // namespace

CsvTable CsvTable::parse(std::string text, std::string path) {
  detail::normalize_text(text);
  auto owned = std::make_shared<const std::string>(std::move(text));
  const std::string_view view(*owned);
  return parse_text(std::move(owned), view, std::move(path));
}

CsvTable CsvTable::parse_text(std::shared_ptr<const void> owner, std::string_view text,
                              std::string path) {
  CsvTable t;
  t.path_ = std::move(path);
  t.text_owner_ = std::move(owner);
  t.text_ = text;
  const std::string_view original = text;
  if (std::optional<std::string> plain = detail::plain_csv(text, t.path_)) {
    // A spreadsheet's dialect, rewritten; the file's own text is kept for quoting fields.
    struct Both {
      std::shared_ptr<const void> file;
      std::string plain;
    };
    auto both = std::make_shared<Both>(Both{std::move(t.text_owner_), std::move(*plain)});
    t.text_ = both->plain;
    t.text_owner_ = std::move(both);
  }
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
      const std::string header_field = header_name(trim_spaces(
          l.substr(f0, comma == std::string_view::npos ? std::string_view::npos : comma - f0)));
      const std::string_view field = header_field;
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
  t.data_start_ = pos;

  // Data rows: split at line boundaries into one chunk per worker, parse in parallel, then
  // gather into columns. The result (and the first error reported) is that of a sequential parse.
  const std::string_view data = all.substr(pos), data_original = original.substr(pos);
  const int w = detail::workers_for(data.size() / 64);
  std::vector<std::size_t> cut{0};
  for (int k = 1; k < w; ++k) {
    std::size_t c = data.size() * static_cast<std::size_t>(k) / static_cast<std::size_t>(w);
    c = std::max(c, cut.back());
    const std::size_t nl = data.find('\n', c);
    cut.push_back(nl == std::string_view::npos ? data.size() : nl + 1);
  }
  cut.push_back(data.size());
  std::vector<Chunk> chunks(static_cast<std::size_t>(w));
  detail::parallel_ranges(static_cast<std::size_t>(w), w, [&](int, std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k)
      parse_chunk(data.substr(cut[k], cut[k + 1] - cut[k]),
                  data_original.substr(cut[k], cut[k + 1] - cut[k]), t.header_, chunks[k]);
  });
  std::size_t first_line = line + 1, rows = 0;
  std::vector<std::size_t> row0;
  for (const Chunk& c : chunks) {
    if (c.failed)
      throw Error(
          fmt::format("{}:{}:{}: {}", t.path_, first_line + c.fail_line, c.fail_col, c.fail_what));
    row0.push_back(rows);
    first_line += c.lines;
    rows += c.rows;
  }
  t.rows_ = rows;
  // Each column allocated, not copied from a prototype (assign() would copy 8 bytes per row and
  // column of uninitialised memory, faulting in every page on one core): the gather below writes
  // every entry, and commits the pages on all workers.
  t.columns_.clear();
  t.columns_.reserve(ncol);
  for (std::size_t c = 0; c < ncol; ++c)
    trueaxis::detail::resize_in_huge_pages(t.columns_.emplace_back(),
                                           static_cast<Eigen::Index>(rows), 1);
  detail::parallel_ranges(chunks.size(), w, [&](int, std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k) {
      const double* v = chunks[k].values.data();
      for (std::size_t r = 0; r < chunks[k].rows; ++r)
        for (std::size_t c = 0; c < ncol; ++c)
          t.columns_[c][static_cast<Eigen::Index>(row0[k] + r)] = *v++;
    }
  });
  return t;
}

int CsvTable::find(std::string_view name) const {
  for (std::size_t i = 0; i < header_.size(); ++i)
    if (header_[i] == name) return static_cast<int>(i);
  for (std::size_t i = 0; i < header_.size(); ++i) {
    try {
      if (column_matches(header_[i], name).holds) return static_cast<int>(i);
    } catch (const Error&) {
      // a name with something not a unit in brackets: not this column
    }
  }
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

int CsvTable::find(std::string_view quantity, Unit unit) {
  int found = -1;
  std::optional<Unit> written;
  for (std::size_t i = 0; i < header_.size(); ++i) {
    ColumnMatch m;
    try {
      m = column_matches(header_[i], quantity);
    } catch (const Error& e) {
      throw Error(where(-1, static_cast<int>(i)) + e.what());
    }
    if (!m.holds) continue;
    if (found >= 0)
      throw Error(fmt::format("{}columns '{}' and '{}' both hold {}",
                              where(-1, static_cast<int>(i)),
                              header_[static_cast<std::size_t>(found)], header_[i], quantity));
    found = static_cast<int>(i);
    written = m.unit;
  }
  if (found < 0) return -1;
  const auto c = static_cast<std::size_t>(found);
  if (unit_.size() != header_.size()) unit_.assign(header_.size(), std::nullopt);
  if (unit_[c]) {
    if (*unit_[c] != unit)
      throw Error(fmt::format("{}column '{}' was read in {} and is now asked for in {}",
                              where(-1, found), header_[c], symbol(*unit_[c]), symbol(unit)));
    return found;
  }
  if (written)
    if (const std::string why = unit_refusal(header_[c], *written, quantity, unit); !why.empty())
      throw Error(where(-1, found) + why);
  if (written && *written != unit) columns_[c] *= unit_factor(*written, unit);
  unit_[c] = unit;
  return found;
}

int CsvTable::require(std::string_view quantity, Unit unit) {
  const int c = find(quantity, unit);
  return c < 0 ? require(quantity) : c;  // require(name) names what the header has
}

std::string CsvTable::where(long row, int col) const {
  // Error path only: walk the text to the row's line (rows are the non-blank lines after the
  // header), then to the start of field `col`, skipping padding, for the exact character column.
  std::size_t start = header_start_, lineno = header_line_;
  if (row >= 0) {
    if (static_cast<std::size_t>(row) >= rows_) throw Error("CsvTable::where: row out of range");
    std::size_t p = data_start_, n = header_line_;
    long seen = -1;
    while (p < text_.size()) {
      const std::size_t nl = std::min(text_.find('\n', p), text_.size());
      ++n;
      if (!blank(text_.substr(p, nl - p)) && ++seen == row) {
        start = p;
        lineno = n;
        break;
      }
      p = nl + 1;
    }
  }
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
  detail::OutFile f(path);
  std::string head;
  for (std::size_t c = 0; c < header.size(); ++c) head += (c ? "," : "") + header[c];
  f.write(head + "\n");
  std::vector<const double*> ptrs;
  for (const auto* c : columns) ptrs.push_back(c->data());
  std::vector<std::string> pieces;
  detail::format_rows(ptrs, static_cast<std::size_t>(n), pieces);
  f.write(pieces);
  f.close();
}

}  // namespace trueaxis::io
