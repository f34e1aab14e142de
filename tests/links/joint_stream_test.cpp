// The nominal a streaming link holds: the start check against the anchor, the ramp-in blend (from what
// the controller holds to the program, smooth at both ends, the correction counted once), the program
// clock that moves only by cycles consumed, and the hold at the end, against the program sampled here.
#include <gtest/gtest.h>

#include "deflex/link/joint_stream.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

JointVector deg6(double a, double b, double c, double d, double e, double f) {
  JointVector q(6);
  q << a, b, c, d, e, f;
  return q * (kPi / 180.0);
}

std::shared_ptr<const JointTrajectory> line(const RobotModel& robot) {
  return std::make_shared<const JointTrajectory>(
      std::vector<double>{0.0, 2.0, 4.0},
      std::vector<JointVector>{deg6(0, 20, 10, 0, 60, 0), deg6(4, 20, 10, 0, 60, 0), deg6(8, 20, 10, 0, 60, 0)}, robot);
}

TEST(JointStream, StartsWithinTheToleranceAndBlendsTheOffsetOut) {
  const RobotModel robot = builtin_irb6700();
  const auto program = line(robot);
  JointStreamConfig c;
  c.ramp_in_s = 0.5;
  JointStream stream(program, c);
  const JointVector zero = JointVector::Zero(6);
  JointVector arm = program->points().front();
  arm[1] += deg_to_rad(1.2);
  EXPECT_FALSE(stream.begin(arm, zero));  // 1.2 deg away
  EXPECT_FALSE(stream.started());
  EXPECT_NEAR(stream.distance()[1], deg_to_rad(1.2), 1e-12);
  arm[1] = program->points().front()[1] + deg_to_rad(0.6);
  ASSERT_TRUE(stream.begin(arm, zero));
  JointVector q(6), qd(6), blend(6), blend_d(6), p(6);
  stream.sample(q, qd, blend, blend_d);
  EXPECT_LT((q + blend - arm).norm(), 1e-12);  // the first nominal is where the arm is
  EXPECT_LT((qd + blend_d).norm(), 1e-12);     // at rest
  // Halfway through the ramp (0.25 s of 5 ms cycles consumed), the smoothstep weight is 1/2.
  for (int k = 0; k < 50; ++k) stream.consumed(0.005);
  stream.sample(q, qd, blend, blend_d);
  program->sample(0.25, p);
  EXPECT_LT((q - p).norm(), 1e-12);  // the program part is the program, un-blended
  EXPECT_NEAR(blend[1], 0.5 * deg_to_rad(0.6), 1e-12);
  // The blend's velocity there is the smoothstep's peak slope, 1.5 x offset / ramp.
  EXPECT_NEAR(blend_d[1], -1.5 * deg_to_rad(0.6) / 0.5, 1e-9);
  // After the ramp: the program itself.
  for (int k = 0; k < 80; ++k) stream.consumed(0.005);
  stream.sample(q, qd, blend, blend_d);
  program->sample(0.65, p);
  EXPECT_LT((q - p).norm(), 1e-12);
  EXPECT_EQ(blend.norm(), 0.0);
}

TEST(JointStream, TheCorrectionTheControllerAlreadyHoldsIsNotBlendedInTwice) {
  // A restart: the controller holds deflex's last command, program - dtheta. The blend then starts
  // at zero: the next command (program - dtheta) is exactly what the controller holds.
  const RobotModel robot = builtin_irb6700();
  const auto program = line(robot);
  JointStream stream(program, JointStreamConfig{});
  const JointVector dtheta = deg6(0.01, -0.03, 0.02, 0, 0.01, 0);
  ASSERT_TRUE(stream.begin(program->points().front() - dtheta, dtheta));
  JointVector q(6), qd(6), blend(6), blend_d(6);
  stream.sample(q, qd, blend, blend_d);
  EXPECT_EQ(blend.norm(), 0.0);
  // The old rule (blend from the arm against the program alone) would have applied dtheta twice.
  ASSERT_TRUE(stream.begin(program->points().front() - dtheta, JointVector::Zero(6)));
  stream.sample(q, qd, blend, blend_d);
  EXPECT_LT((blend + dtheta).norm(), 1e-15);
}

TEST(JointStream, TheProgramMovesOnlyByCyclesConsumedAndTheEndIsHeld) {
  const RobotModel robot = builtin_irb6700();
  const auto program = line(robot);
  JointStreamConfig c;
  c.ramp_in_s = 0.0;
  JointStream stream(program, c);
  JointVector q(6), qd(6), blend(6), blend_d(6);
  stream.consumed(0.004);  // before a session nothing moves
  EXPECT_EQ(stream.program_time_s(), 0.0);
  ASSERT_TRUE(stream.begin(program->points().front(), JointVector::Zero(6)));
  for (int k = 0; k < 250; ++k) stream.consumed(0.004);
  EXPECT_NEAR(stream.program_time_s(), 1.0, 1e-12);
  // However long nothing is consumed (a silence, a stalled PC), the program stays where it was.
  stream.sample(q, qd, blend, blend_d);
  const JointVector held = q;
  stream.sample(q, qd, blend, blend_d);
  EXPECT_EQ(q, held);
  for (int k = 0; k < 2000; ++k) stream.consumed(0.004);
  EXPECT_TRUE(stream.finished());
  stream.sample(q, qd, blend, blend_d);
  EXPECT_EQ(q, program->points().back());
  EXPECT_EQ(qd.norm(), 0.0);
  JointStreamConfig bad;
  bad.ramp_in_s = -1.0;
  EXPECT_THROW(JointStream(program, bad), InputError);
  bad.ramp_in_s = 1.0;
  bad.start_tolerance_rad = 0.0;
  EXPECT_THROW(JointStream(program, bad), InputError);
}

}  // namespace
}  // namespace deflex
