// trueaxis::records — a machine's calibration history: every result file trueaxis writes,
// stored with who measured it, when, with which instrument, in which state (as found, as left),
// and its headline figures, in an embedded SQLite database (one file, no server) or on a
// PostgreSQL server.
//
// Schema (version kSchemaVersion; a newer one is refused, an older one migrated on open):
//   meta(key, value)                         'schema_version'
//   machines(id, created)
//   records(id, machine, date, kind, state, operator, instrument, temperature_C, note,
//           trueaxis_version, file_name, digest, content)   unique (machine, digest)
//   figures(record, seq, name, axis, value, u, unit)         seq: the order in the result
// Version 1 had no figures.seq (their order was SQLite's rowid). The same schema on PostgreSQL
// for a history shared by many workstations.
// Every statement is parameterised: machine ids, notes and file contents are data, never SQL.
// An add is one transaction: a process killed in the middle leaves the database as it was.
//
// Units: figures in the unit they state (µm for lengths, µrad for angles); temperature in °C;
// dates ISO 8601 (YYYY-MM-DD, optionally with a time).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace trueaxis::records {

inline constexpr int kSchemaVersion = 2;

// A headline figure of a result: its name as the standard gives it ("A", "E0", "G", "flatness"),
// the axis or plane it belongs to ("" when none), its value and standard uncertainty (none when
// the result states none), and its unit.
struct Figure {
  std::string name, axis;
  double value = 0;
  std::optional<double> u;
  std::string unit;
};

// The headline figures of a result file's JSON text, by its kind (positioning: A, B, E, M, R;
// circular: G per direction and H; acceptance-e0: E0 (or E150) and R0; acceptance-probing: PForm,
// PSize; separation and guideway: straightness; surface: flatness; space: the residual after
// compensation; ballgauge map and parametric model: the largest error; length verification:
// the worst fraction of the MPE; fit: the form; scan: machine time). `axis` names the axis for
// kinds whose file does not (positioning). Throws Error when the text is not a result.
std::vector<Figure> headline_figures(const std::string& kind, const std::string& json,
                                     const std::string& axis = "");

enum class State { None, AsFound, AsLeft };
const char* to_string(State s);  // "", "as-found", "as-left"

// What `record add` stores with a file.
struct AddOptions {
  std::string machine;  // required, any text
  std::string date;     // ISO 8601; empty: today (UTC)
  State state = State::None;
  std::string operator_name, instrument, note, axis;
  std::optional<double> temperature;  // °C
  bool new_machine = false;           // register an unknown machine instead of refusing it
  // Throws Error: no machine, a date that is not ISO 8601, a temperature out of −50 … 100 °C,
  // text that is not UTF-8 or holds a NUL character (neither can be stored on every back end).
  void validate() const;
};

struct Record {
  long long id = 0;
  std::string machine, date, kind;
  State state = State::None;
  std::string operator_name, instrument, note, trueaxis_version, file_name;
  std::optional<double> temperature;
  std::vector<Figure> figures;
};

// One figure's history and its drift (records trend).
struct TrendPoint {
  std::string date;  // ISO 8601 (the day counts)
  double value = 0;
  std::optional<double> u;
  State state = State::None;
  long long record = 0;
};

struct TrendOptions {
  // The figure's upper limit, in its unit (the figures grow as a machine wears): the date the
  // trend reaches it.
  std::optional<double> tolerance;
  // Which points Database::trend fits. A machine drifts between adjustments, which its as-found
  // values show; an as-left value is where an adjustment put it. Auto: the as-found points when
  // the history has as-found and as-left ones, else all.
  enum class Use { Auto, AsFound, AsLeft, All } use = Use::Auto;
  // "auto", "as-found", "as-left" or "all"; throws Error naming the choices otherwise.
  static Use use_of(const std::string& name);
  std::string unit;       // the figure's unit, for the messages
  void validate() const;  // throws Error
};

// The drift per year by weighted least squares of value against time (weights 1/u² when every
// point states its u, else equal), its standard uncertainty from the points' u and their
// scatter about the line (the larger: the covariance scaled by χ²/dof when that exceeds 1), and
// the date the line reaches the tolerance with its standard uncertainty (the line's covariance
// propagated to the crossing). Not resolved, with the reason, when there are too few points or
// dates, or the drift does not stand out of its uncertainty (|drift| < 2u) or falls (it never
// reaches the upper limit).
struct Trend {
  std::string figure, axis, unit;
  std::vector<TrendPoint> points;      // the points fitted, oldest first
  std::string fitted_on = "all";       // "as found", "as left" or "all" (Database::trend)
  std::vector<TrendPoint> not_fitted;  // the history's other points (drawn, not fitted)
  std::optional<double> drift_per_year, u_drift;  // unit per year
  std::optional<double> value_now, u_value_now;   // the line at the last point's date
  std::optional<double> cov_now_drift;            // their covariance (unit² per year)
  std::optional<std::string> due;                 // ISO 8601 date
  std::optional<double> u_due_days;
  std::string not_resolved;  // why no drift or no due date ("" when both are given)
  std::string summary() const;
  // The fitted line on a day (days since 1970-01-01) and its standard uncertainty from the
  // line's covariance (nullopt when the drift has no uncertainty). Precondition: drift_per_year.
  std::pair<double, std::optional<double>> line_at(long long day) const;
};

