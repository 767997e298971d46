// Machine records: results stored with their machine, date and state and read back exactly;
// refusals; strings that cannot break a query; a newer schema refused, an older one migrated;
// two processes adding at once, and one killed while adding, lose nothing and leave the database
// consistent; a read-only database is read, a full disk loses nothing. Every test of the
// database runs on both back ends, SQLite and PostgreSQL (a server the tests start).
#include "trueaxis/records/records.hpp"

#include <SQLiteCpp/SQLiteCpp.h>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

#include "../test_util.hpp"
#include "backends.hpp"
#include "trueaxis/acceptance/acceptance.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/acceptance/acceptance.hpp"
#include "trueaxis/sim/machine.hpp"

using namespace trueaxis;

namespace {

// A probing result (ISO 10360-5) of the virtual CMM, different for each seed.
std::string probing_file(const std::string& name, std::uint64_t seed) {
  sim::MachineOptions mo;
  mo.seed = 1;
  const auto m = sim::random_machine(mo);
  const auto setup = acceptance::example_setup(acceptance::Volume::of(m));
  acceptance::VirtualProbeOptions p;
  p.noise = 0.2e-3;
  p.seed = seed;
  acceptance::ProbingOptions o;
  o.mpe_form = 1.8e-3;
  const auto r = acceptance::run_probing(setup, acceptance::virtual_touch(m, p), o);
  const std::string path = test::temp_dir() + "/" + name;
  io::write_probing_result(path, r);
  return path;
}

}  // namespace

// Each test of the database, on each back end.
class RecordsOn : public ::testing::TestWithParam<std::string> {
 protected:
  std::string fresh_db(const std::string& name) const {
    return test::fresh_records(GetParam(), name);
  }
  bool sqlite() const { return GetParam() == "sqlite"; }
};

TEST_P(RecordsOn, ResultsAreStoredWithTheirFiguresAndReadBackExactly) {
  const std::string path = fresh_db("roundtrip");
  sim::MachineOptions mo;
  mo.seed = 2;
  const auto m = sim::random_machine(mo);
  const auto volume = acceptance::Volume::of(m);
  const auto setup = acceptance::example_setup(volume);
  acceptance::E0Options eo;
  eo.mpe = ballgauge::Mpe::parse("2.5+L/250");
  const auto e0 = acceptance::run_e0(setup, volume, acceptance::virtual_touch(m), eo);
  const std::string e0_path = test::temp_dir() + "/records-e0.json";
  io::write_e0_result(e0_path, e0);
  const std::string probing = probing_file("records-probing.json", 1);

  records::Database db(path);
  EXPECT_EQ(db.schema_version(), records::kSchemaVersion);
  records::AddOptions a;
  a.machine = "CMM-7";
  a.date = "2025-03-01";
  a.state = records::State::AsFound;
  a.operator_name = "J. Smith";
  a.instrument = "gauge blocks set 12";
  a.temperature = 20.3;
  a.new_machine = true;
  const auto r1 = db.add(e0_path, a);
  EXPECT_EQ(r1.kind, "acceptance-e0");
  ASSERT_EQ(r1.figures.size(), 2u);  // E0 and R0
  EXPECT_EQ(r1.figures[0].name, "E0");
  EXPECT_DOUBLE_EQ(r1.figures[0].value, e0.e0_max * 1e3);
  a.new_machine = false;
  a.date = "2025-03-02";
  a.state = records::State::AsLeft;
  const auto r2 = db.add(probing, a);
  ASSERT_EQ(r2.figures.size(), 2u);  // PForm and PSize, with u = U/2
  EXPECT_EQ(r2.figures[0].name, "PForm");
  ASSERT_TRUE(r2.figures[0].u);

  const auto all = db.list();
  ASSERT_EQ(all.size(), 2u);
  EXPECT_EQ(all[0].machine, "CMM-7");
  EXPECT_EQ(all[0].state, records::State::AsFound);
  EXPECT_EQ(all[1].state, records::State::AsLeft);
  ASSERT_TRUE(all[0].temperature);
  EXPECT_DOUBLE_EQ(*all[0].temperature, 20.3);
  EXPECT_EQ(all[0].instrument, "gauge blocks set 12");
  EXPECT_DOUBLE_EQ(all[1].figures[0].value, r2.figures[0].value);
  EXPECT_EQ(db.content(r1.id), test::read_file(e0_path));
  EXPECT_EQ(db.show(r2.id).kind, "acceptance-probing");
  EXPECT_NE(test::error_of([&] { db.show(999); }).find("no record 999"), std::string::npos);
  records::ListFilter f;
  f.kind = "acceptance-probing";
  EXPECT_EQ(db.list(f).size(), 1u);
  f = {};
  f.to = "2025-03-01";
  EXPECT_EQ(db.list(f).size(), 1u);
  const auto ms = db.machines();
  ASSERT_EQ(ms.size(), 1u);
  EXPECT_EQ(ms[0].records, 2);
  EXPECT_EQ(ms[0].first, "2025-03-01");
  EXPECT_EQ(ms[0].last, "2025-03-02");
  // The export: a JSON array with the figures by name.
  const auto j = nlohmann::json::parse(records::to_json(all));
  ASSERT_EQ(j.size(), 2u);
  EXPECT_EQ(j[0]["state"], "as-found");
  EXPECT_DOUBLE_EQ(j[0]["figures"]["E0"]["value"].get<double>(), e0.e0_max * 1e3);
  EXPECT_TRUE(j[0]["figures"]["E0"]["u"].is_null());  // the file states none: null, not 0
  const std::string csv = records::to_csv(all);
  EXPECT_NE(csv.find("CMM-7,2025-03-02,acceptance-probing,as-left"), std::string::npos) << csv;
  // Reopened: the same.
  const records::Database again(path);
  EXPECT_EQ(again.list().size(), 2u);
}

