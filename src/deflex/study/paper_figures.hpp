// The published figures of the reference study (Tables 1 and 2 of the paper), for side-by-side
// comparison with our results.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace deflex {

/// One row of the paper's Table 1 or 2: a load, UC (the mean over the three speeds) and C at each
/// speed (mm/s -> mm).
struct PaperRow {
  double load_N = 0.0;
  double uc_mm = 0.0;
  std::map<int, double> c_mm;
  /// 1 - C/UC, the mean over the row's speeds (its UC is already their mean): the paper's own way of
  /// quoting compensation. NaN when no speed has a finite ratio.
  [[nodiscard]] double mean_compensation() const;
};

struct PaperTable {
  std::string setup;    ///< "offline" or "online"
  std::string caption;  ///< "Table 1. Offline compensation ..."
  std::vector<PaperRow> rows;
  /// Row whose load is within `tolerance_N` of `load_N`, or nullptr.
  [[nodiscard]] const PaperRow* row_for(double load_N, double tolerance_N = 1.0) const;
};

struct PaperFigures {
  std::vector<PaperTable> tables;
  std::vector<int> speeds_mm_s;  ///< {10, 30, 50}
  /// Table of a setup ("offline", "online"), or nullptr for setups the paper did not run.
  [[nodiscard]] const PaperTable* table_for(const std::string& setup) const;
};

/// Tables 1 and 2 of the paper (compliance-compensation-paper, section 4), as published.
PaperFigures paper_reference();

}  // namespace deflex
