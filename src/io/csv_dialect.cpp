// What spreadsheets and instruments write besides plain CSV (RFC 4180): Excel's "sep=;" first
// line, semicolon- or tab-separated columns with decimal commas (the German, French and Italian
// locales), quoted fields. Every CSV reader rewrites such a text into plain CSV of exactly the
// same length, byte for byte, so that each line and column a message names is the file's own.
#include <fmt/format.h>

#include <optional>
#include <string>
#include <string_view>

#include "fast_text.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::io::detail {
namespace {

// The line "sep=X" that Excel writes before the header (X one character), or 0.
char excel_separator(std::string_view line) {
  const std::string_view t = trim(line);
  if (t.size() == 5 && (t.substr(0, 4) == "sep=" || t.substr(0, 4) == "SEP=")) return t[4];
  return 0;
}

}  // namespace

std::optional<std::string> plain_csv(std::string_view text, const std::string& path) {
  // The first non-blank line that is not a comment, and the one after it if that is "sep=X".
  std::size_t pos = 0, line = 0, sep_start = std::string_view::npos, sep_size = 0;
  std::string_view header;
  std::size_t header_start = 0, header_line = 0;
  char separator = 0;
  while (pos < text.size()) {
    const std::size_t nl = std::min(text.find('\n', pos), text.size());
    const std::string_view l = text.substr(pos, nl - pos);
    ++line;
    // (The text is normalised: no CR. '#' starts a comment line in the runs files.)
    if (const std::string_view content = trim(l); !content.empty() && content.front() != '#') {
      const char excel = sep_start == std::string_view::npos ? excel_separator(l) : 0;
      if (excel) {
        separator = excel;
        sep_start = pos;
        sep_size = l.size();
      } else {
        header = l;
        header_start = pos;
        header_line = line;
        break;
      }
    }
    pos = nl + 1;
  }
  if (!separator) {
    if (header.find(';') != std::string_view::npos)
      separator = ';';
    else if (header.find('\t') != std::string_view::npos &&
             header.find(',') == std::string_view::npos)
      separator = '\t';
    else
      separator = ',';
  }
  const bool quotes = text.find('"', header_start) != std::string_view::npos;
  if (separator == ',' && !quotes && sep_start == std::string_view::npos) return std::nullopt;
  std::string out(text);
  if (sep_start != std::string_view::npos) out.replace(sep_start, sep_size, sep_size, ' ');
  // Outside quotes the separator becomes ',' and, when the separator is not ',', a ',' is a
  // decimal comma and becomes '.'; inside quotes a ',' is a decimal comma; the quotes become
  // spaces, which the readers trim.
  bool quoted = false;
  std::size_t ln = header_line, line_start = header_start, open_at = 0;
  auto unclosed = [&] {
    return Error(fmt::format("{}:{}:{}: a quoted field is not closed on its line", path, ln,
                             open_at - line_start + 1));
  };
  for (std::size_t i = header_start; i < out.size(); ++i) {
    char& c = out[i];
    if (c == '\n') {
      if (quoted) throw unclosed();
      ++ln;
      line_start = i + 1;
    } else if (c == '"') {
      if (!quoted) open_at = i;
      quoted = !quoted;
      c = ' ';
    } else if (c == ',') {
      if (quoted || separator != ',') c = '.';
    } else if (c == separator && !quoted) {
      c = ',';
    }
  }
  if (quoted) throw unclosed();
  return out;
}

}  // namespace trueaxis::io::detail
