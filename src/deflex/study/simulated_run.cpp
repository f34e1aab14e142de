// One protocol run on the simulated cell (see simulated_run.hpp).
#include "deflex/study/detail/simulated_run.hpp"

#include <fmt/format.h>

#include <cmath>
#include <memory>

#include "deflex/cell/daq_stream.hpp"
#include "deflex/cell/egm_path_controller.hpp"
#include "deflex/cell/egm_position_controller.hpp"
#include "deflex/cell/fanuc_j519_controller.hpp"
#include "deflex/cell/force_sensor.hpp"
#include "deflex/cell/laser_tracker.hpp"
#include "deflex/cell/ldbb_device.hpp"
#include "deflex/cell/motoros2_rt_controller.hpp"
#include "deflex/cell/path_drift.hpp"
#include "deflex/cell/robot_controller.hpp"
#include "deflex/cell/rsi_controller.hpp"
#include "deflex/cell/simple_message_server.hpp"
#include "deflex/cell/ur_rtde_controller.hpp"
#include "deflex/force/ldbb_force_model.hpp"
#include "deflex/model/compliance.hpp"
#include "deflex/offline/compensate_path.hpp"
#include "deflex/online/online_strategy.hpp"
#include "deflex/paths/circle_path.hpp"
#include "deflex/runtime/session.hpp"
#include "deflex/runtime/session_settings.hpp"
#include "deflex/sensors/datagram_force_source.hpp"
#include "deflex/sensors/wrench_tare.hpp"
#include "deflex/study/detail/cell_arm.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/transport/memory_network.hpp"
#include "deflex/transport/memory_stream.hpp"