TEST_P(RecordsOn, UnknownMachinesDuplicatesAndNonResultsAreRefused) {
  const std::string path = fresh_db("refusals");
  records::Database db(path);
  const std::string probing = probing_file("records-refuse.json", 2);
  records::AddOptions a;
  a.machine = "VMC-1";
  EXPECT_NE(test::error_of([&] { db.add(probing, a); }).find("--new-machine"), std::string::npos);
  a.new_machine = true;
  db.add(probing, a);
  EXPECT_NE(test::error_of([&] { db.add(probing, a); }).find("already stored"), std::string::npos);
  a.machine = "VMC-2";  // the same file for another machine is another record
  EXPECT_NO_THROW(db.add(probing, a));
  const std::string not_result = test::temp_file("records-not.json", "{\"a\": 1}");
  EXPECT_THROW(db.add(not_result, a), Error);
  a.date = "29/11/2026";
  EXPECT_NE(test::error_of([&] { db.add(probing, a); }).find("ISO 8601"), std::string::npos);
  a.date = "2026-13-01";
  EXPECT_THROW(db.add(probing, a), Error);
  EXPECT_EQ(db.list().size(), 2u);
  if (sqlite()) {
    EXPECT_THROW(records::Database(test::temp_dir() + "/no/such/dir/r.db"), Error);
    const std::string junk = test::temp_file("records-junk.db", std::string(4096, 'x'));
    EXPECT_NE(test::error_of([&] { records::Database{junk}; }).find("not an SQLite database"),
              std::string::npos);
  } else {
    // A server that is not there, and a database the server does not have: named, not crashed.
    EXPECT_NE(test::error_of([] {
                records::Database("postgresql://nobody@127.0.0.1:1/x");
              }).find("cannot reach the PostgreSQL server"),
              std::string::npos);
    const std::string url = path.substr(0, path.rfind('/') + 1) + "no_such_database";
    EXPECT_NE(test::error_of([&] { records::Database{url}; }).find("no_such_database"),
              std::string::npos);
  }
}

// Machine ids, notes and file contents are data: quotes, semicolons, SQL and a 1 MB note are
// stored and read back as they were; a NUL character or bytes that are not UTF-8 in a text are
// refused by name (no back end can store both), and nothing is stored.
TEST_P(RecordsOn, NoStringCanBreakAQuery) {
  const std::string path = fresh_db("strings");
  records::Database db(path);
  records::AddOptions a;
  a.machine = "M'1\"; DROP TABLE records; --";
  a.operator_name = "O'Brien; Ångström µm";
  a.note = std::string(1 << 20, 'n') + "'; DELETE FROM figures; --";
  a.new_machine = true;
  const auto r = db.add(probing_file("records-strings.json", 3), a);
  const auto back = db.show(r.id);
  EXPECT_EQ(back.machine, a.machine);
  EXPECT_EQ(back.operator_name, a.operator_name);
  EXPECT_EQ(back.note, a.note);
  EXPECT_EQ(back.figures.size(), 2u);
  records::ListFilter f;
  f.machine = a.machine;
  EXPECT_EQ(db.list(f).size(), 1u);
  f.machine = "' OR '1'='1";
  EXPECT_EQ(db.list(f).size(), 0u);
  a.note = "";
  a.operator_name = std::string("O'Brien\0x", 9);
  const std::string other = probing_file("records-strings-2.json", 4);
  EXPECT_NE(test::error_of([&] { db.add(other, a); }).find("operator holds a NUL"),
            std::string::npos);
  a.operator_name = "ok";
  a.note = "\xC3\x28 not UTF-8";
  EXPECT_NE(test::error_of([&] { db.add(other, a); }).find("note is not UTF-8"), std::string::npos);
  EXPECT_EQ(db.list().size(), 1u);
}

