// CSV data files with a unit-carrying header row.
//
// Written here rather than taken from a library: Debian's libcsv hands over each cell as bytes
// through callbacks and leaves the numbers, the line endings, the header rules and the messages to
// the caller, which is all this file does; the reader streams with one buffer for the whole file
// and no string per cell (bench/io_bench measures it).
#include "deflex/text/csv_table.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <system_error>

#include "deflex/text/errors.hpp"
#include "deflex/text/format_number.hpp"
#include "deflex/text/input_file.hpp"
#include "deflex/text/input_ranges.hpp"
#include "deflex/text/nearest_name.hpp"
#include "deflex/text/parse_number.hpp"

namespace deflex {
namespace {

constexpr std::size_t kReadChunk = std::size_t{1} << 20;
constexpr std::size_t kLongestLine = std::size_t{1} << 20;  // a row longer than 1 MiB is not a data row

std::string_view trim(std::string_view s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string_view::npos) {
    return {};
  }
  const auto e = s.find_last_not_of(" \t");
  return s.substr(b, e - b + 1);
}

// A header cell written quoted by a spreadsheet ("x_mm") names the column x_mm.
std::string_view unquote(std::string_view cell) {
  if (cell.size() >= 2 && cell.front() == '"' && cell.back() == '"') {
    return cell.substr(1, cell.size() - 2);
  }
  return cell;
}

}  // namespace

CsvReader::CsvReader(const std::string& path, InputKind kind)
    : source_(path), file_(std::make_unique<InputFile>(path, kind)) {
  read_header();
}

CsvReader::CsvReader(std::string text, std::string source) : source_(std::move(source)), buffer_(std::move(text)) {
  eof_ = true;
  read_header();
}

CsvReader::~CsvReader() = default;

bool CsvReader::next_line(std::string_view& out) {
  while (true) {
    if (first_bytes_ && (buffer_.size() - begin_ >= 3 || eof_)) {
      first_bytes_ = false;
      if (buffer_.compare(begin_, 3, "\xEF\xBB\xBF") == 0) {
        begin_ += 3;
      }
    }
    if (pending_cr_ && begin_ < buffer_.size()) {
      pending_cr_ = false;
      if (buffer_[begin_] == '\n') {
        ++begin_;  // the '\n' of a "\r\n" ending
      }
    }
    const char* data = buffer_.data();
    const std::size_t size = buffer_.size();
    // The line ends at its first '\n' or '\r': memchr for each (the library's vector search) instead of a test
    // of every byte, which was 3 % of a million-row identification.
    const void* nl = std::memchr(data + begin_, '\n', size - begin_);
    std::size_t end = nl != nullptr ? static_cast<std::size_t>(static_cast<const char*>(nl) - data) : size;
    if (const void* cr = std::memchr(data + begin_, '\r', end - begin_)) {
      end = static_cast<std::size_t>(static_cast<const char*>(cr) - data);
    }
    if (end < size) {
      out = std::string_view(data + begin_, end - begin_);
      pending_cr_ = data[end] == '\r';
      begin_ = end + 1;
      ++line_;
      return true;
    }
    if (eof_) {
      if (begin_ >= size) {
        return false;
      }
      out = std::string_view(data + begin_, size - begin_);  // the last line, without an ending
      begin_ = size;
      ++line_;
      return true;
    }
    if (size - begin_ > kLongestLine) {
      throw DataError(
          fmt::format("{}:{}: a line longer than {} bytes: not a CSV data file", source_, line_ + 1, kLongestLine));
    }
    // Keep the partial line, read the next chunk behind it.
    buffer_.erase(0, begin_);
    begin_ = 0;
    const std::size_t kept = buffer_.size();
    buffer_.resize(kept + kReadChunk);
    const std::size_t got = file_->read(buffer_.data() + kept, kReadChunk);
    buffer_.resize(kept + got);
    eof_ = got == 0;
  }
}

