// The case-study file: the paper's protocol (circle, laps, speeds, setups and loads), deflex's own
// settings for its online setups, the calibration procedure, the error budget, and the simulated
// cell's hardware (cell/cell_config.hpp), in one place (data/cases/paper.yaml is the paper's case;
// docs/error-budget.md explains each size). SI units inside; the YAML file uses mm, deg, um, N, s as
// its keys say.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "deflex/cell/cell_config.hpp"
#include "deflex/cell/coupled_tick.hpp"
#include "deflex/model/types.hpp"

namespace deflex::study {

/// The compensation strategy of a setup.
enum class Strategy {
  kOffline,     ///< paper Fig. 2: compensated program from the LDBB force model
  kOnline,      ///< paper Fig. 3: force sensor, compensation every controller cycle
  kHybrid,      ///< offline program + online correction of measured minus modelled force
  kPredictive,  ///< online, with the wrench predicted where the command will be executed
};
[[nodiscard]] const char* to_string(Strategy s);

/// How deflex reaches the controller in a setup.
enum class LinkKind {
  kProgram,   ///< the controller runs a (compensated) robot program of its own: no link
  kEgmJoint,  ///< ABB EGM position guidance: deflex streams the program (egm_joint_link.hpp)
  kEgmPath,   ///< ABB EGM path correction: the controller runs its program, deflex sends offsets
  /// ROS-Industrial simple message over TCP: deflex streams joint points to the robot program's
  /// streaming server (the paper's own kind of link, ~100 ms; simple_message_link.hpp)
  kSimpleMessage,
  // The values above seed the runs of their setups (run_seed): a further link is added at the end.
  kRsi,         ///< KUKA RSI axis correction: the controller runs its KRL program, deflex answers offsets
  kFanucJ519,   ///< FANUC Stream Motion: deflex streams the program, one command a status
  kMotoros2Rt,  ///< Yaskawa MotoROS2 real-time: deflex streams the program as joint increments
  kUrRtde,      ///< Universal Robots RTDE: deflex streams the program into the registers servoj reads
};
/// Every link a setup may name, in the order the case file's error lists them.
inline constexpr std::array<LinkKind, 8> kAllLinks = {
    LinkKind::kProgram,       LinkKind::kEgmJoint,  LinkKind::kEgmPath,    LinkKind::kRsi,
    LinkKind::kSimpleMessage, LinkKind::kFanucJ519, LinkKind::kMotoros2Rt, LinkKind::kUrRtde};
[[nodiscard]] const char* to_string(LinkKind k);
/// Whether deflex streams the program over the link (the controller then runs none of its own).
[[nodiscard]] bool streams_program(LinkKind k);
struct CaseConfig;
/// The controller's cycle deflex runs a link at in the study (s): EGM's and simple message's from the
/// case file, every other link's the runtime's default (0 for kProgram).
[[nodiscard]] double link_period_s(const CaseConfig& config, LinkKind link);

/// One strategy setup of the protocol (a row group of the paper's tables).
struct SetupConfig {
  std::string name;  ///< "offline", "online", ... (JSON "setup")
  Strategy strategy = Strategy::kOffline;
  LinkKind link = LinkKind::kProgram;
  bool sensor_mounted = false;
  std::vector<double> loads_n;
  /// How many of the study's seeds the setup runs (its first ones); 0: every seed. A setup that only
  /// shows how a controller's timing costs compensation needs no spread over seeds, and its own
  /// unloaded and uncompensated runs per seed are most of its time (case file "seeds", 1..1000).
  int seeds = 0;
  std::vector<double> paper_uc_mm;                ///< paper's UC per load (empty: none)
  std::vector<std::array<double, 3>> paper_c_mm;  ///< paper's C1..C3 per load
};

/// What a user would give `deflex online` for the online setups (the same settings, the same code).
struct OnlineSettings {
  double lowpass_hz = 25.0;           ///< the paper's 25 Hz
  double dead_band_n = 0.0;           ///< the paper's lower threshold
  double fault_threshold_n = 5000.0;  ///< the paper's upper threshold
  double max_joint_correction_rad = 0.01;
  double max_tcp_correction_m = 0.005;
  double max_rate_rad_s = 0.05;
  double max_tcp_rate_m_s = 0.005;  ///< the correction's TCP rate bound (deflex online --max-tcp-rate-mm-s)
  double watchdog_s = 0.05;
  double ramp_in_s = 1.0;
  double stream_period_s = 0.1;  ///< simple message: a point every this long (the paper's ~100 ms)
  int stream_buffer_depth = 2;   ///< simple message: points kept queued on the controller
};

/// The quasi-static calibration while moving (the paper's, after Theissen et al.): arcs in the
/// operating space (not the test circle), each run unloaded and then loaded by the LDBB, the deflection
/// measured by the tracker time-synchronously between the two passes.
struct CalibrationConfig {
  int arcs = 6;             ///< calibration arcs (each at its own height, radius and bar direction)
  double arc_rad = 2.6;     ///< the angle each arc sweeps (150 deg)
  double speed_m_s = 0.02;  ///< TCP speed along the arcs (quasi-static)
  double load_n = 500.0;    ///< LDBB set-point during the loaded passes
  int points_per_arc = 15;  ///< measurements along each arc
  double window_s = 0.2;    ///< tracker samples averaged per measurement (time-synchronous)
  /// Where the calibration's force comes from: the LDBB's report (its set-point along the nominal
  /// bar, as the paper's LDBB-based procedure takes it; false) or, with the sensor mounted, the
  /// sensor's conditioned reading (true).
  bool force_from_sensor = false;
};

struct CircleConfig {
  Vector3 center_m = Vector3::Zero();
  Pose tcp_orientation = Pose::Identity();  ///< rotation part used for every point
  int points = 81;                          ///< configurations of the programmed circle (paper: 81)
};

/// The error budget runs at one speed and load of the tables, on the study's first seed, with the
/// protocol's laps: its "every effect" figure is the table's own run.
struct BudgetConfig {
  double speed_m_s = 0.05;
  int load_index = 2;  ///< into the loads of each setup the budget runs (budget_setups())
};

struct CaseConfig {
  std::string name;
  std::string source = "<memory>";
  std::uint64_t seed = 1;
  /// Seeds the study runs (seed, seed + 1, ...): each its own cell (true robot, sensor, calibration)
  /// and its own runs; the tables give the mean and spread over them.
  int seeds = 1;
  CircleConfig circle;
  int laps_cw = 3;
  int laps_ccw = 3;
  std::vector<double> speeds_m_s;
  std::vector<double> sweep_speeds_m_s;
  double sweep_load_n = 650.0;
  std::vector<SetupConfig> setups;
  cell::CellConfig cell;  ///< the hardware
  OnlineSettings online;
  CalibrationConfig calibration;
  BudgetConfig budget;
  /// Give the compensators the true joint stiffness instead of an identified one (tests only:
  /// the model-consistent cell).
  bool exact_model = false;
  /// How the cell's loaded ticks solve the arm and the bar together (the study's fast computation
  /// loosens the tolerance; the exact one keeps these defaults).
  cell::CoupledTickOptions coupled_tick;

