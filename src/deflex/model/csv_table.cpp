// CSV data files with a unit-carrying header row.
#include "deflex/model/csv_table.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string_view>

#include <fmt/format.h>

#include "deflex/model/errors.hpp"
#include "deflex/model/input_ranges.hpp"
#include "deflex/model/nearest_name.hpp"
#include "deflex/model/parse_number.hpp"

namespace deflex {
namespace {

// A data file larger than this is refused before it is read: 1 GiB holds some 30 million tracker
// samples, over eight hours at 1000 Hz.
constexpr std::uintmax_t kMaxFileBytes = std::uintmax_t{1} << 30;

std::string trim(std::string_view s) { return std::string(trim_view(s)); }

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::size_t b = 0;
  while (true) {
    const auto e = line.find(',', b);
    out.push_back(trim(std::string_view(line).substr(b, e == std::string::npos ? std::string::npos : e - b)));
    if (e == std::string::npos) {
      break;
    }
    b = e + 1;
  }
  return out;
}

// A header cell written quoted by a spreadsheet ("x_mm") names the column x_mm.
std::string unquote(const std::string& cell) {
  if (cell.size() >= 2 && cell.front() == '"' && cell.back() == '"') {
    return cell.substr(1, cell.size() - 2);
  }
  return cell;
}

// Lines ending in LF, CRLF or a lone CR (old Mac, some loggers), all alike.
std::vector<std::string> split_lines(std::string_view text) {
  std::vector<std::string> lines;
  std::size_t b = 0;
  while (b <= text.size()) {
    const auto e = text.find_first_of("\r\n", b);
    if (e == std::string_view::npos) {
      if (b < text.size()) {
        lines.emplace_back(text.substr(b));
      }
      break;
    }
    lines.emplace_back(text.substr(b, e - b));
    b = e + 1;
    if (text[e] == '\r' && b < text.size() && text[b] == '\n') {
      ++b;
    }
  }
  return lines;
}

}  // namespace

std::string read_text_file(const std::string& path, const char* what) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (!ec && size > kMaxFileBytes) {
    throw DataError(fmt::format("{}: the {} is {} bytes; deflex reads files up to {} bytes", path, what, size,
                                kMaxFileBytes));
  }
  if (!ec && std::filesystem::is_directory(path)) {
    throw DataError(fmt::format("{}: is a directory, not a {}", path, what));
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw DataError(fmt::format("{}: cannot read the {}", path, what));
  }
  std::stringstream ss;
  ss << in.rdbuf();
  std::string text = ss.str();
  // A UTF-8 byte order mark (Excel writes one) is not part of the first column's name.
  if (text.rfind("\xEF\xBB\xBF", 0) == 0) {
    text.erase(0, 3);
  }
  return text;
}

CsvTable CsvTable::read_file(const std::string& path) { return parse(read_text_file(path, "file"), path); }

