// One protocol run on the simulated cell (see simulated_run.hpp).
#include "deflex/cell/simulated_run.hpp"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <random>

#include "deflex/cell/force_sensor.hpp"
#include "deflex/cell/ldbb_device.hpp"
#include "deflex/cell/path_drift.hpp"
#include "deflex/egm/egm_codec.hpp"
#include "deflex/force/ldbb_force_model.hpp"
#include "deflex/model/errors.hpp"
#include "deflex/offline/compensate_path.hpp"
#include "deflex/online/online_compensator.hpp"
#include "deflex/paths/circle_path.hpp"

namespace deflex::cell {
namespace {

std::uint64_t splitmix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// Seeds of the run's components, each from the run's own seed.
enum class Component : std::uint64_t { kLdbb = 1, kSensor = 2, kTracker = 3, kDrift = 4 };
std::uint64_t component_seed(std::uint64_t run, Component c) {
  return splitmix(run ^ (static_cast<std::uint64_t>(c) * 0x632be59bd9b4e019ULL));
}

Vector3 circle_at(const CaseConfig& c, double angle) {
  return c.circle.center_m + c.radius_m() * Vector3(std::cos(angle), std::sin(angle), 0.0);
}

JointProgram program_from(const std::vector<JointVector>& closed) {
  // The path is closed (last = first); the program holds the distinct points.
  return JointProgram(std::vector<JointVector>(closed.begin(), closed.end() - 1));
}

}  // namespace

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
  auto robot = std::make_shared<const TrueRobot>(config, sensor_mounted, splitmix(config.seed ^ 0xabcdefULL));
  CellCalibration calibration =
      calibrate_setup(*robot, splitmix(config.seed ^ (sensor_mounted ? 0x1111ULL : 0x2222ULL)));
  CirclePath circle;
  circle.centre_m = config.circle.center_m;
  circle.radius_m = config.radius_m();
  circle.points = config.controller.program_points;
  std::vector<Pose> poses = sample_circle(circle, Eigen::Quaterniond(config.circle.tcp_orientation.linear()));
  IkRequest first;
  if (calibration.identified.dof() == 6) {
    JointVector seed(6);
    seed << 0.0, deg_to_rad(20.0), deg_to_rad(10.0), 0.0, deg_to_rad(60.0), 0.0;
    first.seed = seed;
  }
  JointPath path = solve_path_ik(calibration.identified, poses, first);
  JointProgram program = program_from(path.q);
  return SetupCell{std::move(robot), std::move(calibration), std::move(poses), std::move(path), std::move(program)};
}

JointProgram offline_program(const SetupCell& setup, double load_n) {
  const CaseConfig& c = setup.robot->config();
  const LdbbForceModel force(c.pivot_m(), load_n, c.ldbb.push);
  OfflineOptions options;
  options.predict = false;
  const OfflineResult r =
      compensate_path(setup.calibration.identified, setup.nominal_path, setup.circle_poses, force, options);
  std::vector<JointVector> q;
  q.reserve(r.points.size());
  for (const auto& p : r.points) {
    q.push_back(p.q_command);
  }
  return program_from(q);
}

std::vector<TrackerTrace> split_laps(const RunOutput& run) {
  std::vector<TrackerTrace> laps;
  for (std::size_t i = 0; i < run.lap_start.size(); ++i) {
    const std::size_t b = run.lap_start[i];
    const std::size_t e = i + 1 < run.lap_start.size() ? run.lap_start[i + 1] : run.trace.size();
    if (e > b + 1) {
      laps.emplace_back(run.trace.begin() + static_cast<std::ptrdiff_t>(b),
                        run.trace.begin() + static_cast<std::ptrdiff_t>(e));
    }
  }
  return laps;
}

