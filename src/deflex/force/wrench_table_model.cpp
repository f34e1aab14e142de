// Per-point wrench table.
#include "deflex/force/wrench_table_model.hpp"

#include <cmath>

#include <fmt/format.h>

#include "deflex/text/csv_table.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {

WrenchTableModel::WrenchTableModel(const CsvTable& table) : source_(table.source()) {
  table.require({"fx_N", "fy_N", "fz_N"});
  // A misspelt index column ("Index") would otherwise be ignored and every row taken in file order.
  table.allow_only({"index", "fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm"});
  if (table.rows() == 0) {
    throw DataError(fmt::format("{}: no wrench rows", table.source()));
  }
  static const char* const kColumns[6] = {"fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm"};
  const bool indexed = table.has("index");
  const std::size_t n = table.rows();
  wrenches_.assign(n, Wrench::Zero());
  std::vector<std::size_t> row_of(n, n);  // which row gave each index; n = none yet
  for (std::size_t r = 0; r < n; ++r) {
    std::size_t index = r;
    if (indexed) {
      const double v = table.at(r, "index");
      if (v < 0.0 || v != std::floor(v)) {
        table.fail(r, "index", fmt::format("{} is not a non-negative integer point index", v));
      }
      if (v >= static_cast<double>(n)) {
        table.fail(r, "index", fmt::format("index {} is beyond the table's {} rows (indices run 0..{})", v, n, n - 1));
      }
      index = static_cast<std::size_t>(v);
      if (row_of[index] != n) {
        table.fail(r, "index", fmt::format("index {} already given on line {}", index, table.line_of(row_of[index])));
      }
    }
    row_of[index] = r;
    for (int c = 0; c < 6; ++c) {
      if (table.has(kColumns[c])) {
        wrenches_[index][c] = table.at(r, kColumns[c]);
      }
    }
  }
  // With unique indices inside 0..n-1 and n rows, every index is present; nothing to check.
}

WrenchTableModel WrenchTableModel::read_file(const std::string& path) {
  return WrenchTableModel(CsvTable::read_file(path));
}

Wrench WrenchTableModel::wrench_at(std::size_t index, const Pose& /*base_T_tcp*/) const {
  if (index >= wrenches_.size()) {
    throw InputError(
        fmt::format("{}: no wrench for path point {} (the table has {} points)", source_, index, wrenches_.size()));
  }
  return wrenches_[index];
}

std::string WrenchTableModel::describe() const {
  return fmt::format("per-point wrench table {} ({} points, base frame, moment about the TCP)", source_,
                     wrenches_.size());
}

}  // namespace deflex
