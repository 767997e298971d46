// The records' tests run on both back ends: an SQLite file, and a database on a PostgreSQL
// server of the tests' own (tests/records/postgres.sh). Under ctest the server is started once
// for the run (a fixture; its state directory in $TRUEAXIS_TEST_POSTGRES); a test program run
// alone starts one for itself and stops it when it exits.
#pragma once

#include <SQLiteCpp/SQLiteCpp.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <pqxx/connection>
#include <pqxx/nontransaction>
#include <pqxx/result>
#include <string>

#include "../test_util.hpp"

namespace trueaxis::test {

class PostgresServer {
 public:
  static const std::string& url() {
    static PostgresServer server;
    return server.url_;
  }
  ~PostgresServer() {
    if (own_ && getpid() == pid_)
      (void)std::system(("bash " + script() + " stop " + state_ + " >/dev/null 2>&1").c_str());
  }

 private:
  std::string url_, state_;
  bool own_ = false;
  pid_t pid_ = getpid();
  static std::string script() { return std::string(TRUEAXIS_TEST_SOURCE) + "/records/postgres.sh"; }
  PostgresServer() {
    if (const char* s = std::getenv("TRUEAXIS_TEST_POSTGRES"); s != nullptr && *s != '\0') {
      state_ = s;
    } else {
      state_ = std::string(TRUEAXIS_TEST_TMP) + "/postgres-" + std::to_string(getpid());
      own_ = std::system(("bash " + script() + " start " + state_).c_str()) == 0;
    }
    url_ = read_file(state_ + "/url");
    while (!url_.empty() && (url_.back() == '\n' || url_.back() == '\r')) url_.pop_back();
    if (url_.empty())
      ADD_FAILURE() << "no PostgreSQL server for the tests (" << state_
                    << "/url): is the postgresql package installed?";
  }
};

// A fresh, empty records location for this test: a file for "sqlite", a new database on the
// tests' server for "postgresql". `name` must be unique among the tests.
inline std::string fresh_records(const std::string& backend, const std::string& name) {
  if (backend == "sqlite") {
    const std::string path = temp_dir() + "/" + name + ".db";
    std::filesystem::remove(path);
    return path;
  }
  const std::string& admin = PostgresServer::url();
  std::string db = "t_";
  for (const char c : name) db += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  pqxx::connection c(admin);
  pqxx::nontransaction n(c);
  n.exec("DROP DATABASE IF EXISTS " + db + " WITH (FORCE)");
  n.exec("CREATE DATABASE " + db);
  return admin.substr(0, admin.rfind('/') + 1) + db;
}

// The first column of the first row of `sql` on the records at `location`, as text ("" for
// none): for checks the library's interface does not offer.
inline std::string raw_value(const std::string& location, const std::string& sql) {
  if (location.rfind("postgresql://", 0) == 0) {
    pqxx::connection c(location);
    pqxx::nontransaction n(c);
    const auto r = n.exec(sql);
    return r.empty() || r[0][0].is_null() ? "" : r[0][0].c_str();
  }
  SQLite::Database d(location, SQLite::OPEN_READWRITE);
  SQLite::Statement q(d, sql);
  return q.executeStep() ? q.getColumn(0).getString() : "";
}

}  // namespace trueaxis::test
