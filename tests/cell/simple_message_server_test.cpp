// The simulated RAPID streaming server against frames written by hand from the protocol facts
// (support/simple_message_frames.hpp), in both byte orders: SUCCESS replies carrying the header only,
// FAILURE when the buffer is full, STOP_TRAJECTORY stopping the arm, no reply to a frame of another
// type or too short, an out-of-step LENGTH closing the connection, JOINT_POSITION and ROBOT_STATUS
// published every 0.1 s with the arm's joints, an out-of-range point refused and the motion stopped,
// an emergency stop reported; the arm reaches the points it took.
#include <gtest/gtest.h>

#include "deflex/cell/simple_message_server.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/transport/memory_stream.hpp"
#include "support/simple_message_frames.hpp"

namespace deflex::cell {
namespace {

using test::Bytes;

JointVector server_start() {
  JointVector q(6);
  q << 0.1, 0.4, 0.2, 0.0, 0.9, 0.0;
  return q;
}

std::vector<float> floats(const JointVector& q) {
  std::vector<float> f;
  for (int j = 0; j < q.size(); ++j) f.push_back(static_cast<float>(q[j]));
  return f;
}

// The client side, by hand: writes hand-made frames, collects what comes back.
struct Client {
  RobotModel robot = builtin_irb6700();
  ManualClock clock;
  MemoryStreamPair motion{clock, 0.0002};
  MemoryStreamPair state{clock, 0.0002};
  SimpleMessageServerConfig config;
  std::unique_ptr<SimpleMessageServer> server;
  bool big;
  double t = 0.0;
  Bytes motion_in, state_in;

