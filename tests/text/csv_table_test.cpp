// CSV reading and writing: the streaming reader against the whole-table reader, line endings, byte
// order marks, separators, chunk boundaries, locale independence, and the writer's %.10g text.
#include <algorithm>
#include <bit>
#include <clocale>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "deflex/text/csv_table.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/parse_number.hpp"

namespace deflex {
namespace {

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("deflex_csv_" + name)).string();
}

void write_text(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

std::string message_of(const std::string& text) {
  try {
    (void)CsvTable::parse(text, "f.csv");
  } catch (const DataError& e) {
    return e.what();
  }
  return "";
}

TEST(CsvTable, EveryLineEndingReadsTheSameRows) {
  for (const std::string eol : {"\n", "\r\n", "\r"}) {
    const std::string text = "# note" + eol + "a_m,b_N" + eol + eol + "1,2" + eol + "# c" + eol + "3.5,-4e-3" + eol;
    const CsvTable t = CsvTable::parse(text, "f.csv");
    ASSERT_EQ(t.rows(), 2U) << "ending " << (eol == "\r" ? "CR" : eol == "\n" ? "LF" : "CRLF");
    EXPECT_EQ(t.columns(), (std::vector<std::string>{"a_m", "b_N"}));
    EXPECT_EQ(t.at(1, "a_m"), 3.5);
    EXPECT_EQ(t.at(1, "b_N"), -4e-3);
    EXPECT_EQ(t.line_of(0), 4);  // a blank line counts as a line
    EXPECT_EQ(t.line_of(1), 6);
  }
}

TEST(CsvTable, AByteOrderMarkIsNotPartOfTheFirstColumnsName) {
  const CsvTable t = CsvTable::parse("\xEF\xBB\xBFindex,fx_N\n0,1\n", "f.csv");
  EXPECT_TRUE(t.has("index"));
  EXPECT_EQ(t.at(0, "index"), 0.0);
}

TEST(CsvTable, ASemicolonOrTabSeparatedFileIsToldToUseCommas) {
  EXPECT_NE(message_of("a;b\n1;2\n").find("f.csv:1: header: the columns are separated by ';'"), std::string::npos)
      << message_of("a;b\n1;2\n");
  EXPECT_NE(message_of("a\tb\n1\t2\n").find("separated by '\\t'"), std::string::npos);
  // A comma header with a semicolon row (a spreadsheet's decimal comma): named in the row's message.
  EXPECT_NE(message_of("a,b\n1;5,2\n").find("f.csv:2: column 'a': '1;5' is not a number (the row is separated by ';'"),
            std::string::npos)
      << message_of("a,b\n1;5,2\n");
}

TEST(CsvTable, BadCellsAreNamedByLineAndColumn) {
  EXPECT_NE(message_of("a,b\n1,x\n").find("f.csv:2: column 'b': 'x' is not a number"), std::string::npos);
  EXPECT_NE(message_of("a,b\n1,nan\n").find("f.csv:2: column 'b': 'nan' is not a finite number"), std::string::npos);
  EXPECT_NE(message_of("a,b\n1,1e999\n").find("column 'b': '1e999' is not a"), std::string::npos)
      << message_of("a,b\n1,1e999\n");
  EXPECT_NE(message_of("a,b\n1,\n").find("f.csv:2: column 'b': empty cell"), std::string::npos);
  EXPECT_NE(message_of("a,b\n1,2,3\n").find("f.csv:2: 3 cells, the header has 2 columns"), std::string::npos);
  EXPECT_NE(message_of("a,b\n1\n").find("f.csv:2: 1 cells, the header has 2 columns"), std::string::npos);
  EXPECT_NE(message_of("a,a\n1,2\n").find("column 'a' appears twice"), std::string::npos);
  EXPECT_NE(message_of("a,,b\n1,2,3\n").find("column 2 has no name"), std::string::npos);
  EXPECT_NE(message_of("# only a comment\n").find("no header row"), std::string::npos);
  EXPECT_NE(message_of("a,b\n1,+-2\n").find("'+-2' is not a number"), std::string::npos);
  EXPECT_NE(message_of("a,b\n1,2x\n").find("'2x' is not a number"), std::string::npos);
}

// The reader takes a row of plain numbers in one scan and leaves anything else to the cell-by-cell path; either
// way a cell means what parse_double makes of it, trimmed, inside its column's range, or the row is refused with
// that path's message.
TEST(CsvTable, EveryCellMeansWhatParseDoubleMakesOfIt) {
  const std::vector<std::string> cells{"1.5",
                                       "  +1.5\t",
                                       "+.5",
                                       "5.",
                                       "-0",
                                       "00012",
                                       "1e+3",
                                       "1E-3",
                                       "-2.5e-12",
                                       "4.9e-324",
                                       "1e-400",
                                       "1e400",
                                       "3.14159265358979323846264338327950288",
                                       "100000",
                                       "-1e5",
                                       "100000.0000001",
                                       "1e",
                                       "1.2.3",
                                       "0x10",
                                       "inf",
                                       "-inf",
                                       "nan",
                                       "NaN",
                                       "infinity",
                                       "+",
                                       "-",
                                       "",
                                       " ",
                                       "1 2",
                                       "+-1",
                                       "++1",
                                       "-+1",
                                       "1_000",
                                       ".",
                                       "e5",
                                       "1e5x",
                                       "\t-7\t"};
  const auto trimmed = [](const std::string& s) {
    const auto b = s.find_first_not_of(" \t");
    return b == std::string::npos ? std::string() : s.substr(b, s.find_last_not_of(" \t") - b + 1);
  };
  for (const std::string& cell : cells) {
    const std::optional<double> v = parse_double(trimmed(cell));
    const bool ok = v && *v >= -1e5 && *v <= 1e5;  // x_mm's range
    // The cell first, last, and between two others: (header, row, its column).
    const std::vector<std::tuple<std::string, std::string, std::size_t>> rows{
        {"x_mm,b_mm", cell + ",2", 0}, {"a_mm,x_mm", "2," + cell, 1}, {"a_mm,x_mm,c_mm", "2," + cell + ",3", 1}};
    for (const auto& [header, row, column] : rows) {
      const std::string text = header + "\n" + row + "\n";
      if (ok) {
        const CsvTable t = CsvTable::parse(text, "f.csv");
        ASSERT_EQ(t.rows(), 1U) << text;
        EXPECT_EQ(std::bit_cast<std::uint64_t>(t.at(0, column)), std::bit_cast<std::uint64_t>(*v)) << text;
      } else {
        EXPECT_THROW((void)CsvTable::parse(text, "f.csv"), DataError) << text;
      }
    }
  }
  // The cell-by-cell path's message for a row the one scan leaves to it, after good cells.
  EXPECT_NE(message_of("x_mm,y_mm\n1,2\n1, 1e6 \n").find("f.csv:3: column 'y_mm': 1e+06 mm is outside"),
            std::string::npos)
      << message_of("x_mm,y_mm\n1,2\n1, 1e6 \n");
}

TEST(CsvTable, NumbersMeanTheSameInEveryLocale) {
  // The reader never consults the locale (std::from_chars); a German locale, where strtod would take
  // "1,5" and refuse "1.5", is set when the machine has one.
  const char* old = std::setlocale(LC_NUMERIC, nullptr);
  const std::string saved = old != nullptr ? old : "C";
  const bool german = std::setlocale(LC_NUMERIC, "de_DE.UTF-8") != nullptr;
  const CsvTable t = CsvTable::parse("a\n+1.5\n.25\n-3e2\n", "f.csv");
  std::setlocale(LC_NUMERIC, saved.c_str());
  EXPECT_EQ(t.at(0, "a"), 1.5);
  EXPECT_EQ(t.at(1, "a"), 0.25);
  EXPECT_EQ(t.at(2, "a"), -300.0);
  if (!german) {
    GTEST_LOG_(INFO) << "no de_DE locale on this machine: read in the C locale only";
  }
}

TEST(CsvReader, StreamsAFileLargerThanItsBufferWithTheSameValuesAndLines) {
  // 3 MiB of rows with CRLF endings, so lines and endings straddle the 1 MiB read chunks.
  const std::string path = temp_path("stream.csv");
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1e3, 1e3);
  std::string text = "\xEF\xBB\xBFt_s,x_mm,y_mm\r\n";
  std::vector<double> expected;
  while (text.size() < 3U * 1024U * 1024U) {
    char line[128];
    const double a = u(rng), b = u(rng), c = u(rng);
    std::snprintf(line, sizeof line, "%.17g,%.17g,%.17g\r\n", a, b, c);
    text += line;
    expected.insert(expected.end(), {a, b, c});
  }
  write_text(path, text);
  CsvReader reader(path);
  ASSERT_EQ(reader.columns(), (std::vector<std::string>{"t_s", "x_mm", "y_mm"}));
  std::size_t row = 0;
  while (reader.next()) {
    ASSERT_LT(3 * row + 2, expected.size());
    for (std::size_t c = 0; c < 3; ++c) {
      ASSERT_EQ(reader[c], expected[3 * row + c]) << "row " << row << " column " << c;  // exact: %.17g round-trips
    }
    ASSERT_EQ(reader.line(), static_cast<int>(row) + 2);
    ++row;
  }
  EXPECT_EQ(3 * row, expected.size());
  const CsvTable table = CsvTable::read_file(path);
  EXPECT_EQ(table.rows(), row);
  EXPECT_EQ(table.at(row - 1, "y_mm"), expected.back());
  std::filesystem::remove(path);
}

