// Reading numeric CSV data files with a header row whose column names carry units
// (`q1_deg`, `fx_N`, `t_s`). Every deflex data reader goes through this, so errors look alike:
// "FILE:LINE: column 'fx_N': 'abc' is not a number".
//
// Two ways in: CsvReader streams a file a row at a time (memory independent of the file's length:
// one 1 MiB read buffer and one row of values), CsvTable keeps every row (a flat array of values,
// 8 bytes a cell). Both parse the same way: numbers with std::from_chars (the process locale never
// changes what "1.5" means), a UTF-8 byte-order mark skipped, LF, CRLF and CR-only line endings,
// '#' comment lines and blank lines skipped, cells trimmed of spaces and tabs.
#pragma once

// The text module's other headers compile as C++17 (the model's consumers may be); this one takes
// and gives std::span.
#if __cplusplus < 202002L
#error "deflex/text/csv_table.hpp needs C++20 (std::span); the model's headers and text/errors.hpp need C++17"
#endif

#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>

#include "deflex/text/input_file.hpp"
#include "deflex/text/output_file.hpp"

namespace deflex {

struct InputRange;

/// Streams a CSV file of numbers: a header row, then one row of finite numbers per line, every row
/// with the header's number of cells, each number inside the range its column's unit allows
/// (input_ranges.hpp: 1e308 mm is an error naming the line and column). Columns may come in any order; they are found
/// by name. Errors throw DataError naming the file, the line and the column.
/// Thread safety: one thread at a time (next() moves its read position and its row).
class CsvReader {
 public:
  /// Opens the file (input_file.hpp: a regular file within the limit of `kind`) and reads its header
  /// row. Throws DataError when the file cannot be read, has no header, a header cell is empty or
  /// repeated, or the header is separated by ';' or tabs.
  explicit CsvReader(const std::string& path, InputKind kind = InputKind::kCsvStream);
  /// Reads from text held in memory; `source` names it in messages.
  CsvReader(std::string text, std::string source);
  ~CsvReader();
  CsvReader(const CsvReader&) = delete;
  CsvReader& operator=(const CsvReader&) = delete;

  [[nodiscard]] const std::string& source() const { return source_; }
  [[nodiscard]] const std::vector<std::string>& columns() const { return columns_; }
  [[nodiscard]] bool has(const std::string& column) const { return index_.count(column) != 0; }
  /// Column position; throws DataError "FILE: missing column 'x' (have: ...)".
  [[nodiscard]] std::size_t column(const std::string& name) const;
  /// Fails when any of `required` is missing, naming all that are.
  void require(const std::vector<std::string>& required) const;
  /// Fails on a column not in `allowed`, suggesting the nearest allowed name ('Index' -> 'index'), so
  /// a misspelt optional column is never silently ignored.
  void allow_only(const std::vector<std::string>& allowed) const;
  /// Reads only the columns named in `used` from here on: the cells of every other column are counted
  /// but not parsed (any text, a label or a note, or nothing) and read as NaN. For files whose format
  /// says other columns are ignored (tracker CSV).
  void read_only(const std::vector<std::string>& used);

  /// Reads the next data row; false at the end of the file. Throws DataError for a bad row.
  bool next();
  /// The current row's values (valid until the next call to next()).
  [[nodiscard]] std::span<const double> row() const { return row_; }
  [[nodiscard]] double operator[](std::size_t column) const { return row_[column]; }
  /// The file's line number of the current row (1-based).
  [[nodiscard]] int line() const { return line_of_row_; }
  /// Throws DataError "FILE:LINE: column 'c': message" for the current row.
  [[noreturn]] void fail(const std::string& column, const std::string& message) const;

 private:
  bool next_line(std::string_view& out);  // the next line (without its ending), false at the end
  void read_header();
  void parse_row(std::string_view line);
  bool parse_plain_row(std::string_view line);  // the common row in one scan; false: leave it to parse_row

  std::string source_;
  std::unique_ptr<InputFile> file_;  // null when reading text held in memory
  std::string buffer_;               // the bytes read and not yet consumed, from begin_
  std::size_t begin_ = 0;            // first unconsumed byte of buffer_
  bool eof_ = false;
  bool pending_cr_ = false;  // the last line ended with '\r': a '\n' right after it is the same ending
  bool first_bytes_ = true;  // a byte-order mark is skipped only at the very start
  int line_ = 0;
  int line_of_row_ = 0;
  std::vector<std::string> columns_;
  std::map<std::string, std::size_t> index_;
  std::vector<const InputRange*> ranges_;  // each column's physical range, from the unit in its name
  std::vector<bool> skipped_;              // read_only(): columns whose cells are not parsed
  std::vector<double> row_;
};

/// A whole CSV file of numbers in memory (see CsvReader for the rules).
/// Thread safety: immutable once read: any number of threads may share one.
class CsvTable {
 public:
  /// Reads and checks the whole file (at most 1 GiB, InputKind::kCsvTable). Throws DataError. A
  /// non-empty `only` reads those columns alone and ignores every other (CsvReader::read_only()).
  static CsvTable read_file(const std::string& path, const std::vector<std::string>& only = {});
  static CsvTable parse(const std::string& text, const std::string& source, const std::vector<std::string>& only = {});

