#include "io/csv.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "io/atomic_file.h"
#include "test_dir.h"

namespace depthbias::io {
namespace {

std::string ErrorOf(const std::string& text) {
  try {
    ParseCsv(text, "t.csv");
  } catch (const IoError& e) {
    return e.what();
  }
  return "";
}

TEST(Csv, QuotedFieldsCommasQuotesAndLineBreaks) {
  const CsvTable t = ParseCsv("a,b,c\n\"x,y\",\"say \"\"hi\"\"\",\"two\nlines\"\n1,2,3\n", "t.csv");
  ASSERT_EQ(t.rows.size(), 2u);
  EXPECT_EQ(t.rows[0][0], "x,y");
  EXPECT_EQ(t.rows[0][1], "say \"hi\"");
  EXPECT_EQ(t.rows[0][2], "two\nlines");
  EXPECT_EQ(t.lines[0], 2);
  EXPECT_EQ(t.lines[1], 4);  // the quoted line break counts
}

TEST(Csv, BomCrlfBlankLinesAndSpaces) {
  const CsvTable t = ParseCsv("\xEF\xBB\xBF" "a , b\r\n\r\n 1 , 2 \r\n", "t.csv");
  EXPECT_EQ(t.header, (std::vector<std::string>{"a", "b"}));
  ASSERT_EQ(t.rows.size(), 1u);
  EXPECT_EQ(t.rows[0][0], "1");
  EXPECT_EQ(t.lines[0], 3);
}

TEST(Csv, NumbersAndMissingCells) {
  const CsvTable t = ParseCsv("a,b,c,d\n1.5,,nan,-2e3\n", "t.csv");
  EXPECT_DOUBLE_EQ(t.Number(0, 0), 1.5);
  EXPECT_TRUE(std::isnan(t.Number(0, 1)));
  EXPECT_TRUE(std::isnan(t.Number(0, 2)));
  EXPECT_DOUBLE_EQ(t.Number(0, 3), -2000.0);
  EXPECT_THROW(t.RequiredNumber(0, 1), IoError);
}

TEST(Csv, ErrorsNameFileLineAndColumn) {
  const CsvTable t = ParseCsv("a,b\n1,2\n3,abc\n", "t.csv");
  try {
    t.Number(1, 1);
    FAIL();
  } catch (const IoError& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("t.csv:3"), std::string::npos) << w;
    EXPECT_NE(w.find("'b'"), std::string::npos) << w;
    EXPECT_NE(w.find("abc"), std::string::npos) << w;
  }
  EXPECT_NE(ErrorOf("a,b\n1,2,3\n").find("t.csv:2"), std::string::npos);
  EXPECT_NE(ErrorOf("a,b\n\"open,2\n").find("unterminated"), std::string::npos);
  EXPECT_NE(ErrorOf("a,a\n1,2\n").find("twice"), std::string::npos);
  EXPECT_NE(ErrorOf("").find("empty"), std::string::npos);
  EXPECT_NE(ErrorOf("a,b\n\"x\"y,2\n").find("after a closing quote"), std::string::npos);
  EXPECT_THROW(t.RequireColumn("c"), IoError);
}

TEST(Csv, FormatThenParseRoundTrips) {
  const std::vector<std::string> header = {"name", "value"};
  const std::vector<std::vector<std::string>> rows = {
      {"plain", CsvNumber(0.1)}, {"with, comma \"q\"", CsvNumber(-1e-300)},
      {"nan", CsvNumber(std::numeric_limits<double>::quiet_NaN())}};
  const CsvTable t = ParseCsv(FormatCsv(header, rows), "r.csv");
  ASSERT_EQ(t.rows.size(), 3u);
  EXPECT_EQ(t.rows[1][0], "with, comma \"q\"");
  EXPECT_EQ(t.Number(0, 1), 0.1);  // shortest form reads back exactly
  EXPECT_EQ(t.Number(1, 1), -1e-300);
  EXPECT_TRUE(std::isnan(t.Number(2, 1)));
}

TEST(Csv, WriteCsvIsReadBack) {
  const auto dir = testing::FreshDir("io");
  const std::string path = (dir / "t.csv").string();
  WriteCsv(path, {"x"}, {{"1"}, {"2"}});
  const CsvTable t = ReadCsv(path);
  EXPECT_EQ(t.file, path);
  EXPECT_EQ(t.rows.size(), 2u);
}

}  // namespace
}  // namespace depthbias::io