CsvTable CsvTable::parse(const std::string& raw_text, const std::string& source) {
  CsvTable t;
  t.source_ = source;
  const std::string_view text =
      raw_text.rfind("\xEF\xBB\xBF", 0) == 0 ? std::string_view(raw_text).substr(3) : std::string_view(raw_text);
  int line_no = 0;
  bool have_header = false;
  std::vector<const InputRange*> ranges;
  for (const std::string& line : split_lines(text)) {
    ++line_no;
    const std::string tl = trim(line);
    if (tl.empty() || tl[0] == '#') {
      continue;
    }
    const auto cells = split(tl);
    if (!have_header) {
      if (cells.size() == 1) {
        for (const char sep : {';', '\t', '|'}) {
          if (tl.find(sep) != std::string::npos) {
            throw DataError(fmt::format("{}:{}: header '{}' is one column: deflex CSV files separate columns with "
                                        "commas, this one uses '{}'",
                                        source, line_no, tl, sep == '\t' ? std::string("\\t") : std::string(1, sep)));
          }
        }
      }
      for (std::size_t i = 0; i < cells.size(); ++i) {
        const std::string name = unquote(cells[i]);
        if (name.empty()) {
          throw DataError(fmt::format("{}:{}: header: column {} has no name", source, line_no, i + 1));
        }
        if (parse_double(name)) {
          throw DataError(fmt::format("{}:{}: header: column {} is named '{}', a number: the first row must name "
                                      "the columns (e.g. t_s,x_mm,y_mm,z_mm)",
                                      source, line_no, i + 1, name));
        }
        if (!t.index_.emplace(name, i).second) {
          throw DataError(fmt::format("{}:{}: header: column '{}' appears twice", source, line_no, name));
        }
        t.columns_.push_back(name);
        ranges.push_back(&range_for_name(name));
      }
      have_header = true;
      continue;
    }
    if (cells.size() != t.columns_.size()) {
      const bool other_sep = tl.find(';') != std::string::npos || tl.find('\t') != std::string::npos;
      throw DataError(fmt::format("{}:{}: {} cells, the header has {} columns{}", source, line_no, cells.size(),
                                  t.columns_.size(),
                                  other_sep ? " (deflex CSV files separate cells with commas, and the decimal "
                                              "separator is a point)"
                                            : ""));
    }
    std::vector<double> row(cells.size());
    for (std::size_t i = 0; i < cells.size(); ++i) {
      const std::string& c = cells[i];
      if (c.empty()) {
        throw DataError(fmt::format("{}:{}: column '{}': empty cell", source, line_no, t.columns_[i]));
      }
      const std::optional<double> v = parse_double(c);
      if (!v) {
        throw DataError(fmt::format("{}:{}: column '{}': {}", source, line_no, t.columns_[i], not_a_number(c)));
      }
      if (const auto bad = range_violation(*v, *ranges[i])) {
        throw DataError(fmt::format("{}:{}: column '{}': {}", source, line_no, t.columns_[i], *bad));
      }
      row[i] = *v;
    }
    t.values_.push_back(std::move(row));
    t.lines_.push_back(line_no);
  }
  if (!have_header) {
    throw DataError(fmt::format("{}: no header row (the file is empty)", source));
  }
  return t;
}

void CsvTable::allow_only(const std::vector<std::string>& allowed) const {
  for (const std::string& c : columns_) {
    if (std::find(allowed.begin(), allowed.end(), c) == allowed.end()) {
      throw DataError(fmt::format("{}: unknown column '{}'{} (this file takes: {})", source_, c,
                                  did_you_mean(c, allowed), fmt::join(allowed, ", ")));
    }
  }
}

std::size_t CsvTable::column(const std::string& name) const {
  const auto it = index_.find(name);
  if (it == index_.end()) {
    throw DataError(fmt::format("{}: missing column '{}' (have: {})", source_, name, fmt::join(columns_, ", ")));
  }
  return it->second;
}

double CsvTable::at(std::size_t row, const std::string& name) const { return values_[row][column(name)]; }

void CsvTable::fail(std::size_t row, const std::string& name, const std::string& message) const {
  throw DataError(fmt::format("{}:{}: column '{}': {}", source_, lines_[row], name, message));
}

void CsvTable::require(const std::vector<std::string>& required) const {
  std::vector<std::string> missing;
  for (const auto& r : required) {
    if (!has(r)) {
      missing.push_back(r);
    }
  }
  if (!missing.empty()) {
    throw DataError(fmt::format("{}: missing column{} {} (have: {})", source_, missing.size() > 1 ? "s" : "",
                                fmt::join(missing, ", "), fmt::join(columns_, ", ")));
  }
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

struct CsvWriter::Impl {
  std::ofstream out;
};

CsvWriter::CsvWriter(const std::string& path, const std::vector<std::string>& columns)
    : path_(path), width_(columns.size()), impl_(std::make_shared<Impl>()) {
  impl_->out.open(path);
  if (!impl_->out) {
    throw Error(fmt::format("{}: cannot write the file", path));
  }
  impl_->out << fmt::format("{}\n", fmt::join(columns, ","));
}

void CsvWriter::row(const std::vector<double>& values) {
  if (values.size() != width_) {
    throw InputError(fmt::format("{}: row of {} values for {} columns", path_, values.size(), width_));
  }
  impl_->out << fmt::format("{:.10g}\n", fmt::join(values, ","));
  if (!impl_->out) {
    throw Error(fmt::format("{}: write failed", path_));
  }
}

void CsvWriter::comment(const std::string& text) { impl_->out << "# " << text << "\n"; }

}  // namespace deflex