  explicit Client(bool big_endian, std::size_t buffer = 4) : big(big_endian) {
    config.byte_order = big ? simple_message::ByteOrder::kBig : simple_message::ByteOrder::kLittle;
    config.buffer_points = buffer;
    server = std::make_unique<SimpleMessageServer>(config, robot, server_start(), motion.server(), state.server());
  }
  void send(const Bytes& b) { ASSERT_EQ(motion.client().write(b.data(), b.size()), static_cast<long>(b.size())); }
  // One 4 ms servo tick, then read what reached the client.
  void tick() {
    t += 0.004;
    clock.set(t);
    server->tick(t);
    clock.set(t + 0.0003);
    unsigned char buf[4096];
    for (long n = motion.client().read(buf, sizeof(buf)); n > 0; n = motion.client().read(buf, sizeof(buf))) {
      motion_in.insert(motion_in.end(), buf, buf + n);
    }
    for (long n = state.client().read(buf, sizeof(buf)); n > 0; n = state.client().read(buf, sizeof(buf))) {
      state_in.insert(state_in.end(), buf, buf + n);
    }
  }
  std::vector<test::HandParsed> replies() { return test::hand_split(big, motion_in); }
  std::vector<test::HandParsed> topics() { return test::hand_split(big, state_in); }
};

TEST(SimpleMessageServer, AcceptsPointsWithHeaderOnlySuccessRepliesAndRunsThem) {
  for (bool big : {false, true}) {
    Client c(big);
    JointVector target = server_start();
    target[0] += 0.01;
    c.send(test::hand_traj_pt(big, 2, 0, 0, floats(target), 0.0f, 0.1f));
    c.tick();
    const auto r = c.replies();
    ASSERT_EQ(r.size(), 1u);
    // ABB's RAPID server: LENGTH 12, JOINT_TRAJ_PT, SERVICE_REPLY, SUCCESS, no data.
    EXPECT_EQ(r[0].length, 12);
    EXPECT_EQ(r[0].type, 11);
    EXPECT_EQ(r[0].comm, 3);
    EXPECT_EQ(r[0].reply, 1);
    EXPECT_TRUE(r[0].data.empty());
    for (int k = 0; k < 100; ++k) c.tick();
    // The arm is at the point (float32 on the wire) and rests there.
    EXPECT_EQ(c.server->motion().position()[0], static_cast<double>(static_cast<float>(target[0])));
    EXPECT_EQ(c.server->counters().accepted, 1u);
    EXPECT_EQ(c.server->last_sequence(), 0);
  }
}

TEST(SimpleMessageServer, AFullBufferAnswersFailureAndTakesNothing) {
  for (bool big : {false, true}) {
    Client c(big, 2);
    for (int k = 0; k < 3; ++k) {
      JointVector target = server_start();
      target[0] += 0.01 * (k + 1);
      c.send(test::hand_traj_pt(big, 2, 0, k, floats(target), 0.0f, 0.1f));
    }
    c.tick();
    const auto r = c.replies();
    ASSERT_EQ(r.size(), 3u);
    EXPECT_EQ(r[0].reply, 1);
    EXPECT_EQ(r[1].reply, 1);
    EXPECT_EQ(r[2].reply, 2);  // FAILURE: two points wait already
    EXPECT_EQ(c.server->counters().refused_full, 1u);
    EXPECT_EQ(c.server->last_sequence(), 1);
  }
}

TEST(SimpleMessageServer, StopTrajectoryStopsTheArmAndEmptiesTheBuffer) {
  Client c(false);
  for (int k = 0; k < 4; ++k) {
    JointVector target = server_start();
    target[0] += 0.02 * (k + 1);
    c.send(test::hand_traj_pt(false, 2, 0, k, floats(target), 0.0f, 0.1f));
  }
  for (int k = 0; k < 30; ++k) c.tick();  // 120 ms: the arm is moving
  EXPECT_FALSE(c.server->motion().at_rest());
  c.send(test::hand_traj_pt(false, 2, 0, -4, {}, 0.0f, 0.0f));
  c.tick();
  auto r = c.replies();
  ASSERT_EQ(r.size(), 5u);
  EXPECT_EQ(r[4].reply, 1);
  EXPECT_EQ(c.server->counters().stops, 1u);
  EXPECT_EQ(c.server->motion().queued(), 0u);
  for (int k = 0; k < 50; ++k) c.tick();
  EXPECT_TRUE(c.server->motion().at_rest());
  const double held = c.server->motion().position()[0];
  EXPECT_LT(held, server_start()[0] + 0.08 - 1e-3);  // it never reached the last point
  for (int k = 0; k < 50; ++k) c.tick();
  EXPECT_EQ(c.server->motion().position()[0], held);
}

TEST(SimpleMessageServer, FramesOfAnotherTypeOrTooShortGetNoReplyAndABadLengthClosesTheConnection) {
  Client c(false);
  c.send(test::hand_header(false, 1, 2, 0));  // PING request: the motion server does not speak it
  test::HandFrame short_point{false, {}};
  short_point.i32(12 + 40).i32(11).i32(2).i32(0);
  for (int k = 0; k < 10; ++k) short_point.i32(0);  // 40 data bytes: fewer than the 52 of a point
  c.send(short_point.bytes);
  c.tick();
  EXPECT_TRUE(c.replies().empty());
  EXPECT_EQ(c.server->counters().skipped, 2u);
  EXPECT_FALSE(c.server->counters().motion_closed);
  test::HandFrame bad{false, {}};
  bad.i32(100000).i32(11);
  c.send(bad.bytes);
  c.tick();
  EXPECT_TRUE(c.server->counters().out_of_step);
  unsigned char buf[16];
  EXPECT_EQ(c.motion.client().read(buf, sizeof(buf)), StreamTransport::kClosed);
}

TEST(SimpleMessageServer, PublishesJointPositionAndStatusEveryTenthOfASecond) {
  for (bool big : {false, true}) {
    Client c(big);
    for (int k = 0; k < 250; ++k) c.tick();  // 1 s
    const auto topics = c.topics();
    int joints = 0, statuses = 0;
    for (const auto& f : topics) {
      EXPECT_EQ(f.comm, 1);  // TOPIC
      if (f.type == 10) {
        ++joints;
        ASSERT_EQ(f.data.size(), 44u);
        EXPECT_EQ(f.i32(big, 0), 0);  // ROS_stateServer's sequence is 0
        for (std::size_t j = 0; j < 6; ++j) {
          EXPECT_EQ(f.f32(big, 1 + j), static_cast<float>(server_start()[static_cast<int>(j)]));
        }
        for (std::size_t j = 6; j < 10; ++j) EXPECT_EQ(f.f32(big, 1 + j), 0.0f);
      } else if (f.type == 13) {
        ++statuses;
        ASSERT_EQ(f.data.size(), 28u);
        EXPECT_EQ(f.i32(big, 1), 0);  // e_stopped
        EXPECT_EQ(f.i32(big, 3), 0);  // in_error
      } else {
        ADD_FAILURE() << "message type " << f.type;
      }
    }
    EXPECT_EQ(joints, 11);  // at the first tick (0.004 s), then at 0.1, 0.2, ..., 1.0 s
    EXPECT_EQ(statuses, joints);
  }
}

TEST(SimpleMessageServer, AnOutOfRangePointIsRefusedAndStopsTheMotion) {
  Client c(false);
  JointVector target = server_start();
  target[0] += 0.05;
  c.send(test::hand_traj_pt(false, 2, 0, 0, floats(target), 0.0f, 0.1f));
  for (int k = 0; k < 30; ++k) c.tick();
  EXPECT_FALSE(c.server->motion().at_rest());
  JointVector wild = server_start();
  wild[2] = c.robot.upper_limits()[2] + 0.1;
  c.send(test::hand_traj_pt(false, 2, 0, 1, floats(wild), 0.0f, 0.1f));
  c.send(test::hand_traj_pt(false, 2, 0, 2, floats(target), 0.0f, -1.0f));  // a negative duration
  c.tick();
  const auto r = c.replies();
  ASSERT_EQ(r.size(), 3u);
  EXPECT_EQ(r[1].reply, 2);
  EXPECT_EQ(r[2].reply, 2);
  EXPECT_EQ(c.server->counters().refused_invalid, 2u);
  EXPECT_EQ(c.server->motion().counters().stops, 1u);
}

TEST(SimpleMessageServer, AnEmergencyStopIsReportedAndEveryPointRefused) {
  Client c(true);
  c.tick();
  c.server->emergency_stop(c.t);
  for (int k = 0; k < 30; ++k) c.tick();
  bool saw = false;
  for (const auto& f : c.topics()) {
    if (f.type == 13) saw = saw || f.i32(true, 1) == 1;
  }
  EXPECT_TRUE(saw);
  c.send(test::hand_traj_pt(true, 2, 0, 0, floats(server_start()), 0.0f, 0.1f));
  c.tick();
  const auto r = c.replies();
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].reply, 2);
}

TEST(SimpleMessageServer, IndustrialCoreStyleRepliesEchoThePoint) {
  Client c(false);
  c.config.reply_with_data = true;
  c.server =
      std::make_unique<SimpleMessageServer>(c.config, c.robot, server_start(), c.motion.server(), c.state.server());
  c.send(test::hand_traj_pt(false, 2, 0, 41, floats(server_start()), 0.0f, 0.1f));
  c.tick();
  const auto r = c.replies();
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].length, 64);
  EXPECT_EQ(r[0].i32(false, 0), 41);
}

}  // namespace
}  // namespace deflex::cell
