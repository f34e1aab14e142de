// Results of a case study (per setup, load and speed) and their forms: JSON, terminal tables in the
// paper's layout beside the paper's figures, Markdown and CSV.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "deflex/evaluate/paper_figures.hpp"

namespace deflex {

/// Figures of one load of one setup. Every map is keyed by the TCP speed in mm/s; lengths in mm.
struct LoadResult {
  double load_N = 0.0;
  std::map<int, double> uc_mm;         ///< mean distance of the loaded uncompensated path from the unloaded one
  std::map<int, double> c_mm;          ///< the same for the loaded compensated path
  std::map<int, double> compensation;  ///< 1 - C/UC at the same speed (fraction, 0.67 = 67%)
  std::map<int, double> uc_std_mm, c_std_mm;    ///< standard deviation of the distances (optional)
  std::map<int, double> uc_max_mm, c_max_mm;    ///< largest distance (optional)
  std::map<int, double> iso_accuracy_uc_mm, iso_accuracy_c_mm;  ///< ISO 9283 AT_p vs the unloaded path (optional)
  std::map<int, double> iso_repeatability_mm;                   ///< ISO 9283 RT_p of the compensated runs (optional)
  /// The time-synchronous (along-path) error against the unloaded run at the same time (optional): it
  /// sees lag that the nearest-point distance does not.
  std::map<int, double> uc_sync_mm, c_sync_mm;

  /// Mean of uc_mm over the speeds: the paper's UC column. NaN when uc_mm is empty.
  [[nodiscard]] double uc_mean_mm() const;
  /// Sets compensation[v] = compensation_ratio(uc_mm[v], c_mm[v]) for every speed with both.
  void fill_compensation();
};

/// One strategy setup: "offline", "online" (the paper's two), "hybrid", "online-latency-comp", ...
struct SetupResult {
  std::string setup;
  std::string description;
  std::vector<LoadResult> loads;
};

/// One point of a speed sweep (beyond the paper's 10-50 mm/s).
struct SweepPoint {
  std::string setup;
  double load_N = 0.0;
  double speed_mm_s = 0.0;
  double uc_mm = 0.0;
  double c_mm = 0.0;
  double compensation = 0.0;
};

struct StudyResult {
  std::vector<SetupResult> setups;
  std::vector<int> speeds_mm_s;          ///< the table columns C1, C2, C3 ... (mm/s)
  std::vector<SweepPoint> speed_sweep;   ///< optional
  std::string case_name;                 ///< optional, shown in headings
  std::uint64_t seed = 0;
  double wall_time_s = 0.0;              ///< optional, 0 = not reported
};

/// {"setups":[{"setup":"offline","description":..,"loads":[{"load_N":125,"uc_mm":{"10":..,"30":..,"50":..},
///  "c_mm":{..},"compensation":{..}, (optional maps when filled)}, ...]}, ...], "speeds_mm_s":[..],
///  "speed_sweep":[{"setup","load_N","speed_mm_s","uc_mm","c_mm","compensation"}], "paper":{...}}.
/// NaN values are written as null.
nlohmann::json study_to_json(const StudyResult& study);
/// The inverse of study_to_json (for `deflex report` from a saved JSON). Throws DataError naming the
/// field on a malformed document.
StudyResult study_from_json(const nlohmann::json& doc, const std::string& source = "JSON");

/// The speed columns of the tables (mm/s): study.speeds_mm_s when given, else every speed any load
/// reports, ascending. The report module lays its tables and charts out by the same columns.
[[nodiscard]] std::vector<int> study_speeds_mm_s(const StudyResult& study);
/// m[speed_mm_s], NaN when the map has no value at that speed.
[[nodiscard]] double value_at_speed(const std::map<int, double>& m, int speed_mm_s);
/// A fraction as whole percent ("67%"); one that rounds to zero prints "0%", not "-0%"; "n/a" if not finite.
[[nodiscard]] std::string percent_text(double fraction);

/// Terminal text: for each setup a table in the paper's layout (rows loads; columns UC, C1, C2, C3
/// in mm, then compensation %), each cell "ours (paper)" where the paper has the figure.
std::string study_tables_text(const StudyResult& study);
/// The same tables in GitHub Markdown.
std::string study_tables_markdown(const StudyResult& study);
/// Long format, one row per setup, load and speed: setup,load_N,speed_mm_s,uc_mm,c_mm,compensation,
/// ... ,paper_uc_mm,paper_c_mm (empty cell where there is no figure). Throws Error on a write failure.
void write_study_csv(const StudyResult& study, const std::string& path);

}  // namespace deflex