// Days since 1970-01-01 of an ISO 8601 date's day (proleptic Gregorian); throws Error when it is
// not one. And back.
long long day_number(const std::string& date);
std::string date_of_day(long long day);

Trend fit_trend(std::vector<TrendPoint> points, const TrendOptions& options = {});
std::string to_json(const Trend& trend, const std::string& machine);

struct MachineSummary {
  std::string id;
  long long records = 0;
  std::string first, last;  // dates
};

struct ListFilter {
  std::string machine, kind, from, to;  // empty: any; dates inclusive
};

// ReadOnly: for reading (list, show, export, trend); nothing is locked or written, and a
// database on a read-only disk or directory can be read.
enum class Access { ReadWrite, ReadOnly };

class Database {
 public:
  // Opens the records at `location`: a PostgreSQL server when it is a URL
  // (postgresql://[user[:password]@]host[:port]/dbname, libpq's connection URI; the database
  // must exist), else an SQLite file, created when absent for ReadWrite. The schema is created
  // or migrated to kSchemaVersion. Throws Error: a file that is not a database, one written by a
  // newer trueaxis (schema newer than kSchemaVersion), a directory that cannot be written, a
  // server that cannot be reached; for ReadOnly, a database that does not exist.
  explicit Database(const std::string& location, Access access = Access::ReadWrite);
  ~Database();
  Database(Database&&) noexcept;
  Database& operator=(Database&&) noexcept;

  // Stores the result file at `path`: refuses a file that is not a trueaxis result, a machine
  // not yet known (unless new_machine) and a file already stored for that machine. Returns the
  // stored record.
  Record add(const std::string& path, const AddOptions& options);
  std::vector<MachineSummary> machines() const;
  std::vector<Record> list(const ListFilter& filter = {}) const;
  Record show(long long id) const;          // throws Error when there is no such record
  std::string content(long long id) const;  // the stored file, as it was
  int schema_version() const;
  // Where the records are, for messages and reports: the file's path, or the server's URL with
  // any password masked.
  std::string describe() const;
  // One figure's history on one machine, oldest first (axis "" matches a figure without one).
  // Throws Error naming the figures the machine has when there is none of that name.
  Trend history(const std::string& machine, const std::string& figure,
                const std::string& axis) const;
  // The figures a machine's records hold: (name, axis) pairs, sorted.
  std::vector<std::pair<std::string, std::string>> figures(const std::string& machine) const;
  // That history with its drift and due date (fit_trend), named with its figure, axis and unit.
  Trend trend(const std::string& machine, const std::string& figure, const std::string& axis,
              const TrendOptions& options = {}) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::vector<Record> query(const ListFilter& filter, long long id) const;  // id 0: any
};

// A figure's upper limit for `record due`: "A=25" (every axis), "A@X=20", "G_ccw@XY=15",
// "E0=3.5", in the figure's unit.
struct Limit {
  std::string figure, axis;  // axis "": any axis or none
  double value = 0;
  static Limit parse(const std::string& text);  // throws Error naming what is wrong
  bool applies_to(const std::string& name, const std::string& on_axis) const {
    return name == figure && (axis.empty() || axis == on_axis);
  }
};

struct DueOptions {
  int interval_months = 12;   // the longest time between two visits
  std::vector<Limit> limits;  // figures whose trend may bring the date forward
  std::string machine;        // "" for every machine
  std::string today;          // ISO 8601; "" for today (UTC): what is overdue
  void validate() const;      // throws Error
};

// One machine's next due date: the last visit plus the interval, or earlier when a figure's
// trend reaches its limit before that (the trend's central date, with its u).
struct Due {
  std::string machine, last_visit, due;
  std::optional<double> u_days;    // when a trend set the date
  std::string because;             // "12 months after the last visit", "A@X reaches 25 µm …"
  bool overdue = false;            // due before `today`
  std::vector<std::string> notes;  // limits whose trend could not give a date, and why
};
std::vector<Due> due_dates(const Database& db, const DueOptions& options);
std::string to_json(const std::vector<Due>& due);
std::string add_months(const std::string& date, int months);  // the day clamped to the month's end

// The records as a JSON array ({"id", "machine", "date", "kind", "state", "operator",
// "instrument", "temperature_C", "note", "file", "trueaxis_version", "figures": {name or
// name@axis: {"value", "u", "unit"}}}) or CSV (one row per figure).
std::string to_json(const std::vector<Record>& records);
std::string to_csv(const std::vector<Record>& records);

std::string today_utc();  // ISO 8601 (YYYY-MM-DD)

// The database path the commands use: `explicit_path`, else $TRUEAXIS_DB, else
// trueaxis-records.db in the working directory.
std::string database_path(const std::string& explicit_path);

}  // namespace trueaxis::records