TEST(CsvReader, ALineWithoutEndLongerThanAMebibyteIsRefusedNotBuffered) {
  const std::string path = temp_path("long.csv");
  write_text(path, "a\n" + std::string(3U * 1024U * 1024U, '1'));
  try {
    CsvReader reader(path);
    while (reader.next()) {
    }
    FAIL() << "a 3 MiB line was read";
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find("long.csv:2: a line longer than"), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
}

TEST(CsvReader, AMissingFileIsNamed) {
  try {
    CsvReader reader(temp_path("does_not_exist.csv"));
    FAIL();
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find("does_not_exist.csv: the data file does not exist"), std::string::npos);
  }
}

TEST(CsvWriter, WritesPrintfsTenDigitsAndReadsBack) {
  const std::string path = temp_path("write.csv");
  const std::vector<double> values{0.1, -2.5e-12, 123456789012.0, 1.0 / 3.0, 0.0, -0.0, 1e11};
  {
    CsvWriter w(path, {"a", "b", "c", "d", "e", "f", "g"});
    w.comment("made by a test");
    w.row(values);
    w.finish();
  }
  std::ifstream in(path);
  std::string header, comment, line;
  std::getline(in, header);
  std::getline(in, comment);
  std::getline(in, line);
  EXPECT_EQ(header, "a,b,c,d,e,f,g");
  EXPECT_EQ(comment, "# made by a test");
  std::string printf_line;
  for (std::size_t i = 0; i < values.size(); ++i) {
    char cell[40];
    std::snprintf(cell, sizeof cell, "%.10g", values[i]);
    printf_line += (i > 0 ? "," : "") + std::string(cell);
  }
  EXPECT_EQ(line, printf_line);
  const CsvTable t = CsvTable::read_file(path);
  EXPECT_NEAR(t.at(0, "d"), 1.0 / 3.0, 1e-10);
  std::filesystem::remove(path);
}

TEST(CsvWriter, ARowOfTheWrongWidthIsRefused) {
  const std::string path = temp_path("width.csv");
  CsvWriter w(path, {"a", "b"});
  EXPECT_THROW(w.row(std::vector<double>{1.0}), InputError);
  w.finish();
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace deflex
