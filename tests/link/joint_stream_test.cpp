// The nominal a streaming link holds: the start check, the ramp-in blend (from where the arm is to
// the program, smooth at both ends), the program clock that stops in a silence, and the hold at the
// end, against the program sampled here.
#include <gtest/gtest.h>

#include "deflex/link/joint_stream.hpp"
#include "deflex/model/errors.hpp"
#include "deflex/model/robot_io.hpp"

namespace deflex {
namespace {

JointVector deg6(double a, double b, double c, double d, double e, double f) {
  JointVector q(6);
  q << a, b, c, d, e, f;
  return q * (kPi / 180.0);
}

std::shared_ptr<const JointTrajectory> line(const RobotModel& robot) {
  return std::make_shared<const JointTrajectory>(std::vector<double>{0.0, 2.0, 4.0},
                                                 std::vector<JointVector>{deg6(0, 20, 10, 0, 60, 0),
                                                                          deg6(4, 20, 10, 0, 60, 0),
                                                                          deg6(8, 20, 10, 0, 60, 0)},
                                                 robot);
}

TEST(JointStream, StartsWithinTheToleranceAndBlendsTheOffsetOut) {
  const RobotModel robot = builtin_irb6700();
  const auto program = line(robot);
  JointStreamConfig c;
  c.ramp_in_s = 0.5;
  JointStream stream(program, c);
  JointVector arm = program->points().front();
  arm[1] += deg_to_rad(1.2);
  EXPECT_FALSE(stream.begin(10.0, arm));  // 1.2 deg away
  EXPECT_NEAR(stream.distance()[1], deg_to_rad(1.2), 1e-12);
  arm[1] = program->points().front()[1] + deg_to_rad(0.6);
  ASSERT_TRUE(stream.begin(10.0, arm));
  JointVector q(6), qd(6), p(6);
  stream.advance(10.0, q, qd);
  EXPECT_LT((q - arm).norm(), 1e-12);  // the first nominal is where the arm is
  EXPECT_LT(qd.norm(), 1e-12);         // at rest
  // Halfway through the ramp, the smoothstep weight is 1/2.
  stream.advance(10.25, q, qd);
  program->sample(0.25, p);
  EXPECT_NEAR(q[1] - p[1], 0.5 * deg_to_rad(0.6), 1e-12);
  // After the ramp: the program itself.
  stream.advance(10.6, q, qd);
  program->sample(0.6, p);
  EXPECT_LT((q - p).norm(), 1e-12);
}

TEST(JointStream, ASilenceStopsTheProgramClockAndTheEndIsHeld) {
  const RobotModel robot = builtin_irb6700();
  const auto program = line(robot);
  JointStreamConfig c;
  c.ramp_in_s = 0.0;
  c.pause_after_s = 0.5;
  JointStream stream(program, c);
  JointVector q(6), qd(6);
  ASSERT_TRUE(stream.begin(0.0, program->points().front()));
  for (double t = 0.004; t <= 1.0; t += 0.004) stream.advance(t, q, qd);
  const double before = stream.program_time_s();
  EXPECT_NEAR(before, 1.0, 0.005);
  EXPECT_TRUE(stream.paused_at(1.8));  // 0.8 s without a message
  ASSERT_TRUE(stream.begin(1.8, q));   // the arm is where it stopped
  stream.advance(1.8, q, qd);
  EXPECT_NEAR(stream.program_time_s(), before, 1e-12);
  for (double t = 1.804; t <= 9.0; t += 0.004) stream.advance(t, q, qd);
  EXPECT_TRUE(stream.finished());
  EXPECT_EQ(q, program->points().back());
  EXPECT_EQ(qd.norm(), 0.0);
  JointStreamConfig bad;
  bad.ramp_in_s = -1.0;
  EXPECT_THROW(JointStream(program, bad), InputError);
}

}  // namespace
}  // namespace deflex
