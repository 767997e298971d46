// The records on a PostgreSQL server (backend.hpp), through libpqxx: a history that many
// workstations share. Parameters travel as text ($1 … $n), bytes as BYTEA in its hex form.
#include <fmt/format.h>

#include <cstdlib>
#include <pqxx/binarystring>
#include <pqxx/connection>
#include <pqxx/except>
#include <pqxx/nontransaction>
#include <pqxx/result>
#include <pqxx/transaction>

#include "backend.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::records::detail {
namespace {

// PostgreSQL's type oids (pg_type.dat) of the columns the schema has.
constexpr pqxx::oid kInt8 = 20, kInt2 = 21, kInt4 = 23, kFloat4 = 700, kFloat8 = 701,
                    kNumeric = 1700, kBytea = 17;
// The writers' lock: one add at a time over every workstation ("trueaxis" in ASCII).
constexpr long long kWriterLock = 0x7472756561786973LL;

std::string hex_bytea(const std::string& bytes) {
  static constexpr char digits[] = "0123456789abcdef";
  std::string s = "\\x";
  s.reserve(2 + 2 * bytes.size());
  for (const unsigned char c : bytes) {
    s += digits[c >> 4];
    s += digits[c & 15];
  }
  return s;
}

// The URL without its password, for messages: postgresql://user:secret@host → user:***@host.
std::string without_password(const std::string& url) {
  const auto scheme = url.find("://");
  if (scheme == std::string::npos) return url;
  const auto at = url.find('@', scheme + 3);
  if (at == std::string::npos) return url;
  const auto colon = url.find(':', scheme + 3);
  const auto slash = url.find('/', scheme + 3);
  if (colon == std::string::npos || colon > at || (slash != std::string::npos && slash < at))
    return url;
  return url.substr(0, colon + 1) + "***" + url.substr(at);
}

std::string trimmed(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  return s;
}

class Postgres final : public Backend {
 public:
  Postgres(const std::string& url, Access access) : url_(without_password(url)) {
    guard([&] {
      conn_ = std::make_unique<pqxx::connection>(url);
      if (access == Access::ReadOnly) {
        pqxx::nontransaction n(*conn_);
        n.exec("SET default_transaction_read_only = on");
      }
    });
  }

  std::vector<Row> query(const std::string& sql, const std::vector<Param>& params) override {
    std::vector<std::string> store(params.size());
    std::vector<const char*> values(params.size(), nullptr);
    for (std::size_t i = 0; i < params.size(); ++i) {
      std::visit(
          [&](const auto& p) {
            using T = std::decay_t<decltype(p)>;
            if constexpr (std::is_same_v<T, std::monostate>) {
              return;
            } else if constexpr (std::is_same_v<T, Blob>) {
              store[i] = hex_bytea(p.bytes);
            } else if constexpr (std::is_same_v<T, std::string>) {
              if (p.find('\0') != std::string::npos)
                throw Error("a text with a NUL character cannot be stored");
              store[i] = p;
            } else if constexpr (std::is_same_v<T, double>) {
              store[i] = fmt::format("{:.17g}", p);  // exact: 17 significant digits
            } else {
              store[i] = std::to_string(p);
            }
            values[i] = store[i].c_str();
          },
          params[i]);
    }
    return guard([&] {
      const auto dyn = pqxx::prepare::make_dynamic_params(values);
      pqxx::result r;
      if (txn_) {
        r = txn_->exec_params(sql, dyn);
      } else {
        pqxx::nontransaction n(*conn_);
        r = n.exec_params(sql, dyn);
      }
      std::vector<Row> rows;
      rows.reserve(r.size());
      const auto columns = r.columns();
      for (const auto& row : r) {
        Row out(static_cast<std::size_t>(columns));
        for (pqxx::row::size_type c = 0; c < columns; ++c) {
          const pqxx::field f = row[c];
          if (f.is_null()) continue;
          const pqxx::oid type = r.column_type(c);
          auto& v = out[static_cast<std::size_t>(c)];
          if (type == kInt8 || type == kInt2 || type == kInt4)
            v = static_cast<std::int64_t>(std::strtoll(f.c_str(), nullptr, 10));
          else if (type == kFloat8 || type == kFloat4 || type == kNumeric)
            v = std::strtod(f.c_str(), nullptr);  // the server writes the shortest exact form
          else if (type == kBytea)
            v = pqxx::binarystring(f).str();
          else
            v = std::string(f.c_str(), f.size());
        }
        rows.push_back(std::move(out));
      }
      return rows;
    });
  }

  void script(const std::string& sql) override {
    guard([&] {
      if (txn_) {
        txn_->exec(sql);
      } else {
        pqxx::nontransaction n(*conn_);
        n.exec(sql);
      }
    });
  }
  void begin(bool write) override {
    guard([&] {
      txn_ = std::make_unique<pqxx::work>(*conn_);
      if (write) txn_->exec(fmt::format("SELECT pg_advisory_xact_lock({})", kWriterLock));
    });
  }
  void commit() override {
    guard([&] {
      txn_->commit();
      txn_.reset();
    });
  }
  void rollback() noexcept override {
    try {
      txn_.reset();  // a work not committed aborts
    } catch (...) {
    }
  }
  const char* key_type() const override {
    return "BIGINT GENERATED BY DEFAULT AS IDENTITY PRIMARY KEY";
  }
  const char* blob_type() const override { return "BYTEA"; }
  const char* real_type() const override { return "DOUBLE PRECISION"; }
  std::string describe() const override { return url_; }

 private:
  std::string url_;
  std::unique_ptr<pqxx::connection> conn_;
  std::unique_ptr<pqxx::work> txn_;

  template <class F>
  auto guard(F&& f) -> decltype(f()) {
    try {
      return f();
    } catch (const pqxx::broken_connection& e) {
      throw Error(fmt::format("cannot reach the PostgreSQL server: {}", trimmed(e.what())));
    } catch (const pqxx::sql_error& e) {
      std::string why = trimmed(e.what());
      if (e.sqlstate() == "25006") why = "the database is opened read-only: " + why;
      if (e.sqlstate().rfind("53", 0) == 0)
        why = "the server is out of disk or memory (nothing of this change was written): " + why;
      throw Error(why);
    } catch (const pqxx::failure& e) {
      throw Error(trimmed(e.what()));
    }
  }
};

}  // namespace

std::unique_ptr<Backend> open_postgresql(const std::string& url, Access access) {
  return std::make_unique<Postgres>(url, access);
}

}  // namespace trueaxis::records::detail
