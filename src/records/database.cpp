// The records' SQLite database (records.hpp), through SQLiteCpp: parameterised statements only,
// one transaction per add.
#include <SQLiteCpp/SQLiteCpp.h>
#include <fmt/format.h>

#include <chrono>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <sstream>

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

std::string today() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char b[16];
  std::strftime(b, sizeof b, "%Y-%m-%d", &tm);
  return b;
}

// A number, or NULL when there is none (never a zero in its place).
void bind_optional(SQLite::Statement& q, int index, const std::optional<double>& v) {
  if (v)
    q.bind(index, *v);
  else
    q.bind(index);
}

State state_of(const std::string& s) {
  if (s == "as-found") return State::AsFound;
  if (s == "as-left") return State::AsLeft;
  return State::None;
}

// Runs `f`, turning SQLite's exceptions into the project's, with what was being done.
template <class F>
auto guarded(const std::string& what, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const SQLite::Exception& e) {
    throw Error(fmt::format("records database: {}: {}", what, e.what()));
  }
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
  // ISO 8601: a calendar date, optionally with a time.
  static const std::regex iso(
      R"(\d{4}-\d{2}-\d{2}([T ]\d{2}:\d{2}(:\d{2}(\.\d+)?)?(Z|[+-]\d{2}:?\d{2})?)?)");
  if (!date.empty() && !std::regex_match(date, iso))
    throw Error(fmt::format("record: the date '{}' is not ISO 8601 (e.g. 2026-11-29)", date));
  if (!date.empty()) {
    const int month = std::stoi(date.substr(5, 2)), day = std::stoi(date.substr(8, 2));
    if (month < 1 || month > 12 || day < 1 || day > 31)
      throw Error(fmt::format("record: the date '{}' has no such month or day", date));
  }
  if (temperature && !(*temperature > -50 && *temperature < 100))
    throw Error("record: the temperature must be a number of °C (−50 … 100)");
}

struct Database::Impl {
  SQLite::Database db;
  explicit Impl(const std::string& path)
      : db(path, SQLite::OPEN_READWRITE | SQLite::OPEN_CREATE | SQLite::OPEN_FULLMUTEX) {}
};

Database::Database(const std::string& path) {
  const auto parent = std::filesystem::path(path).parent_path();
  if (!parent.empty() && !std::filesystem::is_directory(parent))
    throw Error(fmt::format("records database {}: no such directory {}", path, parent.string()));
  guarded("opening " + path, [&] {
    impl_ = std::make_unique<Impl>(path);
    // Another process adding at the same time waits for it (up to 10 s) instead of failing.
    impl_->db.setBusyTimeout(10000);
    impl_->db.exec("PRAGMA foreign_keys = ON");
    SQLite::Transaction t(impl_->db, SQLite::TransactionBehavior::IMMEDIATE);
    impl_->db.exec("CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL)");
    SQLite::Statement q(impl_->db, "SELECT value FROM meta WHERE key = 'schema_version'");
    int version = 0;
    if (q.executeStep()) version = std::atoi(q.getColumn(0).getString().c_str());
    if (version > kSchemaVersion)
      throw Error(fmt::format(
          "records database {} was written by a newer trueaxis (schema {}; this one reads up to "
          "{}): update trueaxis to open it",
          path, version, kSchemaVersion));
    if (version < 1) {
      impl_->db.exec(
          "CREATE TABLE machines (id TEXT PRIMARY KEY, created TEXT NOT NULL);"
          "CREATE TABLE records (id INTEGER PRIMARY KEY, machine TEXT NOT NULL REFERENCES "
          "machines(id), date TEXT NOT NULL, kind TEXT NOT NULL, state TEXT NOT NULL, operator "
          "TEXT NOT NULL, instrument TEXT NOT NULL, temperature_C REAL, note TEXT NOT NULL, "
          "trueaxis_version TEXT NOT NULL, file_name TEXT NOT NULL, digest TEXT NOT NULL, "
          "content BLOB NOT NULL, UNIQUE (machine, digest));"
          "CREATE TABLE figures (record INTEGER NOT NULL REFERENCES records(id), name TEXT NOT "
          "NULL, axis TEXT NOT NULL, value REAL NOT NULL, u REAL, unit TEXT NOT NULL);"
          "CREATE INDEX figures_by_record ON figures(record);"
          "CREATE INDEX records_by_machine ON records(machine, date);");
      SQLite::Statement v(impl_->db,
                          "INSERT OR REPLACE INTO meta (key, value) VALUES ('schema_version', ?)");
      v.bind(1, std::to_string(kSchemaVersion));
      v.exec();
    }
    t.commit();
  });
}

