// The records' storage behind one interface (records.hpp): SQLite (one file, embedded) or
// PostgreSQL (a server many workstations share), the same schema and the same statements on
// both. Private to src/records.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "trueaxis/records/records.hpp"

namespace trueaxis::records::detail {

// A column's value as read: NULL, an integer, a real, or text (a BLOB's bytes are text too).
using Value = std::variant<std::monostate, std::int64_t, double, std::string>;
using Row = std::vector<Value>;

// A statement's parameter. Blob: bytes stored as a BLOB (SQLite) or BYTEA (PostgreSQL).
struct Blob {
  std::string bytes;
};
using Param = std::variant<std::monostate, std::int64_t, double, std::string, Blob>;

bool is_null(const Value& v);
std::string text(const Value& v);      // "" for NULL
std::int64_t integer(const Value& v);  // 0 for NULL
double real(const Value& v);           // NaN for NULL

class Backend {
 public:
  virtual ~Backend() = default;
  // One statement with parameters $1 … $n (numbered in the order they first appear; a number
  // may repeat). Returns its rows. Throws Error with the backend's own message.
  virtual std::vector<Row> query(const std::string& sql, const std::vector<Param>& params) = 0;
  // Several statements without parameters (the schema).
  virtual void script(const std::string& sql) = 0;
  // A transaction. write: the writers' lock is taken at once, so that two processes writing
  // one after the other wait for each other instead of both reading and one failing to write.
  virtual void begin(bool write) = 0;
  virtual void commit() = 0;
  virtual void rollback() noexcept = 0;
  // The column types of the schema: an auto-numbered 64-bit key, bytes, a double.
  virtual const char* key_type() const = 0;
  virtual const char* blob_type() const = 0;
  virtual const char* real_type() const = 0;
  virtual std::string describe() const = 0;  // the path or the server, for messages
};

// Throws Error: a file that is not a database, a directory that cannot be written; for
// ReadOnly, a file that does not exist.
std::unique_ptr<Backend> open_sqlite(const std::string& path, Access access);
// `url`: postgresql://[user[:password]@]host[:port]/dbname[?…] (libpq's connection URI).
std::unique_ptr<Backend> open_postgresql(const std::string& url, Access access);

// A transaction that rolls back unless committed.
class Transaction {
 public:
  Transaction(Backend& b, bool write) : b_(b) { b_.begin(write); }
  ~Transaction() {
    if (!done_) b_.rollback();
  }
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;
  void commit() {
    b_.commit();
    done_ = true;
  }

 private:
  Backend& b_;
  bool done_ = false;
};

}  // namespace trueaxis::records::detail
