// One run of the protocol on the simulated cell: the controller drives the programmed circle at a
// TCP speed for the laps of the protocol, the LDBB loads the TCP (or not), the strategy of the run
// corrects it (or not), and the laser tracker records the TCP at its rate.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "deflex/cell/cell_calibration.hpp"
#include "deflex/cell/controller.hpp"
#include "deflex/evaluate/tracker_trace.hpp"
#include "deflex/paths/path_ik.hpp"

namespace deflex::cell {

/// Everything one setup's runs share, built once (read-only while runs execute in parallel).
struct SetupCell {
  std::shared_ptr<const TrueRobot> robot;
  CellCalibration calibration;
  std::vector<Pose> circle_poses;  ///< the programmed circle, closed (last = first)
  JointPath nominal_path;          ///< IK of circle_poses with the nominal kinematics
  JointProgram nominal_program;    ///< the uncompensated program (distinct points)
};

/// Builds the setup: true robot from (seed) (the same robot for every setup), calibration, path.
[[nodiscard]] SetupCell build_setup_cell(const CaseConfig& config, bool sensor_mounted);

enum class RunKind { kUnloaded, kUncompensated, kCompensated };

struct RunSpec {
  RunKind kind = RunKind::kUnloaded;
  Strategy strategy = Strategy::kOffline;  ///< used for kCompensated
  double load_n = 0.0;
  double speed_m_s = 0.01;
  int laps_cw = 3;
  int laps_ccw = 3;
  std::uint64_t seed = 1;  ///< this run's own seed (see run_seed)
};

struct RunOutput {
  TrackerTrace trace;                  ///< tracker samples during the laps (t from the start of motion)
  std::vector<std::size_t> lap_start;  ///< index of each lap's first sample in `trace`
  double simulated_s = 0.0;
  int online_cycles = 0;
  int corrections_dropped = 0;
  double max_tcp_correction_m = 0.0;
};

/// A run's seed from the case seed and the run's identity, so results do not depend on the order
/// or the thread that runs them.
[[nodiscard]] std::uint64_t run_seed(std::uint64_t case_seed, bool sensor_mounted, RunKind kind, Strategy strategy,
                                     double load_n, double speed_m_s, std::uint64_t extra = 0);

/// Runs one protocol run. Throws InputError for a compensated run the setup cannot do (an online
/// strategy without the sensor) or when the offline compensation fails.
[[nodiscard]] RunOutput simulate_run(const SetupCell& setup, const RunSpec& spec);

/// The compensated program of the offline strategy (paper, Figure 2) for a load, from the
/// identified model and the LDBB force model (nominal pivot, set-point force).
[[nodiscard]] JointProgram offline_program(const SetupCell& setup, double load_n);

/// Splits a run's trace into its laps (for ISO 9283 repeatability).
[[nodiscard]] std::vector<TrackerTrace> split_laps(const RunOutput& run);

}  // namespace deflex::cell
