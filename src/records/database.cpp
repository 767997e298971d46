// The records' database (records.hpp) on either back end (backend.hpp): parameterised
// statements only, one transaction per add, the schema created or migrated on open.
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>

#include "backend.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/result_file.hpp"
#include "trueaxis/records/records.hpp"

#ifndef TRUEAXIS_VERSION_TEXT
#define TRUEAXIS_VERSION_TEXT "unknown"
#endif

namespace trueaxis::records {
namespace {

// FNV-1a, 64 bits: the stored file's identity, the same on every platform and version.
std::string digest(const std::string& bytes) {
  std::uint64_t h = 1469598103934665603ull;
  for (const unsigned char c : bytes) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return fmt::format("{:016x}-{}", h, bytes.size());
}

// A number, or NULL when there is none (never a zero in its place).
detail::Param optional_param(const std::optional<double>& v) {
  return v ? detail::Param(*v) : detail::Param();
}

State state_of(const std::string& s) {
  if (s == "as-found") return State::AsFound;
  if (s == "as-left") return State::AsLeft;
  return State::None;
}

// Runs `f`, naming the database and what was being done in its errors.
template <class F>
auto guarded(const detail::Backend& b, const std::string& what, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const Error& e) {
    throw Error(fmt::format("records database {}: {}: {}", b.describe(), what, e.what()));
  }
}

// Text every back end stores as it is: UTF-8 (RFC 3629) without NUL.
void check_text(const char* field, const std::string& s) {
  if (s.find('\0') != std::string::npos)
    throw Error(fmt::format("record: the {} holds a NUL character, which cannot be stored", field));
  for (std::size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    const std::size_t n = c < 0x80         ? 1
                          : (c >> 5) == 6  ? 2
                          : (c >> 4) == 14 ? 3
                          : (c >> 3) == 30 ? 4
                                           : 0;
    bool ok = n != 0 && i + n <= s.size();
    for (std::size_t k = 1; ok && k < n; ++k) ok = (static_cast<unsigned char>(s[i + k]) >> 6) == 2;
    if (ok && n == 2) ok = c >= 0xC2;  // no overlong form
    if (ok && n == 3) {
      const auto c1 = static_cast<unsigned char>(s[i + 1]);
      ok = !(c == 0xE0 && c1 < 0xA0) && !(c == 0xED && c1 >= 0xA0);  // overlong, surrogates
    }
    if (ok && n == 4) {
      const auto c1 = static_cast<unsigned char>(s[i + 1]);
      ok = c <= 0xF4 && !(c == 0xF0 && c1 < 0x90) && !(c == 0xF4 && c1 >= 0x90);
    }
    if (!ok) throw Error(fmt::format("record: the {} is not UTF-8 text (byte {})", field, i + 1));
    i += n;
  }
}

// ISO 8601 as the records store it: a calendar date YYYY-MM-DD, optionally with a time
// (T or a space, hh:mm, optionally :ss and a fraction, optionally Z or an offset ±hh[:]mm).
bool iso8601(const std::string& s) {
  std::size_t i = 0;
  const auto digits = [&](std::size_t n) {
    for (std::size_t k = 0; k < n; ++k, ++i)
      if (i >= s.size() || !std::isdigit(static_cast<unsigned char>(s[i]))) return false;
    return true;
  };
  const auto is = [&](const char* chars) {
    if (i < s.size() && std::strchr(chars, s[i]) != nullptr && s[i] != '\0') return ++i, true;
    return false;
  };
  if (!(digits(4) && is("-") && digits(2) && is("-") && digits(2))) return false;
  if (i == s.size()) return true;
  if (!(is("T ") && digits(2) && is(":") && digits(2))) return false;
  if (is(":")) {
    if (!digits(2)) return false;
    if (is(".")) {
      if (!digits(1)) return false;
      while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i]))) ++i;
    }
  }
  if (i == s.size()) return true;
  if (is("Z")) return i == s.size();
  if (!(is("+-") && digits(2))) return false;
  is(":");
  return digits(2) && i == s.size();
}