namespace deflex::study {
namespace {

// Seeds of the run's components, each from the run's own seed.
enum class Component : std::uint64_t { kLdbb = 1, kSensor = 2, kTracker = 3, kDrift = 4 };
std::uint64_t component_seed(std::uint64_t run, Component c) {
  return splitmix(run ^ (static_cast<std::uint64_t>(c) * 0x632be59bd9b4e019ULL));
}

// The cell's network: the controller (10.0.0.2), the cell PC running deflex (10.0.0.1), and the DAQ.
const DatagramAddress kDeflexForce{0x0a000001, 6600};  // 10.0.0.1:6600
const DatagramAddress kDaq{0x0a000003, 5000};          // 10.0.0.3:5000

// Where a link's two ends listen: the ports a user would give `deflex online` and set on the controller
// (EGM's and RSI's controller sends to deflex's port; FANUC's and MotoROS2's listens on the protocol's
// own; UR RTDE is a TCP connection, the cell's stream pair).
struct LinkAddresses {
  DatagramAddress deflex;
  DatagramAddress controller;
};
LinkAddresses link_addresses(LinkKind link) {
  constexpr std::uint32_t kPc = 0x0a000001, kRobot = 0x0a000002;
  switch (link) {
    case LinkKind::kRsi:
      return {{kPc, 49152}, {kRobot, 49152}};
    case LinkKind::kFanucJ519:
      return {{kPc, 6510}, {kRobot, 60015}};
    case LinkKind::kMotoros2Rt:
      return {{kPc, 6510}, {kRobot, motoros2_rt::kDefaultPort}};
    default:
      return {{kPc, 6510}, {kRobot, 6511}};
  }
}

}  // namespace

std::uint64_t splitmix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

std::uint64_t run_seed(std::uint64_t case_seed, bool sensor_mounted, RunKind kind, Strategy strategy, double load_n,
                       double speed_m_s, std::uint64_t extra) {
  std::uint64_t h = splitmix(case_seed);
  h = splitmix(h ^ (sensor_mounted ? 0x51ULL : 0x17ULL));
  h = splitmix(h ^ static_cast<std::uint64_t>(kind));
  // The uncompensated and unloaded runs of a setup do not depend on the strategy that follows.
  h = splitmix(h ^ (kind == RunKind::kCompensated ? static_cast<std::uint64_t>(strategy) + 11 : 0));
  h = splitmix(h ^ static_cast<std::uint64_t>(std::llround(load_n * 1000.0)));
  h = splitmix(h ^ static_cast<std::uint64_t>(std::llround(speed_m_s * 1e6)));
  return splitmix(h ^ extra);
}

SetupCell build_setup_cell(const CaseConfig& config, bool sensor_mounted) {
  // The same physical robot in every setup: its draws depend on the case seed only.
  auto robot =
      std::make_shared<const cell::TrueRobot>(config.cell, sensor_mounted, splitmix(config.seed ^ 0xabcdefULL));
  CellCalibration calibration =
      calibrate_setup(config, *robot, splitmix(config.seed ^ (sensor_mounted ? 0x1111ULL : 0x2222ULL)));
  CirclePath circle;
  circle.centre_m = config.circle.center_m;
  circle.radius_m = config.radius_m();
  circle.points = config.circle.points;
  std::vector<Pose> poses = sample_circle(circle, Eigen::Quaterniond(config.circle.tcp_orientation.linear()));
  IkRequest first;
  if (calibration.identified.dof() == 6) first.seed = standing_pose(calibration.identified);
  JointPath path = solve_path_ik(calibration.identified, poses, first);
  return SetupCell{std::move(robot), std::move(calibration), std::move(poses), std::move(path)};
}

namespace {

// The protocol's program timed with its speed ramped over `ramp_points` segments into and out of every
// point where it is at rest (the start, the turn from clockwise to anticlockwise, the end): segment i
// of a ramp runs at sin(pi/2 i / (ramp_points + 1)) of the speed.
JointTrajectory ramped_program(const std::vector<Pose>& poses, std::vector<JointVector> joints, double speed_m_s,
                               double settle_s, std::size_t turn, int ramp_points, const RobotModel& model) {
  const std::size_t last = poses.size() - 1;
  std::vector<double> t;
  std::vector<JointVector> q;
  if (settle_s > 0.0) {
    t.push_back(0.0);
    q.push_back(joints.front());
  }
  t.push_back(settle_s);
  q.push_back(joints.front());
  for (std::size_t i = 1; i <= last; ++i) {
    // Segment i joins points i - 1 and i: its distance in segments from the nearest point at rest.
    std::size_t from_rest = std::min(i, last - i + 1);
    if (turn > 0 && turn < last) from_rest = std::min(from_rest, i <= turn ? turn - i + 1 : i - turn);
    const double x = std::min(1.0, static_cast<double>(from_rest) / (ramp_points + 1));
    const double share = std::sin(0.5 * kPi * x);  // full speed with no step in the acceleration
    const double d = (poses[i].translation() - poses[i - 1].translation()).norm();
    t.push_back(t.back() + std::max(d / (speed_m_s * share), 1e-3));
    q.push_back(std::move(joints[i]));
  }
  return JointTrajectory(std::move(t), std::move(q), model,
                         fmt::format("path at {:g} mm/s, ramped at rest", speed_m_s * 1e3));
}

}  // namespace

JointTrajectory protocol_program(const std::vector<Pose>& circle_poses, const std::vector<JointVector>& q,
                                 double speed_m_s, double settle_s, int laps_cw, int laps_ccw, const RobotModel& model,
                                 int ramp_points) {
  if (circle_poses.size() != q.size() || q.size() < 4) {
    throw InputError("protocol program: a closed circle of at least 4 points is needed");
  }
  const std::size_t n = q.size() - 1;  // distinct points; index n repeats index 0
  std::vector<Pose> poses;
  std::vector<JointVector> joints;
  poses.push_back(circle_poses[0]);
  joints.push_back(q[0]);
  // The circle's points run anticlockwise (seen from above); clockwise laps walk them backwards.
  for (int lap = 0; lap < laps_cw; ++lap) {
    for (std::size_t k = 1; k <= n; ++k) {
      poses.push_back(circle_poses[n - k]);
      joints.push_back(q[n - k]);
    }
  }
  const std::size_t turn = laps_ccw > 0 ? poses.size() - 1 : 0;
  for (int lap = 0; lap < laps_ccw; ++lap) {
    for (std::size_t k = 1; k <= n; ++k) {
      poses.push_back(circle_poses[k]);
      joints.push_back(q[k]);
    }
  }
  if (ramp_points > 0) {
    if (!std::isfinite(speed_m_s) || !(speed_m_s > 0.0) || !(settle_s >= 0.0)) {
      throw InputError("protocol program: a positive speed and a hold of >= 0 s are needed");
    }
    return ramped_program(poses, std::move(joints), speed_m_s, settle_s, turn, ramp_points, model);
  }
  return trajectory_at_tcp_speed(poses, joints, speed_m_s, model, settle_s);
}

std::vector<JointVector> offline_configurations(const CaseConfig& config, const SetupCell& setup, double load_n) {
  const LdbbForceModel force(config.pivot_m(), load_n, config.cell.ldbb.push);
  OfflineOptions options;
  options.predict = false;
  const OfflineResult r =
      compensate_path(setup.calibration.identified, setup.nominal_path, setup.circle_poses, force, options);
  std::vector<JointVector> q;
  q.reserve(r.points.size());
  for (const auto& p : r.points) {
    q.push_back(p.q_command);
  }
  return q;
}

double identified_model_error(const CaseConfig& config, const SetupCell& setup, double load_n, double* scale) {
  const LdbbForceModel force(config.pivot_m(), load_n, config.cell.ldbb.push);
  const RobotModel& model = setup.calibration.identified;
  const cell::TrueRobot& robot = *setup.robot;
  Workspace ws(model);
  Workspace ws_true(robot.true_model());
  double error_sum = 0.0, scale_sum = 0.0;
  int n = 0;
  for (std::size_t i = 0; i + 1 < setup.nominal_path.q.size(); ++i) {
    const JointVector& q = setup.nominal_path.q[i];
    const Wrench w = force.wrench_at(i, tcp_pose(model, ws, q));
    const Vector3 d_model = tcp_deflection(model, ws, q, w).head<3>();
    cell::TrueRobotState state = robot.initial_state(q);
    const Vector3 unloaded = robot.solve(ws_true, q, Wrench::Zero(), state);
    const Vector3 d_true = robot.solve(ws_true, q, w, state) - unloaded;
    if (!(d_true.norm() > 0.0)) continue;
    error_sum += (d_model - d_true).norm() / d_true.norm();
    scale_sum += d_model.norm() / d_true.norm();
    ++n;
  }
  if (scale != nullptr) *scale = n > 0 ? scale_sum / n : NAN;
  return n > 0 ? error_sum / n : NAN;
}

JointVector standing_pose(const RobotModel& model) {
  JointVector q = JointVector::Zero(model.dof());
  if (q.size() == 6) q << 0.0, deg_to_rad(20.0), deg_to_rad(10.0), 0.0, deg_to_rad(60.0), 0.0;
  return q;
}

deflex::SensorConfig sensor_config_from_sheet(const CaseConfig& config, const cell::SensorCalibration& sheet) {
  deflex::SensorConfig sc;
  sc.name = "MSC10-class 3-component sensor (calibration sheet)";
  sc.components = 3;
  sc.crosstalk.topLeftCorner<3, 3>() = sheet.decoupling;
  sc.flange_T_sensor = Pose::Identity();
  sc.flange_T_sensor.translation() = Vector3(0, 0, sheet.height_m);
  sc.payload_mass_kg = sheet.ee_mass_kg;
  sc.payload_cog_sensor_m = sheet.ee_cog_m;
  sc.gravity_base_m_s2 = Vector3(0, 0, -cell::kGravity);
  sc.lowpass_cutoff_hz = config.online.lowpass_hz;
  sc.sample_rate_hz = config.cell.sensor.rate_hz;
  sc.dead_band_N = config.online.dead_band_n;
  sc.fault_threshold_N = config.online.fault_threshold_n;
  return sc;
}

double tare_limit_n(const cell::SensorConfig& sensor) { return 0.1 + 3.0 * sensor.noise_n; }

deflex::SensorConfig tare_sensor(deflex::SensorConfig sheet_config, cell::ForceSensorDaq& sensor,
                                 const cell::TrueRobot& robot, const JointVector& q_tare, double max_std_n) {
  // Where the flange truly points (the arm standing unloaded) and where deflex thinks the sensor
  // points (nominal kinematics, the sheet's mount).
  const RobotModel& nominal = robot.nominal_model();
  Workspace ws_true(robot.true_model());
  Workspace ws_nominal(nominal);
  forward_kinematics(robot.true_model(), ws_true, q_tare);
  forward_kinematics(nominal, ws_nominal, q_tare);
  const Matrix3 base_R_flange = ws_true.base_T_flange.linear();
  const Matrix3 base_R_sensor = ws_nominal.base_T_flange.linear() * sheet_config.flange_T_sensor.linear();
  TareSettings settings;
  settings.max_std_force_n = max_std_n;
  settings.expected_wrench_sensor = payload_wrench_sensor(
      sheet_config.payload_mass_kg, sheet_config.payload_cog_sensor_m, sheet_config.gravity_base_m_s2, base_R_sensor);
  settings.expected_wrench_sensor.tail<3>().setZero();  // a 3-component sensor reads no moments
  WrenchTare tare;
  tare.start(settings, sheet_config.sample_rate_hz);
  const Matrix3 decoupling = sheet_config.crosstalk.topLeftCorner<3, 3>();
  for (int i = 0; tare.result().state == TareState::kCollecting && i < 100000; ++i) {
    ForceSample fs;
    fs.t_s = i / sheet_config.sample_rate_hz;
    // Read before the tare's own clock starts: the sensor's zero drift counts from the tare's end.
    fs.wrench_sensor.head<3>() = decoupling * sensor.sample(Vector3::Zero(), base_R_flange, 0.0);
    tare.add(fs);
  }
  if (tare.result().state != TareState::kDone) {
    throw Error("run: the sensor's tare was refused: " + describe(tare.result(), settings));
  }
  sheet_config.bias_sensor.head<3>() = tare.result().offset_sensor.head<3>();
  return sheet_config;
}

namespace {

// What a run is: the case, its setup, the run's spec and what follows from it, the program the
// controller runs and the run's length in servo ticks.
struct RunPlan {
  const CaseConfig& config;
  const SetupCell& setup;
  const RunSpec& spec;
  const cell::TrueRobot& robot;
  const cell::CellConfig& c;
  bool loaded;
  bool compensated;
  bool linked;
  std::shared_ptr<const JointTrajectory> program;
  double settle_s;
  double run_end_s;
  double dt;
  long ticks;
  runtime::SessionConfig session;  // deflex's settings on a link (the link's defaults otherwise)
};

// The cell's network and its three hosts, and the robot program's motion and state connections
// (simple message; UR RTDE's one connection is the motion one), on a clock this simulation advances.
struct RunNetwork {
  RunNetwork(const cell::CellConfig& c, LinkKind link)
      // MotoROS2's reply is 2053 bytes.
      : network(clock, link == LinkKind::kMotoros2Rt ? 4096 : 2048),
        controller_port(network.add_endpoint(link_addresses(link).controller, c.controller.network_latency_s)),
        deflex_egm_port(network.add_endpoint(link_addresses(link).deflex, c.controller.network_latency_s)),
        daq_port(network.add_endpoint(kDaq, c.sensor.daq_latency_s)),
        deflex_force_port(network.add_endpoint(kDeflexForce, 0.0)),
        motion_stream(clock, c.controller.network_latency_s),
        state_stream(clock, c.controller.network_latency_s) {}

