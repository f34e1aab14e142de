// The simulated cell's hardware, as sized by a case file (data/cases/paper.yaml; every size is
// explained in docs/error-budget.md): the true robot, the end effector, the force sensor and its DAQ,
// the Loaded Double Ball Bar, the laser tracker, the robot controller and its EGM interface, and the
// drift between runs. None of it is ever shown to a compensation strategy: the strategies meet the
// cell only through the controller links, as they would meet a real one.
// SI units inside; the case file uses mm, deg, um, N, s as its keys say.
#pragma once

#include <string>
#include <vector>

#include "deflex/model/types.hpp"

namespace deflex::cell {

/// The true robot: what the compensators never see.
struct TrueRobotConfig {
  double stiffness_scale = 1.0;   ///< true K = built-in K * scale * seeded factor per joint
  double stiffness_spread = 0.0;  ///< 1-sigma of the seeded log-factor per joint
  /// Per joint, the band its true stiffness is drawn in (Nm/rad; the factor is drawn again until the
  /// joint lands inside): the identified stiffness of arms of this class. Empty: no band.
  std::vector<double> stiffness_band_min_nm_per_rad, stiffness_band_max_nm_per_rad;
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
  std::vector<double> hardening_softening;       ///< s per joint
  std::vector<double> hardening_torque_nm;       ///< tau_h per joint
  double upper_arm_ei_nm2 = 0.0;                 ///< upper arm bending stiffness EI, joint 2 to joint 3 (0: rigid)
  double base_tilt_compliance_rad_per_nm = 0.0;  ///< foundation and base: tilt per Nm of moment about the base
  /// Stiffness that depends on the joint's motion: the process deflection of a joint is scaled by
  ///   (1 - speed_stiffening tanh(|v|/v_ref)) (1 + direction_asymmetry tanh(v/v_ref) sign(tau)),
  /// v the joint's speed: moving joints appear stiffer (the paper's hypothesis), and a joint yields
  /// more when it moves with its process torque than against it.
  double speed_stiffening = 0.0;
  double direction_asymmetry = 0.0;
  double speed_ref_rad_s = 0.01;
  /// The drives' position loops: the motor lags its command by servo_following_s times its speed,
  /// and yields to a changing process torque by servo_compliance_fraction of the joint's compliance
  /// until the integral action (time constant servo_integral_s) has taken the torque over.
  double servo_following_s = 0.0;
  double servo_compliance_fraction = 0.0;
  double servo_integral_s = 0.1;
  /// The deflected configuration's fixed point stops once a step moves no joint by more than this
  /// (rad). The map contracts by about 1e-3 a step (compliance x force x reach), so the error left is
  /// about a thousandth of it; the kinematics are those of the configuration a step before, within it.
  double fixed_point_step_rad = 1e-10;
  /// When > 0 (the study's fast computation), a first step below this (rad) ends the fixed point at
  /// once: its error left is the contraction times the step (~1.3e-3 x 1e-5 rad, ~30 nm at the TCP),
  /// and the end poses move on to it along the Jacobian already taken (error ~ reach x step^2, below a
  /// nanometre) instead of a second forward kinematics. 0: off (the exact computation).
  double first_order_step_rad = 0.0;
};

/// Run-to-run drift and path repeatability of the true robot: every run (the unloaded reference and
/// each loaded run are different runs at different times) is displaced by its own small rigid
/// motion plus a slow random wander within the run.
struct DriftConfig {
  double offset_m = 0.0;          ///< 1-sigma per axis of the run's rigid offset (thermal drift)
  double offset_time_s = 1200.0;  ///< its correlation time: runs this far apart drift nearly independently
  double rotation_rad = 0.0;      ///< 1-sigma per axis of the run's small rotation about the base origin
  double wander_m = 0.0;          ///< stationary 1-sigma per axis of the wander within a run
  double wander_time_s = 1.0;     ///< correlation time of the wander (Ornstein-Uhlenbeck process)
  /// The motors warm more under load: a loaded run's own extra rigid offset, 1-sigma per axis at the
  /// reference load, growing with the square of the load (heat goes with the current squared).
  double load_offset_m = 0.0;
  double load_reference_n = 650.0;
};

struct ToolConfig {
  double ee_length_m = 0.25;  ///< mounting face (flange or sensor top) to TCP ball centre
  double ee_mass_kg = 0.0;
  Vector3 ee_cog_m = Vector3::Zero();  ///< in the mounting-face frame
};

/// The force sensor and its DAQ (the sensor, when mounted, also sits between flange and end effector
/// as an elastic element).
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
  double gravity_mass_error = 0.0;  ///< relative error of the end effector's mass on the calibration sheet
  /// Calibration-sheet errors the user never learns: the true sensitivity of each channel differs
  /// from the sheet's by a seeded relative error (1-sigma), and the sensor is mounted turned by this
  /// angle about the tool axis (flange z) from the frame the user assumes.
  double sensitivity_error = 0.0;
  double misalignment_rad = 0.0;
  double daq_latency_s = 0.0005;  ///< from the sample to deflex's force port (DAQ program + network)
  /// The zero drifts after it was tared at the start of a run (temperature, creep): a linear drift
  /// whose change over 10 minutes is zero_drift_n (1-sigma per channel, drawn per run).
  double zero_drift_n = 0.0;
  /// A 3-component sensor's force channels also answer to the bending and torsional moments about
  /// its point of origin (the process force's lever to the TCP), which it cannot measure and so
  /// cannot decouple: each force channel reads up to moment_crosstalk x nominal_lateral_force_n per
  /// nominal_moment_nm of each moment (drawn once per physical sensor), and the response grows by
  /// moment_overload_growth per nominal moment beyond the nominal (the spring body leaves the range
  /// it was calibrated in).
  double moment_crosstalk = 0.0;
  /// What the user's sheet gets wrong about the mounting: the end effector's centre of gravity (from
  /// CAD, 1-sigma per axis) and the sensor's height (measured by hand, 1-sigma). The sheet gives no
  /// bias: the user tares with the arm still (deflex's tare, study/simulated_run.cpp).
  double sheet_cog_error_m = 0.0;
  double sheet_height_error_m = 0.0;
  double nominal_moment_nm = 50.0;
  double nominal_lateral_force_n = 1000.0;
  double moment_overload_growth = 0.0;
  /// Draw the per-sample noise from the faster generator (noise_engine.hpp): the same distribution,
  /// another stream. The sensor's own draws and the run's zero drift stay on the reference one.
  bool fast_noise = false;
};

