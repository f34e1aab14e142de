// The error budget's arithmetic.
#include "deflex/study/error_budget.hpp"

#include <cmath>
#include <limits>

namespace deflex {

double one_at_a_time_sensitivity(double residual_all_mm, double residual_without_mm) {
  if (!(residual_all_mm > 0.0) || !std::isfinite(residual_all_mm) || !std::isfinite(residual_without_mm)) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  return (residual_all_mm - residual_without_mm) / residual_all_mm;
}

}  // namespace deflex