void CsvReader::read_header() {
  std::string_view line;
  while (next_line(line)) {
    const std::string_view tl = trim(line);
    if (tl.empty() || tl[0] == '#') {
      continue;
    }
    if (tl.find(',') == std::string_view::npos) {
      for (const char sep : {';', '\t', '|'}) {
        if (tl.find(sep) != std::string_view::npos) {
          throw DataError(
              fmt::format("{}:{}: header: the columns are separated by '{}': deflex CSV files separate "
                          "columns with commas (export with ',' as the separator and '.' as the decimal "
                          "point)",
                          source_, line_, sep == '\t' ? std::string("\\t") : std::string(1, sep)));
        }
      }
    }
    std::size_t i = 0;
    for_each_csv_cell(tl, [&](std::string_view cell) {
      ++i;
      const std::string_view name = unquote(cell);
      if (name.empty()) {
        throw DataError(fmt::format("{}:{}: header: column {} has no name", source_, line_, i));
      }
      if (parse_double(name)) {
        throw DataError(
            fmt::format("{}:{}: header: column {} is named '{}', a number: the first row must name the "
                        "columns (e.g. t_s,x_mm,y_mm,z_mm)",
                        source_, line_, i, name));
      }
      if (!index_.emplace(std::string(name), i - 1).second) {
        throw DataError(fmt::format("{}:{}: header: column '{}' appears twice", source_, line_, name));
      }
      columns_.emplace_back(name);
      ranges_.push_back(&range_for_name(columns_.back()));
    });
    row_.resize(columns_.size());
    skipped_.assign(columns_.size(), false);
    return;
  }
  throw DataError(fmt::format("{}: no header row (the file is empty)", source_));
}

// A row of plain numbers (each cell an optional blank, an optional '+', what std::from_chars reads as a finite
// number, an optional blank; as many cells as the header has; each value inside its column's range) in one scan of
// the line: no search for the commas first, no trimming, no check of each character before from_chars. parse_row
// spends twice this on such a row (perf of a million-row identification: 17 % of the run in the splitting and the
// checks, 9 % in from_chars itself). False at the first thing that is not so, with nothing decided: parse_row then
// reads the row again and gives the message. It accepts only rows parse_row accepts, with the same values: a cell
// it takes is, trimmed, exactly the text from_chars read (a comma or the line's end follows it), and the only texts
// from_chars reads that parse_row's character check refuses are NaN and the infinities, which are not finite.
bool CsvReader::parse_plain_row(std::string_view line) {
  if (std::find(skipped_.begin(), skipped_.end(), true) != skipped_.end()) {
    return false;  // a skipped column may hold text: parse_row reads such rows
  }
  const char* p = line.data();
  const char* const end = p + line.size();
  const auto blanks = [&] {
    while (p != end && (*p == ' ' || *p == '\t')) {
      ++p;
    }
  };
  const std::size_t width = columns_.size();
  for (std::size_t i = 0; i < width; ++i) {
    blanks();
    if (p != end && *p == '+') {
      ++p;
      if (p != end && (*p == '+' || *p == '-')) {
        return false;
      }
    }
    double v = 0.0;
    const auto r = std::from_chars(p, end, v, std::chars_format::general);
    if (r.ec != std::errc() || !std::isfinite(v)) {
      return false;
    }
    p = r.ptr;
    blanks();
    if (i + 1 < width) {
      if (p == end || *p != ',') {
        return false;
      }
      ++p;
    } else if (p != end) {
      return false;
    }
    const InputRange& range = *ranges_[i];
    if (!(v >= range.min && v <= range.max)) {  // range_violation's test
      return false;
    }
    row_[i] = v;
  }
  return true;
}

