// The paper's protocol on the simulated cell, end to end (paper, section 3): per seed, setup, load
// and speed an unloaded, a loaded uncompensated (UC) and a loaded compensated (C) run, evaluated by
// the paper's mean distance from the unloaded path, a time-synchronous error and ISO 9283; the speed
// sweep; the error budget. Each seed is its own cell (true robot, sensor, calibration); the figures
// are the mean and spread over the seeds. Runs are independent and seeded by their identity, so they
// run on every core and the figures do not depend on the scheduling.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "deflex/cell/coupled_tick.hpp"
#include "deflex/evaluate/lap_split.hpp"
#include "deflex/model/tracker_trace.hpp"
#include "deflex/study/case_config.hpp"
#include "deflex/study/study_tables.hpp"

namespace deflex::study {

struct CaseStudyOptions {
  bool quick = false;  ///< one clockwise and one anticlockwise lap per run
  int seeds = 0;       ///< seeds to run (0: the case's protocol.seeds)
  bool speed_sweep = true;
  bool error_budget = true;
  int threads = 0;  ///< 0: one per hardware thread
  /// The slow reference computation: the cell's noise from the reference generator and its solvers at
  /// their tightest tolerances. Off (the default), the study computes the same runs and calibrations
  /// faster, its printed means within a tenth of their spread over the seeds of the exact ones
  /// (docs/case-study.md, "How long it takes"; tests/study/fast_mode_test.cpp checks it).
  bool exact = false;
  /// Progress in [0, 1] with a short label; called from worker threads, one call at a time.
  std::function<void(double fraction, const std::string& label)> progress;
  /// Called with every run of the first seed at the error budget's speed and the highest load
  /// (and the unloaded runs at that speed), for --write-traces: a name and the tracker trace.
  /// Called from worker threads, one call at a time.
  std::function<void(const std::string& name, const TrackerTrace& trace)> trace_sink;
};

/// Traces for the path plots of one setup at one load and speed (the study's first seed).
struct PlotTraces {
  std::string title;
  std::string setup;
  double load_n = 0.0;
  double speed_mm_s = 0.0;
  TrackerTrace unloaded, uc, c;  ///< the last lap of each run, thinned
  TrackerTrace unloaded_mean;    ///< the mean of the unloaded laps: the reference the distances are taken to
  /// Every lap of the loaded runs, in order, thinned, each with its direction of travel as the
  /// trace shows it (not as the protocol says).
  std::vector<DirectedLap> uc_laps, c_laps;
};

/// What deflex's links did in the online runs (every run of the study, summed or maximised).
struct LinkSummary {
  std::string setup;
  std::string link;                        ///< the link kind (egm-joint, egm-path, ...)
  bool joint_commands = true;              ///< the link sends joints (else Cartesian offsets)
  std::uint64_t cycles = 0;                ///< controller messages answered
  std::uint64_t rejected = 0;              ///< datagrams counted and not answered
  std::uint64_t guard_trips = 0;           ///< commands the final check stopped (must be 0)
  double max_command_deviation_rad = 0.0;  ///< largest |command - nominal|, any joint, any cycle
  double bound_rad = 0.0;                  ///< the bound it must stay within
  double max_tcp_correction_m = 0.0;
  double measured_delay_s = 0.0;  ///< the link's measured delay (mean over the runs)
  /// What the setup's compensation came to at its highest load, so each link's timing shows in it: UC
  /// (the mean over the speeds and seeds), C (the same) and 1 - C/UC from the two as printed.
  double load_n = 0.0;
  double uc_mm = 0.0;
  double c_mm = 0.0;
  double compensation = 0.0;
  /// What the controller itself counted of deflex's stream over the compensated runs, in words ("" for a
  /// controller that counts nothing of the kind): RSI's late cycles, FANUC's peak jerk against its limit,
  /// MotoROS2's truncated increments, UR's protective stops (a stop of any controller ends the study).
  std::string controller_note;
};

/// Where a study's CPU time went, summed over its threads (s of thread CPU time).
struct StudyPhaseTimes {
  double calibration_s = 0.0;  ///< the calibrations of the seeds' cells
  double unloaded_s = 0.0;     ///< the unloaded reference runs (simulated)
  double loaded_s = 0.0;       ///< the loaded runs of the tables and the sweep (simulated)
  double evaluation_s = 0.0;   ///< the references' means and indexes, the runs' metrics and plotted laps
  double budget_s = 0.0;       ///< the error budget's cells, calibrations and runs, all in
  double assembly_s = 0.0;     ///< the tables, the plots and the setups' descriptions
};

struct CaseStudyOutput {
  StudyResult study;
  std::vector<LinkSummary> links;
  std::vector<PlotTraces> plots;
  std::vector<std::string> setup_paragraphs;  ///< the cell and calibration in words
  double simulated_s = 0.0;                   ///< total simulated robot time (runs and calibrations)
  int runs = 0;
  int calibrations = 0;
  /// What the cell's coupled solves of the arm and the bar did, over every loaded tick of the study
  /// (runs and calibrations): ticks, solves of the arm, ticks that reached the cap.
  cell::CoupledTickCounters coupled;
  cell::CoupledTickOptions coupled_options;  ///< the tolerance and cap those solves had
  StudyPhaseTimes phases;                    ///< where the CPU time went
};

/// Runs the whole study. Throws deflex::Error on a case the cell cannot run (unreachable circle ...).
[[nodiscard]] CaseStudyOutput run_case_study(const CaseConfig& config, const CaseStudyOptions& options);

/// The coupled solves of a study in words: the method, its tolerance and cap, how many ticks and
/// solves, and every tick that reached the cap.
[[nodiscard]] std::string describe_coupled_solves(const cell::CoupledTickCounters& counters,
                                                  const cell::CoupledTickOptions& options = {});

/// Runs `jobs` on `threads` threads (0: hardware), largest first as given; rethrows the first
/// exception after every thread has stopped.
void run_parallel(std::vector<std::function<void()>>& jobs, int threads);

}  // namespace deflex::study
