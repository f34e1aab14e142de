// How the EGM links order the controller's packets, the cases met in the field: a stray packet 100,000
// ahead of the running sequence number (it was answered, and the real controller's next 93 packets
// were refused as out of order), a sequence number wider than its 32-bit field (protobuf would have
// truncated it), a restart told by a silence measured from the last packet the controller sent (not
// from the last one the link took), and a stray from another sender while the controller talks.
// The packets are written by hand from the field numbers, not by deflex's codec.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "links/link_harness.hpp"
#include "wire/protobuf_bytes.hpp"

namespace deflex {
namespace {

using test::Bytes;
using test::len_field;

// EgmRobot { header 1 { seqno 1, tm 2 }, feedBack 2 { joints 1 }, planned 3 { joints 1 } }, degrees.
Bytes egm_robot(std::uint64_t seqno, std::uint32_t tm_ms, const JointVector& q_deg) {
  Bytes header, joints, feedback, planned, out;
  test::varint_field(header, 1, seqno);  // a varint: nothing stops a sender from writing more than 32 bits
  test::varint_field(header, 2, tm_ms);
  for (int i = 0; i < q_deg.size(); ++i) test::double_field(joints, 1, q_deg[i]);
  len_field(feedback, 1, joints);
  len_field(planned, 1, joints);
  len_field(out, 1, header);
  len_field(out, 2, feedback);
  len_field(out, 3, planned);
  return out;
}

JointVector pose_deg() {
  JointVector q(6);
  q << 0, 20, 10, 0, 60, 0;
  return q;
}

// A controller of our own on the raw wire, against the path-correction link.
struct Wire {
  RobotModel robot = test::bench_robot();
  ManualClock clock;
  MemoryNetwork network{clock};
  MemoryTransport& sensor = network.add_endpoint(test::kSensorAddress, 0.0);
  MemoryTransport& controller = network.add_endpoint(test::kControllerAddress, 0.0);
  MemoryTransport& stranger = network.add_endpoint(test::kStrangerAddress, 0.0);
  OnlineCompensator compensator{robot, test::bench_sensor(), test::bench_online()};
  OnlineStrategy strategy{robot, StrategyKind::kOnline, nullptr};
  test::ConstantForce force;
  EgmPathLink link{compensator, strategy, sensor, clock};
  double t = 0.0;

  Wire() { link.read_force_from(&force); }