void CsvReader::parse_row(std::string_view line) {
  std::size_t i = 0;
  const std::size_t width = columns_.size();
  for_each_csv_cell(line, [&](std::string_view cell) {
    if (i >= width) {
      ++i;
      return;  // counted, reported below
    }
    const std::string& name = columns_[i];
    if (skipped_[i]) {
      row_[i++] = std::numeric_limits<double>::quiet_NaN();
      return;
    }
    if (cell.empty()) {
      throw DataError(fmt::format("{}:{}: column '{}': empty cell", source_, line_, name));
    }
    const std::optional<double> v = parse_double(cell);
    if (!v) {
      if (cell.find(';') != std::string_view::npos) {
        throw DataError(
            fmt::format("{}:{}: column '{}': '{}' is not a number (the row is separated by ';': deflex "
                        "CSV files separate cells with commas)",
                        source_, line_, name, cell));
      }
      throw DataError(fmt::format("{}:{}: column '{}': {}", source_, line_, name, not_a_number(cell)));
    }
    if (const auto bad = range_violation(*v, *ranges_[i])) {
      throw DataError(fmt::format("{}:{}: column '{}': {}", source_, line_, name, *bad));
    }
    row_[i++] = *v;
  });
  if (i != width) {
    const bool other_sep = line.find(';') != std::string_view::npos || line.find('\t') != std::string_view::npos;
    throw DataError(fmt::format("{}:{}: {} cells, the header has {} columns{}", source_, line_, i, width,
                                other_sep ? " (deflex CSV files separate cells with commas, and the decimal "
                                            "separator is a point)"
                                          : ""));
  }
}

bool CsvReader::next() {
  std::string_view line;
  while (next_line(line)) {
    const std::string_view tl = trim(line);
    if (tl.empty() || tl[0] == '#') {
      continue;
    }
    if (!parse_plain_row(tl)) {
      parse_row(tl);
    }
    line_of_row_ = line_;
    return true;
  }
  return false;
}

std::size_t CsvReader::column(const std::string& name) const {
  const auto it = index_.find(name);
  if (it == index_.end()) {
    throw DataError(fmt::format("{}: missing column '{}' (have: {})", source_, name, fmt::join(columns_, ", ")));
  }
  return it->second;
}

namespace {
void require_columns(const std::string& source, const std::vector<std::string>& columns,
                     const std::map<std::string, std::size_t>& index, const std::vector<std::string>& required) {
  std::vector<std::string> missing;
  for (const auto& r : required) {
    if (index.count(r) == 0) {
      missing.push_back(r);
    }
  }
  if (!missing.empty()) {
    throw DataError(fmt::format("{}: missing column{} {} (have: {})", source, missing.size() > 1 ? "s" : "",
                                fmt::join(missing, ", "), fmt::join(columns, ", ")));
  }
}
}  // namespace

void CsvReader::read_only(const std::vector<std::string>& used) {
  for (std::size_t i = 0; i < columns_.size(); ++i) {
    skipped_[i] = std::find(used.begin(), used.end(), columns_[i]) == used.end();
  }
}

void CsvReader::require(const std::vector<std::string>& required) const {
  require_columns(source_, columns_, index_, required);
}

namespace {
void allow_only_columns(const std::string& source, const std::vector<std::string>& columns,
                        const std::vector<std::string>& allowed) {
  for (const std::string& c : columns) {
    if (std::find(allowed.begin(), allowed.end(), c) == allowed.end()) {
      throw DataError(fmt::format("{}: unknown column '{}'{} (this file takes: {})", source, c,
                                  did_you_mean(c, allowed), fmt::join(allowed, ", ")));
    }
  }
}
}  // namespace

void CsvReader::allow_only(const std::vector<std::string>& allowed) const {
  allow_only_columns(source_, columns_, allowed);
}

void CsvReader::fail(const std::string& name, const std::string& message) const {
  throw DataError(fmt::format("{}:{}: column '{}': {}", source_, line_of_row_, name, message));
}

