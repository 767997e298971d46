// trueaxis::io — CSV tables with a header row.
//
// Format: first non-blank line is the header (comma-separated names); every further non-blank
// line holds one number per column. Fields may be padded with spaces; "\r\n" and "\r" line ends
// and a UTF-8 byte-order mark are accepted. What spreadsheets write in other locales reads to the
// same numbers: Excel's "sep=;" first line, ';' or tab separators with decimal commas, RFC 4180
// quoted fields, a Latin-1 'µ' in a header name (read as UTF-8). Readers reject anything malformed
// with an Error whose message names the file, the 1-based line and the 1-based character column:
// non-numbers, NaN/Inf, missing or extra fields, duplicated or empty column names.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "trueaxis/io/units.hpp"

namespace trueaxis::io {

// A parsed numeric CSV table, column-major.
class CsvTable {
 public:
  // Parses `text`; `path` is used only in error messages.
  static CsvTable parse(std::string text, std::string path);
  // Reads and parses the file at `path`. Throws Error when the file cannot be read.
  static CsvTable read(const std::string& path);

  const std::string& path() const { return path_; }
  const std::vector<std::string>& header() const { return header_; }
  std::size_t rows() const { return rows_; }
  std::size_t cols() const { return header_.size(); }

  // Index of the column called `name`, or else of a column holding `name` with a unit in its name
  // ("name [mm]"), or -1. Values are not converted: see find(quantity, unit).
  int find(std::string_view name) const;
  // Index of the column called `name`; throws Error naming the file and header line otherwise.
  int require(std::string_view name) const;
  // Index of the column holding `quantity` in a unit of `unit`'s kind, or -1. Its name may carry
  // the unit, "x [mm]", "x (µm)", "x / nm", "x_mm" (see units.hpp); the values are then
  // converted to `unit` in place, once. A name without a unit is taken to be in `unit`. Throws
  // Error naming the header field when the unit is of another kind ("deviation [s]"), or a plain
  // number carries one, or two columns hold the quantity ("x" and "x [mm]").
  int find(std::string_view quantity, Unit unit);
  // As find(quantity, unit); throws Error naming the file and header line when there is none.
  int require(std::string_view quantity, Unit unit);
  // Column values (length rows()).
  const Eigen::VectorXd& column(int c) const { return columns_[static_cast<std::size_t>(c)]; }

  // "path:line:col: " for the field at (row, col); row -1 means the header line.
  std::string where(long row, int col) const;

 private:
  // The whole file's text (for locating fields in messages), kept alive by its owner: a string
  // or a read-only mapping of the file.
  static CsvTable parse_text(std::shared_ptr<const void> owner, std::string_view text,
                             std::string path);
  std::string path_;
  std::shared_ptr<const void> text_owner_;
  std::string_view text_;
  std::vector<std::string> header_;
  std::vector<Eigen::VectorXd> columns_;
  // The unit each column's values are in once find(quantity, unit) converted them; nullopt
  // before.
  std::vector<std::optional<Unit>> unit_;
  std::size_t header_start_ = 0, header_line_ = 1;  // byte offset and 1-based line of the header
  std::size_t data_start_ = 0;                      // byte offset just after the header line
  std::size_t rows_ = 0;
};

// Writes a CSV with a header row. All columns must have the same length. Numbers are written
// with the shortest representation that reads back exactly. Throws Error if the file cannot be
// written. The path "-" writes to standard output.
void write_csv(const std::string& path, const std::vector<std::string>& header,
               const std::vector<const Eigen::VectorXd*>& columns);

}  // namespace trueaxis::io
