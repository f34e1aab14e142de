// The controller's queue of joint moves with zones against closed forms worked out here: a move from
// rest (ramp up, constant velocity, ramp down to the point), two moves blended in a zone (the arm
// passes b + (v2 - v1) tb / 4 at the corner's time), a move that comes too late (the arm stops at the
// point, then starts again from rest), StopMove (the arm stops at x + v ts / 2), the queue's capacity,
// and a move slowed to the joints' speed limits.
#include <cmath>

#include <gtest/gtest.h>

#include "deflex/cell/joint_move_queue.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/errors.hpp"

namespace deflex::cell {
namespace {

JointVector start() {
  JointVector q(6);
  q << 0.1, 0.4, 0.2, 0.0, 0.9, 0.0;
  return q;
}

JointVector step(double j1, double j2 = 0.0) {
  JointVector d = JointVector::Zero(6);
  d[0] = j1;
  d[1] = j2;
  return d;
}

JointMoveConfig fine_points() {
  JointMoveConfig c;
  c.zone_m = 0.0;  // fine: every move ends at rest
  c.latency_s = 0.05;
  c.ramp_s = 0.1;
  c.stop_time_s = 0.1;
  return c;
}

JointMoveConfig big_zone() {
  JointMoveConfig c = fine_points();
  c.zone_m = 10.0;  // larger than any move here: each zone is half the move (tb = T / 2)
  return c;
}

void expect_near(const JointVector& a, const JointVector& b, double tol = 1e-12) {
  EXPECT_LT((a - b).cwiseAbs().maxCoeff(), tol) << a.transpose() << "\n" << b.transpose();
}

TEST(JointMoveQueue, AMoveFromRestRampsUpRunsAndStopsExactlyAtItsPoint) {
  const RobotModel robot = builtin_irb6700();
  JointMoveQueue q(fine_points(), robot, start(), 4);
  const JointVector d = step(0.01);  // 0.1 rad/s over 0.1 s: far below any speed limit
  const JointVector v = d / 0.1;
  ASSERT_TRUE(q.push(0.0, start() + d, 0.1));
  // Known at 0, startable after the 50 ms latency; ramp tb = 50 ms centred on s = 0.1 s.
  expect_near(q.advance(0.05), start());
  EXPECT_TRUE(q.at_rest() || q.velocity().isZero());
  expect_near(q.advance(0.09), start() + (0.04 * 0.04 / (4.0 * 0.05)) * v);
  expect_near(q.advance(0.15), start() + 0.05 * v);  // end of the ramp: on the line a + v (t - s)
  // Fine point: ramp down over [0.15, 0.25]: at 0.2, b - tb v + v tau - v tau^2 / (4 tb).
  expect_near(q.advance(0.2), start() + (0.05 + 0.05 - 0.05 * 0.05 / 0.2) * v);
  expect_near(q.advance(0.25), start() + d);
  expect_near(q.advance(1.0), start() + d);
  EXPECT_TRUE(q.at_rest());
  EXPECT_EQ(q.counters().taken, 1u);
  EXPECT_EQ(q.counters().corner_failures, 0u);  // a fine point is no failure
}

TEST(JointMoveQueue, TwoMovesBlendInTheZoneAndMissTheCornerByDvTbOverFour) {
  const RobotModel robot = builtin_irb6700();
  JointMoveQueue q(big_zone(), robot, start(), 4);
  const JointVector d1 = step(0.01), d2 = step(0.0, 0.012);
  ASSERT_TRUE(q.push(0.0, start() + d1, 0.1));
  ASSERT_TRUE(q.push(0.0, start() + d1 + d2, 0.1));
  const JointVector v1 = d1 / 0.1, v2 = d2 / 0.1;
  // Move 1 runs on [0.1, 0.2] nominally (its ramp from rest spans [0.05, 0.15]); the zone blend spans
  // [0.15, 0.25]; at 0.2 the arm is at b1 + (v2 - v1) tb / 4 with tb = 0.05.
  expect_near(q.advance(0.15), start() + 0.05 * v1);
  expect_near(q.advance(0.2), start() + d1 + (0.05 / 4.0) * (v2 - v1));
  EXPECT_EQ(q.counters().blended, 1u);
  expect_near(q.advance(0.25), start() + d1 + 0.05 * v2);  // on move 2's line a2 + v2 (t - 0.2)
  expect_near(q.advance(0.35), start() + d1 + d2);         // move 2 ramps down to its point
  expect_near(q.advance(0.40), start() + d1 + d2);
  EXPECT_EQ(q.counters().corner_failures, 1u);  // no third move came: the arm stopped there
}

TEST(JointMoveQueue, AMoveKnownTooLateForTheZoneStopsTheArmAtThePointFirst) {
  const RobotModel robot = builtin_irb6700();
  JointMoveQueue q(big_zone(), robot, start(), 4);
  const JointVector d1 = step(0.01), d2 = step(0.01);
  ASSERT_TRUE(q.push(0.0, start() + d1, 0.1));
  q.advance(0.14);
  // Known at 0.14: usable from 0.19, but the blend had to be decided at 0.15.
  ASSERT_TRUE(q.push(0.14, start() + d1 + d2, 0.1));
  expect_near(q.advance(0.25), start() + d1);  // decelerated to rest at the point
  EXPECT_EQ(q.counters().corner_failures, 1u);
  // From rest again at 0.25: ramp to 0.35, line, ramp down, at the point at 0.25 + 0.05 + 0.1 + 0.05.
  expect_near(q.advance(0.30), start() + d1 + (0.05 * 0.05 / 0.2) * (d2 / 0.1));
  expect_near(q.advance(0.45), start() + d1 + d2);
  EXPECT_EQ(q.counters().blended, 0u);
}

TEST(JointMoveQueue, StopMoveEmptiesTheQueueAndStopsAtXPlusVTsOverTwo) {
  const RobotModel robot = builtin_irb6700();
  JointMoveQueue q(fine_points(), robot, start(), 4);
  const JointVector d = step(0.01);
  const JointVector v = d / 0.1;
  ASSERT_TRUE(q.push(0.0, start() + d, 0.1));
  ASSERT_TRUE(q.push(0.0, start() + 2 * d, 0.1));
  // At 0.12 the arm is on its ramp: x = q0 + v 0.07^2 / 0.2, speed 0.7 v.
  q.stop(0.12);
  EXPECT_EQ(q.queued(), 0u);
  EXPECT_EQ(q.counters().stops, 1u);
  const JointVector x = start() + (0.07 * 0.07 / 0.2) * v;
  expect_near(q.advance(0.17), x + (0.05 - 0.05 * 0.05 / 0.2) * (0.7 * v));
  expect_near(q.advance(0.5), x + 0.05 * (0.7 * v));
  EXPECT_TRUE(q.at_rest());
  q.stop(0.6);  // at rest: nothing to stop
  EXPECT_EQ(q.counters().stops, 1u);
}

TEST(JointMoveQueue, AFullQueueRefusesAMoveUntilThePlannerTakesOne) {
  const RobotModel robot = builtin_irb6700();
  JointMoveQueue q(big_zone(), robot, start(), 2);
  EXPECT_TRUE(q.push(0.0, start() + step(0.01), 0.1));
  EXPECT_TRUE(q.push(0.0, start() + step(0.02), 0.1));
  EXPECT_FALSE(q.push(0.0, start() + step(0.03), 0.1));
  EXPECT_EQ(q.queued(), 2u);
  q.advance(0.049);
  EXPECT_FALSE(q.push(0.049, start() + step(0.03), 0.1));
  q.advance(0.05);  // the first is taken once its latency has passed
  EXPECT_EQ(q.queued(), 1u);
  EXPECT_TRUE(q.push(0.05, start() + step(0.03), 0.1));
  EXPECT_THROW(JointMoveQueue(fine_points(), robot, start(), 0), InputError);
  JointMoveConfig bad = fine_points();
  bad.ramp_s = 0.0;
  EXPECT_THROW(JointMoveQueue(bad, robot, start(), 2), InputError);
}

TEST(JointMoveQueue, AMoveFasterThanAJointCanGoTakesLonger) {
  const RobotModel robot = builtin_irb6700();
  ASSERT_TRUE(robot.has_max_speed());
  JointMoveQueue q(fine_points(), robot, start(), 4);
  const double vmax = robot.max_speed()[0];
  const JointVector d = step(0.5 * vmax);  // asked in 0.1 s, possible in 0.5 s
  ASSERT_TRUE(q.push(0.0, start() + d, 0.1));
  q.advance(0.05);
  EXPECT_EQ(q.counters().stretched, 1u);
  // Ramp tb = 0.05 from 0.05, line at vmax from s = 0.1 s, ramp down from 0.55 to 0.65.
  expect_near(q.advance(0.3), start() + (0.2 * vmax) * step(1.0), 1e-12);
  EXPECT_LE(q.velocity().cwiseAbs().maxCoeff(), vmax * (1 + 1e-12));
  expect_near(q.advance(0.65), start() + d);
}

}  // namespace
}  // namespace deflex::cell