CsvTable CsvTable::drain(CsvReader& reader, const std::vector<std::string>& only) {
  if (!only.empty()) {
    reader.read_only(only);
  }
  CsvTable t;
  t.source_ = reader.source();
  t.columns_ = reader.columns();
  for (std::size_t i = 0; i < t.columns_.size(); ++i) {
    t.index_.emplace(t.columns_[i], i);
  }
  while (reader.next()) {
    const auto r = reader.row();
    t.values_.insert(t.values_.end(), r.begin(), r.end());
    t.lines_.push_back(reader.line());
  }
  return t;
}

CsvTable CsvTable::read_file(const std::string& path, const std::vector<std::string>& only) {
  CsvReader reader(path, InputKind::kCsvTable);
  return drain(reader, only);
}

CsvTable CsvTable::parse(const std::string& text, const std::string& source, const std::vector<std::string>& only) {
  CsvReader reader(text, source);
  return drain(reader, only);
}

std::size_t CsvTable::column(const std::string& name) const {
  const auto it = index_.find(name);
  if (it == index_.end()) {
    throw DataError(fmt::format("{}: missing column '{}' (have: {})", source_, name, fmt::join(columns_, ", ")));
  }
  return it->second;
}

double CsvTable::at(std::size_t row, const std::string& name) const { return at(row, column(name)); }

void CsvTable::fail(std::size_t row, const std::string& name, const std::string& message) const {
  throw DataError(fmt::format("{}:{}: column '{}': {}", source_, lines_[row], name, message));
}

void CsvTable::require(const std::vector<std::string>& required) const {
  require_columns(source_, columns_, index_, required);
}

void CsvTable::allow_only(const std::vector<std::string>& allowed) const {
  allow_only_columns(source_, columns_, allowed);
}

std::string csv_text_cell(const std::string& text) {
  const bool plain = text.find_first_of(",\"\r\n") == std::string::npos && trim_view(text).size() == text.size();
  if (plain) {
    return text;
  }
  std::string out = "\"";
  for (const char c : text) {
    out += c;
    if (c == '"') {
      out += '"';
    }
  }
  out += '"';
  return out;
}

CsvWriter::CsvWriter(OutputFile& out, const std::vector<std::string>& columns) : out_(&out), width_(columns.size()) {
  fmt::format_to(std::back_inserter(buffer_), "{}\n", fmt::join(columns, ","));
}

CsvWriter::CsvWriter(const std::string& path, const std::vector<std::string>& columns)
    : own_(std::make_unique<OutputFile>(path)), out_(own_.get()), width_(columns.size()) {
  fmt::format_to(std::back_inserter(buffer_), "{}\n", fmt::join(columns, ","));
}

// Unfinished, nothing more is written: a file of its own is discarded with own_.
CsvWriter::~CsvWriter() = default;

void CsvWriter::flush() {
  if (finished_) {
    throw std::logic_error(fmt::format("{}: CSV written after it was finished", out_->path()));
  }
  out_->write(std::string_view(buffer_.data(), buffer_.size()));
  buffer_.clear();
}

void CsvWriter::flush_if_full() {
  if (buffer_.size() >= 65536) {
    flush();
  }
}

void CsvWriter::row(std::span<const double> values) {
  if (values.size() != width_) {
    throw InputError(fmt::format("{}: row of {} values for {} columns", out_->path(), values.size(), width_));
  }
  // printf's %.10g, locale-free, straight into the buffer (format_g10: exactly std::to_chars', faster).
  char cell[kFormatG10MaxChars + 1];
  for (std::size_t i = 0; i < values.size(); ++i) {
    char* p = cell;
    if (i > 0) {
      *p++ = ',';
    }
    buffer_.append(cell, format_g10(p, values[i]));
  }
  buffer_.push_back('\n');
  flush_if_full();
}

void CsvWriter::comment(const std::string& text) {
  fmt::format_to(std::back_inserter(buffer_), "# {}\n", text);
  flush_if_full();
}

void CsvWriter::finish() {
  flush();
  finished_ = true;
  if (own_) {
    own_->commit();
  }
}

}  // namespace deflex