TEST_P(RecordsOn, ADatabaseFromANewerTrueaxisIsRefused) {
  const std::string path = fresh_db("newer");
  { records::Database db(path); }
  test::raw_value(path, "UPDATE meta SET value = '99' WHERE key = 'schema_version'");
  for (const auto access : {records::Access::ReadWrite, records::Access::ReadOnly}) {
    const std::string e = test::error_of([&] { records::Database db(path, access); });
    EXPECT_NE(e.find("newer trueaxis"), std::string::npos) << e;
    EXPECT_NE(e.find("schema 99"), std::string::npos) << e;
  }
}

// Two processes adding at once: every record is there. A process killed while adding leaves
// every record whole (its figures with it) and the database usable.
TEST_P(RecordsOn, ConcurrentAddsLoseNothingAndAKilledAddLeavesItConsistent) {
  const std::string path = fresh_db("concurrent");
  { records::Database db(path); }
  constexpr int kEach = 8;
  std::vector<std::string> files[2];
  for (int p = 0; p < 2; ++p)
    for (int i = 0; i < kEach; ++i)
      files[p].push_back(probing_file(fmt::format("records-c{}-{}.json", p, i), 100 + p * 50 + i));
  pid_t kids[2];
  for (int p = 0; p < 2; ++p) {
    kids[p] = fork();
    ASSERT_GE(kids[p], 0);
    if (kids[p] == 0) {
      int code = 0;
      try {
        records::Database db(path);
        records::AddOptions a;
        a.machine = fmt::format("M{}", p);
        a.new_machine = true;
        for (const auto& f : files[p]) {
          db.add(f, a);
          a.new_machine = false;
        }
      } catch (...) {
        code = 1;
      }
      _exit(code);
    }
  }
  for (const pid_t k : kids) {
    int status = 0;
    waitpid(k, &status, 0);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  }
  records::Database db(path);
  EXPECT_EQ(db.list().size(), 2u * kEach);
  // A process adding in a loop, killed: whatever it stored is whole.
  const pid_t k = fork();
  ASSERT_GE(k, 0);
  if (k == 0) {
    try {
      records::Database child(path);
      records::AddOptions a;
      a.machine = "killed";
      a.new_machine = true;
      for (int i = 0;; ++i) {
        a.note = std::to_string(i);  // the same file again would be a duplicate: a new machine
        a.machine = fmt::format("killed-{}", i);
        child.add(files[0][0], a);
      }
    } catch (...) {
    }
    _exit(0);
  }
  usleep(300000);
  kill(k, SIGKILL);
  int status = 0;
  waitpid(k, &status, 0);
  const records::Database after(path);
  const auto all = after.list();
  EXPECT_GE(all.size(), 2u * kEach);
  for (const auto& r : all) EXPECT_EQ(r.figures.size(), 2u) << r.machine;
  if (sqlite()) {
    EXPECT_EQ(test::raw_value(path, "PRAGMA integrity_check"), "ok");
  }
  EXPECT_EQ(test::raw_value(
                path, "SELECT COUNT(*) FROM figures WHERE record NOT IN (SELECT id FROM records)"),
            "0");
}

