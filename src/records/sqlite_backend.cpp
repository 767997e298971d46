// The records on SQLite (backend.hpp), through SQLiteCpp: one file, no server.
#include <SQLiteCpp/SQLiteCpp.h>
#include <fmt/format.h>
#include <sqlite3.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include "backend.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::records::detail {

bool is_null(const Value& v) {
  return std::holds_alternative<std::monostate>(v);
}

std::string text(const Value& v) {
  if (const auto* s = std::get_if<std::string>(&v)) return *s;
  if (const auto* i = std::get_if<std::int64_t>(&v)) return std::to_string(*i);
  if (const auto* d = std::get_if<double>(&v)) return fmt::format("{}", *d);
  return "";
}

std::int64_t integer(const Value& v) {
  if (const auto* i = std::get_if<std::int64_t>(&v)) return *i;
  if (const auto* d = std::get_if<double>(&v)) return static_cast<std::int64_t>(*d);
  if (const auto* s = std::get_if<std::string>(&v)) return std::atoll(s->c_str());
  return 0;
}

double real(const Value& v) {
  if (const auto* d = std::get_if<double>(&v)) return *d;
  if (const auto* i = std::get_if<std::int64_t>(&v)) return static_cast<double>(*i);
  if (const auto* s = std::get_if<std::string>(&v)) return std::strtod(s->c_str(), nullptr);
  return std::numeric_limits<double>::quiet_NaN();
}

namespace {

// $1 … $n (PostgreSQL's placeholders) as ?1 … ?n, SQLite's numbered ones.
std::string numbered(const std::string& sql) {
  std::string s = sql;
  for (auto& c : s)
    if (c == '$') c = '?';
  return s;
}

class Sqlite final : public Backend {
 public:
  Sqlite(const std::string& path, Access access) : path_(path) {
    const bool exists = std::filesystem::exists(path);
    if (access == Access::ReadOnly && !exists)
      throw Error(fmt::format("no records database at {} ('record add' creates one)", path));
    const auto parent = std::filesystem::path(path).parent_path();
    if (!parent.empty() && !std::filesystem::is_directory(parent))
      throw Error(fmt::format("records database {}: no such directory {}", path, parent.string()));
    guard("opening it", [&] {
      db_ = std::make_unique<SQLite::Database>(
          path, access == Access::ReadOnly
                    ? SQLite::OPEN_READONLY
                    : SQLite::OPEN_READWRITE | SQLite::OPEN_CREATE | SQLite::OPEN_FULLMUTEX);
      // Another process writing at the same time is waited for (up to 10 s), not failed.
      db_->setBusyTimeout(10000);
      db_->exec("PRAGMA foreign_keys = ON");
    });
  }

  std::vector<Row> query(const std::string& sql, const std::vector<Param>& params) override {
    return guard("", [&] {
      SQLite::Statement q(*db_, numbered(sql));
      for (std::size_t i = 0; i < params.size(); ++i) {
        const int k = static_cast<int>(i + 1);
        std::visit(
            [&](const auto& p) {
              using T = std::decay_t<decltype(p)>;
              if constexpr (std::is_same_v<T, std::monostate>)
                q.bind(k);
              else if constexpr (std::is_same_v<T, Blob>)
                q.bind(k, p.bytes.data(), static_cast<int>(p.bytes.size()));
              else if constexpr (std::is_same_v<T, std::string>)
                q.bind(k, p);  // with its length: every byte is kept
              else
                q.bind(k, p);
            },
            params[i]);
      }
      std::vector<Row> rows;
      while (q.executeStep()) {
        Row r(static_cast<std::size_t>(q.getColumnCount()));
        for (int c = 0; c < q.getColumnCount(); ++c) {
          const SQLite::Column col = q.getColumn(c);
          switch (col.getType()) {
            case SQLITE_INTEGER:
              r[static_cast<std::size_t>(c)] = static_cast<std::int64_t>(col.getInt64());
              break;
            case SQLITE_FLOAT:
              r[static_cast<std::size_t>(c)] = col.getDouble();
              break;
            case SQLITE_NULL:
              break;
            default:  // text or blob: the bytes as they are
              r[static_cast<std::size_t>(c)] =
                  std::string(static_cast<const char*>(col.getBlob()),
                              static_cast<std::size_t>(col.getBytes()));
          }
        }
        rows.push_back(std::move(r));
      }
      return rows;
    });
  }

  void script(const std::string& sql) override {
    guard("", [&] { db_->exec(sql); });
  }
  void begin(bool write) override {
    guard("", [&] { db_->exec(write ? "BEGIN IMMEDIATE" : "BEGIN"); });
  }
  void commit() override {
    guard("", [&] { db_->exec("COMMIT"); });
  }
  void rollback() noexcept override {
    try {
      db_->exec("ROLLBACK");
    } catch (...) {  // nothing was begun, or SQLite rolled back already (a full disk)
    }
  }
  const char* key_type() const override { return "INTEGER PRIMARY KEY"; }
  const char* blob_type() const override { return "BLOB"; }
  const char* real_type() const override { return "REAL"; }
  std::string describe() const override { return path_; }

 private:
  std::string path_;
  std::unique_ptr<SQLite::Database> db_;

  // SQLite's exceptions as the project's, in words that say what happened to the data.
  template <class F>
  auto guard(const char* what, F&& f) -> decltype(f()) {
    try {
      return f();
    } catch (const SQLite::Exception& e) {
      const int code = e.getErrorCode() & 0xff;  // the primary code
      std::string why = e.what();
      if (code == SQLITE_FULL)
        why =
            "the disk is full (nothing of this change was kept; what was stored before is "
            "intact)";
      else if (code == SQLITE_READONLY || code == SQLITE_CANTOPEN ||
               (code == SQLITE_IOERR && !writable_dir(path_)))
        why = fmt::format("{}: the file or its directory cannot be written ({})",
                          code == SQLITE_CANTOPEN ? "cannot be opened" : "read-only", e.what());
      else if (code == SQLITE_IOERR)
        why = fmt::format(
            "writing to the disk failed; is it full? (nothing of this change was kept; what was "
            "stored before is intact) ({})",
            e.what());
      else if (code == SQLITE_NOTADB)
        why = "it is not an SQLite database";
      throw Error(*what ? fmt::format("{}: {}", what, why) : why);
    }
  }
  // Whether the file's directory can be written (a journal is created next to the file).
  static bool writable_dir(const std::string& path) {
    const auto dir = std::filesystem::path(path).parent_path();
    return ::access(dir.empty() ? "." : dir.c_str(), W_OK) == 0;
  }
};

}  // namespace

std::unique_ptr<Backend> open_sqlite(const std::string& path, Access access) {
  return std::make_unique<Sqlite>(path, access);
}

}  // namespace trueaxis::records::detail
