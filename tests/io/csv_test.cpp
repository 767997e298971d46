#include "trueaxis/io/csv.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "../../src/io/fast_text.hpp"
#include "../test_util.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/io/files.hpp"

using trueaxis::Error;
using trueaxis::io::CsvTable;

namespace {

std::string error_of(const std::string& text) {
  try {
    CsvTable::parse(text, "f.csv");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(Csv, ParsesHeaderAndNumbers) {
  const auto t = CsvTable::parse("x, a ,b\r\n0,1.5,-2\n\n10, +3e-1 ,4\n", "f.csv");
  ASSERT_EQ(t.cols(), 3u);
  ASSERT_EQ(t.rows(), 2u);
  EXPECT_EQ(t.header()[1], "a");
  EXPECT_DOUBLE_EQ(t.column(1)[1], 0.3);
  EXPECT_DOUBLE_EQ(t.column(2)[0], -2);
  EXPECT_EQ(t.require("b"), 2);
  EXPECT_EQ(t.where(1, 1), "f.csv:4:5: ");
}

// Plain rows are read by a fast path and anything else line by line: padded, signed, CRLF and
// blank lines mixed in give the same table either way, and a row that fails half-way leaves no
// values behind.
TEST(Csv, PlainAndPaddedRowsReadAlike) {
  const auto t =
      CsvTable::parse("x,a,b\n0,1,2\n\t10 ,\t+5e0 , -0.25\r\n  \n20,3,4\n30,+.5,1e-3", "f.csv");
  ASSERT_EQ(t.rows(), 4u);
  const double a[] = {1, 5, 3, 0.5}, b[] = {2, -0.25, 4, 1e-3};
  for (int r = 0; r < 4; ++r) {
    EXPECT_EQ(t.column(0)[r], 10.0 * r);
    EXPECT_EQ(t.column(1)[r], a[r]);
    EXPECT_EQ(t.column(2)[r], b[r]);
  }
  EXPECT_EQ(t.where(3, 2), "f.csv:6:8: ");
  EXPECT_EQ(error_of("x,a,b\n0,1,2\n1,2,3x\n"), "f.csv:3:5: '3x' is not a number (column 'b')");
  EXPECT_NE(error_of("x,a,b\n0,1,2\n1,2\n").find("f.csv:3:4: missing field for column 'b'"),
            std::string::npos);
}

TEST(Csv, RejectsNonNumberWithLineAndColumn) {
  EXPECT_EQ(error_of("x,a\n0,1\n1,abc\n"), "f.csv:3:3: 'abc' is not a number (column 'a')");
}

TEST(Csv, RejectsNanAndInf) {
  EXPECT_EQ(error_of("x,a\n0,nan\n"), "f.csv:2:3: NaN is not allowed (column 'a')");
  EXPECT_EQ(error_of("x,a\n0,1\n1,-inf\n"), "f.csv:3:3: Inf is not allowed (column 'a')");
}

TEST(Csv, RejectsMissingExtraAndEmptyFields) {
  EXPECT_NE(error_of("x,a,b\n0,1\n").find("f.csv:2:4: missing field for column 'b'"),
            std::string::npos);
  EXPECT_NE(error_of("x,a\n0,1,2\n").find("f.csv:2:5: extra field"), std::string::npos);
  EXPECT_EQ(error_of("x,a\n0, \n"), "f.csv:2:3: empty field in column 'a'");
}

TEST(Csv, RejectsBadHeaders) {
  EXPECT_EQ(error_of(""), "f.csv:1:1: empty file: expected a header row");
  EXPECT_EQ(error_of("x,x\n1,2\n"), "f.csv:1:3: duplicated column name 'x'");
  EXPECT_EQ(error_of("x,,a\n1,2,3\n"), "f.csv:1:3: empty column name (column 2)");
}

TEST(Csv, MissingColumnAndMissingFile) {
  const auto t = CsvTable::parse("x,a\n1,2\n", "f.csv");
  try {
    t.require("b");
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "f.csv:1:1: missing column 'b' (header has: x, a)");
  }
  EXPECT_THROW(CsvTable::read("/nonexistent/file.csv"), Error);
}

TEST(Csv, WriteReadRoundTripIsExact) {
  Eigen::VectorXd a(3), b(3);
  a << 0.1, 1.0 / 3.0, -2e-17;
  b << 9.87654321e11, 5, 6;  // inputs are bounded by 1e12
  const std::string p = trueaxis::test::temp_file("rt.csv", "");
  trueaxis::io::write_csv(p, {"a", "b"}, {&a, &b});
  const auto t = CsvTable::read(p);
  EXPECT_EQ(t.column(0), a);
  EXPECT_EQ(t.column(1), b);
}

// Large inputs are parsed in parallel chunks split at line boundaries. The result, and the line
// numbers in errors, must be those of a sequential parse wherever the chunks happen to be cut.
TEST(Csv, LargeFileParsedInChunksMatchesSequentialMeaning) {
  constexpr int kRows = 300000;  // ~10 MB: several chunks on any multi-core machine
  std::string text = "x,a,b\n";
  std::vector<int> line_of_row;
  int line = 1;
  for (int i = 0; i < kRows; ++i) {
    if (i % 1000 == 7) {  // blank lines scattered through every chunk
      text += "\n  \n";
      line += 2;
    }
    text += std::to_string(i) + "," + std::to_string(i * 0.5) + ", " + std::to_string(-i) + "\n";
    line_of_row.push_back(++line);
  }
  const auto t = CsvTable::parse(text, "big.csv");
  ASSERT_EQ(t.rows(), static_cast<std::size_t>(kRows));
  for (int i : {0, 1, kRows / 3, kRows / 2, kRows - 1}) {
    EXPECT_EQ(t.column(0)[i], i);
    EXPECT_EQ(t.column(1)[i], i * 0.5);
    EXPECT_EQ(t.column(2)[i], -i);
  }
  EXPECT_EQ(t.where(kRows - 1, 2), fmt::format("big.csv:{}:{}: ", line_of_row.back(),
                                               std::to_string(kRows - 1).size() +
                                                   std::to_string((kRows - 1) * 0.5).size() + 4));
  // An error late in the file names its absolute line; with two errors the earlier one wins.
  const int bad = kRows * 3 / 4;
  std::string late = text;
  const std::string row = "\n" + std::to_string(bad) + ",";
  late.replace(late.find(row) + row.size(), 1, "q");
  EXPECT_EQ(
      error_of(late).rfind(
          fmt::format("f.csv:{}:{}: 'q", line_of_row[bad], std::to_string(bad).size() + 2), 0),
      0u);
  std::string two = late;
  const std::string early = "\n" + std::to_string(kRows / 10) + ",";
  two.replace(two.find(early) + early.size(), 1, "z");
  EXPECT_EQ(error_of(two).rfind(fmt::format("f.csv:{}:", line_of_row[kRows / 10]), 0), 0u);
}

TEST(Csv, LargeWriteReadRoundTripIsExact) {
  constexpr int kRows = 200000;
  Eigen::VectorXd a(kRows), b(kRows);
  for (int i = 0; i < kRows; ++i) {
    a[i] = i * 0.01;
    b[i] = std::sin(i * 1e-3) * 1e-7 + 1.0 / (i + 3);
  }
  const std::string p = trueaxis::test::temp_file("big_rt.csv", "");
  trueaxis::io::write_csv(p, {"a", "b"}, {&a, &b});
  const auto t = CsvTable::read(p);
  EXPECT_EQ(t.column(0), a);
  EXPECT_EQ(t.column(1), b);
}

// Files of a megabyte or more are mapped rather than copied when they need no normalising; the
// table, the located errors and the line-end handling must be the same as reading them as text.
TEST(Csv, LargeFilesReadFromDiskAsFromText) {
  std::string lf = "x,a,b\n";
  for (int i = 0; i < 100000; ++i)
    lf += std::to_string(i) + "," + std::to_string(i * 0.25) + "," + std::to_string(-i) + "\n";
  ASSERT_GT(lf.size(), std::size_t{1} << 20);
  std::string crlf;
  for (char c : lf) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
  const std::string bom = "\xEF\xBB\xBF" + lf;
  const auto expect = CsvTable::parse(lf, "mem.csv");
  for (const auto& [name, text] : {std::pair{"lf.csv", lf}, {"crlf.csv", crlf}, {"bom.csv", bom}}) {
    const std::string p = trueaxis::test::temp_file(name, text);
    const auto t = CsvTable::read(p);
    ASSERT_EQ(t.rows(), expect.rows()) << name;
    EXPECT_EQ(t.header(), expect.header()) << name;
    for (int c = 0; c < 3; ++c) EXPECT_EQ(t.column(c), expect.column(c)) << name;
    EXPECT_EQ(t.where(77777, 2), p + expect.where(77777, 2).substr(std::string("mem.csv").size()))
        << name;
    // The text read back for locating fields is the normalised one.
    EXPECT_TRUE(trueaxis::io::detail::Text::read(p).view() == lf) << name;
  }
  // An error near the end of a mapped file is located as in the text.
  std::string bad = lf;
  bad.replace(bad.rfind("\n99998,") + 7, 1, "q");
  const std::string p = trueaxis::test::temp_file("bad_big.csv", bad);
  try {
    CsvTable::read(p);
    FAIL() << "no error";
  } catch (const trueaxis::Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind(p + ":100000:7: 'q", 0), 0u) << e.what();
  }
}

// Found by fuzzing: CR-only files were read as one giant line (and the error quoted the whole
// file), a UTF-8 byte-order mark made 'x' a missing column, tab-separated files were reported
// as a missing column (they are read now, see SpreadsheetDialectsReadAsPlainCsv), and an error
// quoted a 4 MB token.
TEST(Csv, LineEndsByteOrderMarkTabsAndLongTokens) {
  for (const char* text :
       {"x,a\r\n0,1\r\n10,2\r\n", "x,a\r0,1\r10,2\r", "\xEF\xBB\xBFx,a\n0,1\n10,2\n"}) {
    const auto t = CsvTable::parse(text, "f.csv");
    ASSERT_EQ(t.rows(), 2u) << text;
    EXPECT_EQ(t.header()[0], "x");
    EXPECT_EQ(t.column(1)[1], 2);
  }
  EXPECT_EQ(error_of("x,a\r0,1\r10,q\r"), "f.csv:3:4: 'q' is not a number (column 'a')");
  const std::string huge = "x,a\n0," + std::string(4 << 20, 'q') + "\n";
  const std::string m = error_of(huge);
  EXPECT_LT(m.size(), 120u) << m.substr(0, 200);
  EXPECT_NE(m.find("f.csv:2:3: 'qqqq"), std::string::npos) << m.substr(0, 200);
}

// Found by fuzzing: a directory or /dev/zero given as a file (memory grew without limit).
TEST(Csv, OnlyRegularFilesAreRead) {
  EXPECT_EQ(trueaxis::test::error_of([] { CsvTable::read("/dev/zero"); }),
            "/dev/zero: not a regular file (a device, pipe or socket)");
  const std::string dir = trueaxis::test::temp_dir();
  EXPECT_EQ(trueaxis::test::error_of([&] { CsvTable::read(dir); }),
            dir + ": not a regular file (a directory)");
  EXPECT_EQ(trueaxis::test::error_of([&] { CsvTable::read(dir + "/none.csv"); }),
            dir + "/none.csv: no such file");
}

// Found by fuzzing: 1e308 in a probe file ran through to bare inf/-nan tokens in result.json.
TEST(Csv, AbsurdMagnitudesAreRefusedWhereTheyStand) {
  EXPECT_EQ(error_of("x,a\n0,1\n10,1e308\n"),
            "f.csv:3:4: 1e+308 is out of range in column 'a' (its size must be below 1e+12)");
  EXPECT_EQ(error_of("x,a\n-2e12,1\n"),
            "f.csv:2:1: -2e+12 is out of range in column 'x' (its size must be below 1e+12)");
}

// Found by fuzzing: 'fit -o /dev/full' exited 0 with the file lost; concurrent runs writing the
// same output could leave a mix of both; reports created missing directories while every other
// output refused. Now: write errors are errors, files are put in place whole, and every output
// refuses a missing directory.
TEST(Csv, OutputsAreWholeOrNotAtAllAndNeedTheirDirectory) {
  namespace fs = std::filesystem;
  const Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(5, 0, 4);
  EXPECT_NE(trueaxis::test::error_of([&] {
              trueaxis::io::write_csv("/dev/full", {"x"}, {&x});
            }).find("/dev/full: write error"),
            std::string::npos);
  const std::string dir = trueaxis::test::temp_dir();
  EXPECT_EQ(trueaxis::test::error_of(
                [&] { trueaxis::io::write_csv(dir + "/no/such/t.csv", {"x"}, {&x}); }),
            dir + "/no/such/t.csv: the directory '" + dir +
                "/no/such' does not exist (create it "
                "first)");
  // A file that is never finished leaves the old one as it was, and no temporary behind.
  const std::string p = trueaxis::test::temp_file("old.csv", "x\n1\n");
  {
    trueaxis::io::detail::OutFile f(p);
    f.write("x\n2\n");
  }  // destroyed without close(): an exception on the way
  EXPECT_EQ(CsvTable::read(p).column(0)[0], 1);
  for (const auto& e : fs::directory_iterator(dir))
    EXPECT_EQ(e.path().filename().string().find(".partial-"), std::string::npos) << e.path();
  trueaxis::io::write_csv(p, {"x"}, {&x});
  EXPECT_EQ(CsvTable::read(p).rows(), 5u);
}

// Found by fuzzing: a 2 GB CSV took 45-58 s and 10.5 GB of memory before it was refused. A file
// over the limit is refused by its size, before anything is read (a sparse file here).
TEST(Csv, AFileOverTheLimitIsRefusedBeforeReading) {
  const std::string p = trueaxis::test::temp_dir() + "/huge.csv";
  { std::ofstream(p) << "x,a\n"; }
  std::filesystem::resize_file(p, trueaxis::io::detail::kMaxInputBytes + 1);
  // The size refusal comes from the file system's answer, not from reading (no timing asserted).
  const std::string m = trueaxis::test::error_of([&] { CsvTable::read(p); });
  std::filesystem::remove(p);
  EXPECT_NE(m.find("huge.csv: 1.1 GB is more than trueaxis reads in one file"), std::string::npos)
      << m;
}

// The examples and the demo's copies of Moody's files are written like every result: whole, or
// not at all; into a folder that does not exist, refused by name.
TEST(Files, WriteTextReplacesWholeOrRefusesByName) {
  const std::string p = trueaxis::test::temp_file("text.txt", "old\n");
  trueaxis::io::write_text(p, "new\n");
  EXPECT_EQ(CsvTable::read(p).header()[0], "new");
  const std::string missing = trueaxis::test::temp_dir() + "/no-such-folder/a.txt";
  const std::string m = trueaxis::test::error_of([&] { trueaxis::io::write_text(missing, "x"); });
  EXPECT_NE(m.find("no-such-folder"), std::string::npos) << m;
  EXPECT_FALSE(std::filesystem::exists(missing));
}

// What Excel, LibreOffice and instruments write in other locales reads to the same numbers as a
// plain file: ';' or tab separators with decimal commas, Excel's "sep=;" line, RFC 4180 quotes,
// a byte-order mark, CRLF, a Latin-1 'µ' in a header. Messages name the file's own line and
// column and quote the field as written.
TEST(Csv, SpreadsheetDialectsReadAsPlainCsv) {
  const auto plain = CsvTable::parse("x,a\n0,1.5\n10,-2.25\n", "plain.csv");
  for (const char* text : {
           "x;a\n0;1,5\n10;-2,25\n",                             // German Excel
           "sep=;\nx;a\n0;1,5\n10;-2,25\n",                      // with Excel's sep line
           "\xEF\xBB\xBFsep=;\r\nx;a\r\n0;1,5\r\n10;-2,25\r\n",  // BOM, CRLF
           "x\ta\n0\t1,5\n10\t-2,25\n",                          // tab, decimal comma
           "x\ta\n0\t1.5\n10\t-2.25\n",                          // tab, decimal point
           "\"x\",\"a\"\n\"0\",\"1.5\"\n\"10\",\"-2.25\"\n",     // RFC 4180, all quoted
           "x,a\n0,\"1,5\"\n10,\"-2,25\"\n",                     // quoted decimal commas
           "\"x\";\"a\"\n0;\"1,5\"\n10;-2,25\n",                 // quoted ';' file
       }) {
    SCOPED_TRACE(text);
    const auto t = CsvTable::parse(text, "f.csv");
    ASSERT_EQ(t.header(), plain.header());
    ASSERT_EQ(t.rows(), plain.rows());
    for (int c = 0; c < 2; ++c) EXPECT_EQ(t.column(c), plain.column(c));
  }
  // Lines and columns are the file's (the sep line counts), the field quoted as written.
  EXPECT_EQ(error_of("sep=;\nx;a\n0;1,5\n10;q\n"), "f.csv:4:4: 'q' is not a number (column 'a')");
  EXPECT_EQ(error_of("x;a\n0;1.234,5\n"), "f.csv:2:3: '1.234,5' is not a number (column 'a')");
  EXPECT_EQ(error_of("x,a\n0,\"1\n10,2\n"), "f.csv:2:3: a quoted field is not closed on its line");
  EXPECT_EQ(error_of("x;a\n0;1,5;7\n"), "f.csv:2:7: extra field: the header has 2 columns");
  EXPECT_EQ(error_of("sep=;\n\n"), "f.csv:1:1: empty file: expected a header row");
  // A Latin-1 (Windows-1252) µ in a header is read as UTF-8 µ; a UTF-8 one is kept.
  EXPECT_EQ(CsvTable::parse("x,dev_\xB5m\n0,1\n", "f.csv").header()[1], "dev_\xC2\xB5m");
  EXPECT_EQ(CsvTable::parse("x,dev_\xC2\xB5m\n0,1\n", "f.csv").header()[1], "dev_\xC2\xB5m");
}

// The same through a file on disk (read() maps large files; a dialect is rewritten in a copy).
TEST(Csv, SpreadsheetDialectFromDisk) {
  const std::string dir = trueaxis::test::temp_dir();
  const std::string p = dir + "/excel.csv";
  std::string text = "\xEF\xBB\xBFsep=;\r\nx;a\r\n";
  for (int i = 0; i < 60000; ++i) text += fmt::format("{};{},5\r\n", i, i % 7);
  {
    std::FILE* f = std::fopen(p.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    std::fwrite(text.data(), 1, text.size(), f);
    std::fclose(f);
  }
  const auto t = CsvTable::read(p);
  ASSERT_EQ(t.rows(), 60000u);
  EXPECT_EQ(t.column(1)[59999], 59999 % 7 + 0.5);
  EXPECT_EQ(t.where(2, 1), p + ":5:3: ");
}

// Column names that carry their unit, as instruments and spreadsheets write them: the values are
// converted to the unit the reader asks for; a unit of another kind is refused at its place.
TEST(Csv, UnitsInNamesConvertToTheReadersUnit) {
  using trueaxis::io::Unit;
  constexpr double kRoundOff = 1e-15;  // relative: one conversion factor's rounding
  auto t = CsvTable::parse(
      "x [m], a (nm), b_um, c / mm, d, e [\xC2\xB5rad], f_deg\n0.5,250,1.5,2,7,10,90\n", "f.csv");
  EXPECT_EQ(t.find("x"), 0);  // by quantity, not converted
  EXPECT_EQ(t.require("x", Unit::Millimetre), 0);
  EXPECT_DOUBLE_EQ(t.column(0)[0], 500);
  EXPECT_EQ(t.require("x", Unit::Millimetre), 0);  // asked again: converted once
  EXPECT_DOUBLE_EQ(t.column(0)[0], 500);
  EXPECT_EQ(t.require("a", Unit::Micrometre), 1);
  EXPECT_NEAR(t.column(1)[0], 0.25, 0.25 * kRoundOff);
  EXPECT_EQ(t.require("b", Unit::Micrometre), 2);
  EXPECT_EQ(t.column(2)[0], 1.5);
  EXPECT_EQ(t.require("c", Unit::Micrometre), 3);
  EXPECT_EQ(t.column(3)[0], 2000);
  EXPECT_EQ(t.require("d", Unit::Micrometre), 4);  // no unit written: the reader's unit
  EXPECT_EQ(t.column(4)[0], 7);
  EXPECT_FALSE(trueaxis::io::split_column_name(t.header()[4]).unit.has_value());
  EXPECT_EQ(t.require("e", Unit::Radian), 5);
  EXPECT_NEAR(t.column(5)[0], 1e-5, 1e-5 * kRoundOff);
  EXPECT_EQ(t.require("f", Unit::Radian), 6);
  EXPECT_NEAR(t.column(6)[0], M_PI / 2, M_PI / 2 * kRoundOff);
  EXPECT_EQ(trueaxis::io::split_column_name(t.header()[6]).unit, Unit::Degree);
  EXPECT_EQ(t.find("g", Unit::Millimetre), -1);

  auto refused = [](const std::string& text, const char* quantity, Unit unit) {
    try {
      CsvTable::parse(text, "f.csv").require(quantity, unit);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(refused("x,t [s]\n1,2\n", "t", Unit::Millimetre),
            "f.csv:1:3: column 't [s]' is in s, a time; t holds a length (for example in mm)");
  EXPECT_EQ(refused("x,n [mm]\n1,2\n", "n", Unit::Count),
            "f.csv:1:3: column 'n [mm]' is in mm, a length; n holds a plain number and takes no "
            "unit");
  EXPECT_EQ(refused("x, x [mm]\n1,2\n", "x", Unit::Millimetre),
            "f.csv:1:4: columns 'x' and 'x [mm]' both hold x");
  EXPECT_EQ(refused("y,x [furlong]\n1,2\n", "x", Unit::Millimetre).substr(0, 48),
            "f.csv:1:3: column 'x [furlong]': 'furlong' is no");
  // A column read in one unit is not then handed out in another.
  auto u = CsvTable::parse("x [mm]\n1\n", "f.csv");
  u.require("x", Unit::Millimetre);
  EXPECT_THROW(u.require("x", Unit::Micrometre), Error);
}

// What a name means: the quantity/unit forms, and names whose last word only looks like a unit.
TEST(Csv, ColumnNamesSplitIntoQuantityAndUnit) {
  using trueaxis::io::split_column_name;
  using trueaxis::io::Unit;
  EXPECT_EQ(split_column_name("deviation [\xC2\xB5m]").quantity, "deviation");
  EXPECT_EQ(split_column_name("deviation [\xC2\xB5m]").unit, Unit::Micrometre);
  EXPECT_EQ(split_column_name("deviation (\xCE\xBCm)").unit, Unit::Micrometre);  // Greek mu
  EXPECT_EQ(split_column_name("deviation [\xB5m]").unit, Unit::Micrometre);      // Latin-1
  EXPECT_EQ(split_column_name("height / nm").unit, Unit::Nanometre);
  EXPECT_EQ(split_column_name("target_mm").quantity, "target");
  EXPECT_EQ(split_column_name("pitch_urad").unit, Unit::Microradian);
  EXPECT_EQ(split_column_name("temp [\xC2\xB0"
                              "C]")
                .unit,
            Unit::Celsius);
  // Short last words stay part of the name unless the reader names the quantity.
  for (const char* name : {"probe_c", "laser_in", "time_s", "b_m", "p1", "a_dx"}) {
    SCOPED_TRACE(name);
    EXPECT_EQ(split_column_name(name).quantity, name);
    EXPECT_FALSE(split_column_name(name).unit.has_value());
  }
  EXPECT_EQ(trueaxis::io::column_matches("time_s", "time").unit, Unit::Second);
  EXPECT_EQ(trueaxis::io::column_matches("Material_Temp_C", "material_temp").unit, Unit::Celsius);
  EXPECT_FALSE(trueaxis::io::column_matches("times", "time").holds);
  EXPECT_FALSE(trueaxis::io::column_matches("time_x", "time").holds);
  EXPECT_THROW(split_column_name("x [furlong]"), Error);
  EXPECT_THROW(split_column_name("x / furlong"), Error);
  EXPECT_EQ(split_column_name("probe A (front)").quantity, "probe A (front)");  // not a unit
  EXPECT_FALSE(split_column_name("probe A (front)").unit.has_value());
  EXPECT_NEAR(trueaxis::io::unit_factor(Unit::Inch, Unit::Millimetre), 25.4, 1e-14);
  EXPECT_NEAR(trueaxis::io::unit_factor(Unit::Arcsecond, Unit::Microradian), 4.84813681109536,
              1e-13);
}
