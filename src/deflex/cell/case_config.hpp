// The case-study file: every parameter of the simulated cell and of the paper's protocol, in one
// place (data/cases/paper.yaml is the paper's case; docs/error-budget.md explains each size).
// SI units inside; the YAML file uses mm, deg, um, N, s as its keys say.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "deflex/model/types.hpp"

namespace deflex::cell {

/// One strategy setup of the protocol (a row group of the paper's tables).
enum class Strategy {
  kOffline,        ///< paper Fig. 2: compensated program from the LDBB force model
  kOnline,         ///< paper Fig. 3: force sensor, compensation every cycle
  kHybrid,         ///< offline feed-forward + online correction of measured minus modelled force
  kOnlineLatency,  ///< online, with the wrench and pose predicted one delay ahead
};
[[nodiscard]] const char* to_string(Strategy s);

struct SetupConfig {
  std::string name;  ///< "offline", "online", ... (JSON "setup")
  Strategy strategy = Strategy::kOffline;
  bool sensor_mounted = false;
  std::vector<double> loads_n;
  std::vector<double> paper_uc_mm;                ///< paper's UC per load (empty: none)
  std::vector<std::array<double, 3>> paper_c_mm;  ///< paper's C1..C3 per load
};

/// The true robot: what the compensators never see.
struct TrueRobotConfig {
  double stiffness_scale = 1.0;               ///< true K = built-in K * scale * seeded factor per joint
  double stiffness_spread = 0.0;              ///< 1-sigma of the seeded log-factor per joint
  double coupling_23 = 0.0;                   ///< off-diagonal K23/sqrt(K22 K33) (coupled joint stiffness)
  double forearm_ei_nm2 = 0.0;                ///< forearm bending stiffness EI (0: rigid link)
  double forearm_length_m = 1.2125;           ///< cantilever length, elbow to wrist centre
  std::vector<double> lost_motion_rad;        ///< half-width of each joint's lost motion band
  std::vector<double> lost_motion_torque_nm;  ///< joint torque that moves a joint across its band
  /// Static joint torque from gravity at the operating space (Nm): it preloads the lost motion, so a
  /// joint that gravity holds to one side (2, 3) never crosses its band under the process load.
  std::vector<double> gravity_torque_nm;
  double dh_length_sigma_m = 0.0;   ///< kinematic errors: 1-sigma of a, d
  double dh_angle_sigma_rad = 0.0;  ///< 1-sigma of alpha, offset
  /// Torque-dependent gear stiffness (hardening of the reducers), per joint: the tangent compliance
  /// at total joint torque x is C (1 + s exp(-|x|/tau_h)), i.e. (1+s) times softer near zero torque
  /// than at large torque (C: the true compliance above). Empty or zero s: linear gears.
  std::vector<double> hardening_softening;  ///< s per joint
  std::vector<double> hardening_torque_nm;  ///< tau_h per joint
};

/// Run-to-run drift and path repeatability of the true robot: every run (the unloaded reference and
/// each loaded run are different runs at different times) is displaced by its own small rigid
/// motion plus a slow random wander within the run. Unknown to every strategy.
struct DriftConfig {
  double offset_m = 0.0;       ///< 1-sigma per axis of the run's rigid offset (thermal drift)
  double rotation_rad = 0.0;   ///< 1-sigma per axis of the run's small rotation about the base origin
  double wander_m = 0.0;       ///< stationary 1-sigma per axis of the wander within a run
  double wander_time_s = 1.0;  ///< correlation time of the wander (Ornstein-Uhlenbeck process)
};

struct ToolConfig {
  double ee_length_m = 0.25;  ///< mounting face (flange or sensor top) to TCP ball centre
  double ee_mass_kg = 0.0;
  Vector3 ee_cog_m = Vector3::Zero();  ///< in the mounting-face frame
};

struct SensorConfig {
  double height_m = 0.06;                 ///< flange to sensor top (adds overhang)
  double lateral_compliance_m_per_n = 0;  ///< sensor + adapter plates, x/y of the sensor frame
  double axial_compliance_m_per_n = 0;
  double rotational_compliance_rad_per_nm = 0;
  double crosstalk = 0.0;                       ///< largest off-diagonal of the true crosstalk matrix
  double crosstalk_calibration_residual = 0.0;  ///< left after the decoupling matrix is applied
  double noise_n = 0.0;                         ///< 1-sigma per channel, per sample
  Vector3 bias_n = Vector3::Zero();
  double rate_hz = 1000.0;
  double gravity_mass_error = 0.0;  ///< relative error of the identified EE mass
  /// Calibration-sheet errors the user never learns: the true sensitivity of each channel differs
  /// from the sheet's by a seeded relative error (1-sigma), and the sensor is mounted turned by this
  /// angle about the tool axis (flange z) from the frame the user assumes.
  double sensitivity_error = 0.0;
  double misalignment_rad = 0.0;
};

struct LdbbConfig {
  double bar_length_m = 0.15;
  double inclination_rad = 0.0;  ///< phi, bar to the XY plane (Figure 4)
  bool push = true;
  double time_constant_s = 0.3;  ///< pneumatic first-order response
  double ripple = 0.0;           ///< relative amplitude
  double ripple_hz = 2.0;
  double noise = 0.0;                       ///< relative 1-sigma per servo cycle
  double force_bias = 0.0;                  ///< true force = set-point * (1 + bias): unknown to the force model
  Vector3 pivot_error_m = Vector3::Zero();  ///< true pivot minus the force model's pivot
  double ball_friction = 0.0;               ///< friction coefficient of the ball joints
  double ball_radius_m = 0.0127;
  double settle_s = 2.0;  ///< force build-up before the laps start
};

struct TrackerConfig {
  double noise_m = 0.0;  ///< 1-sigma per axis per sample
  double rate_hz = 1000.0;
};

struct ControllerConfig {
  double servo_period_s = 0.004;
  int program_points = 81;    ///< points of the programmed circle (paper: 81)
  double egm_delay_s = 0.0;   ///< corrections reach the servo this much later
  double egm_filter_s = 0.0;  ///< controller's low-pass on corrections (time constant)
};

struct OnlineConfig {
  double cycle_s = 0.1;          ///< compensation cycle (paper: about 100 ms)
  double compute_delay_s = 0.0;  ///< from the force sample to the correction leaving the PC
  double lowpass_hz = 25.0;
  double threshold_low_n = 0.0;
  double threshold_high_n = 5000.0;
  double max_correction_rad = 0.01;
};

struct CalibrationConfig {
  int poses = 12;           ///< around the circle
  double load_n = 500.0;    ///< in +-x, +-y, +-z of the base
  double load_error = 0.0;  ///< relative 1-sigma of the applied calibration load
  int samples = 1000;       ///< tracker samples averaged per measurement
};

struct CircleConfig {
  Vector3 center_m = Vector3::Zero();
  Pose tcp_orientation = Pose::Identity();  ///< rotation part used for every point
};

struct BudgetConfig {
  double speed_m_s = 0.05;
  int load_index = 2;
  int laps_each_way = 1;
};

struct CaseConfig {
  std::string name;
  std::string source = "<memory>";
  std::string robot_file;  ///< empty: the built-in IRB6700
  std::uint64_t seed = 1;
  CircleConfig circle;
  int laps_cw = 3;
  int laps_ccw = 3;
  std::vector<double> speeds_m_s;
  std::vector<double> sweep_speeds_m_s;
  double sweep_load_n = 650.0;
  std::vector<SetupConfig> setups;
  TrueRobotConfig robot;
  ToolConfig tool;
  SensorConfig sensor;
  LdbbConfig ldbb;
  TrackerConfig tracker;
  ControllerConfig controller;
  OnlineConfig online;
  CalibrationConfig calibration;
  DriftConfig drift;
  BudgetConfig budget;
  /// Give the compensators the true joint stiffness instead of an identified one (tests only:
  /// the model-consistent cell).
  bool exact_model = false;

