// Opening a session's force source and taking its tare (see session_force.hpp).
#include "deflex/runtime/session_force.hpp"

#include <cmath>
#include <sstream>

#include <fmt/format.h>

#include "deflex/model/kinematics.hpp"
#include "deflex/runtime/session_settings.hpp"
#include "deflex/sensors/wrench_tare.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/input_ranges.hpp"
#include "deflex/text/parse_number.hpp"

namespace deflex::runtime {
namespace {

std::string name_of(const char* key) { return setting_name(*find_session_setting(key)); }

// "q1,...,qN" in degrees, one a joint.
JointVector tare_pose(const std::string& text, const RobotModel& robot) {
  std::vector<double> deg;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const std::string_view t = trim_view(item);
    const std::optional<double> v = parse_double(t);
    if (!v)
      throw InputError(fmt::format("{}: {} (value {})", name_of("tare_pose_deg"), not_a_number(t), deg.size() + 1));
    if (const auto bad = range_violation(*v, range::kAngleDeg)) {
      throw InputError(fmt::format("{}: value {}: {}", name_of("tare_pose_deg"), deg.size() + 1, *bad));
    }
    deg.push_back(*v);
  }
  if (deg.size() != static_cast<std::size_t>(robot.dof())) {
    throw InputError(fmt::format("{}: {} joints, the robot has {}", name_of("tare_pose_deg"), deg.size(), robot.dof()));
  }
  JointVector q(robot.dof());
  for (int i = 0; i < robot.dof(); ++i) q[i] = deg_to_rad(deg[static_cast<std::size_t>(i)]);
  return q;
}

void tare(const ForceConfig& f, const RobotModel& robot, const SensorConfig& sensor, const JointTrajectory* program,
          const OpenedForceSource& source, const LogSink& log) {
  if (sensor.bias_sensor.cwiseAbs().maxCoeff() > 0.0) {
    throw InputError(fmt::format(
        "{}: the sensor configuration {} gives a bias too ({:.3f} {:.3f} {:.3f} N ...): the offset would be taken out "
        "twice; set its bias to zero or leave the tare out",
        name_of("tare"), sensor.source, sensor.bias_sensor[0], sensor.bias_sensor[1], sensor.bias_sensor[2]));
  }
  TareSettings ts;
  ts.window_s = f.tare_window_s;
  ts.max_std_force_n = f.tare_max_std_n;
  ts.max_std_torque_nm = f.tare_max_std_nm;
  std::string pose_text = "no payload in the sensor configuration: the tare takes out all it reads";
  if (sensor.payload_mass_kg > 0.0) {
    JointVector q;
    if (!f.tare_pose_deg.empty()) {
      q = tare_pose(f.tare_pose_deg, robot);
      pose_text = "the payload's weight at the tare pose kept in the reading";
    } else if (program != nullptr) {
      q = program->points().front();
      pose_text = "the payload's weight at the program's start kept in the reading";
    } else {
      throw InputError(fmt::format(
          "{}: the sensor configuration has a payload, and this link streams no program: give the joints the arm "
          "holds during the tare, so that its weight is not taken out as an offset",
          name_of("tare_pose_deg")));
    }
    Workspace ws(robot);
    forward_kinematics(robot, ws, q);
    const Matrix3 base_R_sensor = ws.base_T_flange.linear() * sensor.flange_T_sensor.linear();
    ts.expected_wrench_sensor = payload_wrench_sensor(sensor.payload_mass_kg, sensor.payload_cog_sensor_m,
                                                      sensor.gravity_base_m_s2, base_R_sensor);
  }
  if (log) log(LogLevel::kInfo, fmt::format("tare: hold the arm still for {:g} s ({})", ts.window_s, pose_text));
  const std::string result = describe(source.rdt->tare(ts), ts);
  if (log) log(LogLevel::kInfo, fmt::format("tare: {}", result));
}

}  // namespace

OpenedForceSource open_session_force(const SessionConfig& config, const RobotModel& robot, SensorConfig& sensor,
                                     const JointTrajectory* program, const LogSink& log) {
  const ForceConfig& f = config.force;
  if (f.source.empty()) throw InputError(fmt::format("{}: required", name_of("force_source")));
  ForceSourceOptions fo;
  fo.loop = f.loop;
  fo.bind_address = config.network.bind_address;
  fo.rdt_calibration.spec = f.rdt_calibration;
  fo.rdt_calibration.rate_hz = f.rdt_rate_hz;
  fo.rdt_stream.buffered = f.rdt_buffered;
  OpenedForceSource source = open_force_source(f.source, fo);
  if (source.sample_rate_hz > 0.0 && std::abs(source.sample_rate_hz - sensor.sample_rate_hz) > 1e-9) {
    if (log) {
      log(LogLevel::kInfo,
          fmt::format("the force source streams at {:g} Hz: the low-pass filter is designed for it (the sensor "
                      "configuration says {:g} Hz)",
                      source.sample_rate_hz, sensor.sample_rate_hz));
    }
    sensor.sample_rate_hz = source.sample_rate_hz;
  }
  if (f.tare) tare(f, robot, sensor, program, source, log);
  return source;
}

}  // namespace deflex::runtime