bool is_url(const std::string& location) {
  return location.rfind("postgresql://", 0) == 0 || location.rfind("postgres://", 0) == 0;
}

}  // namespace

const char* to_string(State s) {
  switch (s) {
    case State::AsFound:
      return "as-found";
    case State::AsLeft:
      return "as-left";
    case State::None:
      break;
  }
  return "";
}

void AddOptions::validate() const {
  if (machine.empty()) throw Error("record: give the machine's id");
  if (!date.empty() && !iso8601(date))
    throw Error(fmt::format("record: the date '{}' is not ISO 8601 (e.g. 2026-11-29)", date));
  if (!date.empty()) {
    const int month = std::stoi(date.substr(5, 2)), day = std::stoi(date.substr(8, 2));
    if (month < 1 || month > 12 || day < 1 || day > 31)
      throw Error(fmt::format("record: the date '{}' has no such month or day", date));
  }
  if (temperature && !(*temperature > -50 && *temperature < 100))
    throw Error("record: the temperature must be a number of °C (−50 … 100)");
  check_text("machine id", machine);
  check_text("operator", operator_name);
  check_text("instrument", instrument);
  check_text("note", note);
  check_text("axis", axis);
}

struct Database::Impl {
  std::unique_ptr<detail::Backend> b;
};

namespace {

using detail::Param;
using detail::Row;

// The schema's version, 0 when the meta table holds none; the back end's Error when there is no
// meta table at all.
int stored_version(detail::Backend& b) {
  const auto rows = b.query("SELECT value FROM meta WHERE key = 'schema_version'", {});
  return rows.empty() ? 0 : std::atoi(detail::text(rows[0][0]).c_str());
}

void refuse_newer(const detail::Backend& b, int version) {
  if (version > kSchemaVersion)
    throw Error(fmt::format(
        "records database {} was written by a newer trueaxis (schema {}; this one reads up to "
        "{}): update trueaxis to open it",
        b.describe(), version, kSchemaVersion));
}

// Creates the schema, or migrates an older one, in one transaction with the writers' lock.
void create_or_migrate(detail::Backend& b) {
  detail::Transaction t(b, true);
  b.script("CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL)");
  const int version = stored_version(b);
  refuse_newer(b, version);
  if (version == kSchemaVersion) return;  // rolled back: nothing was changed
  if (version < 1) {
    b.script(fmt::format(
        "CREATE TABLE machines (id TEXT PRIMARY KEY, created TEXT NOT NULL);"
        "CREATE TABLE records (id {key}, machine TEXT NOT NULL REFERENCES machines(id), date "
        "TEXT NOT NULL, kind TEXT NOT NULL, state TEXT NOT NULL, operator TEXT NOT NULL, "
        "instrument TEXT NOT NULL, temperature_C {real}, note TEXT NOT NULL, trueaxis_version "
        "TEXT NOT NULL, file_name TEXT NOT NULL, digest TEXT NOT NULL, content {blob} NOT NULL, "
        "UNIQUE (machine, digest));"
        "CREATE TABLE figures (record BIGINT NOT NULL REFERENCES records(id), seq INTEGER NOT "
        "NULL, name TEXT NOT NULL, axis TEXT NOT NULL, value {real} NOT NULL, u {real}, unit "
        "TEXT NOT NULL);"
        "CREATE INDEX figures_by_record ON figures(record, seq);"
        "CREATE INDEX records_by_machine ON records(machine, date);",
        fmt::arg("key", b.key_type()), fmt::arg("real", b.real_type()),
        fmt::arg("blob", b.blob_type())));
  } else if (version == 1) {
    // Version 1 existed on SQLite only: the figures' order was their rowid.
    b.script(
        "ALTER TABLE figures ADD COLUMN seq INTEGER NOT NULL DEFAULT 0;"
        "UPDATE figures SET seq = rowid;"
        "DROP INDEX figures_by_record;"
        "CREATE INDEX figures_by_record ON figures(record, seq);");
  }
  b.query(
      "INSERT INTO meta (key, value) VALUES ('schema_version', $1) ON CONFLICT (key) DO UPDATE "
      "SET value = excluded.value",
      {Param(std::to_string(kSchemaVersion))});
  t.commit();
}

std::unique_ptr<detail::Backend> open_backend(const std::string& location, Access access) {
  return is_url(location) ? detail::open_postgresql(location, access)
                          : detail::open_sqlite(location, access);
}

}  // namespace