// Opened for reading, a database is listed and nothing is written; one in a directory and file
// that cannot be written is still read, and adding to it fails with the reason.
TEST_P(RecordsOn, AReadOnlyDatabaseIsReadAndRefusesWritesClearly) {
  const std::string path = fresh_db("readonly");
  records::AddOptions a;
  a.machine = "RO-1";
  a.new_machine = true;
  { records::Database(path).add(probing_file("records-ro.json", 5), a); }
  a.new_machine = false;
  const std::string more = probing_file("records-ro-2.json", 6);
  {
    const records::Database ro(path, records::Access::ReadOnly);
    EXPECT_EQ(ro.list().size(), 1u);
    EXPECT_EQ(ro.machines().size(), 1u);
    const std::string e =
        test::error_of([&] { records::Database(path, records::Access::ReadOnly).add(more, a); });
    EXPECT_NE(e.find("read-only"), std::string::npos) << e;
  }
  if (sqlite()) {
    EXPECT_NE(test::error_of([&] {
                records::Database(test::temp_dir() + "/absent.db", records::Access::ReadOnly);
              }).find("no records database"),
              std::string::npos);
    // A read-only directory and file. Root may write anything: the check runs as 'nobody'.
    const std::string dir = std::filesystem::path(path).parent_path().string() + "/ro-dir";
    std::filesystem::create_directories(dir);
    const std::string db = dir + "/r.db";
    std::filesystem::copy_file(path, db, std::filesystem::copy_options::overwrite_existing);
    ::chmod(db.c_str(), 0444);
    ::chmod(dir.c_str(), 0555);
    const pid_t k = fork();
    ASSERT_GE(k, 0);
    if (k == 0) {
      int code = 0;
      if (geteuid() == 0 && setuid(65534) != 0) _exit(9);
      try {
        if (records::Database(db, records::Access::ReadOnly).list().size() != 1) code = 3;
        const std::string e = test::error_of([&] { records::Database(db).add(more, a); });
        if (e.find("cannot be written") == std::string::npos) {
          fprintf(stderr, "read-only: %s\n", e.c_str());
          code = 4;
        }
      } catch (const std::exception& e) {
        fprintf(stderr, "read-only: %s\n", e.what());
        code = 5;
      }
      _exit(code);
    }
    int status = 0;
    waitpid(k, &status, 0);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << WEXITSTATUS(status);
    ::chmod(dir.c_str(), 0755);
    EXPECT_EQ(records::Database(db, records::Access::ReadOnly).list().size(), 1u);
  }
}

