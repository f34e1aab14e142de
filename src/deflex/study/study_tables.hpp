// Results of a case study (per setup, load and speed, over one or several seeds) and their forms:
// JSON, terminal tables in the paper's layout beside the paper's figures (mean and spread over the
// seeds), Markdown and CSV.
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>  // the declarations below; the caller includes <nlohmann/json.hpp> to use them

#include "deflex/study/error_budget.hpp"
#include "deflex/study/paper_figures.hpp"

namespace deflex {

/// Several seeds' values of one figure: the mean, the sample standard deviation over the seeds (0 for
/// one) and the range. NaN values are left out; n counts the rest.
struct Spread {
  double mean = std::numeric_limits<double>::quiet_NaN();
  double sd = 0.0;
  double min = std::numeric_limits<double>::quiet_NaN();
  double max = std::numeric_limits<double>::quiet_NaN();
  int n = 0;
};
[[nodiscard]] Spread spread_of(const std::vector<double>& values);

/// Figures of one load of one setup. Every map is keyed by the TCP speed in mm/s; lengths in mm.
/// With several seeds the plain maps hold the mean over the seeds and the *_by_seed maps the values
/// they are the mean of, in the study's seed order.
/// Thread safety: a value: const calls from any number of threads; fill_compensation() and
/// fill_means() need it to themselves.
struct LoadResult {
  double load_N = 0.0;
  std::map<int, double> uc_mm;                ///< mean distance of the loaded uncompensated path from the unloaded one
  std::map<int, double> c_mm;                 ///< the same for the loaded compensated path
  std::map<int, double> compensation;         ///< 1 - C/UC at the same speed (fraction, 0.67 = 67%)
  std::map<int, double> uc_std_mm, c_std_mm;  ///< standard deviation of the distances (optional)
  std::map<int, double> uc_max_mm, c_max_mm;  ///< largest distance (optional)
  std::map<int, double> iso_accuracy_uc_mm, iso_accuracy_c_mm;  ///< ISO 9283 AT_p vs the unloaded path (optional)
  std::map<int, double> iso_repeatability_mm;                   ///< ISO 9283 RT_p of the compensated runs (optional)
  /// The time-synchronous (along-path) error against the unloaded run at the same time (optional): it
  /// sees lag that the nearest-point distance does not.
  std::map<int, double> uc_sync_mm, c_sync_mm;
  /// Per seed (optional; one value each for a single seed).
  std::map<int, std::vector<double>> uc_mm_by_seed, c_mm_by_seed, uc_sync_mm_by_seed, c_sync_mm_by_seed;

  /// Mean of uc_mm over the speeds: the paper's UC column. NaN when uc_mm is empty.
  [[nodiscard]] double uc_mean_mm() const;
  /// Sets compensation[v] = compensation_ratio(uc_mm[v], c_mm[v]) for every speed with both.
  void fill_compensation();
  /// Sets the plain maps to the means of the *_by_seed maps, then fill_compensation().
  void fill_means();
  /// Spread over the seeds of C at a speed, of UC (mean over the speeds, per seed), and of the
  /// compensation (mean over the speeds of 1 - C/UC, per seed). A study without per-seed values
  /// gives its single value with sd 0.
  [[nodiscard]] Spread c_spread(int speed_mm_s) const;
  [[nodiscard]] Spread uc_mean_spread() const;
  [[nodiscard]] Spread compensation_spread() const;
  [[nodiscard]] int seeds() const;
};

/// One strategy setup: "offline", "online" (the paper's two), "hybrid", "online-latency-comp", ...
struct SetupResult {
  std::string setup;
  std::string description;
  std::vector<LoadResult> loads;
  /// The paper's table (PaperFigures::table_for's key) this setup is compared with when its own name
  /// is not one of the paper's: "online" for online compensation over the paper's own kind of link.
  /// Empty: the setup is compared by its name, or not at all.
  std::string paper_table = {};
  /// How the report marks that comparison: "simple message, 100 ms (the paper's kind of link)".
  std::string paper_label = {};
};

/// One point of a speed sweep (beyond the paper's 10-50 mm/s).
struct SweepPoint {
  std::string setup;
  double load_N = 0.0;
  double speed_mm_s = 0.0;
  double uc_mm = 0.0;  ///< mean over the seeds
  double c_mm = 0.0;   ///< mean over the seeds
  double compensation = 0.0;
  double c_sync_mm = std::numeric_limits<double>::quiet_NaN();         ///< time-synchronous error, mean over the seeds
  std::vector<double> uc_mm_by_seed, c_mm_by_seed, c_sync_mm_by_seed;  ///< optional
};

struct StudyResult {
  std::vector<SetupResult> setups;
  std::vector<int> speeds_mm_s;            ///< the table columns C1, C2, C3 ... (mm/s)
  std::vector<SweepPoint> speed_sweep;     ///< optional
  std::vector<ErrorBudget> error_budgets;  ///< optional
  std::string case_name;                   ///< optional, shown in headings
  std::uint64_t seed = 0;                  ///< the first seed
  std::vector<std::uint64_t> seeds;        ///< every seed the figures are over (empty: just `seed`)
  double wall_time_s = 0.0;                ///< optional, 0 = not reported