RunOutput simulate_run(const SetupCell& setup, const RunSpec& spec) {
  const TrueRobot& robot = *setup.robot;
  const CaseConfig& c = robot.config();
  const bool loaded = spec.kind != RunKind::kUnloaded;
  const bool compensated = spec.kind == RunKind::kCompensated;
  const bool online = compensated && spec.strategy != Strategy::kOffline;
  if (online && !robot.sensor_mounted()) {
    throw InputError(fmt::format("run: the {} strategy needs the force sensor mounted", to_string(spec.strategy)));
  }
  const bool uses_offline_program =
      compensated && (spec.strategy == Strategy::kOffline || spec.strategy == Strategy::kHybrid);
  const JointProgram program = uses_offline_program ? offline_program(setup, spec.load_n) : setup.nominal_program;

  LapSchedule schedule;
  schedule.omega_rad_s = spec.speed_m_s / c.radius_m();
  schedule.settle_s = c.ldbb.settle_s;
  schedule.laps_cw = spec.laps_cw;
  schedule.laps_ccw = spec.laps_ccw;

  const double dt = c.controller.servo_period_s;
  const auto ticks = static_cast<long>(std::ceil(schedule.duration_s() / dt));
  LdbbDevice ldbb(c.ldbb, c.pivot_m(), spec.load_n, component_seed(spec.seed, Component::kLdbb));
  // One physical sensor for the whole case: its crosstalk and true sensitivities come from the case
  // seed; its noise from the run's.
  ForceSensorDaq sensor(c.sensor, c.tool, component_seed(spec.seed, Component::kSensor),
                        splitmix(c.seed ^ 0x5e5503ULL));
  PathDrift drift(c.drift, component_seed(spec.seed, Component::kDrift));
  std::mt19937_64 tracker_rng(component_seed(spec.seed, Component::kTracker));
  std::normal_distribution<double> normal(0.0, 1.0);
  const LdbbForceModel force_model(c.pivot_m(), std::max(spec.load_n, 1.0), c.ldbb.push);

  // The online strategy's view of its sensor: the calibration sheet and the identified payload.
  std::unique_ptr<OnlineCompensator> compensator;
  Matrix3 coupling = Matrix3::Identity();  // inverse of the decoupling: model force -> raw reading
  if (online) {
    deflex::SensorConfig sc;
    sc.name = "simulated MSC10-class 3-component sensor";
    sc.components = 3;
    sc.crosstalk.topLeftCorner<3, 3>() = sensor.calibration().decoupling;
    sc.flange_T_sensor = Pose::Identity();
    sc.flange_T_sensor.translation() = Vector3(0, 0, c.sensor.height_m);
    sc.payload_mass_kg = sensor.calibration().ee_mass_kg;
    sc.payload_cog_sensor_m = sensor.calibration().ee_cog_m;
    sc.bias_sensor.head<3>() = sensor.calibration().bias_n;
    sc.lowpass_cutoff_hz = c.online.lowpass_hz;
    sc.sample_rate_hz = c.sensor.rate_hz;
    sc.dead_band_N = c.online.threshold_low_n;
    sc.fault_threshold_N = c.online.threshold_high_n;
    deflex::OnlineConfig oc;
    oc.period_s = c.online.cycle_s;
    oc.max_joint_correction_rad = c.online.max_correction_rad;
    oc.watchdog_s = 2.0 * c.online.cycle_s + 0.05;
    compensator = std::make_unique<OnlineCompensator>(setup.calibration.identified, sc, oc);
    coupling = sensor.calibration().decoupling.inverse();
  }
  // Latency compensation predicts the wrench and the pose this far ahead: compute and link delays,
  // the controller's filter, half a cycle of hold and the 25 Hz filter's group delay.
  const double lead_s = spec.strategy == Strategy::kOnlineLatency
                            ? c.online.compute_delay_s + c.controller.egm_delay_s + c.controller.egm_filter_s +
                                  0.5 * c.online.cycle_s + std::sqrt(2.0) / (2.0 * kPi * c.online.lowpass_hz)
                            : 0.0;

  RunOutput out;
  out.simulated_s = schedule.duration_s();
  Workspace ws(robot.true_model());
  const int n = robot.true_model().dof();
  JointVector q_plan(n), q_cmd(n), offset = JointVector::Zero(n), offset_target = JointVector::Zero(n);
  program.at(0.0, q_plan);
  TrueRobotState state = robot.initial_state(q_plan);
  Vector3 p_prev = drift.apply(robot.solve(ws, q_plan, Wrench::Zero(), state));
  Vector3 v_prev = Vector3::Zero();
  Matrix3 base_R_flange = ws.base_T_flange.linear();
  CorrectionChannel channel(256);
  const double filter_alpha = c.controller.egm_filter_s > 0 ? 1.0 - std::exp(-dt / c.controller.egm_filter_s) : 1.0;
  const double daq_period = 1.0 / c.sensor.rate_hz;
  const double tracker_period = 1.0 / c.tracker.rate_hz;
  double next_daq = daq_period, next_cycle = c.online.cycle_s, next_tracker = schedule.settle_s;
  const double motion_end = schedule.duration_s();
  const std::size_t expected = static_cast<std::size_t>(schedule.motion_s() * c.tracker.rate_hz) + 2;
  out.trace.reserve(expected);
  double lap_angle_start = 0.0;
  bool lap_open = false;
  int lap_direction = 0;
  CorrectionMessage msg;
  EgmCodec codec(n);
  std::array<unsigned char, 2048> packet{};
  std::array<JointVector, 64> planned_sent;
  planned_sent.fill(JointVector::Zero(n));
  std::uint32_t seqno = 0;

  auto model_force_base = [&](double t_s) {
    Pose p = Pose::Identity();
    p.translation() = circle_at(c, schedule.angle(t_s));
    return Vector3(force_model.wrench_at(0, p).head<3>());
  };

  for (long k = 1; k <= ticks; ++k) {
    const double t = static_cast<double>(k) * dt;
    program.at(schedule.angle(t), q_plan);
    if (channel.pop_arrived(t, msg)) {
      offset_target = msg.offset_rad;  // the correction as an offset from the planned joints
    }
    offset += (offset_target - offset) * filter_alpha;
    q_cmd = q_plan + offset;

    Wrench w = Wrench::Zero();
    if (loaded) {
      ldbb.advance(dt);
      w = ldbb.wrench(p_prev, v_prev);
    }
    drift.advance(dt);
    // Drift moves the whole arm (thermal growth, repeatability), so the LDBB sees it too.
    const Vector3 p = drift.apply(robot.solve(ws, q_cmd, w, state));
    base_R_flange = ws.base_T_flange.linear();

    if (online) {
      for (; next_daq <= t + 1e-12; next_daq += daq_period) {
        Vector3 raw = sensor.sample(w.head<3>(), base_R_flange);
        if (spec.strategy == Strategy::kHybrid) {
          // Online part of the hybrid strategy: only measured minus modelled force is corrected
          // online (the model's part is in the offline program).
          raw -= coupling * (base_R_flange.transpose() * model_force_base(next_daq));
        } else if (spec.strategy == Strategy::kOnlineLatency) {
          // Predicted wrench: the measurement plus the model's change over the lead along the path.
          raw += coupling *
                 (base_R_flange.transpose() * (model_force_base(next_daq + lead_s) - model_force_base(next_daq)));
        }
        ForceSample s;
        s.t_s = next_daq;
        s.wrench_sensor.head<3>() = raw;
        compensator->push_force(s);
      }
      if (t + 1e-12 >= next_cycle) {
        next_cycle += c.online.cycle_s;
        // One exchange over the link; a packet that fails to encode or decode is dropped, as a lost
        // datagram would be, and the servo carries on with the last correction.
        [&] {
          // Controller -> sensor: EgmRobot with the feedback (motor-side command) and planned joints,
          // through the same codec a real UDP link uses.
          ++seqno;
          EgmRobotMessage robot_msg;
          robot_msg.seqno = seqno;
          robot_msg.tm_ms = egm_time_stamp_ms(t);  // wraps like the controller clock
          robot_msg.feedback_joints_deg = q_cmd * (180.0 / kPi);
          robot_msg.planned_joints_deg = q_plan * (180.0 / kPi);
          robot_msg.motor_state = 1;
          robot_msg.mci_state = 3;
          robot_msg.rapid_exec_state = 2;
          planned_sent[seqno % planned_sent.size()] = q_plan;
          const std::size_t robot_bytes = codec.encode_robot(robot_msg, packet.data(), packet.size());
          EgmRobotMessage received;
          if (robot_bytes == 0 || codec.decode_robot(packet.data(), robot_bytes, received) != EgmDecodeStatus::kOk) {
            ++out.corrections_dropped;
            return;
          }
          // Sensor side: the compensation cycle. The latency-compensated strategy evaluates the
          // deflection where the arm will be when the correction takes effect.
          CycleInput in;
          in.t_s = t;
          in.q_feedback = received.feedback_joints_deg * (kPi / 180.0);
          if (lead_s > 0.0) {
            program.at(schedule.angle(t + lead_s), in.q_planned);
          } else {
            in.q_planned = received.planned_joints_deg * (kPi / 180.0);
          }
          const CycleOutput o = compensator->step(in);
          ++out.online_cycles;
          out.max_tcp_correction_m = std::max(out.max_tcp_correction_m, o.tcp_correction_m);
          if (static_cast<int>(o.status) < 0) return;
          EgmSensorMessage reply;
          reply.seqno = received.seqno;
          reply.tm_ms = received.tm_ms;
          reply.planned_joints_deg = received.planned_joints_deg - o.dtheta * (180.0 / kPi);
          const std::size_t sensor_bytes = codec.encode_sensor(reply, packet.data(), packet.size());
          // Controller: decodes the target and turns it into an offset from the planned joints it
          // reported under that sequence number.
          EgmSensorMessage target;
          if (sensor_bytes == 0 || !codec.decode_sensor(packet.data(), sensor_bytes, target)) {
            ++out.corrections_dropped;
            return;
          }
          CorrectionMessage m;
          m.reference_s = t;
          m.arrival_s = t + c.online.compute_delay_s + c.controller.egm_delay_s;
          m.offset_rad = target.planned_joints_deg * (kPi / 180.0) - planned_sent[target.seqno % planned_sent.size()];
          if (!channel.push(m)) ++out.corrections_dropped;
        }();
      }
    }

    // Tracker samples between the last servo tick and this one (TCP interpolated linearly).
    for (; next_tracker <= t + 1e-12 && next_tracker <= motion_end + 1e-12; next_tracker += tracker_period) {
      const double f = (next_tracker - (t - dt)) / dt;
      const Vector3 pt = p_prev + (p - p_prev) * f;
      const int dir = schedule.direction(next_tracker);
      const double angle = schedule.angle(next_tracker);
      if (!lap_open || dir != lap_direction || std::abs(angle - lap_angle_start) >= 2.0 * kPi - 1e-9) {
        if (dir != 0) {
          out.lap_start.push_back(out.trace.size());
          lap_angle_start = angle;
          lap_direction = dir;
          lap_open = true;
        }
      }
      TrackerSample s;
      s.t_s = next_tracker - schedule.settle_s;
      s.p_m = pt + c.tracker.noise_m * Vector3(normal(tracker_rng), normal(tracker_rng), normal(tracker_rng));
      out.trace.push_back(s);
    }
    v_prev = (p - p_prev) / dt;
    p_prev = p;
  }
  return out;
}

}  // namespace deflex::cell