// The disk fills while a record is added (the file size limit of a child process, as a full
// disk answers): the add fails and says so, and every record stored before is intact.
TEST(Records, AFullDiskLosesNothingStoredBefore) {
  const std::string path = test::fresh_records("sqlite", "full-disk");
  records::AddOptions a;
  a.machine = "FULL-1";
  a.new_machine = true;
  { records::Database(path).add(probing_file("records-full.json", 7), a); }
  a.new_machine = false;
  a.note = std::string(4 << 20, 'n');  // 4 MB: far past the limit below
  const std::string more = probing_file("records-full-2.json", 8);
  const pid_t k = fork();
  ASSERT_GE(k, 0);
  if (k == 0) {
    signal(SIGXFSZ, SIG_IGN);  // a write past the limit fails (EFBIG) instead of killing
    const auto size = static_cast<rlim_t>(std::filesystem::file_size(path));
    const rlimit limit{size + 65536, size + 65536};
    setrlimit(RLIMIT_FSIZE, &limit);
    const std::string e = test::error_of([&] { records::Database(path).add(more, a); });
    if (e.find("disk") == std::string::npos) fprintf(stderr, "full disk: %s\n", e.c_str());
    _exit(e.find("disk") == std::string::npos ? 3 : 0);
  }
  int status = 0;
  waitpid(k, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << WEXITSTATUS(status);
  records::Database db(path);
  ASSERT_EQ(db.list().size(), 1u);
  EXPECT_EQ(db.list()[0].figures.size(), 2u);
  EXPECT_EQ(test::raw_value(path, "PRAGMA integrity_check"), "ok");
  a.note = "after";
  EXPECT_EQ(db.add(more, a).figures.size(), 2u);  // and it is usable again
}

// A database of schema 1 (figures ordered by SQLite's rowid) is migrated when opened: the
// figures keep their order, the version becomes the current one.
TEST(Records, ASchemaOneDatabaseIsMigrated) {
  const std::string path = test::fresh_records("sqlite", "schema-1");
  {
    SQLite::Database raw(path, SQLite::OPEN_READWRITE | SQLite::OPEN_CREATE);
    raw.exec(
        "CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);"
        "INSERT INTO meta VALUES ('schema_version', '1');"
        "CREATE TABLE machines (id TEXT PRIMARY KEY, created TEXT NOT NULL);"
        "CREATE TABLE records (id INTEGER PRIMARY KEY, machine TEXT NOT NULL REFERENCES "
        "machines(id), date TEXT NOT NULL, kind TEXT NOT NULL, state TEXT NOT NULL, operator "
        "TEXT NOT NULL, instrument TEXT NOT NULL, temperature_C REAL, note TEXT NOT NULL, "
        "trueaxis_version TEXT NOT NULL, file_name TEXT NOT NULL, digest TEXT NOT NULL, "
        "content BLOB NOT NULL, UNIQUE (machine, digest));"
        "CREATE TABLE figures (record INTEGER NOT NULL REFERENCES records(id), name TEXT NOT "
        "NULL, axis TEXT NOT NULL, value REAL NOT NULL, u REAL, unit TEXT NOT NULL);"
        "CREATE INDEX figures_by_record ON figures(record);"
        "INSERT INTO machines VALUES ('OLD-1', '2025-01-01');"
        "INSERT INTO records VALUES (1, 'OLD-1', '2025-01-02', 'positioning', 'as-found', '', "
        "'', NULL, '', '1.0', 'p.json', 'abc-3', X'7B7D');"
        "INSERT INTO figures VALUES (1, 'R', 'X', 3.5, NULL, 'µm');"
        "INSERT INTO figures VALUES (1, 'A', 'X', 7.25, NULL, 'µm');");
  }
  const records::Database db(path, records::Access::ReadOnly);
  EXPECT_EQ(db.schema_version(), records::kSchemaVersion);
  const auto r = db.show(1);
  ASSERT_EQ(r.figures.size(), 2u);
  EXPECT_EQ(r.figures[0].name, "R");  // the order they were stored in, not by name
  EXPECT_EQ(r.figures[1].name, "A");
  EXPECT_EQ(r.figures[1].value, 7.25);
  EXPECT_EQ(db.content(1), "{}");
}

TEST(Records, DaysAndDatesRoundTripOverLeapYears) {
  EXPECT_EQ(records::day_number("1970-01-01"), 0);
  EXPECT_EQ(records::day_number("2000-03-01") - records::day_number("2000-02-28"), 2);  // leap
  EXPECT_EQ(records::day_number("2100-03-01") - records::day_number("2100-02-28"), 1);  // not
  EXPECT_EQ(records::day_number("2026-11-29T10:00:00Z"), records::day_number("2026-11-29"));
  for (long long d = -800000; d < 800000; d += 997)
    ASSERT_EQ(records::day_number(records::date_of_day(d)), d) << records::date_of_day(d);
  EXPECT_THROW(records::day_number("29/11/2026"), Error);
  EXPECT_THROW(records::day_number("2026-13-01"), Error);
}

// A figure drifting linearly, tested every few months with noise of known u: the fitted drift
// lies within its stated uncertainty of the true one as often as a normal distribution says,
// and so does the date the line reaches the tolerance.
TEST(Records, TrendRecoversTheDriftAndDueDateWithinTheirUncertainty) {
  constexpr double kDrift = 1.5, kStart = 4.0, kU = 0.4, kTolerance = 12;  // µm, µm/year
  constexpr int kRuns = 400;
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, kU);
  std::uniform_int_distribution<int> jitter(-20, 20);
  const long long day0 = records::day_number("2024-01-15");
  int drift_in_2u = 0, due_in_2u = 0, due_given = 0;
  for (int run = 0; run < kRuns; ++run) {
    std::vector<records::TrendPoint> pts;
    for (int visit = 0; visit < 9; ++visit) {  // every ~3 months over two years
      const long long day = day0 + visit * 91 + jitter(rng);
      records::TrendPoint p;
      p.date = records::date_of_day(day);
      p.value = kStart + kDrift * static_cast<double>(day - day0) / 365.2425 + noise(rng);
      p.u = kU;
      pts.push_back(p);
    }
    std::shuffle(pts.begin(), pts.end(), rng);  // any order: sorted by date
    records::TrendOptions o;
    o.tolerance = kTolerance;
    const auto t = records::fit_trend(pts, o);
    ASSERT_TRUE(t.drift_per_year && t.u_drift) << t.summary();
    EXPECT_LT(std::abs(*t.drift_per_year - kDrift), 5 * *t.u_drift);
    drift_in_2u += std::abs(*t.drift_per_year - kDrift) <= 2 * *t.u_drift;
    if (t.due) {
      ++due_given;
      const double true_due = static_cast<double>(day0) + (kTolerance - kStart) / kDrift * 365.2425;
      const double err = static_cast<double>(records::day_number(*t.due)) - true_due;
      due_in_2u += std::abs(err) <= 2 * *t.u_due_days + 1;  // a day: the date's rounding
    }
  }
  EXPECT_EQ(due_given, kRuns);  // a drift of 1.5 ± ~0.2 µm/year always stands out
  // 95 % within 2u for a normal estimate; at least 91 % of 400 (3σ of the binomial below 95 %).
  EXPECT_GE(drift_in_2u, 364) << drift_in_2u;
  EXPECT_GE(due_in_2u, 364) << due_in_2u;
}

