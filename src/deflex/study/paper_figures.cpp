// Tables 1 and 2 of the reference paper, as published (section 4).
#include "deflex/study/paper_figures.hpp"

#include <cmath>

#include "deflex/evaluate/path_metrics.hpp"

namespace deflex {

double PaperRow::mean_compensation() const {
  double sum = 0.0;
  int n = 0;
  for (const auto& [v, c] : c_mm) {
    const double comp = compensation_ratio(uc_mm, c);
    if (std::isfinite(comp)) {
      sum += comp;
      ++n;
    }
  }
  return n > 0 ? sum / n : kNaN;
}

const PaperRow* PaperTable::row_for(double load_N, double tolerance_N) const {
  for (const auto& r : rows) {
    if (std::abs(r.load_N - load_N) <= tolerance_N) {
      return &r;
    }
  }
  return nullptr;
}

const PaperTable* PaperFigures::table_for(const std::string& setup) const {
  for (const auto& t : tables) {
    if (t.setup == setup) {
      return &t;
    }
  }
  return nullptr;
}

PaperFigures paper_reference() {
  PaperFigures p;
  p.speeds_mm_s = {10, 30, 50};
  p.tables.push_back(
      {"offline",
       "Table 1. Offline compensation: mean distance of the uncompensated (UC) and compensated (C1, C2, C3 at 10, "
       "30, 50 mm/s) paths from the unloaded path",
       {{125.0, 0.12, {{10, 0.04}, {30, 0.04}, {50, 0.04}}},
        {375.0, 0.38, {{10, 0.13}, {30, 0.13}, {50, 0.13}}},
        {625.0, 0.62, {{10, 0.21}, {30, 0.21}, {50, 0.20}}}}});
  p.tables.push_back(
      {"online",
       "Table 2. Online compensation (force sensor mounted): mean distance of the uncompensated (UC) and "
       "compensated (C1, C2, C3 at 10, 30, 50 mm/s) paths from the unloaded path",
       {{150.0, 0.23, {{10, 0.07}, {30, 0.07}, {50, 0.08}}},
        {400.0, 0.65, {{10, 0.16}, {30, 0.15}, {50, 0.15}}},
        {650.0, 1.10, {{10, 0.25}, {30, 0.19}, {50, 0.21}}}}});
  return p;
}

}  // namespace deflex