  /// One 4 ms cycle: `packet` from `from`, the link polls; true when an answer came back to `from`.
  bool cycle(const Bytes& packet, MemoryTransport* from = nullptr) {
    MemoryTransport& port = from != nullptr ? *from : controller;
    t += 0.004;
    clock.set(t);
    EXPECT_TRUE(port.send_to(packet.data(), packet.size(), test::kSensorAddress));
    while (link.poll(0.0) != LinkPollResult::kIdle) {
    }
    unsigned char buf[512];
    DatagramAddress who;
    bool answered = false;
    while (port.receive(buf, sizeof(buf), who) >= 0) answered = true;
    return answered;
  }
  Bytes next(std::uint64_t seqno) {
    return egm_robot(seqno, static_cast<std::uint32_t>(std::lround(t * 1000.0 + 4.0)), pose_deg());
  }
};

TEST(EgmSequencing, AStrayPacketFarAheadIsNotAnsweredAndTheControllerGoesOn) {
  Wire w;
  for (std::uint64_t s = 1; s <= 50; ++s) ASSERT_TRUE(w.cycle(w.next(s)));
  EXPECT_FALSE(w.cycle(w.next(100050)));  // from the controller's own address
  for (std::uint64_t s = 51; s <= 150; ++s) EXPECT_TRUE(w.cycle(w.next(s))) << s;
  EXPECT_EQ(w.link.counters().far_ahead, 1u);
  EXPECT_EQ(w.link.counters().out_of_order, 0u);
  EXPECT_EQ(w.link.counters().replies, 150u);
  EXPECT_EQ(w.link.counters().restarts, 0u);
}

TEST(EgmSequencing, AControllerThatRestartsWithAJumpIsFollowedAfterThreePackets) {
  Wire w;
  for (std::uint64_t s = 1; s <= 50; ++s) ASSERT_TRUE(w.cycle(w.next(s)));
  EXPECT_FALSE(w.cycle(w.next(7000)));
  EXPECT_FALSE(w.cycle(w.next(7001)));
  EXPECT_TRUE(w.cycle(w.next(7002)));  // three in a row: a new sequence
  EXPECT_TRUE(w.cycle(w.next(7003)));
  EXPECT_EQ(w.link.counters().restarts, 1u);
}

TEST(EgmSequencing, ASequenceNumberWiderThan32BitsIsRejectedNotTruncated) {
  Wire w;
  for (std::uint64_t s = 1; s <= 10; ++s) ASSERT_TRUE(w.cycle(w.next(s)));
  // 2^32 + 11: protobuf keeps the low 32 bits, 11, which would have looked like the next packet.
  EXPECT_FALSE(w.cycle(w.next((std::uint64_t{1} << 32) + 11)));
  EXPECT_EQ(w.link.counters().sequence_out_of_range, 1u);
  EXPECT_TRUE(w.cycle(w.next(11)));
}

TEST(EgmSequencing, TheSilenceThatMeansARestartIsMeasuredFromTheLastPacketReceived) {
  Wire w;
  for (std::uint64_t s = 1; s <= 10; ++s) ASSERT_TRUE(w.cycle(w.next(s)));
  // For 0.8 s the controller keeps sending, but only packets the link refuses (duplicates): it has
  // not gone silent, so another sender cannot take over and its next good packet is no restart.
  for (int k = 0; k < 200; ++k) EXPECT_FALSE(w.cycle(w.next(10)));
  EXPECT_FALSE(w.cycle(w.next(11), &w.stranger));
  EXPECT_EQ(w.link.counters().foreign_sender, 1u);
  EXPECT_TRUE(w.cycle(w.next(11)));
  EXPECT_EQ(w.link.counters().restarts, 0u);
  EXPECT_EQ(w.link.counters().duplicate, 200u);
  // A real silence (nothing at all for 0.6 s) is a restart, whatever the number.
  w.t += 0.6;
  EXPECT_TRUE(w.cycle(w.next(5000)));
  EXPECT_EQ(w.link.counters().restarts, 1u);
}

TEST(EgmSequencing, ArrivalDiagnosticsFollowTheControllersTimeStamps) {
  Wire w;
  for (std::uint64_t s = 1; s <= 20; ++s) ASSERT_TRUE(w.cycle(w.next(s)));
  EXPECT_LT(w.link.last_cycle().arrival.arrival_delay_s, 1e-9);
  // Packet 21 stamped as sent 12 ms before it arrives relative to the others; two cycles missing.
  w.t += 0.008;  // packets 21 and 22 never came
  ASSERT_TRUE(w.cycle(egm_robot(23, static_cast<std::uint32_t>(std::lround(w.t * 1000.0 + 4.0 - 12.0)), pose_deg())));
  EXPECT_EQ(w.link.last_cycle().arrival.missed_before, 2u);
  EXPECT_NEAR(w.link.last_cycle().arrival.arrival_delay_s, 0.012, 1e-9);
  EXPECT_EQ(w.link.counters().missed, 2u);
  EXPECT_EQ(w.link.counters().late, 1u);  // 12 ms behind the quickest: later than a 4 ms period
  EXPECT_GT(w.link.counters().jitter_s, 0.0);
}

TEST(EgmSequencing, PacketsOvertakenInTheNetworkAreLateButARestartFromTheFirstNumberIsNot) {
  Wire w;
  for (std::uint64_t s = 1; s <= 8; ++s) ASSERT_TRUE(w.cycle(w.next(s)));
  // 9, 10 and 11 are overtaken by 12: they arrive behind it with their own (older) time stamps, and
  // continue each other, which before made them a confirmed new sequence.
  const auto stamped = [&](std::uint64_t seqno, double sent_s) {
    return egm_robot(seqno, static_cast<std::uint32_t>(std::lround(sent_s * 1000.0)), pose_deg());
  };
  const double t8 = w.t;  // what 8 carried (next() stamps the time its cycle reaches)
  EXPECT_TRUE(w.cycle(stamped(12, t8 + 0.016)));
  for (std::uint64_t s = 9; s <= 11; ++s) EXPECT_FALSE(w.cycle(stamped(s, t8 + 0.004 * static_cast<double>(s - 8))));
  EXPECT_TRUE(w.cycle(stamped(13, t8 + 0.020)));
  EXPECT_EQ(w.link.counters().out_of_order, 3u);
  EXPECT_EQ(w.link.counters().restarts, 0u);
  // A controller restarted early in its session: its first number again, a newer time stamp, no
  // silence. A restart at once, though 1 is within the reordering window of 13 (whether the link
  // resumes then is the re-anchor's rule: its offset against the last one sent).
  (void)w.cycle(w.next(1));
  EXPECT_EQ(w.link.counters().restarts, 1u);
  EXPECT_EQ(w.link.counters().out_of_order, 3u);
}

TEST(EgmSequencing, AControllerClockSetBackIsAJumpOfItsClockNotJitter) {
  // The controller's clock goes back 5 s (set by hand, NTP): before, its 32-bit step read as 4.29e9 ms
  // and the jitter showed 268,435,145 ms.
  Wire w;
  for (std::uint64_t s = 1; s <= 20; ++s) ASSERT_TRUE(w.cycle(w.next(s)));
  const auto at = [&](std::uint64_t seqno, double shift_s) {
    return egm_robot(seqno, static_cast<std::uint32_t>(std::lround((w.t + 0.004 + shift_s) * 1000.0)), pose_deg());
  };
  for (std::uint64_t s = 21; s <= 40; ++s) EXPECT_TRUE(w.cycle(at(s, -5.0))) << s;
  EXPECT_EQ(w.link.counters().clock_jumps, 1u);
  EXPECT_LT(w.link.counters().jitter_s, 0.001);
  EXPECT_LT(w.link.counters().max_arrival_delay_s, 0.001);
  EXPECT_EQ(w.link.counters().late, 0u);
  EXPECT_EQ(w.link.counters().restarts, 0u);
  // And forward by an hour: the same.
  for (std::uint64_t s = 41; s <= 60; ++s) EXPECT_TRUE(w.cycle(at(s, 3600.0))) << s;
  EXPECT_EQ(w.link.counters().clock_jumps, 2u);
  EXPECT_LT(w.link.counters().jitter_s, 0.001);
}

}  // namespace
}  // namespace deflex
