// The commanded TCP path with its times, for time alignment: from a Cartesian CSV (t_s and x_mm..z_mm
// or x_m..z_m), a joint trajectory (t_s,q1_deg,...) or deflex's online cycle log (program_t_s and
// q_nominal1_deg, ...), the joint forms through the robot's forward kinematics.
#pragma once

#include <string>

#include "deflex/model/robot_model.hpp"
#include "deflex/model/tracker_trace.hpp"

namespace deflex {

/// What the file was read as ("Cartesian path", "joint trajectory", "cycle log").
struct CommandedPath {
  TrackerTrace trace;  ///< TCP positions (m, base frame) at program time (s)
  std::string kind;
};

/// Reads the file and, for the joint forms, computes the TCP with `model` (nullptr: refused with a
/// message saying a robot is needed). Times must increase strictly (a cycle log's repeated cycles of
/// one program time are kept once). Throws DataError naming the file, line and column.
CommandedPath read_commanded_path(const std::string& path, const RobotModel* model);

}  // namespace deflex
