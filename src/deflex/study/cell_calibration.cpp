// The compliance calibration experiment on the simulated cell (see cell_calibration.hpp).
#include "deflex/study/detail/cell_calibration.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>

#include "deflex/cell/force_sensor.hpp"
#include "deflex/cell/laser_tracker.hpp"
#include "deflex/cell/ldbb_device.hpp"
#include "deflex/cell/path_drift.hpp"
#include "deflex/identify/calibration_planner.hpp"
#include "deflex/online/force_pipeline.hpp"
#include "deflex/paths/circle_path.hpp"
#include "deflex/paths/joint_trajectory.hpp"
#include "deflex/paths/path_ik.hpp"
#include "deflex/study/detail/cell_arm.hpp"
#include "deflex/study/detail/simulated_run.hpp"
#include "deflex/text/errors.hpp"

namespace deflex::study {
namespace {

// One calibration arc: the LDBB's bar inclination (which sets the arc's radius, r = L cos phi, and
// the force's vertical part), the arc's height above the test circle, push or pull, and where it
// starts. Six of them span the operating space and the force directions, none on the test circle
// (each is at least 30 mm above or below it); more repeat the pattern with turned starts.
struct Arc {
  double phi_rad;
  double dz_m;
  bool push;
  double start_rad;
};

Arc arc_of(int k) {
  static const Arc kArcs[6] = {{deg_to_rad(15), 0.05, true, 0.0},   {deg_to_rad(15), -0.05, false, 2.1},
                               {deg_to_rad(50), 0.05, false, 4.2},  {deg_to_rad(50), -0.05, true, 1.0},
                               {deg_to_rad(-30), -0.03, true, 3.1}, {deg_to_rad(-30), 0.03, false, 5.2}};
  Arc a = kArcs[k % 6];
  const int round = k / 6;  // the round of six arcs
  a.start_rad += 0.37 * round;
  return a;
}

struct Pass {
  TrackerTrace trace;
  std::vector<double> force_t;      // times of the conditioned force samples (sensor mounted)
  std::vector<Vector3> force_base;  // the conditioned process force, base frame at the WAP
};

// What every arc of a setup's calibration shares: the case, the arm and deflex's model of it, today's
// bar, the force sensor and its sheet, and the arm's state, which carries on from pass to pass.
struct CalibrationRig {
  CalibrationRig(const CaseConfig& config, const cell::TrueRobot& arm, std::uint64_t calibration_seed)
      : c(config),
        cc(config.cell),
        cal(config.calibration),
        robot(arm),
        nominal(arm.nominal_model()),
        seed(calibration_seed),
        ldbb_config(config.cell.ldbb),
        force_from_sensor(arm.sensor_mounted() && config.calibration.force_from_sensor),
        sensor(cc.sensor, cc.tool, splitmix(seed ^ 0x5e5ULL), splitmix(c.seed ^ 0x5e5503ULL)),
        // With the sensor's force, the user tares it once, the arm standing unloaded where the session
        // starts; without, the sheet is not used.
        sheet(force_from_sensor ? tare_sensor(sensor_config_from_sheet(c, sensor.calibration()), sensor, arm,
                                              standing_pose(arm.nominal_model()), tare_limit_n(config.cell.sensor))
                                : sensor_config_from_sheet(c, sensor.calibration())),
        sensor_T_wap(sheet.flange_T_sensor.inverse() * nominal.flange_T_wap()),
        ws(arm.true_model()),
        ws_nominal(nominal),
        dt(cc.controller.servo_period_s),
        hold_s(std::max(1.5, 5.0 * cc.ldbb.time_constant_s)),
        seed_q(standing_pose(arm.nominal_model())) {}

