// Reading numeric CSV data files with a header row whose column names carry units
// (`q1_deg`, `fx_N`, `t_s`). Every deflex data reader goes through this, so errors look alike:
// "FILE:LINE: column 'fx_N': 'abc' is not a number".
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace deflex {

/// A CSV file of numbers: a header row, then one row of values per line. Lines starting with '#'
/// and blank lines are skipped. Columns may come in any order; they are found by name.
class CsvTable {
 public:
  /// Reads and checks the whole file: every cell of every row must be a finite number inside the
  /// range its column's unit allows (input_ranges.hpp; NaN, inf, 1e308 and empty cells are errors
  /// naming the line and column), and every row must have the header's number of cells. A UTF-8 byte
  /// order mark, CRLF and CR-only line endings are taken; a header separated by ';' or tabs is named
  /// as such. Throws DataError.
  static CsvTable read_file(const std::string& path);
  static CsvTable parse(const std::string& text, const std::string& source);

  [[nodiscard]] const std::string& source() const { return source_; }
  [[nodiscard]] const std::vector<std::string>& columns() const { return columns_; }
  [[nodiscard]] std::size_t rows() const { return values_.size(); }
  [[nodiscard]] bool has(const std::string& column) const { return index_.count(column) != 0; }
  /// Column position; throws DataError "FILE: missing column 'x' (have: ...)".
  [[nodiscard]] std::size_t column(const std::string& name) const;
  /// Value of a cell by row (0-based data row) and column name.
  [[nodiscard]] double at(std::size_t row, const std::string& column) const;
  [[nodiscard]] double at(std::size_t row, std::size_t column) const { return values_[row][column]; }
  /// The file's line number of a data row, for messages about a row's meaning (1-based).
  [[nodiscard]] int line_of(std::size_t row) const { return lines_[row]; }
  /// Throws DataError "FILE:LINE: column 'c': message" for a row.
  [[noreturn]] void fail(std::size_t row, const std::string& column, const std::string& message) const;
  /// Fails when any of `required` is missing, naming all that are.
  void require(const std::vector<std::string>& required) const;
  /// Fails on a column not in `allowed`, suggesting the nearest allowed name ('Index' -> 'index'), so
  /// a misspelt optional column is never silently ignored.
  void allow_only(const std::vector<std::string>& allowed) const;

 private:
  std::string source_;
  std::vector<std::string> columns_;
  std::map<std::string, std::size_t> index_;
  std::vector<std::vector<double>> values_;
  std::vector<int> lines_;
};

/// The whole text of a file, refused with DataError naming it when it cannot be read, is a directory
/// or is larger than 1 GiB (checked before reading); a leading UTF-8 byte order mark is dropped.
/// `what` names the kind of file in messages ("robot file", "file").
[[nodiscard]] std::string read_text_file(const std::string& path, const char* what);

/// A text cell for a CSV file: quoted (RFC 4180, inner quotes doubled) when it holds a comma, a
/// quote, a line break or blanks at its ends; as it is otherwise.
[[nodiscard]] std::string csv_text_cell(const std::string& text);

/// Writes a CSV header row and rows with fixed formatting. Throws Error if the file cannot be written.
class CsvWriter {
 public:
  CsvWriter(const std::string& path, const std::vector<std::string>& columns);
  void row(const std::vector<double>& values);
  void comment(const std::string& text);  ///< "# text" line

 private:
  std::string path_;
  std::size_t width_;
  struct Impl;
  std::shared_ptr<Impl> impl_;
};

}  // namespace deflex
