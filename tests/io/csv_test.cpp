#include "trueaxis/io/csv.hpp"

#include <gtest/gtest.h>

#include "../test_util.hpp"
#include "trueaxis/error.hpp"

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
  b << 1e300, 5, 6;
  const std::string p = trueaxis::test::temp_file("rt.csv", "");
  trueaxis::io::write_csv(p, {"a", "b"}, {&a, &b});
  const auto t = CsvTable::read(p);
  EXPECT_EQ(t.column(0), a);
  EXPECT_EQ(t.column(1), b);
}