Database::~Database() = default;
Database::Database(Database&&) noexcept = default;
Database& Database::operator=(Database&&) noexcept = default;

int Database::schema_version() const {
  return guarded("reading its schema", [&] {
    return std::atoi(impl_->db.execAndGet("SELECT value FROM meta WHERE key = 'schema_version'")
                         .getString()
                         .c_str());
  });
}

Record Database::add(const std::string& path, const AddOptions& options) {
  options.validate();
  // A trueaxis result, read by its kind's own reader (file:line:col when it is not).
  const io::ResultFile file = io::read_result_file(path);
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  Record r;
  r.machine = options.machine;
  r.date = options.date.empty() ? today() : options.date;
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
  guarded("adding " + path, [&] {
    // IMMEDIATE: the write lock is taken first, so a second process adding waits for it (the
    // busy timeout) instead of both reading and one then failing to write.
    SQLite::Transaction t(impl_->db, SQLite::TransactionBehavior::IMMEDIATE);
    SQLite::Statement known(impl_->db, "SELECT 1 FROM machines WHERE id = ?");
    known.bind(1, r.machine);
    if (!known.executeStep()) {
      if (!options.new_machine)
        throw Error(fmt::format(
            "no machine '{}' in the records; add it with --new-machine (a typing mistake would "
            "otherwise start a second history)",
            r.machine));
      SQLite::Statement m(impl_->db, "INSERT INTO machines (id, created) VALUES (?, ?)");
      m.bind(1, r.machine);
      m.bind(2, today());
      m.exec();
    }
    SQLite::Statement dup(impl_->db,
                          "SELECT id, date FROM records WHERE machine = ? AND digest = ?");
    dup.bind(1, r.machine);
    dup.bind(2, id);
    if (dup.executeStep())
      throw Error(fmt::format("{} is already stored for machine '{}' (record {}, {})", path,
                              r.machine, dup.getColumn(0).getInt64(),
                              dup.getColumn(1).getString()));
    SQLite::Statement ins(
        impl_->db,
        "INSERT INTO records (machine, date, kind, state, operator, instrument, temperature_C, "
        "note, trueaxis_version, file_name, digest, content) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, "
        "?, ?, ?)");
    ins.bind(1, r.machine);
    ins.bind(2, r.date);
    ins.bind(3, r.kind);
    ins.bind(4, to_string(r.state));
    ins.bind(5, r.operator_name);
    ins.bind(6, r.instrument);
    bind_optional(ins, 7, r.temperature);
    ins.bind(8, r.note);
    ins.bind(9, r.trueaxis_version);
    ins.bind(10, r.file_name);
    ins.bind(11, id);
    ins.bind(12, bytes.data(), static_cast<int>(bytes.size()));
    ins.exec();
    r.id = impl_->db.getLastInsertRowid();
    SQLite::Statement fig(impl_->db,
                          "INSERT INTO figures (record, name, axis, value, u, unit) VALUES (?, ?, "
                          "?, ?, ?, ?)");
    for (const auto& f : r.figures) {
      fig.bind(1, static_cast<std::int64_t>(r.id));
      fig.bind(2, f.name);
      fig.bind(3, f.axis);
      fig.bind(4, f.value);
      bind_optional(fig, 5, f.u);
      fig.bind(6, f.unit);
      fig.exec();
      fig.reset();
    }
    t.commit();
  });
  return r;
}

std::vector<MachineSummary> Database::machines() const {
  return guarded("listing the machines", [&] {
    std::vector<MachineSummary> out;
    SQLite::Statement q(impl_->db,
                        "SELECT m.id, COUNT(r.id), COALESCE(MIN(r.date), ''), "
                        "COALESCE(MAX(r.date), '') FROM machines m LEFT JOIN records r ON "
                        "r.machine = m.id GROUP BY m.id ORDER BY m.id");
    while (q.executeStep())
      out.push_back({q.getColumn(0).getString(), q.getColumn(1).getInt64(),
                     q.getColumn(2).getString(), q.getColumn(3).getString()});
    return out;
  });
}

std::vector<Record> Database::list(const ListFilter& f) const {
  return query(f, 0);
}