  ManualClock clock;
  MemoryNetwork network;
  MemoryTransport& controller_port;
  MemoryTransport& deflex_egm_port;
  MemoryTransport& daq_port;
  MemoryTransport& deflex_force_port;
  MemoryStreamPair motion_stream;
  MemoryStreamPair state_stream;
};

// deflex's side of a linked run (empty for a run of the robot program): the session and the force
// model and source it borrows.
struct DeflexSide {
  std::unique_ptr<LdbbForceModel> force_model;
  std::unique_ptr<DatagramForceSource> force_source;
  std::unique_ptr<runtime::Session> session;
};

// The cell's instruments on a run: the loading bar, the arm's drift and the laser tracker.
struct RunInstruments {
  cell::LdbbDevice ldbb;
  cell::PathDrift drift;
  cell::LaserTracker tracker;
};

// The runtime's kind of a study's controller link.
runtime::LinkKind runtime_link(LinkKind link) {
  switch (link) {
    case LinkKind::kEgmPath:
      return runtime::LinkKind::kEgmPath;
    case LinkKind::kRsi:
      return runtime::LinkKind::kRsi;
    case LinkKind::kSimpleMessage:
      return runtime::LinkKind::kSimpleMessage;
    case LinkKind::kFanucJ519:
      return runtime::LinkKind::kFanucJ519;
    case LinkKind::kMotoros2Rt:
      return runtime::LinkKind::kMotoros2Rt;
    case LinkKind::kUrRtde:
      return runtime::LinkKind::kUrRtde;
    case LinkKind::kProgram:
    case LinkKind::kEgmJoint:
      break;
  }
  return runtime::LinkKind::kEgmJoint;
}

// deflex's settings for a run on a link, as `deflex online --link ...` starts from them (the link's
// cycle and defaults: runtime::default_session_config), with the case file's online section applied
// (bounds, rates, watchdog, ramp-in); the EGM cycles come from the case's controller, simple
// message's from its online section. The reference runs stream the program uncorrected.
runtime::SessionConfig session_config_of(const CaseConfig& config, const RunSpec& spec, bool compensated) {
  const cell::CellConfig& c = config.cell;
  runtime::SessionConfig sc = runtime::default_session_config(runtime_link(spec.link));
  if (spec.link != LinkKind::kProgram) sc.online = online_config_from_case(config, link_period_s(config, spec.link));
  sc.strategy = StrategyKind::kNone;
  if (compensated) {
    sc.strategy = spec.strategy == Strategy::kHybrid       ? StrategyKind::kHybrid
                  : spec.strategy == Strategy::kPredictive ? StrategyKind::kPredictive
                                                           : StrategyKind::kOnline;
  }
  const double ramp_in_s = config.online.ramp_in_s;
  sc.egm_joint.stream.ramp_in_s = ramp_in_s;
  sc.simple_message.stream.ramp_in_s = ramp_in_s;
  sc.fanuc_j519.stream.ramp_in_s = ramp_in_s;
  sc.motoros2_rt.stream.ramp_in_s = ramp_in_s;
  sc.ur_rtde.stream.ramp_in_s = ramp_in_s;
  sc.simple_message.buffer_depth = config.online.stream_buffer_depth;
  sc.egm_path.frame = parse_path_corr_frame(c.controller.path_corr_frame);
  // deflex is the client of FANUC's and MotoROS2's controller: it is told where the controller listens.
  sc.fanuc_j519.controller = link_addresses(spec.link).controller;
  sc.motoros2_rt.controller = link_addresses(spec.link).controller;
  sc.history_cycles = 16;
  return sc;
}

// Checks the run and plans it: its program (the offline strategy's compensated one when it has one)
// and how long the run lasts.
RunPlan plan_simulated_run(const CaseConfig& config, const SetupCell& setup, const RunSpec& spec) {
  const cell::TrueRobot& robot = *setup.robot;
  const cell::CellConfig& c = config.cell;
  const bool loaded = spec.kind != RunKind::kUnloaded;
  const bool compensated = spec.kind == RunKind::kCompensated;
  const bool linked = spec.link != LinkKind::kProgram;
  if (linked && !robot.sensor_mounted()) {
    throw InputError(
        fmt::format("run: the {} link's online strategies need the force sensor mounted", to_string(spec.link)));
  }
  const RobotModel& identified = setup.calibration.identified;
  const bool offline_program =
      compensated && (spec.strategy == Strategy::kOffline || spec.strategy == Strategy::kHybrid);
  const std::vector<JointVector> configurations =
      offline_program ? offline_configurations(config, setup, spec.load_n) : setup.nominal_path.q;
  // FANUC's controller checks the jerk of every command step at its interval: a program that starts,
  // turns or stops at full speed makes it stop the stream (deflex refuses such a program), so a user
  // streaming to it ramps the speed there.
  const int ramp_points = spec.link == LinkKind::kFanucJ519 ? kFanucRampPoints : 0;
  auto program = std::make_shared<const JointTrajectory>(protocol_program(setup.circle_poses, configurations,
                                                                          spec.speed_m_s, c.ldbb.settle_s, spec.laps_cw,
                                                                          spec.laps_ccw, identified, ramp_points));

  const double motion_end_s = program->end_time_s();
  // The arm follows a streamed program a little late: let the tracker see the motion to its end.
  // (The streaming server runs a buffer of points behind: a second.)
  const double run_end_s = motion_end_s + (spec.link == LinkKind::kSimpleMessage ? 1.0 : linked ? 0.5 : 0.0);
  runtime::SessionConfig session = session_config_of(config, spec, compensated);
  // A controller whose cycle can be shorter than the servo's (UR's 2 ms, FANUC's 1 ms) is ticked at its cycle.
  const bool fast_cycle = spec.link == LinkKind::kUrRtde || spec.link == LinkKind::kFanucJ519;
  const double dt =
      fast_cycle ? std::min(c.controller.servo_period_s, session.online.period_s) : c.controller.servo_period_s;
  const auto ticks = static_cast<long>(std::ceil(run_end_s / dt));
  return RunPlan{config,
                 setup,
                 spec,
                 robot,
                 c,
                 loaded,
                 compensated,
                 linked,
                 std::move(program),
                 c.ldbb.settle_s,
                 run_end_s,
                 dt,
                 ticks,
                 std::move(session)};
}

// The controllers whose own cycle deflex's settings set (the stand-ins' defaults otherwise: their
// dead time, lag and limits, as deflex's stand-in session runs them).
std::unique_ptr<cell::RobotController> make_streamed_controller(const RunPlan& plan, RunNetwork& net) {
  const runtime::SessionConfig& sc = plan.session;
  const JointVector& q_start = plan.program->points().front();
  switch (plan.spec.link) {
    case LinkKind::kFanucJ519: {
      cell::FanucJ519ControllerConfig fc;
      fc.interval_s = sc.online.period_s;
      fc.version = sc.fanuc_j519.version;
      return std::make_unique<cell::FanucJ519Controller>(fc, q_start, net.controller_port);
    }
    case LinkKind::kMotoros2Rt: {
      cell::Motoros2RtControllerConfig mc;
      mc.period_s = sc.online.period_s;
      mc.group = sc.motoros2_rt.group;
      return std::make_unique<cell::Motoros2RtController>(mc, q_start, net.controller_port);
    }
    case LinkKind::kUrRtde: {
      cell::UrRtdeControllerConfig uc;
      uc.e_series = sc.online.period_s < 0.005;
      uc.register_offset = sc.ur_rtde.register_offset;
      return std::make_unique<cell::UrRtdeController>(uc, q_start, net.motion_stream.server());
    }
    default:
      return std::make_unique<cell::SimpleMessageServer>(cell::SimpleMessageServerConfig{}, plan.robot.nominal_model(),
                                                         q_start, net.motion_stream.server(),
                                                         net.state_stream.server());
  }
}

// The controller the run's link talks to: the robot program itself, EGM position guidance, EGM path
// correction, KUKA RSI, or one deflex streams the program to (make_streamed_controller).
std::unique_ptr<cell::RobotController> make_run_controller(const RunPlan& plan, RunNetwork& net) {
  const cell::CellConfig& c = plan.c;
  const cell::TrueRobot& robot = plan.robot;
  const std::shared_ptr<const JointTrajectory>& program = plan.program;
  const DatagramAddress deflex = link_addresses(plan.spec.link).deflex;
  switch (plan.spec.link) {
    case LinkKind::kProgram:
      return std::make_unique<cell::ProgramController>(program);
    case LinkKind::kEgmJoint:
      return std::make_unique<cell::EgmPositionGuidanceController>(c.controller, program->points().front(),
                                                                   net.controller_port, deflex);
    case LinkKind::kEgmPath:
      return std::make_unique<cell::EgmPathCorrectionController>(c.controller, robot.nominal_model(), program,
                                                                 net.controller_port, deflex);
    case LinkKind::kRsi: {
      // AXISCORR's limits as deflex controller-setup writes them: deflex's bound, AXISCORRMON 1.2 times it.
      const runtime::SessionConfig& sc = plan.session;
      cell::RsiControllerConfig rc;
      const double bound_deg = rad_to_deg(sc.online.max_joint_correction_rad);
      rc.upper_limit_deg = bound_deg;
      rc.lower_limit_deg = -bound_deg;
      rc.max_correction_deg = 1.2 * bound_deg;
      rc.cycle_s = sc.online.period_s;
      rc.timeout = sc.rsi.controller_timeout;
      rc.sentype = sc.rsi.sentype;
      return std::make_unique<cell::RsiController>(rc, robot.nominal_model(), program, net.controller_port, deflex);
    }
    case LinkKind::kSimpleMessage:
    case LinkKind::kFanucJ519:
    case LinkKind::kMotoros2Rt:
    case LinkKind::kUrRtde:
      break;
  }
  return make_streamed_controller(plan, net);
}

// deflex's side, run as `deflex online` runs it: a session of the runtime on the cell's network, from
// the sensor's calibration sheet and identified payload, the identified robot model, the user's
// settings, the strategy and the link. Empty when the run has no link.
DeflexSide start_deflex_session(const RunPlan& plan, RunNetwork& net, cell::ForceSensorDaq& sensor) {
  DeflexSide side;
  if (!plan.linked) return side;
  const CaseConfig& config = plan.config;
  const cell::CellConfig& c = plan.c;
  const RunSpec& spec = plan.spec;
  const runtime::SessionConfig& sc = plan.session;
  if (sc.strategy == StrategyKind::kHybrid || sc.strategy == StrategyKind::kPredictive) {
    // The user's force model: the LDBB with its nominal pivot and set-point force.
    side.force_model = std::make_unique<LdbbForceModel>(config.pivot_m(), std::max(spec.load_n, 1.0), c.ldbb.push);
  }
  side.force_source = std::make_unique<DatagramForceSource>(net.deflex_force_port);
  runtime::SessionEndpoints endpoints;
  endpoints.datagram = &net.deflex_egm_port;
  endpoints.motion = &net.motion_stream.client();
  endpoints.state = &net.state_stream.client();
  side.session = std::make_unique<runtime::Session>(
      sc, plan.setup.calibration.identified,
      tare_sensor(sensor_config_from_sheet(config, sensor.calibration()), sensor, plan.robot,
                  plan.program->points().front(), tare_limit_n(c.sensor)),
      streams_program(spec.link) ? plan.program : nullptr, side.force_model.get(), side.force_source.get(), net.clock,
      endpoints);
  return side;
}

// The run's bar, drift and tracker, each with its own seed from the run's.
RunInstruments make_run_instruments(const RunPlan& plan) {
  const cell::CellConfig& c = plan.c;
  const RunSpec& spec = plan.spec;
  // The same bar as in the calibration: its seal friction drawn afresh when it is pressurised.
  const cell::LdbbConfig& bar = c.ldbb;
  return RunInstruments{
      cell::LdbbDevice(bar, plan.config.pivot_m(), spec.load_n, component_seed(spec.seed, Component::kLdbb)),
      cell::PathDrift(c.drift, component_seed(spec.seed, Component::kDrift), plan.loaded ? spec.load_n : 0.0),
      cell::LaserTracker(c.tracker, component_seed(spec.seed, Component::kTracker), plan.settle_s, plan.run_end_s,
                         plan.settle_s)};
}

// A run's whole cell, built in the order the cell comes up: the plan, the network, the controller,
// the force sensor and its DAQ, deflex's side, then the bar, the drift and the tracker.
struct SimulatedRun {
  SimulatedRun(const CaseConfig& config, const SetupCell& setup, const RunSpec& spec)
      : plan(plan_simulated_run(config, setup, spec)),
        net(plan.c, spec.link),
        controller(make_run_controller(plan, net)),
        // One physical sensor for the whole case: its crosstalk and true sensitivities come from the
        // case seed; its noise from the run's.
        sensor(plan.c.sensor, plan.c.tool, component_seed(spec.seed, Component::kSensor),
               splitmix(config.seed ^ 0x5e5503ULL)),
        daq(net.daq_port, kDeflexForce),
        deflex(start_deflex_session(plan, net, sensor)),
        instruments(make_run_instruments(plan)) {}