  [[nodiscard]] const std::string& source() const { return source_; }
  [[nodiscard]] const std::vector<std::string>& columns() const { return columns_; }
  [[nodiscard]] std::size_t rows() const { return lines_.size(); }
  [[nodiscard]] bool has(const std::string& column) const { return index_.count(column) != 0; }
  /// Column position; throws DataError "FILE: missing column 'x' (have: ...)".
  [[nodiscard]] std::size_t column(const std::string& name) const;
  /// Value of a cell by row (0-based data row) and column name.
  [[nodiscard]] double at(std::size_t row, const std::string& column) const;
  [[nodiscard]] double at(std::size_t row, std::size_t column) const { return values_[row * columns_.size() + column]; }
  /// The file's line number of a data row, for messages about a row's meaning (1-based).
  [[nodiscard]] int line_of(std::size_t row) const { return lines_[row]; }
  /// Throws DataError "FILE:LINE: column 'c': message" for a row.
  [[noreturn]] void fail(std::size_t row, const std::string& column, const std::string& message) const;
  /// Fails when any of `required` is missing, naming all that are.
  void require(const std::vector<std::string>& required) const;
  /// Fails on a column not in `allowed` (see CsvReader::allow_only).
  void allow_only(const std::vector<std::string>& allowed) const;

 private:
  static CsvTable drain(CsvReader& reader, const std::vector<std::string>& only);

  std::string source_;
  std::vector<std::string> columns_;
  std::map<std::string, std::size_t> index_;
  std::vector<double> values_;  // row-major, rows() x columns().size()
  std::vector<int> lines_;
};

/// Calls f(cell) for every comma-separated cell of `line`, trimmed of spaces and tabs (a trailing comma
/// gives an empty last cell, as a spreadsheet means it). A cell quoted as csv_text_cell() writes it
/// ("a, b") keeps its commas and is handed over with its quotes. The one splitter of every deflex
/// reader of comma-separated lines.
template <typename F>
void for_each_csv_cell(std::string_view line, F&& f) {
  const auto trimmed = [](std::string_view s) {
    const auto b = s.find_first_not_of(" \t");
    if (b == std::string_view::npos) return std::string_view();
    return s.substr(b, s.find_last_not_of(" \t") - b + 1);
  };
  std::size_t start = 0;
  while (true) {
    std::size_t search = start;
    const auto first = line.find_first_not_of(" \t", start);
    if (first != std::string_view::npos && line[first] == '"') {
      search = first + 1;  // the closing quote: a doubled quote "" is one quote inside the cell
      while (search < line.size() && !(line[search] == '"' && (search + 1 >= line.size() || line[search + 1] != '"'))) {
        search += line[search] == '"' ? 2 : 1;
      }
    }
    const auto comma = line.find(',', std::min(search, line.size()));
    if (comma == std::string_view::npos) {
      f(trimmed(line.substr(start)));
      return;
    }
    f(trimmed(line.substr(start, comma - start)));
    start = comma + 1;
  }
}

/// A text cell for a CSV file: quoted (RFC 4180, inner quotes doubled) when it holds a comma, a
/// quote, a line break or blanks at its ends; as it is otherwise.
[[nodiscard]] std::string csv_text_cell(const std::string& text);

/// Writes a CSV header row and rows of numbers (%.10g), buffered: a row is formatted into the
/// writer's own buffer, never into a temporary string, and the buffer goes to the output in 64 kB
/// pieces. The output is an OutputFile (output_file.hpp): nothing appears at the path before the
/// file is committed, and a failed write throws OutputError naming it.
/// Thread safety: one thread at a time (each thread its own writer).
class CsvWriter {
 public:
  /// Into `out`, one output of a transaction: finish() flushes, the transaction commits.
  CsvWriter(OutputFile& out, const std::vector<std::string>& columns);
  /// Into a file of its own: finish() commits it; destroyed unfinished, nothing is written.
  CsvWriter(const std::string& path, const std::vector<std::string>& columns);
  ~CsvWriter();
  CsvWriter(const CsvWriter&) = delete;
  CsvWriter& operator=(const CsvWriter&) = delete;
  void row(std::span<const double> values);
  void row(const std::vector<double>& values) { row(std::span<const double>(values)); }
  void comment(const std::string& text);  ///< "# text" line
  /// Flushes (and commits a file of its own); throws OutputError when the data did not reach it.
  void finish();

 private:
  void flush_if_full();
  void flush();

  std::unique_ptr<OutputFile> own_;  // the file of its own, when given a path
  OutputFile* out_;
  std::size_t width_;
  bool finished_ = false;
  fmt::memory_buffer buffer_;
};

}  // namespace deflex