std::vector<Record> Database::query(const ListFilter& f, long long id) const {
  return guarded("listing the records", [&] {
    std::vector<Record> out;
    SQLite::Statement q(
        impl_->db,
        "SELECT id, machine, date, kind, state, operator, instrument, temperature_C, note, "
        "trueaxis_version, file_name FROM records WHERE (?1 = '' OR machine = ?1) AND (?2 = '' "
        "OR kind = ?2) AND (?3 = '' OR date >= ?3) AND (?4 = '' OR substr(date, 1, 10) <= ?4) "
        "AND (?5 = 0 OR id = ?5) ORDER BY date, id");
    q.bind(1, f.machine);
    q.bind(2, f.kind);
    q.bind(3, f.from);
    q.bind(4, f.to);
    q.bind(5, static_cast<std::int64_t>(id));
    SQLite::Statement figs(impl_->db,
                           "SELECT name, axis, value, u, unit FROM figures WHERE record = ? "
                           "ORDER BY rowid");
    while (q.executeStep()) {
      Record r;
      r.id = q.getColumn(0).getInt64();
      r.machine = q.getColumn(1).getString();
      r.date = q.getColumn(2).getString();
      r.kind = q.getColumn(3).getString();
      r.state = state_of(q.getColumn(4).getString());
      r.operator_name = q.getColumn(5).getString();
      r.instrument = q.getColumn(6).getString();
      if (!q.getColumn(7).isNull()) r.temperature = q.getColumn(7).getDouble();
      r.note = q.getColumn(8).getString();
      r.trueaxis_version = q.getColumn(9).getString();
      r.file_name = q.getColumn(10).getString();
      figs.bind(1, static_cast<std::int64_t>(r.id));
      while (figs.executeStep()) {
        Figure fg;
        fg.name = figs.getColumn(0).getString();
        fg.axis = figs.getColumn(1).getString();
        fg.value = figs.getColumn(2).getDouble();
        if (!figs.getColumn(3).isNull()) fg.u = figs.getColumn(3).getDouble();
        fg.unit = figs.getColumn(4).getString();
        r.figures.push_back(std::move(fg));
      }
      figs.reset();
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
  return guarded("reading a stored file", [&] {
    SQLite::Statement q(impl_->db, "SELECT content FROM records WHERE id = ?");
    q.bind(1, static_cast<std::int64_t>(id));
    if (!q.executeStep()) throw Error(fmt::format("no record {} in the records database", id));
    const auto c = q.getColumn(0);
    return std::string(static_cast<const char*>(c.getBlob()),
                       static_cast<std::size_t>(c.getBytes()));
  });
}

Trend Database::history(const std::string& machine, const std::string& figure,
                        const std::string& axis) const {
  return guarded("reading a figure's history", [&] {
    Trend t;
    t.figure = figure;
    t.axis = axis;
    SQLite::Statement q(impl_->db,
                        "SELECT r.id, r.date, r.state, f.value, f.u, f.unit FROM figures f JOIN "
                        "records r ON r.id = f.record WHERE r.machine = ? AND f.name = ? AND "
                        "f.axis = ? ORDER BY r.date, r.id");
    q.bind(1, machine);
    q.bind(2, figure);
    q.bind(3, axis);
    while (q.executeStep()) {
      TrendPoint p;
      p.record = q.getColumn(0).getInt64();
      p.date = q.getColumn(1).getString();
      p.state = state_of(q.getColumn(2).getString());
      p.value = q.getColumn(3).getDouble();
      if (!q.getColumn(4).isNull()) p.u = q.getColumn(4).getDouble();
      t.unit = q.getColumn(5).getString();
      t.points.push_back(p);
    }
    if (t.points.empty()) {
      // Say which figures there are, so that a misspelt name or axis is seen at once.
      SQLite::Statement names(impl_->db,
                              "SELECT DISTINCT f.name, f.axis FROM figures f JOIN records r ON "
                              "r.id = f.record WHERE r.machine = ? ORDER BY f.name, f.axis");
      names.bind(1, machine);
      std::string known;
      while (names.executeStep()) {
        const std::string a = names.getColumn(1).getString();
        known += (known.empty() ? "" : ", ") + names.getColumn(0).getString() +
                 (a.empty() ? "" : " --axis " + a);
      }
      throw Error(fmt::format("machine '{}' has no figure {}{} in the records{}", machine, figure,
                              axis.empty() ? "" : " on axis " + axis,
                              known.empty() ? " (it has none)" : " (it has: " + known + ")"));
    }
    return t;
  });
}

std::string database_path(const std::string& explicit_path) {
  if (!explicit_path.empty()) return explicit_path;
  if (const char* e = std::getenv("TRUEAXIS_DB"); e != nullptr && *e != '\0') return e;
  return "trueaxis-records.db";
}

}  // namespace trueaxis::records
