#include "pneumaid/io/csv_table.h"

#include <gtest/gtest.h>

#include <cmath>

#include "pneumaid/io/input_error.h"

namespace pneumaid {
namespace {

TEST(CsvTableTest, AcceptsBomCrlfCommentsBlankLinesAndUnits) {
  const std::string text =
      "\xEF\xBB\xBF# rig 3, operator A\r\n\r\nt [ms], u [V],p1 [bar_g]\r\n"
      "0,0,0.5\r\n# a comment between rows\r\n1,+0.5,1e0\r\n";
  const CsvTable table = ParseCsv(text, "log.csv");
  EXPECT_EQ(table.header_line, 3);
  ASSERT_EQ(table.rows(), 2u);
  EXPECT_EQ(table.row_lines[1], 6);
  ASSERT_NE(table.Find("p1"), nullptr);
  EXPECT_EQ(table.Find("p1")->unit, "bar_g");
  EXPECT_EQ(table.Find("t")->unit, "ms");
  EXPECT_EQ(table.Find("u")->values[1], 0.5);
  EXPECT_EQ(table.Find("q1"), nullptr);
}

// A file whose last row has no line end may have been cut while it was
// written (its last number too): the table says so. A last line that is a
// comment, or a line end after the row, is a complete file.
TEST(CsvTableTest, SaysWhenTheLastRowHasNoLineEnd) {
  EXPECT_TRUE(ParseCsv("t,u\n0,1\n1,2.65", "cut.csv").unterminated_last_row);
  EXPECT_FALSE(ParseCsv("t,u\n0,1\n1,2.65\n", "whole.csv").unterminated_last_row);
  EXPECT_FALSE(ParseCsv("t,u\r\n0,1\r\n1,2.65\r\n", "crlf.csv").unterminated_last_row);
  EXPECT_FALSE(ParseCsv("t,u\n0,1\n1,2.65\n# end", "comment.csv").unterminated_last_row);
  // A single-column log has no separator to look for.
  EXPECT_EQ(ParseCsv("t\n0\n1\n", "one.csv").rows(), 2u);
}

// A finite number below the smallest double reads as zero (strtod's
// reading); one above the largest is no finite number (CsvBadInputTest).
TEST(CsvTableTest, ANumberBelowTheSmallestDoubleIsZero) {
  const CsvTable table = ParseCsv("t,q\n0,1e-400\n1,-2.5E-999\n", "tiny.csv");
  EXPECT_EQ(table.Find("q")->values[0], 0.0);
  EXPECT_EQ(table.Find("q")->values[1], 0.0);
  EXPECT_TRUE(std::signbit(table.Find("q")->values[1]));
  // Below it without an exponent; an exponent that a long mantissa overcomes.
  const std::string tiny = "0." + std::string(400, '0') + "1";
  EXPECT_EQ(ParseCsv("t,q\n0," + tiny + "\n", "tiny.csv").Find("q")->values[0], 0.0);
  EXPECT_THROW(ParseCsv("t,q\n0,1" + std::string(400, '0') + "e-10\n", "huge.csv"), InputError);
  EXPECT_THROW(ParseCsv("t,q\n0,1e-\n", "cut.csv"), InputError);
}

// A NUL byte (UTF-16 text without its mark) is named at its line.
TEST(CsvTableTest, ANulByteIsNotUtf8Text) {
  try {
    ParseCsv(std::string("t,u\n0,1\n1,\0\n", 11), "nul.csv");
    FAIL() << "accepted a NUL byte";
  } catch (const InputError& error) {
    EXPECT_EQ(error.line(), 3) << error.what();
    EXPECT_NE(std::string(error.what()).find("a NUL byte: expected UTF-8 text"), std::string::npos)
        << error.what();
  }
}

struct BadCsv {
  const char* name;
  const char* text;
  int line;
  int column;
  const char* message;
};

class CsvBadInputTest : public ::testing::TestWithParam<BadCsv> {};

TEST_P(CsvBadInputTest, NamesLineColumnAndExpectation) {
  const BadCsv& c = GetParam();
  try {
    ParseCsv(c.text, "bad.csv");
    FAIL() << "accepted " << c.name;
  } catch (const InputError& error) {
    EXPECT_EQ(error.file(), "bad.csv");
    EXPECT_EQ(error.line(), c.line) << error.what();
    EXPECT_EQ(error.column(), c.column) << error.what();
    EXPECT_NE(std::string(error.what()).find(c.message), std::string::npos) << error.what();
  }
}

INSTANTIATE_TEST_SUITE_P(
    Cases, CsvBadInputTest,
    ::testing::Values(BadCsv{"empty", "", 0, 0, "empty file"},
                      BadCsv{"only_comments", "# nothing\n\n", 0, 0, "no header"},
                      BadCsv{"no_rows", "t,u\n# none\n", 1, 0, "no data rows"},
                      BadCsv{"ragged_short", "t,u,x\n0,1,2\n1,2\n", 3, 0, "ragged row"},
                      BadCsv{"ragged_long", "t,u\n0,1,2\n", 2, 0, "ragged row"},
                      BadCsv{"not_numeric", "t,u\n0,1\n1,abc\n", 3, 2, "expected a finite number"},
                      BadCsv{"not_finite", "t,u\n0,nan\n", 2, 2, "expected a finite number"},
                      BadCsv{"empty_field", "t,u\n0,\n", 2, 2, "expected a finite number"},
                      BadCsv{"duplicate_column", "t,u,t\n0,1,2\n", 1, 3, "duplicate column"},
                      BadCsv{"unclosed_unit", "t [s,u\n0,1\n", 1, 1, "name [unit]"},
                      // A spreadsheet's export in a comma-decimal locale.
                      BadCsv{"semicolons", "t [s];u [V]\n0;0,5\n", 1, 0,
                             "header separated by ';': expected comma-separated cells"},
                      BadCsv{"tabs", "t\tu\n0\t1\n", 1, 0, "header separated by tabs"},
                      BadCsv{"overflow", "t,u\n0,1e400\n", 2, 2, "expected a finite number"},
                      BadCsv{"utf16_bom", "\xFF\xFEt\0,\0u\0", 1, 0, "UTF-16 byte-order mark"},
                      BadCsv{"cr_only", "t,u\r0,1\r1,2\r", 1, 0, "CR alone"},
                      BadCsv{"cr_then_lf", "t,u\r0,1\r1,2\n", 1, 0, "CR alone"}),
    [](const ::testing::TestParamInfo<BadCsv>& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace pneumaid
