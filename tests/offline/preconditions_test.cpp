// Broken preconditions of the offline compensation refused in every build type (the tests run in
// Release in CI): a desired TCP pose that is not finite. Before, a constant load never looked at the
// pose, so compensate_path returned points whose pose and residual were NaN (and whose figures
// silently left them out); a tool-frame load was refused, but as a "non-finite wrench" of the force
// model, not as the pose the caller gave.
#include <cmath>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "deflex/force/constant_wrench_model.hpp"
#include "deflex/force/tool_wrench_model.hpp"
#include "deflex/offline/compensate_path.hpp"
#include "deflex/offline/offline_csv.hpp"
#include "deflex/paths/path_spec.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/output_file.hpp"
#include "support/error_of.hpp"

namespace deflex {
namespace {

struct Circle {
  RobotModel model = builtin_irb6700();
  std::vector<Pose> poses = sample_circle(default_circle(), Eigen::Quaterniond(0.0, 0.0, 1.0, 0.0));
  JointPath path = solve_path_ik(model, poses, IkRequest{});
};

Wrench push_down() {
  Wrench w = Wrench::Zero();
  w[2] = -400.0;
  return w;
}

TEST(OfflinePreconditions, ADesiredPoseWithANaNPositionIsRefusedNamingThePoint) {
  Circle c;
  c.poses[3].translation().x() = kNaN;
  const ConstantWrenchModel force(push_down());
  const std::string error = test::error_of([&] { (void)compensate_path(c.model, c.path, c.poses, force); });
  EXPECT_NE(error.find("path point 3"), std::string::npos) << error;
  EXPECT_NE(error.find("position"), std::string::npos) << error;

  PathCompensator streamed(c.model, force);
  EXPECT_THROW((void)streamed.compensate(0, c.path.q[3], c.poses[3]), InputError);
}

TEST(OfflinePreconditions, ADesiredPoseWithAnInfiniteOrientationIsRefusedAsThePoseNotTheWrench) {
  Circle c;
  c.poses[5].linear()(1, 1) = std::numeric_limits<double>::infinity();
  const ToolWrenchModel force(push_down());
  const std::string error = test::error_of([&] { (void)compensate_path(c.model, c.path, c.poses, force); });
  EXPECT_NE(error.find("path point 5"), std::string::npos) << error;
  EXPECT_NE(error.find("orientation"), std::string::npos) << error;
}

TEST(OfflinePreconditions, ACsvRowWhoseCommandHasTheWrongJointCountIsRefused) {
  // Before: only the desired joints' count was checked, and a 5-joint command was read past its end
  // into a 6-joint row.
  Circle c;
  const ConstantWrenchModel force(push_down());
  std::vector<OfflinePoint> points = compensate_path(c.model, c.path, c.poses, force).points;
  OfflinePoint& bad = points[2];
  bad.q_command.conservativeResize(5);
  const std::string path = ::testing::TempDir() + "deflex_offline_preconditions.csv";
  OutputFile out(path, "offline CSV");  // never committed: nothing is left at the path
  OfflineCsvWriter writer(out, c.model.dof(), c.model.name(), force.describe(), true);
  writer.write(0, points[0]);
  const std::string error = test::error_of([&] { writer.write(2, bad); });
  EXPECT_NE(error.find("path point 2"), std::string::npos) << error;
  EXPECT_NE(error.find("5 command joints"), std::string::npos) << error;
}

}  // namespace
}  // namespace deflex
