// CSV data files with a unit-carrying header row.
#include "deflex/model/csv_table.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "deflex/model/errors.hpp"

namespace deflex {
namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) {
    return "";
  }
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) {
    out.push_back(trim(cell));
  }
  if (!line.empty() && line.back() == ',') {
    out.emplace_back();
  }
  return out;
}

}  // namespace

CsvTable CsvTable::read_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    throw DataError(fmt::format("{}: cannot read the file", path));
  }
  std::stringstream ss;
  ss << in.rdbuf();
  return parse(ss.str(), path);
}

CsvTable CsvTable::parse(const std::string& text, const std::string& source) {
  CsvTable t;
  t.source_ = source;
  std::stringstream ss(text);
  std::string line;
  int line_no = 0;
  bool have_header = false;
  while (std::getline(ss, line)) {
    ++line_no;
    const std::string tl = trim(line);
    if (tl.empty() || tl[0] == '#') {
      continue;
    }
    const auto cells = split(tl);
    if (!have_header) {
      t.columns_ = cells;
      for (std::size_t i = 0; i < cells.size(); ++i) {
        if (cells[i].empty()) {
          throw DataError(fmt::format("{}:{}: header: column {} has no name", source, line_no, i + 1));
        }
        if (!t.index_.emplace(cells[i], i).second) {
          throw DataError(fmt::format("{}:{}: header: column '{}' appears twice", source, line_no, cells[i]));
        }
      }
      have_header = true;
      continue;
    }
    if (cells.size() != t.columns_.size()) {
      throw DataError(fmt::format("{}:{}: {} cells, the header has {} columns", source, line_no, cells.size(),
                                  t.columns_.size()));
    }
    std::vector<double> row(cells.size());
    for (std::size_t i = 0; i < cells.size(); ++i) {
      const std::string& c = cells[i];
      if (c.empty()) {
        throw DataError(fmt::format("{}:{}: column '{}': empty cell", source, line_no, t.columns_[i]));
      }
      std::size_t used = 0;
      double v = 0.0;
      try {
        v = std::stod(c, &used);
      } catch (const std::logic_error&) {
        used = 0;
      }
      if (used != c.size()) {
        throw DataError(fmt::format("{}:{}: column '{}': '{}' is not a number", source, line_no, t.columns_[i], c));
      }
      if (!std::isfinite(v)) {
        throw DataError(fmt::format("{}:{}: column '{}': '{}' is not a finite number", source, line_no,
                                    t.columns_[i], c));
      }
      row[i] = v;
    }
    t.values_.push_back(std::move(row));
    t.lines_.push_back(line_no);
  }
  if (!have_header) {
    throw DataError(fmt::format("{}: no header row (the file is empty)", source));
  }
  return t;
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
