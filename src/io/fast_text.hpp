// Private: fast text output and input for large numeric files.
//
// A million-station result is ~6 million numbers (80 MB of text). Formatting each number with
// the shortest round-trip form costs ~35 ns (fmt's Dragonbox with a compiled format string), so
// the work is split over the machine's cores in contiguous ranges and the pieces are written in
// order: the bytes are identical to a sequential run.
#pragma once

#include <cstddef>
#include <cstdio>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace trueaxis::io::detail {

// The most a reader takes from one file (bytes): far above any real input (a million-station
// probe file is ~80 MB), far below what would exhaust memory while parsing.
constexpr std::size_t kMaxInputBytes = std::size_t{1} << 30;

// The whole file at `path` in one read, with normalize_text applied. Throws Error naming the
// path when it is not a regular file, is larger than kMaxInputBytes, or cannot be read.
std::string read_text(const std::string& path);

// Drops a UTF-8 byte-order mark and turns CRLF and lone CR line ends into LF, in place.
void normalize_text(std::string& text);

// A spreadsheet's CSV dialect as plain CSV, or nullopt when `text` is plain CSV already: Excel's
// "sep=X" first line (blanked), ';' or tab separators with decimal commas, RFC 4180 quoted
// fields. The rewrite has exactly the length of `text`, so lines and columns are the file's.
// Precondition: `text` is normalised (normalize_text: no CR, no byte-order mark). Throws Error
// (path:line:col) for a quoted field not closed on its line.
std::optional<std::string> plain_csv(std::string_view text, const std::string& path);

// A file's text as read_text gives it, without copying large files: a regular file of a
// megabyte or more that needs no normalising (no byte-order mark, no CR) is mapped read-only and
// its pages brought in at once (a copy into fresh memory costs ~5x as much: a page fault per 4 KB
// written); anything else is read and normalised. The view stays valid while the object (or a
// copy of it) lives. A file truncated by another program while it is mapped is beyond what this
// guards against, as with any memory-mapped reader.
class Text {
 public:
  static Text read(const std::string& path);  // the errors of read_text
  explicit Text(std::string text);            // owns text as given
  std::string_view view() const { return view_; }
  std::shared_ptr<const void> owner() && { return std::move(owner_); }  // what keeps view() valid

 private:
  Text() = default;
  std::shared_ptr<const void> owner_;
  std::string_view view_;
};

// `s` cut to its first line and at most `max` characters ("..." marks a cut), for quoting input
// in an error message.
std::string quote_cut(std::string_view s, std::size_t max = 40);

// Text helpers of the line-oriented readers: a space or tab; lower and upper case (ASCII); `s`
// without leading and trailing spaces and tabs.
inline bool is_blank(char c) {
  return c == ' ' || c == '\t';
}
std::string lower(std::string_view s);
std::string upper(std::string_view s);
std::string_view trim(std::string_view s);

// Limits of the positioning readers (the CSV runs and Renishaw's RTL): larger than any travel
// (mm) or positioning deviation (µm) of a machine tool or CMM.
constexpr double kMaxTarget = 1e6, kMaxDeviation = 1e6;

// Throws Error("path:line:col: what") (col0 is 0-based, the message's column 1-based).
[[noreturn]] void fail_at(const std::string& path, std::size_t line, std::size_t col0,
                          const std::string& what);

// Calls fn(line, text) for every line of `text` (split at '\n', as normalize_text leaves it;
// line numbers from 1).
template <class Fn>
void for_each_line(std::string_view text, Fn&& fn) {
  std::size_t pos = 0, line = 0;
  while (pos < text.size()) {
    const std::size_t nl = text.find('\n', pos);
    const std::size_t end = nl == std::string_view::npos ? text.size() : nl;
    fn(++line, text.substr(pos, end - pos));
    pos = end + 1;
  }
}

// Number of worker threads for `n` items of work (1 for small jobs).
int workers_for(std::size_t n);

// Runs fn(t, begin, end) over `workers` contiguous ranges of [0, n), one thread each (the calling
// thread runs the last range). Exceptions thrown by any range are rethrown here (the first range's
// first).
void parallel_ranges(std::size_t n, int workers,
                     const std::function<void(int, std::size_t, std::size_t)>& fn);

// Appends the shortest decimal form that reads back exactly; returns the new end. `p` must have
// room for 25 characters.
char* write_number(char* p, double v);

// Formats v[i]*scale for i in [0, n) separated by `sep` into `pieces` (concatenated in order they
// are the text), in parallel.
void format_numbers(const double* v, std::size_t n, double scale, char sep,
                    std::vector<std::string>& pieces);

// Formats rows i in [0, n) of the columns (comma-separated, one row per line, NaN written as an
// empty field) into `pieces`, in parallel.
void format_rows(const std::vector<const double*>& columns, std::size_t n,
                 std::vector<std::string>& pieces);

// A file opened for writing that reports failures as trueaxis::Error naming the path. The path
// "-" is standard output (flushed, not closed, by close()). A regular file is written to a
// temporary file in the same directory and renamed into place by close(), so that a failed or
// concurrent run never leaves a file that is half of one run and half of another; a device
// (/dev/null, /dev/full) is written directly. The directory must exist (it is not created).
class OutFile {
 public:
  explicit OutFile(const std::string& path);
  void write(std::string_view s);
  // Writes v[i]*scale for i in [0, n) separated by `sep`, formatted in parallel.
  void numbers(const double* v, std::size_t n, double scale, char sep);
  void write(const std::vector<std::string>& pieces);
  // Flushes, closes and puts the file in place; throws on a write error. A file that is never
  // closed (an exception on the way) is discarded by the destructor and the target left as it
  // was.
  void close();
  ~OutFile();

 private:
  std::string path_;     // as given (for messages)
  std::string target_;   // where the file goes; empty for standard output
  std::string partial_;  // the temporary file written first, renamed to target_ by close()
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f_;
  std::vector<std::string> pieces_;
};

}  // namespace trueaxis::io::detail
