// Broken preconditions of the path functions refused in every build type (the tests run in Release in
// CI): a largest joint step that is NaN, zero or negative, and a timed path through a pose that is not
// finite. Before, a NaN step bound switched the jump check off without a word (any jump passed), a
// negative one failed the second point as a "jump" of a few hundredths of a degree, and a NaN pose
// came out as a time stamp "not a finite number" at a point of the trajectory instead of the pose.
#include <cmath>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "deflex/paths/circle_path.hpp"
#include "deflex/paths/joint_trajectory.hpp"
#include "deflex/paths/path_ik.hpp"
#include "deflex/paths/path_spec.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/errors.hpp"
#include "support/error_of.hpp"

namespace deflex {
namespace {

const Eigen::Quaterniond kDownwardTool(0.0, 0.0, 1.0, 0.0);  // tool z along -z of the base

TEST(PathPreconditions, AJointStepBoundThatIsNotAPositiveNumberIsRefusedAtSetUp) {
  const RobotModel model = builtin_irb6700();
  const std::vector<Pose> poses = sample_circle(default_circle(), kDownwardTool);
  for (const double bound : {kNaN, 0.0, -0.1, -std::numeric_limits<double>::infinity()}) {
    PathIkOptions options;
    options.max_joint_step_rad = bound;
    EXPECT_THROW(PathIkSolver(model, IkRequest{}, options), InputError) << bound;
    const std::string error = test::error_of([&] { (void)solve_path_ik(model, poses, IkRequest{}, options); });
    EXPECT_NE(error.find("max_joint_step_rad"), std::string::npos) << bound << ": " << error;
  }
}

TEST(PathPreconditions, ATimedPathThroughANonFinitePoseNamesThePose) {
  const RobotModel model = builtin_irb6700();
  std::vector<Pose> poses = sample_circle(default_circle(), kDownwardTool);
  const JointPath path = solve_path_ik(model, poses, IkRequest{});
  poses[4].translation().y() = kNaN;
  const std::string error = test::error_of([&] { (void)trajectory_at_tcp_speed(poses, path.q, 0.02, model); });
  EXPECT_NE(error.find("pose 4"), std::string::npos) << error;
  EXPECT_NE(error.find("position"), std::string::npos) << error;
}

TEST(PathPreconditions, ACirclePointAtANonFiniteAngleOrOnANonFiniteCircleIsRefused) {
  // Before: a NaN angle, centre or radius gave a NaN point without an error.
  const CirclePath circle = default_circle();
  std::string error = test::error_of([&] { (void)circle_point(circle, kNaN); });
  EXPECT_NE(error.find("angle"), std::string::npos) << error;
  CirclePath no_radius = circle;
  no_radius.radius_m = std::numeric_limits<double>::infinity();
  error = test::error_of([&] { (void)circle_point(no_radius, 0.0); });
  EXPECT_NE(error.find("radius"), std::string::npos) << error;
  // A finite one lies on the circle: at its radius from the centre.
  EXPECT_NEAR((circle_point(circle, 1.0) - circle.centre_m).norm(), circle.radius_m, 1e-12);
}

}  // namespace
}  // namespace deflex
