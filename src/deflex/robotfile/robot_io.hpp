// Loading and writing robot descriptions: deflex's YAML format, URDF serial chains, and the
// built-in ABB IRB 6700-300/2.70. Format reference: docs/robot-file.md.
#pragma once

#include <string>

#include "deflex/model/robot_model.hpp"

namespace deflex {

/// Loads a robot from a `.yaml`/`.yml` (deflex format) or `.urdf` file. Throws ModelError naming
/// the file, line and field. A bare URDF carries no joint stiffness (has_stiffness() is false).
RobotModel load_robot(const std::string& path);

/// Parses deflex robot YAML from text. `source` names it in errors; relative URDF paths are
/// resolved against `base_dir`.
RobotModel load_robot_yaml_text(const std::string& text, const std::string& source, const std::string& base_dir = ".");

/// The built-in ABB IRB 6700-300/2.70 (data/robots/abb_irb6700_300_270.yaml, compiled in).
RobotModel builtin_irb6700();
/// The built-in robot's YAML text.
const std::string& builtin_irb6700_yaml();

/// `path` if non-empty (load_robot), else the built-in IRB6700.
RobotModel load_robot_or_builtin(const std::string& path);

/// Serial chain of a URDF from `base_link` to `tip_link`. Empty names choose it as
/// choose_urdf_chain() does: base_link -> tool0 when both exist (ROS-Industrial), else the root and
/// the one leaf ending the longest chain of movable joints; joints off the chain are listed in
/// RobotDescription::notes. Fixed joints fold into the transforms; revolute and continuous joints
/// become JointSpecs. Throws ModelError naming the file, line and joint (loops, two parents, a mimic
/// or prismatic joint on the chain, ...).
RobotDescription load_urdf_chain(const std::string& path, const std::string& base_link = "",
                                 const std::string& tip_link = "");

/// deflex YAML for a model (lengths m, angles deg): DH table or URDF reference, limits,
/// stiffness with its note, base, tool and WAP frames. load_robot_yaml_text() reads it back.
std::string robot_to_yaml(const RobotModel& model);

/// Writes robot_to_yaml() to a file of its own (output_file.hpp). Throws InputError or OutputError.
void write_robot_yaml(const RobotModel& model, const std::string& path);

}  // namespace deflex