Database::Database(const std::string& location, Access access) : impl_(std::make_unique<Impl>()) {
  try {
    impl_->b = open_backend(location, access);
  } catch (const Error& e) {
    throw Error(fmt::format("records database {}: {}",
                            is_url(location) ? std::string("on the server") : location, e.what()));
  }
  auto& b = *impl_->b;
  if (access == Access::ReadWrite) {
    guarded(b, "creating or migrating its schema", [&] { create_or_migrate(b); });
    return;
  }
  int version = 0;
  try {
    version = stored_version(b);
  } catch (const Error&) {
    version = 0;  // no meta table
  }
  if (version == 0)
    throw Error(fmt::format("records database {}: it holds no trueaxis records", b.describe()));
  refuse_newer(b, version);
  if (version < kSchemaVersion) {
    // An older schema is migrated, which needs writing once.
    try {
      impl_->b = open_backend(location, Access::ReadWrite);
      create_or_migrate(*impl_->b);
    } catch (const Error& e) {
      throw Error(fmt::format(
          "records database {} was written by an older trueaxis (schema {}) and must be "
          "migrated to schema {}, which needs writing to it: {}",
          b.describe(), version, kSchemaVersion, e.what()));
    }
  }
}

Database::~Database() = default;
Database::Database(Database&&) noexcept = default;
Database& Database::operator=(Database&&) noexcept = default;

std::string Database::describe() const {
  return impl_->b->describe();
}

int Database::schema_version() const {
  return guarded(*impl_->b, "reading its schema", [&] { return stored_version(*impl_->b); });
}

Record Database::add(const std::string& path, const AddOptions& options) {
  options.validate();
  // A trueaxis result, read by its kind's own reader (file:line:col when it is not).
  const io::ResultFile file = io::read_result_file(path);
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  Record r;
  r.machine = options.machine;
  r.date = options.date.empty() ? today_utc() : options.date;
  r.kind = file.kind;
  r.state = options.state;
  r.operator_name = options.operator_name;
  r.instrument = options.instrument;
  r.note = options.note;
  r.temperature = options.temperature;
  r.trueaxis_version = TRUEAXIS_VERSION_TEXT;
  r.file_name = std::filesystem::path(path).filename().string();
  r.figures = headline_figures(file.kind, bytes, options.axis);
  const std::string id = digest(bytes);
  auto& b = *impl_->b;
  guarded(b, "adding " + path, [&] {
    // The writers' lock is taken first, so that a second process adding waits for it instead of
    // both reading and one then failing to write.
    detail::Transaction t(b, true);
    if (b.query("SELECT 1 FROM machines WHERE id = $1", {Param(r.machine)}).empty()) {
      if (!options.new_machine)
        throw Error(fmt::format(
            "no machine '{}' in the records; add it with --new-machine (a typing mistake would "
            "otherwise start a second history)",
            r.machine));
      b.query("INSERT INTO machines (id, created) VALUES ($1, $2)",
              {Param(r.machine), Param(today_utc())});
    }
    const auto dup = b.query("SELECT id, date FROM records WHERE machine = $1 AND digest = $2",
                             {Param(r.machine), Param(id)});
    if (!dup.empty())
      throw Error(fmt::format("{} is already stored for machine '{}' (record {}, {})", path,
                              r.machine, detail::integer(dup[0][0]), detail::text(dup[0][1])));
    const auto ins = b.query(
        "INSERT INTO records (machine, date, kind, state, operator, instrument, temperature_C, "
        "note, trueaxis_version, file_name, digest, content) VALUES ($1, $2, $3, $4, $5, $6, $7, "
        "$8, $9, $10, $11, $12) RETURNING id",
        {Param(r.machine), Param(r.date), Param(r.kind), Param(std::string(to_string(r.state))),
         Param(r.operator_name), Param(r.instrument), optional_param(r.temperature), Param(r.note),
         Param(r.trueaxis_version), Param(r.file_name), Param(id), Param(detail::Blob{bytes})});
    r.id = detail::integer(ins.at(0).at(0));
    for (std::size_t k = 0; k < r.figures.size(); ++k) {
      const auto& f = r.figures[k];
      b.query(
          "INSERT INTO figures (record, seq, name, axis, value, u, unit) VALUES ($1, $2, $3, $4, "
          "$5, $6, $7)",
          {Param(static_cast<std::int64_t>(r.id)), Param(static_cast<std::int64_t>(k)),
           Param(f.name), Param(f.axis), Param(f.value), optional_param(f.u), Param(f.unit)});
    }
    t.commit();
  });
  return r;
}

