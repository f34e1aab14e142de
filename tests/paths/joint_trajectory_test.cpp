// The timed joint trajectory a streaming link holds: it passes through its points, its velocity is
// the derivative of its position (central differences), it starts and ends at rest, holds outside
// its times, and refuses what the robot cannot follow (time order, limits, speed) naming the line and
// joint. CSV round trip.
#include <cmath>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "deflex/paths/joint_trajectory.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/errors.hpp"
#include "support/allocation_guard.hpp"

namespace deflex {
namespace {

JointVector deg6(double a, double b, double c, double d, double e, double f) {
  JointVector q(6);
  q << a, b, c, d, e, f;
  return q * (kPi / 180.0);
}

JointTrajectory wave(const RobotModel& robot) {
  std::vector<double> t;
  std::vector<JointVector> q;
  for (int i = 0; i <= 40; ++i) {
    const double ti = 0.1 * i + 0.02 * std::sin(i);  // uneven spacing
    t.push_back(ti);
    q.push_back(deg6(10 * std::sin(0.5 * ti), 20 + 5 * std::cos(0.3 * ti), 10, 0, 60 - 4 * ti, 3 * ti));
  }
  return JointTrajectory(t, q, robot, "wave");
}

TEST(JointTrajectory, PassesThroughItsPointsWithVelocityTheDerivativeOfPosition) {
  const RobotModel robot = builtin_irb6700();
  const JointTrajectory traj = wave(robot);
  JointVector q(6), qd(6), qa(6), qb(6);
  for (std::size_t i = 0; i < traj.size(); ++i) {
    traj.sample(traj.times_s()[i], q);
    EXPECT_LT((q - traj.points()[i]).norm(), 1e-12) << i;
  }
  double worst = 0.0;
  for (double t = 0.013; t < traj.end_time_s(); t += 0.0371) {
    traj.sample(t, q, &qd);
    const double h = 1e-6;
    traj.sample(t + h, qa);
    traj.sample(t - h, qb);
    worst = std::max(worst, ((qa - qb) / (2 * h) - qd).norm());
  }
  EXPECT_LT(worst, 1e-6);
  // At rest at both ends, and held outside the times.
  traj.sample(traj.start_time_s(), q, &qd);
  EXPECT_EQ(qd.norm(), 0.0);
  traj.sample(traj.end_time_s() + 5.0, q, &qd);
  EXPECT_EQ(q, traj.points().back());
  EXPECT_EQ(qd.norm(), 0.0);
  traj.sample(-3.0, q, &qd);
  EXPECT_EQ(q, traj.points().front());
  // A hold in the middle stays a hold (no overshoot out of it).
  const JointTrajectory hold(
      {0, 1, 2, 3},
      {deg6(0, 20, 10, 0, 60, 0), deg6(5, 20, 10, 0, 60, 0), deg6(5, 20, 10, 0, 60, 0), deg6(10, 20, 10, 0, 60, 0)},
      robot);
  for (double t = 1.0; t <= 2.0; t += 0.05) {
    hold.sample(t, q);
    EXPECT_NEAR(q[0], deg_to_rad(5.0), 1e-12) << t;
  }
  test::AllocationGuard guard;
  for (int i = 0; i < 100; ++i) traj.sample(0.037 * i, q, &qd);
  EXPECT_EQ(guard.allocations(), 0u);
}

TEST(JointTrajectory, RefusesWhatTheRobotCannotFollowNamingTheLineAndJoint) {
  const RobotModel robot = builtin_irb6700();
  const auto error = [&](const std::vector<double>& t, const std::vector<JointVector>& q) {
    try {
      JointTrajectory(t, q, robot, "p.csv", {2, 3, 4});
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const JointVector a = deg6(0, 20, 10, 0, 60, 0);
  EXPECT_NE(error({0, 1, 1}, {a, a, a}).find("p.csv:4: time t_s = 1 s does not increase"), std::string::npos);
  EXPECT_NE(error({0, std::nan(""), 2}, {a, a, a}).find("p.csv:3: time t_s is not a finite number"), std::string::npos);
  EXPECT_NE(error({0, 1, 2}, {a, deg6(0, 20, 75, 0, 60, 0), a}).find("p.csv:3: joint 3 at 75.0000 deg is beyond"),
            std::string::npos);
  // Joint 1's limit is 100 deg/s; a 10 deg step over 0.1 s from rest would peak at 150 deg/s.
  const std::string fast = error({0, 0.1, 0.2}, {a, deg6(10, 20, 10, 0, 60, 0), deg6(10, 20, 10, 0, 60, 0)});
  EXPECT_NE(fast.find("p.csv:3: joint 1 would move at 150.00 deg/s"), std::string::npos) << fast;
  EXPECT_THROW(JointTrajectory({0}, {a}, robot), InputError);
  // The same step over 0.2 s peaks at 75 deg/s: accepted, and its peak is reported.
  const JointTrajectory ok({0, 0.2}, {a, deg6(10, 20, 10, 0, 60, 0)}, robot);
  EXPECT_NEAR(rad_to_deg(ok.peak_speed()[0]), 75.0, 1e-9);
}

TEST(JointTrajectory, CsvRoundTripAndBadFiles) {
  const RobotModel robot = builtin_irb6700();
  const JointTrajectory traj = wave(robot);
  const std::string path = ::testing::TempDir() + "/traj.csv";
  traj.write_csv(path, "a test");
  const JointTrajectory back = JointTrajectory::read_csv(path, robot);
  ASSERT_EQ(back.size(), traj.size());
  for (std::size_t i = 0; i < traj.size(); ++i) {
    EXPECT_NEAR(back.times_s()[i], traj.times_s()[i], 1e-9);
    EXPECT_LT((back.points()[i] - traj.points()[i]).cwiseAbs().maxCoeff(), 1e-11);
  }
  std::ofstream(path)
      << "t_s,q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg,q7_deg\n0,0,20,10,0,60,0,0\n1,0,20,10,0,60,0,0\n";
  EXPECT_THROW((void)JointTrajectory::read_csv(path, robot), DataError);
  std::ofstream(path) << "t_s,q1_deg,q2_deg,q3_deg,q4_deg,q5_deg\n0,0,20,10,0,60\n";
  EXPECT_THROW((void)JointTrajectory::read_csv(path, robot), DataError);
  std::filesystem::remove(path);
}

TEST(JointTrajectory, TimedAtATcpSpeed) {
  const RobotModel robot = builtin_irb6700();
  std::vector<Pose> poses;
  std::vector<JointVector> q;
  for (int i = 0; i < 5; ++i) {
    Pose p = Pose::Identity();
    p.translation() = Vector3(1.5 + 0.01 * i, 0.0, 1.0);  // 10 mm apart
    poses.push_back(p);
    q.push_back(deg6(0, 20 + 0.2 * i, 10, 0, 60, 0));
  }
  const JointTrajectory t = trajectory_at_tcp_speed(poses, q, 0.02, robot, 1.5);
  ASSERT_EQ(t.size(), 6u);  // the hold adds a point
  EXPECT_DOUBLE_EQ(t.times_s()[1], 1.5);
  EXPECT_NEAR(t.end_time_s(), 1.5 + 4 * 0.5, 1e-12);  // 40 mm at 20 mm/s
  EXPECT_THROW((void)trajectory_at_tcp_speed(poses, q, 0.0, robot), InputError);
  EXPECT_THROW((void)trajectory_at_tcp_speed(poses, q, 0.02, robot, -1.0), InputError);
}

}  // namespace
}  // namespace deflex