  /// Circle radius, from the LDBB geometry: r = L cos(phi).
  [[nodiscard]] double radius_m() const;
  /// The nominal pivot (the force model's), below the circle centre by L sin(phi).
  [[nodiscard]] Vector3 pivot_m() const;
};

/// The setups the error budget runs (indexes into config.setups): the first offline setup and the
/// first online one over EGM position guidance (the paper's two).
[[nodiscard]] std::vector<std::size_t> budget_setups(const CaseConfig& config);

/// Loads a case file; every error names the file, line and field. Throws ModelError.
CaseConfig load_case(const std::string& path);
CaseConfig load_case_text(const std::string& text, const std::string& source);
/// The paper's case (data/cases/paper.yaml, compiled in).
CaseConfig paper_case();
const std::string& paper_case_yaml();

/// Every effect of the cell that the error budget switches off one at a time.
enum class Effect {
  kStiffnessMismatch,  ///< per-joint spread of the true stiffness around the scaled built-in one
  kJointCoupling,
  kLinkBending,
  kSensorCompliance,
  kLostMotion,
  kKinematicErrors,
  kLdbbForceError,  ///< the bar's pivot error and ball friction (the force model's geometry)
  kLdbbRipple,      ///< ripple and noise of the pneumatic force
  kSensorErrors,    ///< crosstalk, noise, bias, gravity-compensation error
  kTrackerNoise,
  kLdbbSealFriction,   ///< the cylinder seal's friction, in the calibration and the tests alike
  kLatency,            ///< the controller's EGM dead time and filter, network and DAQ latency
  kPathDrift,          ///< run-to-run drift and path repeatability
  kGearHardening,      ///< torque-dependent gear stiffness
  kSensorCalibration,  ///< sensitivity error and mounting misalignment unknown to the user
  kBaseCompliance,     ///< foundation and base tilt under the process moment
  kMotionStiffness,    ///< stiffness that depends on the joints' speed and direction of motion
  kServo,              ///< the drives' following error and their yielding to a changing torque
  kSensorDrift,        ///< the force sensor's zero drifting after the tare
  kThermalLoadDrift,   ///< the extra warming of a loaded run
  kLdbbStickSlip,      ///< the cylinder seal's stick-slip
  kSensorMoment,       ///< the force sensor's response to bending moments (a 3-component sensor cannot remove it)
  kTrackerClock,       ///< the tracker's own clock: its trigger jitter and rate error
};
inline constexpr std::array<Effect, 23> kAllEffects = {
    Effect::kStiffnessMismatch, Effect::kJointCoupling,   Effect::kLinkBending,       Effect::kSensorCompliance,
    Effect::kLostMotion,        Effect::kKinematicErrors, Effect::kLdbbForceError,    Effect::kLdbbRipple,
    Effect::kSensorErrors,      Effect::kTrackerNoise,    Effect::kLdbbSealFriction,  Effect::kLatency,
    Effect::kPathDrift,         Effect::kGearHardening,   Effect::kSensorCalibration, Effect::kBaseCompliance,
    Effect::kMotionStiffness,   Effect::kServo,           Effect::kSensorDrift,       Effect::kThermalLoadDrift,
    Effect::kLdbbStickSlip,     Effect::kSensorMoment,    Effect::kTrackerClock};
[[nodiscard]] const char* to_string(Effect e);
/// Short description of the effect's size in `config` (for the error budget table).
[[nodiscard]] std::string effect_size(const CaseConfig& config, Effect e);
/// A copy of `config` with the effect switched off.
[[nodiscard]] CaseConfig without_effect(const CaseConfig& config, Effect e);
/// A copy with every extra effect off, the exact stiffness given to the compensators and no noise,
/// except the tracker noise when `keep_tracker_noise`.
[[nodiscard]] CaseConfig model_consistent(const CaseConfig& config, bool keep_tracker_noise = true);

}  // namespace deflex::study
