// The error budget of a simulated case: each effect of the cell, its size, and how the compensated
// residual C changes when that effect alone is switched off (a one-effect-at-a-time sensitivity),
// beside C with every effect on and C with every effect off at once. Part of a study's results
// (study_tables.hpp), so its JSON and CSV carry it.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace deflex {

struct ErrorBudgetEntry {
  std::string effect;                   ///< "force sensor compliance", "lost motion", ...
  std::string size;                     ///< the effect's size in words with units: "0.02 mm/100 N"
  double residual_mm_without_it = 0.0;  ///< compensated residual (mean distance, mm) with this effect alone off
  /// One-effect-at-a-time sensitivity: the fraction by which C falls when this effect alone is
  /// switched off, (C_all - C_without) / C_all. Not a share of the residual: effects interact (one
  /// hides or offsets another, the calibration absorbs part of each), so the effects' values need not
  /// add up to 1, and C with every effect off (ErrorBudget::residual_mm_all_off) is not 1 - their sum.
  double sensitivity = 0.0;
};

struct ErrorBudget {
  std::string setup;  ///< which setup, load and speed the budget was run for
  double load_N = 0.0;
  double speed_mm_s = 0.0;
  double residual_mm_all = 0.0;  ///< compensated residual C with every effect on
  /// C on a cell built with every effect of the cell off at once, calibrated as the others are (its
  /// own calibration, not the exact model); NaN when not run.
  double residual_mm_all_off = std::numeric_limits<double>::quiet_NaN();
  double uc_mm = 0.0;      ///< uncompensated deviation, for scale (0 = not given)
  std::uint64_t seed = 0;  ///< the seed its runs are of (0 = not given)
  int laps = 0;            ///< laps per run (0 = not given)
  std::vector<ErrorBudgetEntry> entries;
};

/// The one-effect-at-a-time sensitivity (all - without) / all; NaN when `residual_all_mm` is not
/// positive or either value is not finite.
double one_at_a_time_sensitivity(double residual_all_mm, double residual_without_mm);

}  // namespace deflex