std::vector<MachineSummary> Database::machines() const {
  auto& b = *impl_->b;
  return guarded(b, "listing the machines", [&] {
    std::vector<MachineSummary> out;
    for (const auto& row :
         b.query("SELECT m.id, COUNT(r.id), COALESCE(MIN(r.date), ''), COALESCE(MAX(r.date), "
                 "'') FROM machines m LEFT JOIN records r ON r.machine = m.id GROUP BY m.id "
                 "ORDER BY m.id",
                 {}))
      out.push_back({detail::text(row[0]), detail::integer(row[1]), detail::text(row[2]),
                     detail::text(row[3])});
    return out;
  });
}

std::vector<Record> Database::list(const ListFilter& f) const {
  return query(f, 0);
}

std::vector<Record> Database::query(const ListFilter& f, long long id) const {
  auto& b = *impl_->b;
  return guarded(b, "listing the records", [&] {
    std::vector<Record> out;
    // The records the filter selects (r), and their figures in one more statement.
    const std::string where =
        " WHERE ($1 = '' OR r.machine = $1) AND ($2 = '' OR r.kind = $2) AND ($3 = '' OR r.date "
        ">= $3) AND ($4 = '' OR substr(r.date, 1, 10) <= $4) AND ($5 = 0 OR r.id = $5)";
    const std::vector<Param> params{Param(f.machine), Param(f.kind), Param(f.from), Param(f.to),
                                    Param(static_cast<std::int64_t>(id))};
    const auto rows = b.query(
        "SELECT r.id, r.machine, r.date, r.kind, r.state, r.operator, r.instrument, "
        "r.temperature_C, r.note, r.trueaxis_version, r.file_name FROM records r" +
            where + " ORDER BY r.date, r.id",
        params);
    std::map<long long, std::vector<Figure>> figures;
    const auto figs = b.query(
        "SELECT f.record, f.name, f.axis, f.value, f.u, f.unit FROM figures f JOIN records r ON "
        "r.id = f.record" +
            where + " ORDER BY f.record, f.seq",
        params);
    for (const auto& g : figs) {
      Figure fg;
      fg.name = detail::text(g[1]);
      fg.axis = detail::text(g[2]);
      fg.value = detail::real(g[3]);
      if (!detail::is_null(g[4])) fg.u = detail::real(g[4]);
      fg.unit = detail::text(g[5]);
      figures[detail::integer(g[0])].push_back(std::move(fg));
    }
    for (const auto& q : rows) {
      Record r;
      r.id = detail::integer(q[0]);
      r.machine = detail::text(q[1]);
      r.date = detail::text(q[2]);
      r.kind = detail::text(q[3]);
      r.state = state_of(detail::text(q[4]));
      r.operator_name = detail::text(q[5]);
      r.instrument = detail::text(q[6]);
      if (!detail::is_null(q[7])) r.temperature = detail::real(q[7]);
      r.note = detail::text(q[8]);
      r.trueaxis_version = detail::text(q[9]);
      r.file_name = detail::text(q[10]);
      if (auto it = figures.find(r.id); it != figures.end()) r.figures = std::move(it->second);
      out.push_back(std::move(r));
    }
    return out;
  });
}

Record Database::show(long long id) const {
  if (id > 0)
    if (auto one = query({}, id); !one.empty()) return one.front();
  throw Error(fmt::format("no record {} in the records database", id));
}

