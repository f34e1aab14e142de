// A per-point wrench table read from CSV (e.g. forces predicted by a process simulation).
//
// Columns (any order, header row): fx_N, fy_N, fz_N required; mx_Nm, my_Nm, mz_Nm optional (zero
// when absent); `index` optional. Without `index`, data row r is path point r. With it, each row
// names its 0-based path point, every index 0..N-1 must appear exactly once, in any order.
// Base frame, moment about the TCP, as every ForceModel.
#pragma once

#include <string>
#include <vector>

#include "deflex/force/force_model.hpp"

namespace deflex {

class CsvTable;

/// Thread safety: immutable once built: any number of threads may share one.
class WrenchTableModel final : public ForceModel {
 public:
  /// Throws DataError naming the file, line and column of any malformed, duplicate or missing row.
  explicit WrenchTableModel(const CsvTable& table);
  static WrenchTableModel read_file(const std::string& path);

  /// Throws InputError for an index beyond the table.
  [[nodiscard]] Wrench wrench_at(std::size_t index, const Pose& base_T_tcp) const override;
  [[nodiscard]] std::string describe() const override;
  [[nodiscard]] std::string label() const override { return "table"; }
  [[nodiscard]] std::optional<std::size_t> points() const override { return wrenches_.size(); }

 private:
  std::string source_;
  std::vector<Wrench> wrenches_;
};

}  // namespace deflex