// Without stated u the scatter gives the uncertainty; too few points, no drift out of the noise,
// or a falling figure: no due date, and the reason.
TEST(Records, TrendSaysWhatTheDataCannotSupport) {
  auto point = [](const std::string& date, double v, std::optional<double> u = std::nullopt) {
    records::TrendPoint p;
    p.date = date;
    p.value = v;
    p.u = u;
    return p;
  };
  records::TrendOptions o;
  o.tolerance = 10;
  EXPECT_NE(records::fit_trend({point("2025-01-01", 3)}, o).not_resolved.find("at least two"),
            std::string::npos);
  const auto two = records::fit_trend({point("2025-01-01", 3), point("2026-01-01", 4)}, o);
  EXPECT_FALSE(two.u_drift);
  EXPECT_FALSE(two.due);
  EXPECT_NE(two.not_resolved.find("cannot be estimated"), std::string::npos);
  // Exactly on a line without u: drift exact, its u zero from zero scatter, due date exact.
  const auto exact =
      records::fit_trend({point("2024-01-01", 2), point("2025-01-01", 2 + 366 / 365.2425),
                          point("2026-01-01", 2 + 731 / 365.2425)},
                         o);
  ASSERT_TRUE(exact.drift_per_year && exact.due);
  EXPECT_NEAR(*exact.drift_per_year, 1, 1e-12);
  EXPECT_EQ(*exact.due,
            records::date_of_day(records::day_number("2024-01-01") + std::llround(8 * 365.2425)));
  const auto flat = records::fit_trend(
      {point("2024-01-01", 3, 0.5), point("2025-01-01", 3.1, 0.5), point("2026-01-01", 2.9, 0.5)},
      o);
  ASSERT_TRUE(flat.u_drift);
  EXPECT_FALSE(flat.due);
  EXPECT_NE(flat.not_resolved.find("does not stand out"), std::string::npos) << flat.summary();
  const auto falling = records::fit_trend(
      {point("2024-01-01", 9, 0.1), point("2025-01-01", 7, 0.1), point("2026-01-01", 5, 0.1)}, o);
  EXPECT_FALSE(falling.due);
  EXPECT_NE(falling.not_resolved.find("falling"), std::string::npos);
  // Scatter larger than the stated u widens the drift's u (Birge ratio).
  const auto tight =
      records::fit_trend({point("2024-01-01", 1, 0.01), point("2025-01-01", 3, 0.01),
                          point("2026-01-01", 3, 0.01), point("2027-01-01", 5, 0.01)});
  EXPECT_GT(*tight.u_drift, 0.1);
}

// The database hands a figure's history to the trend; a figure it does not have is named with
// the ones it has.
TEST_P(RecordsOn, HistoryFromTheDatabase) {
  const std::string path = fresh_db("history");
  records::Database db(path);
  records::AddOptions a;
  a.machine = "CMM-H";
  a.new_machine = true;
  for (int k = 0; k < 3; ++k) {
    a.date = fmt::format("202{}-06-01", 4 + k);
    db.add(probing_file(fmt::format("records-h{}.json", k), 200 + k), a);
    a.new_machine = false;
  }
  const auto h = db.history("CMM-H", "PForm", "");
  ASSERT_EQ(h.points.size(), 3u);
  EXPECT_EQ(h.points[0].date, "2024-06-01");
  EXPECT_EQ(h.unit, "µm");
  ASSERT_TRUE(h.points[2].u);
  const std::string e = test::error_of([&] { db.history("CMM-H", "PFrom", ""); });
  EXPECT_NE(e.find("it has: PForm, PSize"), std::string::npos) << e;
  const auto t = records::fit_trend(h.points);
  EXPECT_TRUE(t.drift_per_year);
  const auto j = nlohmann::json::parse(records::to_json(t, "CMM-H"));
  EXPECT_EQ(j["kind"], "trend");
  EXPECT_EQ(j["points"].size(), 3u);
  EXPECT_TRUE(j["due"]["date"].is_null());
}

INSTANTIATE_TEST_SUITE_P(Backends, RecordsOn, ::testing::Values("sqlite", "postgresql"),
                         [](const auto& info) { return info.param; });