std::string Database::content(long long id) const {
  auto& b = *impl_->b;
  return guarded(b, "reading a stored file", [&] {
    const auto rows = b.query("SELECT content FROM records WHERE id = $1",
                              {Param(static_cast<std::int64_t>(id))});
    if (rows.empty()) throw Error(fmt::format("no record {} in the records database", id));
    return detail::text(rows[0][0]);
  });
}

Trend Database::history(const std::string& machine, const std::string& figure,
                        const std::string& axis) const {
  auto& b = *impl_->b;
  return guarded(b, "reading a figure's history", [&] {
    Trend t;
    t.figure = figure;
    t.axis = axis;
    for (const auto& q :
         b.query("SELECT r.id, r.date, r.state, f.value, f.u, f.unit FROM figures f JOIN "
                 "records r ON r.id = f.record WHERE r.machine = $1 AND f.name = $2 AND f.axis = "
                 "$3 ORDER BY r.date, r.id",
                 {Param(machine), Param(figure), Param(axis)})) {
      TrendPoint p;
      p.record = detail::integer(q[0]);
      p.date = detail::text(q[1]);
      p.state = state_of(detail::text(q[2]));
      p.value = detail::real(q[3]);
      if (!detail::is_null(q[4])) p.u = detail::real(q[4]);
      t.unit = detail::text(q[5]);
      t.points.push_back(p);
    }
    if (t.points.empty()) {
      // Say which figures there are, so that a misspelt name or axis is seen at once.
      std::string known;
      for (const auto& [name, a] : figures(machine))
        known += (known.empty() ? "" : ", ") + name + (a.empty() ? "" : " --axis " + a);
      throw Error(fmt::format("machine '{}' has no figure {}{} in the records{}", machine, figure,
                              axis.empty() ? "" : " on axis " + axis,
                              known.empty() ? " (it has none)" : " (it has: " + known + ")"));
    }
    return t;
  });
}

std::vector<std::pair<std::string, std::string>> Database::figures(
    const std::string& machine) const {
  auto& b = *impl_->b;
  return guarded(b, "listing a machine's figures", [&] {
    std::vector<std::pair<std::string, std::string>> out;
    for (const auto& q : b.query("SELECT DISTINCT f.name, f.axis FROM figures f JOIN records r ON "
                                 "r.id = f.record WHERE r.machine = $1 ORDER BY f.name, f.axis",
                                 {Param(machine)}))
      out.emplace_back(detail::text(q[0]), detail::text(q[1]));
    return out;
  });
}

Trend Database::trend(const std::string& machine, const std::string& figure,
                      const std::string& axis, const TrendOptions& options) const {
  const Trend h = history(machine, figure, axis);
  using Use = TrendOptions::Use;
  Use use = options.use;
  const auto has = [&](State s) {
    return std::any_of(h.points.begin(), h.points.end(),
                       [&](const TrendPoint& p) { return p.state == s; });
  };
  if (use == Use::Auto) use = has(State::AsFound) && has(State::AsLeft) ? Use::AsFound : Use::All;
  std::vector<TrendPoint> fitted, others;
  for (const auto& p : h.points)
    ((use == Use::All || (use == Use::AsFound && p.state == State::AsFound) ||
      (use == Use::AsLeft && p.state == State::AsLeft))
         ? fitted
         : others)
        .push_back(p);
  TrendOptions o = options;
  o.unit = h.unit;
  Trend t = fit_trend(fitted, o);
  t.figure = h.figure;
  t.axis = h.axis;
  t.unit = h.unit;
  t.fitted_on = use == Use::AsFound ? "as found" : use == Use::AsLeft ? "as left" : "all";
  t.not_fitted = std::move(others);
  return t;
}

std::string today_utc() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char b[16];
  std::strftime(b, sizeof b, "%Y-%m-%d", &tm);
  return b;
}

std::string database_path(const std::string& explicit_path) {
  if (!explicit_path.empty()) return explicit_path;
  if (const char* e = std::getenv("TRUEAXIS_DB"); e != nullptr && *e != '\0') return e;
  return "trueaxis-records.db";
}

}  // namespace trueaxis::records