  RunPlan plan;
  RunNetwork net;
  std::unique_ptr<cell::RobotController> controller;
  cell::ForceSensorDaq sensor;
  cell::DaqStream daq;
  DeflexSide deflex;
  RunInstruments instruments;
};

// Drives the run tick by tick: the controller moves the arm, the bar loads it, drift displaces it,
// the tracker records it and, on a link, the DAQ streams the force and deflex answers the controller.
RunOutput drive_simulated_run(SimulatedRun& run) {
  const RunPlan& plan = run.plan;
  const cell::TrueRobot& robot = plan.robot;
  const cell::CellConfig& c = plan.c;
  const bool loaded = plan.loaded;
  const bool linked = plan.linked;
  const double dt = plan.dt;
  const long ticks = plan.ticks;
  const double network_latency_s = c.controller.network_latency_s;
  ManualClock& clock = run.net.clock;
  cell::RobotController& controller = *run.controller;
  cell::ForceSensorDaq& sensor = run.sensor;
  cell::DaqStream& daq = run.daq;
  runtime::Session* const session = run.deflex.session.get();
  cell::LdbbDevice& ldbb = run.instruments.ldbb;
  cell::PathDrift& drift = run.instruments.drift;
  cell::LaserTracker& tracker = run.instruments.tracker;

  RunOutput out;
  out.simulated_s = plan.run_end_s;
  out.trace.reserve(static_cast<std::size_t>((plan.run_end_s - plan.settle_s) * c.tracker.rate_hz) + 2);
  Workspace ws(robot.true_model());
  JointVector q_motor = plan.program->points().front();
  cell::TrueRobotState state = robot.initial_state(q_motor);
  CellArm arm{robot, ws, state, ldbb, drift, cell::CoupledTickSolver(plan.config.coupled_tick)};
  Vector3 p_prev = arm.at_rest(q_motor);
  const double daq_period = 1.0 / c.sensor.rate_hz;
  double next_daq = daq_period;

  for (long k = 1; k <= ticks; ++k) {
    const double t = static_cast<double>(k) * dt;
    clock.set(t);
    q_motor = controller.tick(t);
    Wrench w;
    const Vector3 p = arm.tick(q_motor, loaded, dt, w);
    controller.encoders(state.q_motor);
    if (linked) {
      // The DAQ streams this tick's samples; the EGM message sent this tick reaches deflex after the
      // network's latency, and deflex answers at once (its reply reaches the controller's next tick).
      const Matrix3 base_R_flange = ws.base_T_flange.linear();
      for (; next_daq <= t + 1e-12; next_daq += daq_period) {
        daq.send(next_daq, sensor.sample(w.head<3>(), base_R_flange, next_daq));
      }
      clock.set(t + network_latency_s);
      poll_deflex_session(*session, out.link_cycles, "run");
    }
    tracker.observe(t - dt, p_prev, t, p, out.trace);
    p_prev = p;
  }
  out.coupled = arm.counters();
  return out;
}

// What the controller itself counted that deflex's link must keep at zero or low (RSI's late cycles,
// MotoROS2's truncated increments, FANUC's peak jerk against its limit); throws when the controller
// stopped the motion (a broken setup, never a result). Read before the session's end stops the stream.
void check_controller(const cell::RobotController& controller, RunOutput& out) {
  if (const auto* rsi = dynamic_cast<const cell::RsiController*>(&controller)) {
    if (!rsi->running()) {
      throw Error(
          fmt::format("run: the simulated RSI controller stopped ({})", cell::to_string(rsi->counters().stopped)));
    }
    out.controller_events = rsi->counters().late;
  } else if (const auto* fanuc = dynamic_cast<const cell::FanucJ519Controller*>(&controller)) {
    if (!fanuc->alarm().empty())
      throw Error("run: the simulated FANUC controller stopped the stream: " + fanuc->alarm());
    double peak = 0.0;
    for (const auto& l : cell::FanucJ519ControllerConfig{}.limits)
      peak = std::max(peak, fanuc->check().peak().jerk / l.jerk);
    out.controller_peak = peak;
  } else if (const auto* moto = dynamic_cast<const cell::Motoros2RtController*>(&controller)) {
    if (!moto->dropped().empty())
      throw Error("run: the simulated MotoROS2 controller dropped the session: " + moto->dropped());
    out.controller_events = moto->counters().truncated;
  } else if (const auto* ur = dynamic_cast<const cell::UrRtdeController*>(&controller)) {
    if (ur->safety_mode() != 1 || (!ur->stopped().empty() && ur->stopped().rfind("the program ended", 0) != 0)) {
      throw Error("run: the simulated UR controller stopped: " + ur->stopped());
    }
  }
}

// What deflex's link did over the run, from its session's summary; throws when the simulated
// controller stopped EGM for lack of answers, or stopped the motion itself.
void summarize_deflex_link(SimulatedRun& run, RunOutput& out) {
  check_controller(*run.controller, out);
  const runtime::SessionSummary& summary = run.deflex.session->finish();
  out.link_counters = summary.counters;
  out.measured_delay_s = summary.measured_delay_s;
  out.max_command_deviation_rad = run.plan.spec.link == LinkKind::kEgmPath ? 0.0 : summary.stats.max_deviation_rad;
  out.max_tcp_correction_m = summary.stats.max_deviation_m;
  const auto* egm = dynamic_cast<const cell::EgmPositionGuidanceController*>(run.controller.get());
  if (egm != nullptr && egm->counters().timed_out) {
    throw Error("run: the simulated controller stopped EGM for lack of answers (a broken setup, not a result)");
  }
}

}  // namespace

deflex::OnlineConfig online_config_from_case(const CaseConfig& config, double period_s) {
  deflex::OnlineConfig oc;
  oc.period_s = period_s;
  oc.max_joint_correction_rad = config.online.max_joint_correction_rad;
  oc.max_tcp_correction_m = config.online.max_tcp_correction_m;
  oc.max_correction_rate_rad_s = config.online.max_rate_rad_s;
  oc.max_tcp_rate_m_s = config.online.max_tcp_rate_m_s;
  oc.watchdog_s = std::max(config.online.watchdog_s, 2.0 * period_s);
  return oc;
}

void poll_deflex_session(runtime::Session& session, std::uint64_t& link_cycles, const char* what) {
  while (!session.ended()) {
    const LinkPollResult r = session.poll(0.0);
    if (session.ended() && runtime::exit_code(session.stop_reason()) != 0) {
      const runtime::SessionSummary& end = session.finish();
      throw Error(fmt::format("{}: deflex's {} session ended: {} ({})", what, end.link, runtime::to_string(end.reason),
                              end.reason_text));
    }
    if (r == LinkPollResult::kIdle) break;
    if (r == LinkPollResult::kAnswered) ++link_cycles;
  }
}

RunOutput simulate_run(const CaseConfig& config, const SetupCell& setup, const RunSpec& spec) {
  SimulatedRun run(config, setup, spec);
  RunOutput out = drive_simulated_run(run);
  if (run.plan.linked) summarize_deflex_link(run, out);
  return out;
}

}  // namespace deflex::study
