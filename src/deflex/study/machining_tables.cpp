// The machining study's table and fit as text, CSV and JSON (see machining_study.hpp).
#include <fmt/format.h>

#include <nlohmann/json.hpp>

#include "deflex/study/machining_study.hpp"

namespace deflex::study {
namespace {

std::string um_text(const Spread& s) { return fmt::format("{:+.1f} ± {:.1f}", s.mean * 1e6, s.sd * 1e6); }

struct Column {
  const char* header;
  const char* csv;
  Spread MachiningRow::*cell;
};
constexpr Column kColumns[] = {
    {"climb wall um", "climb_wall_mean_um", &MachiningRow::climb_mean},
    {"climb P-V um", "climb_wall_pv_um", &MachiningRow::climb_pv},
    {"conv. wall um", "conventional_wall_mean_um", &MachiningRow::conventional_mean},
    {"conv. P-V um", "conventional_wall_pv_um", &MachiningRow::conventional_pv},
    {"contour um", "contour_wall_mean_um", &MachiningRow::contour_mean},
    {"contour P-V um", "contour_wall_pv_um", &MachiningRow::contour_pv},
    {"floor flat. um", "pocket_floor_flatness_um", &MachiningRow::pocket_flatness},
    {"pocket width um", "pocket_width_error_um", &MachiningRow::pocket_width},
    {"slot width um", "slot_width_error_um", &MachiningRow::slot_width},
};

nlohmann::json coefficients_json(const CuttingCoefficients& k) {
  nlohmann::json j;
  for (int i = 0; i < 6; ++i) j[kCoefficientKeys[i]] = coefficient_in_user_units(k, i);
  return j;
}

}  // namespace

std::string machining_table_text(const MachiningStudyOutput& out) {
  std::string s = fmt::format(
      "Part errors over {} seed{} (mean ± standard deviation; walls: mean deviation > 0 where material was left, "
      "P-V the profile's peak to valley; widths: measured - nominal)\n",
      out.seeds, out.seeds == 1 ? "" : "s");
  s += fmt::format("{:<14} {:>8}", "strategy", "mm/min");
  for (const Column& c : kColumns) s += fmt::format(" {:>16}", c.header);
  s += "\n";
  for (const MachiningRow& r : out.rows) {
    s += fmt::format("{:<14} {:>8g}", to_string(r.strategy), r.feed_mm_min);
    for (const Column& c : kColumns) s += fmt::format(" {:>16}", um_text(r.*c.cell));
    s += "\n";
  }
  return s;
}

std::string machining_fit_text(const MachiningStudyOutput& out) {
  std::string s =
      "Cutting coefficients fitted from the cell's slot cuts (N/mm^2, N/mm), beside the published set "
      "and the cell's drawn truth\n";
  s += fmt::format("{:<22}", "");
  for (const char* k : kCoefficientKeys) s += fmt::format(" {:>10}", k);
  s += "\n";
  auto row = [&](const std::string& name, const CuttingCoefficients& k) {
    s += fmt::format("{:<22}", name);
    for (int i = 0; i < 6; ++i) s += fmt::format(" {:>10.1f}", coefficient_in_user_units(k, i));
    s += "\n";
  };
  row("published Al7075-T6", out.published);
  for (const MachiningFit& f : out.fits) {
    row(fmt::format("seed {} fitted", f.seed_index + 1), f.fit.k);
    row(fmt::format("seed {} truth", f.seed_index + 1), f.truth);
  }
  return s;
}

std::string machining_table_csv(const MachiningStudyOutput& out) {
  std::string s = "strategy,feed_mm_min,seeds";
  for (const Column& c : kColumns)
    s += fmt::format(",{},{}", c.csv, std::string(c.csv).replace(std::string(c.csv).rfind("_um"), 3, "_sd_um"));
  s += "\n";
  for (const MachiningRow& r : out.rows) {
    s += fmt::format("{},{:g},{}", to_string(r.strategy), r.feed_mm_min, (r.*kColumns[0].cell).n);
    for (const Column& c : kColumns) s += fmt::format(",{:.3f},{:.3f}", (r.*c.cell).mean * 1e6, (r.*c.cell).sd * 1e6);
    s += "\n";
  }
  return s;
}

std::string machining_json(const MachiningStudyOutput& out) {
  nlohmann::json j;
  j["seeds"] = out.seeds;
  j["feeds_mm_min"] = out.feeds_mm_min;
  j["probe_noise_um"] = out.probe_noise_m * 1e6;
  j["published"] = coefficients_json(out.published);
  for (const MachiningRow& r : out.rows) {
    nlohmann::json row;
    row["strategy"] = to_string(r.strategy);
    row["feed_mm_min"] = r.feed_mm_min;
    for (const Column& c : kColumns) {
      row[c.csv] = {{"mean", (r.*c.cell).mean * 1e6}, {"sd", (r.*c.cell).sd * 1e6}, {"n", (r.*c.cell).n}};
    }
    j["table"].push_back(row);
  }
  for (const MachiningFit& f : out.fits) {
    nlohmann::json fj;
    fj["seed"] = f.seed_index + 1;
    fj["fitted"] = coefficients_json(f.fit.k);
    fj["truth"] = coefficients_json(f.truth);
    fj["cuts"] = f.fit.cuts;
    j["fits"].push_back(fj);
  }
  return j.dump(2) + "\n";
}

}  // namespace deflex::study