  const CaseConfig& c;
  const cell::CellConfig& cc;
  const CalibrationConfig& cal;
  const cell::TrueRobot& robot;
  const RobotModel& nominal;
  std::uint64_t seed;
  // The bar: the same physical model as in the tests (its seal friction drawn afresh for every
  // pressurised pass); the calibration knows only what it reports, its set-point.
  cell::LdbbConfig ldbb_config;
  // Where the calibration's force comes from: the LDBB's report (its set-point along the nominal
  // bar), or the sensor when it is mounted and the case asks for it.
  bool force_from_sensor;
  // The sensor and what its sheet says (the same physical sensor as in the runs).
  cell::ForceSensorDaq sensor;
  deflex::SensorConfig sheet;
  Pose sensor_T_wap;
  Workspace ws;
  Workspace ws_nominal;
  cell::TrueRobotState state;
  bool have_state = false;
  cell::CoupledTickCounters coupled;  // the loaded passes' coupled solves
  double dt;
  double hold_s;
  JointVector seed_q;
};

// One arc of the calibration: its geometry, its program, and what its two passes recorded.
struct CalibrationArc {
  int index;
  Arc arc;
  Vector3 pivot;
  JointTrajectory program;
  Pass passes[2];
  std::optional<cell::PathDrift> unloaded_drift;  // the unloaded pass's drift as it started
};

// Plans the k-th arc: its bar's pivot and its program, from where the arm stands.
CalibrationArc plan_calibration_arc(const CalibrationRig& rig, int k) {
  const CaseConfig& c = rig.c;
  const cell::CellConfig& cc = rig.cc;
  const CalibrationConfig& cal = rig.cal;
  const RobotModel& nominal = rig.nominal;
  const Arc arc = arc_of(k);
  const double radius = cc.ldbb.bar_length_m * std::cos(arc.phi_rad);
  const Vector3 centre = c.circle.center_m + Vector3(0, 0, arc.dz_m);
  const Vector3 pivot = centre - Vector3::UnitZ() * (cc.ldbb.bar_length_m * std::sin(arc.phi_rad));
  // The arc's program: poses every ~2 deg at the calibration speed, after a hold for the force.
  const int n = std::max(8, static_cast<int>(std::ceil(cal.arc_rad / deg_to_rad(2.0)))) + 1;
  std::vector<Pose> poses;
  for (int i = 0; i < n; ++i) {
    const double a = arc.start_rad + cal.arc_rad * i / (n - 1);
    Pose p = c.circle.tcp_orientation;
    p.translation() = centre + radius * Vector3(std::cos(a), std::sin(a), 0.0);
    poses.push_back(p);
  }
  IkRequest first;
  if (nominal.dof() == 6) first.seed = rig.have_state ? rig.state.q_actual : rig.seed_q;
  const JointPath path = solve_path_ik(nominal, poses, first);
  return CalibrationArc{
      k, arc, pivot, trajectory_at_tcp_speed(poses, path.q, cal.speed_m_s, nominal, rig.hold_s), {}, std::nullopt};
}

// Runs one pass over an arc's program (loaded = 0: unloaded, 1: loaded) and records what the tracker
// saw and, loaded with the force from the sensor, the conditioned force.
void run_calibration_pass(CalibrationRig& rig, CalibrationArc& arc, int loaded) {
  const cell::CellConfig& cc = rig.cc;
  const CalibrationConfig& cal = rig.cal;
  const cell::TrueRobot& robot = rig.robot;
  const JointTrajectory& program = arc.program;
  const double hold_s = rig.hold_s;
  const double dt = rig.dt;
  Workspace& ws = rig.ws;
  cell::TrueRobotState& state = rig.state;
  Pass& pass = arc.passes[loaded];
  const std::uint64_t pass_seed =
      splitmix(rig.seed ^ (static_cast<std::uint64_t>(arc.index) * 2 + loaded + 1) * 0x9e37ULL);
  cell::LdbbConfig bar = rig.ldbb_config;
  bar.push = arc.arc.push;
  cell::LdbbDevice device(bar, arc.pivot, loaded ? cal.load_n : 0.0, splitmix(pass_seed ^ 1));
  // The loaded pass follows the unloaded one a pass later: its thermal drift has hardly moved.
  cell::PathDrift drift =
      loaded ? cell::PathDrift(cc.drift, splitmix(pass_seed ^ 2), *arc.unloaded_drift, program.end_time_s(), cal.load_n)
             : cell::PathDrift(cc.drift, splitmix(pass_seed ^ 2));
  if (!loaded) arc.unloaded_drift.emplace(drift);
  cell::LaserTracker tracker(cc.tracker, splitmix(pass_seed ^ 3), hold_s, program.end_time_s(), 0.0);
  ForcePipeline pipeline(rig.sheet, rig.sensor_T_wap);
  JointVector q = program.points().front();
  if (!rig.have_state) {
    state = robot.initial_state(q);
    rig.have_state = true;
  } else {
    // The arm moved here unloaded and stood: only the lost motion remembers.
    const cell::TrueRobotState fresh = robot.initial_state(q);
    const auto lost_motion = state.lost_motion;
    state = fresh;
    state.lost_motion = lost_motion;
  }
  CellArm arm{robot, ws, state, device, drift, cell::CoupledTickSolver(rig.c.coupled_tick)};
  Vector3 p_prev = arm.at_rest(q);
  const auto ticks = static_cast<long>(std::ceil(program.end_time_s() / dt));
  double next_sample = 1.0 / cc.sensor.rate_hz;
  for (long i = 1; i <= ticks; ++i) {
    const double t = static_cast<double>(i) * dt;
    program.sample(t, q);
    Wrench w;
    const Vector3 p = arm.tick(q, loaded != 0, dt, w);
    if (rig.force_from_sensor && loaded) {
      const Matrix3 base_R_flange = ws.base_T_flange.linear();
      forward_kinematics(rig.nominal, rig.ws_nominal, q);  // the orientation deflex knows (nominal, encoders)
      const Matrix3 base_R_sensor = rig.ws_nominal.base_T_flange.linear() * rig.sheet.flange_T_sensor.linear();
      for (; next_sample <= t + 1e-12; next_sample += 1.0 / cc.sensor.rate_hz) {
        ForceSample fs;
        fs.t_s = next_sample;
        fs.wrench_sensor.head<3>() = rig.sensor.sample(w.head<3>(), base_R_flange, next_sample);
        const ConditionedWrench cw = pipeline.step(fs, base_R_sensor);
        if (static_cast<int>(cw.status) >= 0) {
          pass.force_t.push_back(next_sample);
          pass.force_base.push_back(cw.wrench_base.head<3>());
        }
      }
    }
    tracker.observe(t - dt, p_prev, t, p, pass.trace);
    p_prev = p;
  }
  rig.coupled.add(arm.counters());
}

// Adds an arc's measurements: at points along the arc, the mean of the tracker samples in a window,
// loaded minus unloaded at the same times (both passes ran the same program), and the force there.
void measure_calibration_arc(CalibrationRig& rig, const CalibrationArc& arc, std::vector<StiffnessMeasurement>& data) {
  const CalibrationConfig& cal = rig.cal;
  const JointTrajectory& program = arc.program;
  const Pass* const passes = arc.passes;
  const double hold_s = rig.hold_s;
  const double motion_s = program.end_time_s() - hold_s;
  for (int j = 0; j < cal.points_per_arc; ++j) {
    const double tj = hold_s + motion_s * (j + 0.5) / cal.points_per_arc;
    Vector3 sum[2] = {Vector3::Zero(), Vector3::Zero()};
    int count[2] = {0, 0};
    for (int pass = 0; pass < 2; ++pass) {
      for (const auto& s : passes[pass].trace) {
        if (std::abs(s.t_s - tj) <= 0.5 * cal.window_s) {
          sum[pass] += s.p_m;
          ++count[pass];
        }
      }
    }
    if (count[0] == 0 || count[1] == 0) continue;
    StiffnessMeasurement m;
    program.sample(tj, m.q);  // the encoders' reading: the commanded joints
    m.dp_m = sum[1] / count[1] - sum[0] / count[0];
    m.wrench_base = Wrench::Zero();
    if (rig.force_from_sensor) {
      Vector3 f = Vector3::Zero();
      int nf = 0;
      for (std::size_t i = 0; i < passes[1].force_t.size(); ++i) {
        if (std::abs(passes[1].force_t[i] - tj) <= 0.5 * cal.window_s) {
          f += passes[1].force_base[i];
          ++nf;
        }
      }
      if (nf == 0) continue;
      m.wrench_base.head<3>() = f / nf;
    } else {
      // The set-point along the bar as the user places it: nominal pivot, nominal TCP.
      const Vector3 tcp = tcp_pose(rig.nominal, rig.ws_nominal, m.q).translation();
      m.wrench_base.head<3>() = (arc.arc.push ? cal.load_n : -cal.load_n) * (tcp - arc.pivot).normalized();
    }
    data.push_back(m);
  }
}

// The planner's poses and loads around the test circle for a second look, each force at the TCP
// ball (the bar has no lever on the tool), in the region the arcs span.
CalibrationPlan plan_second_look(const CalibrationRig& rig) {
  const CaseConfig& c = rig.c;
  CalibrationPlanOptions o;
  const Vector3 reach(c.radius_m() + 0.05, c.radius_m() + 0.05, 0.06);
  o.region_min_m = c.circle.center_m - reach;
  o.region_max_m = c.circle.center_m + reach;
  o.load_n = rig.cal.load_n;
  o.poses = 8;
  o.loads_per_pose = 2;
  o.lever_m = 0.0;
  o.orientation = Eigen::Quaterniond(c.circle.tcp_orientation.linear());
  o.noise_m = std::max(rig.cc.tracker.noise_m, 1e-6);
  return plan_calibration(rig.nominal, o);
}

// Measures one planned point: the arm stands at its configuration, the bar placed along the planned
// force (its table a bar's length behind the TCP), unloaded then loaded, the tracker's mean over the
// last window of each hold; the force as the calibration takes it (the bar's report or the sensor).
bool measure_planned_point(CalibrationRig& rig, const CalibrationPoint& point, int index,
                           std::vector<StiffnessMeasurement>& data) {
  const Vector3 f = point.wrench_base.head<3>();
  const Vector3 along = f.normalized();
  CalibrationArc hold{1000 + index,
                      Arc{0.0, 0.0, true, 0.0},
                      point.base_T_tcp.translation() - rig.cc.ldbb.bar_length_m * along,
                      JointTrajectory({0.0, rig.hold_s + rig.cal.window_s}, {point.q, point.q}, rig.nominal),
                      {},
                      std::nullopt};
  for (int loaded = 0; loaded < 2; ++loaded) run_calibration_pass(rig, hold, loaded);
  Vector3 mean[2] = {Vector3::Zero(), Vector3::Zero()};
  for (int pass = 0; pass < 2; ++pass) {
    if (hold.passes[pass].trace.empty()) return false;
    for (const auto& sample : hold.passes[pass].trace) mean[pass] += sample.p_m;
    mean[pass] /= static_cast<double>(hold.passes[pass].trace.size());
  }
  StiffnessMeasurement m;
  m.q = point.q;
  m.dp_m = mean[1] - mean[0];
  m.wrench_base = Wrench::Zero();
  if (rig.force_from_sensor) {
    const auto& forces = hold.passes[1].force_base;
    if (forces.empty()) return false;
    Vector3 sum = Vector3::Zero();
    for (const auto& fb : forces) sum += fb;
    m.wrench_base.head<3>() = sum / static_cast<double>(forces.size());
  } else {
    m.wrench_base.head<3>() = rig.cal.load_n * along;  // the set-point along the bar as placed
  }
  data.push_back(m);
  return true;
}

// The joints an estimate cannot give the compensators (0-based): not identified at all, or flagged by
// the identification (a relative standard error over its limit, its compliance at the c >= 0 bound,
// collinear with others): a value shown "but should not be used" is not used.
std::vector<int> unusable_joints(const StiffnessEstimate& e) {
  std::vector<int> out;
  for (std::size_t j = 0; j < e.stiffness_nm_per_rad.size(); ++j) {
    const double k = e.stiffness_nm_per_rad[j];
    const int joint = static_cast<int>(j) + 1;
    const bool flagged = std::find(e.unidentifiable_joints.begin(), e.unidentifiable_joints.end(), joint) !=
                         e.unidentifiable_joints.end();
    if (!(std::isfinite(k) && k > 0.0) || flagged) out.push_back(static_cast<int>(j));
  }
  return out;
}

StiffnessEstimate identify_cell(const CalibrationRig& rig, const std::vector<StiffnessMeasurement>& data) {
  if (data.size() < 6) {
    throw InputError("calibration: fewer than 6 measurements (check the calibration section of the case)");
  }
  // Plain least squares: the misfit is systematic (sensor compliance, lost motion, drift), not gross
  // outliers, and a robust re-weighting would throw good measurements away for it.
  IdentificationOptions id_options;
  id_options.robust = false;
  return identify_stiffness(rig.nominal, data, id_options);
}

// "1, 4 and 6" of 0-based joints.
std::string joints_text(const std::vector<int>& joints) {
  std::string s;
  for (std::size_t i = 0; i < joints.size(); ++i) {
    s += fmt::format("{}{}", i == 0 ? "" : (i + 1 == joints.size() ? " and " : ", "), joints[i] + 1);
  }
  return s;
}

// The engineer's second look at the joints the arcs left unusable: those the planner's poses can turn
// (its predicted relative standard error within the identification's limit) are measured again at
// those poses and identified from every measurement; the rest are not measured again. Adds notes.
StiffnessEstimate second_look(CalibrationRig& rig, const std::vector<int>& unusable,
                              std::vector<StiffnessMeasurement>& data, StiffnessEstimate estimate,
                              std::vector<std::string>& notes, int& added, std::vector<int>& remeasured) {
  const CalibrationPlan plan = plan_second_look(rig);
  const double limit = IdentificationOptions{}.max_relative_std_error;
  std::vector<int> can, cannot;
  for (int j : unusable) {
    const double se = plan.predicted_relative_std_error[static_cast<std::size_t>(j)];
    (std::isfinite(se) && se <= limit ? can : cannot).push_back(j);
  }
  if (!cannot.empty()) {
    double worst = 0.0;
    for (int j : cannot) worst = std::max(worst, plan.predicted_relative_std_error[static_cast<std::size_t>(j)]);
    notes.push_back(
        fmt::format("joint{} {}: no load the bar can put on the TCP ball turns {} enough to identify "
                    "(the planner's best poses leave a relative standard error of {})",
                    cannot.size() == 1 ? "" : "s", joints_text(cannot), cannot.size() == 1 ? "it" : "them",
                    std::isfinite(worst) ? fmt::format("{:.0f} %", 100.0 * worst) : "no bound"));
  }
  if (can.empty()) return estimate;
  for (int j : can) remeasured.push_back(j + 1);
  for (std::size_t i = 0; i < plan.points.size(); ++i) {
    if (measure_planned_point(rig, plan.points[i], static_cast<int>(i), data)) ++added;
  }
  notes.push_back(
      fmt::format("joint{} {}: measured again at {} poses and loads the planner added (the bar placed "
                  "along each planned force)",
                  can.size() == 1 ? "" : "s", joints_text(can), added));
  return identify_cell(rig, data);
}

// Why the final estimate gives the compensators no value for 0-based joint `j`.
std::string unusable_reason(const StiffnessEstimate& e, int j) {
  const auto ju = static_cast<std::size_t>(j);
  const double k = e.stiffness_nm_per_rad[ju];
  if (!(std::isfinite(k) && k > 0.0)) return "not identified";
  const double rel = e.std_error_nm_per_rad[ju] / k;
  return std::isfinite(rel) ? fmt::format(
                                  "its estimate {:.3g} Nm/rad has a relative standard error of {:.0f} %, "
                                  "over the identification's {:.0f} %",
                                  k, 100.0 * rel, 100.0 * IdentificationOptions{}.max_relative_std_error)
                            : fmt::format("its estimate {:.3g} Nm/rad is flagged by the identification", k);
}

// The compensators' model from the final estimate: a usable joint takes its identified stiffness,
// any other keeps the assumed one, and the notes say which and why.
CellCalibration calibration_from(const CalibrationRig& rig, const std::vector<StiffnessMeasurement>& data,
                                 StiffnessEstimate estimate, std::vector<std::string> notes, int added) {
  const RobotModel& nominal = rig.nominal;
  const std::vector<int> unusable = unusable_joints(estimate);
  std::vector<double> k(static_cast<std::size_t>(nominal.dof()));
  std::vector<int> kept;
  for (int j = 0; j < nominal.dof(); ++j) {
    const bool use = std::find(unusable.begin(), unusable.end(), j) == unusable.end();
    k[static_cast<std::size_t>(j)] =
        use ? estimate.stiffness_nm_per_rad[static_cast<std::size_t>(j)] : nominal.stiffness()[j];
    if (!use) {
      kept.push_back(j + 1);
      notes.push_back(
          fmt::format("joint {}: {}: kept the assumed stiffness ({:.3g} Nm/rad), the compensators never "
                      "see the estimate",
                      j + 1, unusable_reason(estimate, j), nominal.stiffness()[j]));
    }
  }
  for (const auto& w : estimate.warnings) notes.push_back(w);
  double force_sum = 0.0;
  for (const auto& m : data) force_sum += m.wrench_base.head<3>().norm();
  CellCalibration out{nominal,
                      std::move(estimate),
                      static_cast<int>(data.size()),
                      force_sum / static_cast<double>(data.size()),
                      std::move(notes),
                      rig.coupled,
                      {},
                      std::move(kept)};
  out.identified = nominal.with_stiffness(
      k, fmt::format("identified on the simulated cell while moving ({} measurements on {} arcs{}, residual {:.1f} "
                     "um RMS)",
                     data.size(), rig.cal.arcs, added > 0 ? fmt::format(" and {} planned poses", added) : "",
                     out.estimate.residual_rms_m * 1e6));
  return out;
}

}  // namespace

CellCalibration calibrate_setup(const CaseConfig& c, const cell::TrueRobot& robot, std::uint64_t seed) {
  if (c.exact_model) {
    const auto& k = robot.true_model().stiffness();
    std::vector<double> kv(k.data(), k.data() + k.size());
    return CellCalibration{robot.nominal_model().with_stiffness(kv, "exact true stiffness (model-consistent cell)"),
                           {},
                           0,
                           0.0,
                           {"exact stiffness given: model-consistent cell"},
                           {},
                           {},
                           {}};
  }
  CalibrationRig rig(c, robot, seed);
  std::vector<StiffnessMeasurement> data;
  for (int k = 0; k < c.calibration.arcs; ++k) {
    CalibrationArc arc = plan_calibration_arc(rig, k);
    // Two passes over the same program: unloaded, then loaded. Each is its own run (its own drift),
    // and the joints' lost motion carries on from whatever came before (nothing resets it).
    for (int loaded = 0; loaded < 2; ++loaded) {
      run_calibration_pass(rig, arc, loaded);
    }
    measure_calibration_arc(rig, arc, data);
  }
  StiffnessEstimate estimate = identify_cell(rig, data);
  std::vector<std::string> notes;
  int added = 0;
  const std::vector<int> unusable = unusable_joints(estimate);
  std::vector<int> remeasured;
  if (!unusable.empty()) estimate = second_look(rig, unusable, data, std::move(estimate), notes, added, remeasured);
  CellCalibration out = calibration_from(rig, data, std::move(estimate), std::move(notes), added);
  out.remeasured_joints = std::move(remeasured);
  return out;
}

}  // namespace deflex::study
