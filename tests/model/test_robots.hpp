// Robots used by the model tests, written as YAML text so the tests also exercise the loader.
#pragma once

#include <string>

#include "deflex/robotfile/robot_io.hpp"

namespace deflex::test {

/// A 6R arm in modified DH that is not ortho-parallel (no analytic IK): exercises the numerical
/// solver and the modified convention. Lengths in mm to exercise unit scaling.
inline RobotModel modified_dh_arm() {
  return load_robot_yaml_text(R"(
deflex_robot: 1
name: test arm (modified DH)
units: {length: mm, angle: deg}
kinematics:
  convention: modified_dh
  joints:
    - {a: 0,   alpha: 0,   d: 400, offset: 0,  min: -170, max: 170}
    - {a: 150, alpha: -90, d: 0,   offset: -90, min: -100, max: 100}
    - {a: 600, alpha: 0,   d: 30,  offset: 0,  min: -150, max: 150}
    - {a: 120, alpha: -90, d: 640, offset: 0,  min: -180, max: 180}
    - {a: 0,   alpha: 80,  d: 0,   offset: 0,  min: -120, max: 120}
    - {a: 0,   alpha: -90, d: 100, offset: 0,  min: -350, max: 350}
joint_stiffness_Nm_per_rad: [2.0e6, 1.5e6, 1.0e6, 3.0e5, 2.5e5, 1.5e5]
base_frame: {position: [10, -20, 30], rpy: [0, 0, 15]}
tool_frame: {position: [0, 0, 180], rpy: [0, 20, 0]}
)",
                              "test-modified-dh");
}

/// The built-in IRB6700 with a 300 mm tool tilted 30 degrees, like a spindle or the LDBB ball holder.
inline RobotModel irb6700_with_tool() {
  Pose tool = Pose::Identity();
  tool.translation() = Vector3(0.05, 0.0, 0.3);
  tool.linear() = Eigen::AngleAxisd(deg_to_rad(30.0), Vector3::UnitY()).toRotationMatrix();
  return builtin_irb6700().with_tool(tool);
}

}  // namespace deflex::test
