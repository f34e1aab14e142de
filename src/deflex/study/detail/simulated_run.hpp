// One run of the protocol on the simulated cell: the controller drives the programmed circle at a TCP
// speed for the laps of the protocol, the LDBB loads the TCP (or not), the laser tracker records it.
// A compensated run gets its correction the way a real cell would: the offline strategy as a
// compensated robot program the controller runs, the online strategies from deflex's own controller
// link (any of the runtime's) over the cell's network, fed by the cell's force-sensor DAQ. The
// study builds deflex's side exactly as `deflex online` would; the cell never sees it.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "deflex/cell/coupled_tick.hpp"
#include "deflex/cell/force_sensor.hpp"
#include "deflex/cell/true_robot.hpp"
#include "deflex/link/controller_link.hpp"
#include "deflex/model/tracker_trace.hpp"
#include "deflex/online/sensor_config.hpp"
#include "deflex/paths/joint_trajectory.hpp"
#include "deflex/paths/path_ik.hpp"
#include "deflex/study/case_config.hpp"
#include "deflex/study/detail/cell_calibration.hpp"

namespace deflex::runtime {
class Session;
}

namespace deflex::study {

/// Everything one physical setup's runs share, built once (read-only while runs execute in parallel).
struct SetupCell {
  std::shared_ptr<const cell::TrueRobot> robot;
  CellCalibration calibration;
  std::vector<Pose> circle_poses;  ///< the programmed circle, closed (last = first)
  JointPath nominal_path;          ///< IK of circle_poses with the nominal kinematics
};

/// Builds the setup: the true robot from the case seed (the same robot for every setup), its
/// calibration, the programmed circle.
[[nodiscard]] SetupCell build_setup_cell(const CaseConfig& config, bool sensor_mounted);

enum class RunKind { kUnloaded, kUncompensated, kCompensated };

struct RunSpec {
  RunKind kind = RunKind::kUnloaded;
  Strategy strategy = Strategy::kOffline;  ///< the compensated run's strategy
  LinkKind link = LinkKind::kProgram;      ///< how every run of the setup reaches the controller
  double load_n = 0.0;
  double speed_m_s = 0.01;
  int laps_cw = 3;
  int laps_ccw = 3;
  std::uint64_t seed = 1;  ///< this run's own seed (see run_seed)
};

struct RunOutput {
  TrackerTrace trace;  ///< tracker samples from the start of the laps (t = 0) to the end of the motion
  double simulated_s = 0.0;
  // What deflex's link did (online setups).
  std::uint64_t link_cycles = 0;  ///< controller messages answered
  LinkCounters link_counters;
  double max_command_deviation_rad = 0.0;  ///< largest |command - nominal| of any joint, any cycle
  double max_tcp_correction_m = 0.0;
  double measured_delay_s = 0.0;  ///< the mean of the link's delay measurements over the run
  /// What the controller counted of deflex's stream: RSI's late cycles (its <Delay>), MotoROS2's
  /// increments its safety unit truncated; 0 for the other links.
  std::uint64_t controller_events = 0;
  double controller_peak = 0.0;       ///< FANUC: the stream's peak jerk over the controller's jerk limit (0 otherwise)
  cell::CoupledTickCounters coupled;  ///< what the loaded ticks' coupled solves of the arm and the bar did
};

/// SplitMix64's finaliser: a well-mixed 64-bit value from any seed (the cell's seeds are derived by it).
[[nodiscard]] std::uint64_t splitmix(std::uint64_t x);

/// A run's seed from the case seed and the run's identity, so results do not depend on the order
/// or the thread that runs them.
[[nodiscard]] std::uint64_t run_seed(std::uint64_t case_seed, bool sensor_mounted, RunKind kind, Strategy strategy,
                                     double load_n, double speed_m_s, std::uint64_t extra = 0);

/// The protocol's program for a closed list of configurations around the circle (last = first):
/// hold at the start for `settle_s`, `laps_cw` clockwise laps, then `laps_ccw` anticlockwise ones,
/// at the TCP speed. The circle poses give the distances. `ramp_points` > 0: the speed ramps over that
/// many points into and out of every rest (start, turn, end), segment i of a ramp at sin(pi/2 i /
/// (ramp_points + 1)) of the speed (what a controller that checks the jerk of the stream needs: FANUC's).
[[nodiscard]] JointTrajectory protocol_program(const std::vector<Pose>& circle_poses, const std::vector<JointVector>& q,
                                               double speed_m_s, double settle_s, int laps_cw, int laps_ccw,
                                               const RobotModel& model, int ramp_points = 0);

/// The points of the FANUC setups' speed ramps (12: full speed 54 deg of the circle after a rest, so
/// the program's jerk at 200 mm/s stays within what J519's check leaves it).
inline constexpr int kFanucRampPoints = 12;

/// The compensated configurations of the offline strategy (paper, Figure 2) for a load, closed, from
/// the identified model and the LDBB force model (nominal pivot, set-point force).
[[nodiscard]] std::vector<JointVector> offline_configurations(const CaseConfig& config, const SetupCell& setup,
                                                              double load_n);

/// How well a setup's identified model predicts the true arm on the circle (a diagnostic of the
/// calibration, for the report; no strategy sees it): at every programmed point, the static TCP
/// deflection under the LDBB's nominal force (set-point along the nominal bar) from the identified
/// lumped model against the true robot's (all its elastic effects, from the unloaded pose, lost
/// motion included). Returns the mean over the points of |model - true| / |true|, and the mean of
/// |model| / |true| in `scale`.
[[nodiscard]] double identified_model_error(const CaseConfig& config, const SetupCell& setup, double load_n,
                                            double* scale = nullptr);

/// Where the arm stands before a calibration and seeds the circle's IK (rad): a fixed configuration
/// in front of the robot for a 6-joint arm, zeros for any other.
[[nodiscard]] JointVector standing_pose(const RobotModel& model);

/// What a user's sensor file would hold for the cell's sensor: its calibration sheet (decoupling,
/// payload, the mount as measured), deflex's conditioning settings from the case, and no bias yet.
[[nodiscard]] deflex::SensorConfig sensor_config_from_sheet(const CaseConfig& config,
                                                            const cell::SensorCalibration& sheet);

/// The spread a user's tare accepts for the cell's sensor (N): three times its noise and a little.
[[nodiscard]] double tare_limit_n(const cell::SensorConfig& sensor);

/// The user's tare before a run (deflex's WrenchTare, as `deflex online --tare` takes it): the arm
/// stands unloaded at `q_tare` (rad) for half a second while the sensor is read; the mean of the
/// decoupled readings less the payload's weight as the sheet predicts it there (nominal orientation)
/// becomes the file's bias. Returns the configuration with that bias. Throws Error when the tare is
/// refused (the arm did not stand still: a broken setup). `max_std_n`: the tare's limit on the
/// window's spread (N), set from the sensor's noise as a user would.
[[nodiscard]] deflex::SensorConfig tare_sensor(deflex::SensorConfig sheet_config, cell::ForceSensorDaq& sensor,
                                               const cell::TrueRobot& robot, const JointVector& q_tare,
                                               double max_std_n);

/// deflex's online bounds and rates from the case, at the controller's cycle `period_s`: what a user
/// would give `deflex online` (the force watchdog at least two cycles).
[[nodiscard]] deflex::OnlineConfig online_config_from_case(const CaseConfig& config, double period_s);

/// Lets deflex answer whatever has reached it by now, counting the controller messages it answered;
/// throws Error, naming `what` ("run", "machining run"), when its session ended with an error.
void poll_deflex_session(runtime::Session& session, std::uint64_t& link_cycles, const char* what);

/// Runs one protocol run. Throws Error when the run cannot be done (an online strategy without the
/// sensor, a refused start or a controller that timed out: a broken setup, never a result).
[[nodiscard]] RunOutput simulate_run(const CaseConfig& config, const SetupCell& setup, const RunSpec& spec);

}  // namespace deflex::study
