// The machining study on the simulated cell: the cell's arm mills a small aluminium part (a slot, an
// open pocket whose side walls are finished in climb and in conventional milling, and an outside
// contour round a corner) at two feeds, uncompensated and with each of deflex's strategies, and the
// part is probed as a CMM would probe it: each wall's profile, the floors' flatness, the widths.
//
// The strategies get what a user has: the identified robot model of the cell's own calibration, the
// nominal part and stock, the force sensor over EGM (online, hybrid), and cutting coefficients the
// library fits (fit_cutting_coefficients) from slot cuts the cell itself ran and its sensor logged
// (offline, hybrid). The true coefficients, the true engagement and the true stock stay in the cell;
// the output carries the truth beside the results for the report and the tests only.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "deflex/cell/coupled_tick.hpp"
#include "deflex/machining/coefficient_fit.hpp"
#include "deflex/machining/cutting_coefficients.hpp"

namespace deflex::study {

enum class MachiningStrategy { kUncompensated, kOffline, kOnline, kHybrid };
[[nodiscard]] const char* to_string(MachiningStrategy s);
inline constexpr MachiningStrategy kMachiningStrategies[] = {MachiningStrategy::kUncompensated,
                                                             MachiningStrategy::kOffline, MachiningStrategy::kOnline,
                                                             MachiningStrategy::kHybrid};

struct MachiningStudyOptions {
  bool quick = false;  ///< a shorter part and fewer slot cuts
  int seeds = 0;       ///< 0: 3 (2 with quick)
  int threads = 0;     ///< 0: one per hardware thread
  /// Progress in [0, 1] with a short label; called from worker threads, one call at a time.
  std::function<void(double fraction, const std::string& label)> progress;
};

/// What the probe read on one part (m; deviations > 0 where material was left).
struct PartErrors {
  double climb_wall_mean_m = 0.0, climb_wall_pv_m = 0.0, climb_wall_rms_m = 0.0;
  double conventional_wall_mean_m = 0.0, conventional_wall_pv_m = 0.0, conventional_wall_rms_m = 0.0;
  double contour_wall_mean_m = 0.0, contour_wall_pv_m = 0.0, contour_wall_rms_m = 0.0;
  double pocket_floor_flatness_m = 0.0, pocket_floor_mean_m = 0.0;
  double pocket_width_error_m = 0.0;
  double slot_width_error_m = 0.0;
  double slot_floor_flatness_m = 0.0;
};

/// One wall's probed deviations along it, for the report (m).
struct WallTrace {
  std::string name;
  std::vector<double> along_m, deviation_m;
};

/// The force and the tool's deflection along one pass, sampled, for the report (N, m; stock frame
/// magnitudes in the plane of the cut).
struct PassTrace {
  std::string name;
  std::vector<double> x_m;                ///< the programmed tip's x (the feed's direction)
  std::vector<double> true_force_n;       ///< the cell's cut force (in-plane magnitude)
  std::vector<double> predicted_force_n;  ///< the offline model's (fitted coefficients), at that point
  std::vector<double> deflection_m;       ///< the true tool's in-plane distance from the programmed tip
};

struct MachiningRun {
  MachiningStrategy strategy = MachiningStrategy::kUncompensated;
  double feed_mm_min = 0.0;
  int seed_index = 0;
  PartErrors errors;
  cell::CoupledTickCounters coupled;
  std::uint64_t link_cycles = 0;  ///< EGM messages deflex answered (online, hybrid)
  double seconds = 0.0;           ///< the part's thread time (planning, cutting, probing)
  std::vector<WallTrace> walls;   ///< first seed only
  std::vector<PassTrace> passes;  ///< first seed only
};

/// One seed's coefficient fit from the cell's slot cuts, beside the truth the cell drew (the truth for
/// the report and the tests; no strategy reads it).
struct MachiningFit {
  int seed_index = 0;
  CoefficientFit fit;
  CuttingCoefficients truth;
  double truth_runout_m = 0.0;
  std::vector<double> slot_fz_m;  ///< the slot cuts' feeds per tooth
};

/// A cell of the table: mean and sample standard deviation over the seeds (m).
struct Spread {
  double mean = 0.0, sd = 0.0;
  int n = 0;
};

struct MachiningRow {
  MachiningStrategy strategy = MachiningStrategy::kUncompensated;
  double feed_mm_min = 0.0;
  Spread climb_mean, climb_pv, conventional_mean, conventional_pv, contour_mean, contour_pv;
  Spread pocket_flatness, pocket_width, slot_width;
};

/// The study's sizes of the cell and the cuts (data/cases/effect-ranges.yaml, milling:), SI.
struct MachiningSizes {
  double coefficient_spread = 0.0;  ///< relative 1-sigma of the true coefficients
  double runout_lo_m = 0.0, runout_hi_m = 0.0;
  double stock_cell_m = 0.0;
  double probe_noise_m = 0.0;
  std::vector<double> fz_m;  ///< every feed per tooth cut (the parts' and the slot cuts')
  std::vector<double> ap_m;  ///< every axial depth cut
};

/// Where the study's time went: each phase's thread time summed over the seeds (s, steady clock; with
/// several threads the sum exceeds the wall time).
struct MachiningTimes {
  double calibration_s = 0.0;                ///< the seeds' cells and their compliance calibrations
  double slot_cuts_s = 0.0;                  ///< the slot cuts, their logs and the fits
  double parts_s[4] = {0.0, 0.0, 0.0, 0.0};  ///< the parts, by strategy (kMachiningStrategies' order)
};

struct MachiningStudyOutput {
  std::vector<MachiningRun> runs;
  std::vector<MachiningFit> fits;
  std::vector<MachiningRow> rows;
  CuttingCoefficients published;
  std::vector<double> feeds_mm_min;
  int seeds = 0;
  double probe_noise_m = 0.0;
  MachiningSizes sizes;
  MachiningTimes times;
  double simulated_s = 0.0;
  /// What the cell's coupled solves of the arm and the cut did over every part (not the slot cuts).
  cell::CoupledTickCounters coupled;
  std::vector<std::string> setup_paragraphs;  ///< the part, the tool, the cell in words
};

/// Runs the study. Throws deflex::Error on a cell that cannot run it (an unreachable part ...), and
/// InputError for options out of range (seeds outside 1..20).
[[nodiscard]] MachiningStudyOutput run_machining_study(const MachiningStudyOptions& options);

/// The table as printed: one row per strategy and feed, um, mean +- standard deviation over seeds.
[[nodiscard]] std::string machining_table_text(const MachiningStudyOutput& out);
/// The fitted coefficients of each seed against the published set and the cell's truth.
[[nodiscard]] std::string machining_fit_text(const MachiningStudyOutput& out);
/// The table as CSV (header names units: _um) and the whole output as JSON.
[[nodiscard]] std::string machining_table_csv(const MachiningStudyOutput& out);
[[nodiscard]] std::string machining_json(const MachiningStudyOutput& out);

}  // namespace deflex::study