  /// How many seeds the figures are over (at least 1: `seed` alone when `seeds` is empty).
  [[nodiscard]] std::size_t seed_count() const { return std::max<std::size_t>(1, seeds.size()); }
};

/// {"setups":[{"setup":"offline","description":..,"loads":[{"load_N":125,"uc_mm":{"10":..,"30":..,"50":..},
///  "c_mm":{..},"compensation":{..}, (optional maps when filled; per-seed values as
///  "c_mm_by_seed":{"10":[..],..}), "spread":{"uc_mm":{mean,sd,min,max,n},"c_mm":{"10":{..}},
///  "compensation":{..}}}, ...]}, ...], "speeds_mm_s":[..], "seeds":[..],
///  "speed_sweep":[{"setup","load_N","speed_mm_s","uc_mm","c_mm","compensation","c_sync_mm",
///  "c_mm_by_seed":[..]}], "error_budget":[{"setup","load_N","speed_mm_s","residual_mm_all",
///  "residual_mm_all_off","uc_mm","entries":[{"effect","size","residual_mm_without_it",
///  "sensitivity_one_at_a_time"}]}], "paper":{...}}; a setup compared with a paper table of another
///  name carries "paper_table" and "paper_label".
/// NaN values are written as null.
nlohmann::json study_to_json(const StudyResult& study);
/// The inverse of study_to_json (for `deflex report` from a saved JSON). Throws DataError naming the
/// field on a malformed document.
StudyResult study_from_json(const nlohmann::json& doc, const std::string& source = "JSON");

/// The speed columns of the tables (mm/s): study.speeds_mm_s when given, else every speed any load
/// reports, ascending. The report module lays its tables and charts out by the same columns.
[[nodiscard]] std::vector<int> study_speeds_mm_s(const StudyResult& study);
/// The paper's table a setup is compared with: the one of its own name (offline, online), else the
/// one its paper_table names; nullptr when neither.
[[nodiscard]] const PaperTable* paper_table_of(const PaperFigures& paper, const SetupResult& setup);

/// The fidelity targets (issue 27): our UC within 15 % of the paper's, our C (the mean over the
/// speeds) within 35 %, at every load.
inline constexpr double kUcTarget = 0.15;
inline constexpr double kCTarget = 0.35;

/// Decimals of a length in mm as the tables print ours (the paper prints 2).
inline constexpr int kPrintedMmDecimals = 3;
/// `value` as printed with `decimals` decimals and read back: the number a reader recomputing a
/// percentage from the printed tables starts from. NaN stays NaN.
[[nodiscard]] double as_printed(double value, int decimals = kPrintedMmDecimals);
/// A load's compensation as the tables print it beside its figures: 1 - C / UC from the printed
/// figures, UC the mean over the speeds (the paper's UC column, so ours is stated the way the
/// paper's is) and C at `speed_mm_s`; NaN without both.
[[nodiscard]] double printed_compensation(const LoadResult& load, int speed_mm_s);
/// The same over `speeds`: 1 - (mean of the printed C) / printed UC as the mean; the spread over the
/// seeds of the same quantity per seed (1 - mean C / mean UC of that seed's runs) as sd, min and max.
[[nodiscard]] Spread printed_compensation_spread(const LoadResult& load, const std::vector<int>& speeds);
/// Our printed UC over the paper's, and our printed C summed over the paper's speeds over the paper's
/// C summed over the same speeds (C "averaged over the speeds"); NaN when there is nothing to compare.
[[nodiscard]] double uc_over_paper(const LoadResult& load, const PaperRow& paper);
[[nodiscard]] double c_over_paper(const LoadResult& load, const PaperRow& paper);
/// An error budget entry's one-effect-at-a-time sensitivity from the printed figures (C with every
/// effect and C without this one, 3 decimals each), as the report and the terminal print it.
[[nodiscard]] double printed_sensitivity(const ErrorBudget& budget, const ErrorBudgetEntry& entry);
/// A relative difference as whole percent with its sign ("+18%", "-7%"; "0%", never "-0%"); "n/a"
/// when not finite.
[[nodiscard]] std::string signed_percent_text(double fraction);

/// m[speed_mm_s], NaN when the map has no value at that speed.
[[nodiscard]] double value_at_speed(const std::map<int, double>& m, int speed_mm_s);
/// A fraction in whole percent as percent_text prints it (halves away from zero); NaN if not finite.
[[nodiscard]] double whole_percent(double fraction);
/// A fraction as whole percent ("67%"); one that rounds to zero prints "0%", not "-0%"; "n/a" if not finite.
[[nodiscard]] std::string percent_text(double fraction);

/// Terminal text: for each setup a table in the paper's layout (rows loads; columns UC, C1, C2, C3
/// in mm, then compensation %), each cell "ours (paper)" where the paper has the figure.
std::string study_tables_text(const StudyResult& study);
/// The same tables in GitHub Markdown.
std::string study_tables_markdown(const StudyResult& study);
/// Long format, one row per setup, load and speed: setup,load_N,speed_mm_s,uc_mm,c_mm,compensation,
/// ... ,seeds,c_mm_seed_sd,c_mm_seed_min,c_mm_seed_max,paper_uc_mm,paper_c_mm (empty cell where there
/// is no figure).
[[nodiscard]] std::string study_csv_text(const StudyResult& study);
/// The speed sweep, one row per setup and speed (means and spread over the seeds).
[[nodiscard]] std::string sweep_csv_text(const StudyResult& study);
/// The error budget, one row per setup and effect: C without that effect alone and the one-effect-at-
/// a-time sensitivity (not a share: they need not add up), beside C with every effect on and off.
[[nodiscard]] std::string error_budget_csv_text(const StudyResult& study);
/// The three as files of their own (output_file.hpp). Throw InputError or OutputError naming the file.
void write_study_csv(const StudyResult& study, const std::string& path);
void write_sweep_csv(const StudyResult& study, const std::string& path);
void write_error_budget_csv(const StudyResult& study, const std::string& path);

}  // namespace deflex