  /// Circle radius, from the LDBB geometry: r = L cos(phi).
  [[nodiscard]] double radius_m() const;
  /// The nominal pivot (the force model's), below the circle centre by L sin(phi).
  [[nodiscard]] Vector3 pivot_m() const;
};

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
  kLdbbForceError,  ///< magnitude bias, pivot error, ball friction
  kLdbbRipple,      ///< ripple and noise of the pneumatic force
  kSensorErrors,    ///< crosstalk, noise, bias, gravity-compensation error
  kTrackerNoise,
  kCalibrationNoise,   ///< load error of the calibration experiment
  kLatency,            ///< online cycle, compute delay, EGM delay and filter
  kPathDrift,          ///< run-to-run drift and path repeatability
  kGearHardening,      ///< torque-dependent gear stiffness
  kSensorCalibration,  ///< sensitivity error and mounting misalignment unknown to the user
};
inline constexpr std::array<Effect, 15> kAllEffects = {
    Effect::kStiffnessMismatch, Effect::kJointCoupling,   Effect::kLinkBending,      Effect::kSensorCompliance,
    Effect::kLostMotion,        Effect::kKinematicErrors, Effect::kLdbbForceError,   Effect::kLdbbRipple,
    Effect::kSensorErrors,      Effect::kTrackerNoise,    Effect::kCalibrationNoise, Effect::kLatency,
    Effect::kPathDrift,         Effect::kGearHardening,   Effect::kSensorCalibration};
[[nodiscard]] const char* to_string(Effect e);
/// Short description of the effect's size in `config` (for the error budget table).
[[nodiscard]] std::string effect_size(const CaseConfig& config, Effect e);
/// A copy of `config` with the effect switched off.
[[nodiscard]] CaseConfig without_effect(const CaseConfig& config, Effect e);
/// A copy with every extra effect off, the exact stiffness given to the compensators and no noise,
/// except the tracker noise when `keep_tracker_noise`.
[[nodiscard]] CaseConfig model_consistent(const CaseConfig& config, bool keep_tracker_noise = true);

}  // namespace deflex::cell