struct LdbbConfig {
  double bar_length_m = 0.15;
  double inclination_rad = 0.0;  ///< phi, bar to the XY plane (Figure 4)
  bool push = true;
  double time_constant_s = 0.3;  ///< pneumatic first-order response
  double ripple = 0.0;           ///< relative amplitude
  double ripple_hz = 2.0;
  double noise = 0.0;  ///< relative 1-sigma, correlated over time_constant_s (the chamber's response)
  /// The cylinder's seal friction (one physical model for the calibration and the tests): the seal
  /// carries up to seal_friction x the pneumatic force against the piston's last motion: less force
  /// reaches the TCP while the piston last moved with the load (as when the arm yields to it), more
  /// while it last moved against it (as when the path shortens a pushing bar). Its level differs from
  /// run to run (seal_friction_spread, 1-sigma, drawn when the bar is pressurised), and it changes
  /// sign only after the piston has slid back by the seal's pre-sliding travel. The bar reports its
  /// set-point (pressure x area): the friction is what it does not know.
  double seal_friction = 0.0;
  double seal_friction_spread = 0.0;
  double seal_presliding_m = 0.0001;
  /// The cylinder's seal friction sticks and slips: a sawtooth of this relative amplitude, one tooth
  /// per stick_slip_travel_m of the piston's travel in the cylinder (either way).
  double stick_slip = 0.0;
  double stick_slip_travel_m = 0.0005;
  Vector3 pivot_error_m = Vector3::Zero();  ///< true pivot minus the force model's pivot
  double ball_friction = 0.0;               ///< friction coefficient of the ball joints
  double ball_radius_m = 0.0127;
  double settle_s = 2.0;  ///< force build-up before the laps start
};

struct TrackerConfig {
  double noise_m = 0.0;  ///< 1-sigma per axis per sample
  double rate_hz = 1000.0;
  /// The tracker runs on its own clock, started by the robot program's trigger: the start lands
  /// this late or early (1-sigma per run), and the clock runs fast or slow by this fraction (1-sigma
  /// per run). Its time stamps are its own clock's.
  double trigger_jitter_s = 0.0;
  double clock_rate_error = 0.0;
  /// Draw the per-sample noise from the faster generator (noise_engine.hpp): the same distribution,
  /// another stream. The clock's draws of a run stay on the reference one.
  bool fast_noise = false;
};

/// The robot controller: its servo, and how it treats what an external sensor sends over EGM.
struct ControllerConfig {
  double servo_period_s = 0.004;
  double network_latency_s = 0.0002;  ///< one way, between the controller and the cell PC
  // Position guidance (EGMActJoint/EGMRunJoint): the controller follows the sensor's absolute target.
  double egm_period_s = 0.004;           ///< an EgmRobot message every 4 ms (IRC5)
  double egm_dead_time_s = 0.048;        ///< from a reference to the arm following it
  double egm_lowpass_hz = 20.0;          ///< the controller's filter on the references (\LpFilter)
  double egm_position_gain_per_s = 5.0;  ///< position gain k: speed = k (target - position) + speed reference
  double egm_comm_timeout_s = 1.0;       ///< no answer for this long: EGM stops, the arm holds (\CommTimeout)
  // Path correction (EGMActMove + EGMMoveL/EGMMoveC): the controller runs its program and applies
  // the sensor's absolute offset.
  double path_corr_period_s = 0.048;     ///< EGMActMove \SampleRate
  double path_corr_dead_time_s = 0.048;  ///< from an offset read to the arm moving by it
  double path_corr_filter_s = 0.01;      ///< first-order smoothing of the applied offset
  std::string path_corr_frame = "tool";  ///< the frame EGMActMove is given: tool, flange or path
};

/// Everything physical in the cell.
struct CellConfig {
  std::string robot_file;  ///< the robot's nominal description; empty: the built-in IRB 6700
  TrueRobotConfig robot;
  ToolConfig tool;
  SensorConfig sensor;
  LdbbConfig ldbb;
  TrackerConfig tracker;
  ControllerConfig controller;
  DriftConfig drift;
};

}  // namespace deflex::cell
