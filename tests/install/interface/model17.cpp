// Every header of the model and of the robot files, and the text and version headers a model consumer includes,
// compiled as C++17 with warnings as errors; a small FK to link and run.
#include "deflex/model/arm_configuration.hpp"
#include "deflex/model/compliance.hpp"
#include "deflex/model/folded_chain.hpp"
#include "deflex/model/inverse_kinematics.hpp"
#include "deflex/model/kinematics.hpp"
#include "deflex/model/linear_algebra.hpp"
#include "deflex/model/opw_geometry.hpp"
#include "deflex/model/opw_ik.hpp"
#include "deflex/model/robot_model.hpp"
#include "deflex/model/tracker_trace.hpp"
#include "deflex/model/types.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/version.hpp"

#include <cstdio>

int main() {
  const deflex::RobotModel robot = deflex::builtin_irb6700();
  deflex::Workspace ws(robot);
  const double x = deflex::tcp_pose(robot, ws, deflex::JointVector::Zero(6)).translation().x();
  std::printf("C++%ld: deflex %s, TCP x %.3f m\n", __cplusplus, deflex::kVersion, x);
  return x > 1.0 && x < 3.0 ? 0 : 1;
}
