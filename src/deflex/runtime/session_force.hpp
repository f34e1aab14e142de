// The force source a session reads, opened from its configuration (config.force: udp:PORT, csv:FILE,
// rdt:HOST[:PORT]), and the sensor's tare taken on it before the session starts: one place for
// `deflex online` and Python's deflex.Session, so both open and tare a sensor the same way.
#pragma once

#include <string>

#include "deflex/model/robot_model.hpp"
#include "deflex/online/sensor_config.hpp"
#include "deflex/paths/joint_trajectory.hpp"
#include "deflex/runtime/session_config.hpp"
#include "deflex/runtime/session_report.hpp"
#include "deflex/sensors/force_source_spec.hpp"

namespace deflex::runtime {

/// Opens config.force.source and, with config.force.tare, takes the sensor's offset with the arm still
/// (the payload's weight at the tare pose left in the reading: the pipeline's gravity compensation
/// takes it out at every pose). `sensor` gets the rate the source states (the low-pass filter is
/// designed for the rate the samples come at). `program` (may be null) gives the tare pose when
/// none is set. Throws InputError naming the setting (a bias in the sensor configuration with a tare,
/// a payload without a tare pose, a bad pose), and what open_force_source() throws.
[[nodiscard]] OpenedForceSource open_session_force(const SessionConfig& config, const RobotModel& robot,
                                                   SensorConfig& sensor, const JointTrajectory* program,
                                                   const LogSink& log = {});

}  // namespace deflex::runtime
