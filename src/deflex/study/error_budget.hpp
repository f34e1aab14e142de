// The error budget of a simulated case: each effect of the cell, its size, and how much of the
// compensated residual it explains (found by switching effects off one at a time). Part of a study's
// results (study_tables.hpp), so its JSON and CSV carry it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace deflex {

struct ErrorBudgetEntry {
  std::string effect;                   ///< "force sensor compliance", "lost motion", ...
  std::string size;                     ///< the effect's size in words with units: "0.02 mm/100 N"
  double residual_mm_without_it = 0.0;  ///< compensated residual (mean distance, mm) with this effect off
  /// Share of the residual the effect explains: (residual_all - residual_without) / residual_all.
  /// Shares need not add up to 1 (effects interact; tracker noise stays in every run).
  double share_of_residual = 0.0;
};

struct ErrorBudget {
  std::string setup;  ///< which setup, load and speed the budget was run for
  double load_N = 0.0;
  double speed_mm_s = 0.0;
  double residual_mm_all = 0.0;  ///< compensated residual with every effect on
  double uc_mm = 0.0;            ///< uncompensated deviation, for scale (0 = not given)
  std::uint64_t seed = 0;        ///< the seed its runs are of (0 = not given)
  int laps = 0;                  ///< laps per run (0 = not given)
  std::vector<ErrorBudgetEntry> entries;
};

/// share = (all - without) / all; NaN when `residual_all_mm` is not positive.
double residual_share(double residual_all_mm, double residual_without_mm);

}  // namespace deflex
