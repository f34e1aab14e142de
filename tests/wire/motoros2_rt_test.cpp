// MotoROS2 real-time datagrams against images written here by hand from the packed structs of the
// real-time interface (../shared/reference/motoros2_rt.md), little-endian, doubles given as their
// IEEE bit patterns least significant byte first (0.001 = 3F50624DD2F1A9FC -> FC A9 F1 D2 4D 62 50 3F,
// -0.5 = BFE0000000000000, 1.5 = 3FF8000000000000). Sizes, offsets, sequence arithmetic across the
// wrap; wrong sizes, versions, kinds, tools, booleans and non-finite values refused; no allocation.
#include <cmath>
#include <cstdint>
#include <limits>

#include <gtest/gtest.h>

#include "deflex/wire/motoros2_rt.hpp"
#include "hex_bytes.hpp"
#include "support/allocation_guard.hpp"

namespace deflex {
namespace {

namespace rt = motoros2_rt;
using test::Bytes;
using test::hex;

rt::Command rt_command() {
  rt::Command c;
  c.sequence = 0x01020304;
  c.delta[0][0] = 0.001;  // S, 1 mrad this cycle
  c.delta[0][5] = -0.5;   // T
  c.tool[0] = 3;
  return c;
}

Bytes rt_command_bytes() {
  Bytes b =
      hex("01000000 00000000 04030201"  // version 1, joint increments, sequence
          "FCA9F1D24D62503F");          // delta[0][0] = 0.001 rad
  b = test::zeros_after(b, 4 * 8);
  const Bytes t = hex("000000000000E0BF");  // delta[0][5] = -0.5 rad
  b.insert(b.end(), t.begin(), t.end());
  b = test::zeros_after(b, (64 - 6) * 8);
  const Bytes tools = hex("03000000");
  b.insert(b.end(), tools.begin(), tools.end());
  return test::zeros_after(b, 7 * 4 + 64);  // the other groups' tools, the reserved tail
}

TEST(MotoRos2Rt, CommandIsTheSixHundredTwentyBytePackedStruct) {
  const Bytes expected = rt_command_bytes();
  ASSERT_EQ(expected.size(), rt::kCommandBytes);
  unsigned char out[rt::kCommandBytes];
  ASSERT_EQ(rt::encode(rt_command(), out, sizeof out), rt::kCommandBytes);
  EXPECT_EQ(Bytes(out, out + sizeof out), expected);

  rt::Command back;
  ASSERT_EQ(rt::decode(expected.data(), expected.size(), back), rt::DecodeStatus::kOk);
  EXPECT_EQ(back.sequence, 0x01020304u);
  EXPECT_EQ(back.kind, rt::IncrementKind::kJoint);
  EXPECT_EQ(back.delta[0][0], 0.001);
  EXPECT_EQ(back.delta[0][5], -0.5);
  EXPECT_EQ(back.tool[0], 3);
}

TEST(MotoRos2Rt, ReplyCarriesTheCommandPositionAndTheSafetyUnitsFlag) {
  Bytes reply = hex("2A000000");                               // sequence echo 42
  reply = test::zeros_after(reply, 1024);                      // feedback joints and Cartesian
  const Bytes cmd = hex("0000000000000000 000000000000F83F");  // command_joints[0][1] = 1.5 rad
  reply.insert(reply.end(), cmd.begin(), cmd.end());
  reply = test::zeros_after(reply, 512 - 16 + 512);
  reply.push_back(1);  // fsuInterferenceDetected
  ASSERT_EQ(reply.size(), rt::kReplyBytes);

  rt::Reply r;
  ASSERT_EQ(rt::decode(reply.data(), reply.size(), r), rt::DecodeStatus::kOk);
  EXPECT_EQ(r.sequence_echo, 42u);
  EXPECT_EQ(r.command_joints[0][1], 1.5);
  EXPECT_EQ(r.feedback_joints[0][1], 0.0);
  EXPECT_TRUE(r.fsu_truncated);
  unsigned char out[rt::kReplyBytes];
  ASSERT_EQ(rt::encode(r, out, sizeof out), rt::kReplyBytes);
  EXPECT_EQ(Bytes(out, out + sizeof out), reply);

  reply.back() = 2;  // a C bool is 0 or 1
  EXPECT_EQ(rt::decode(reply.data(), reply.size(), r), rt::DecodeStatus::kBadField);
}

TEST(MotoRos2Rt, RobotStateIsSixBooleansAndAnErrorCode) {
  const Bytes state = hex("01000000 00000000 01000000 01000000 00000000 01000000 B90B0000");
  rt::RobotState s;
  ASSERT_EQ(rt::decode(state.data(), state.size(), s), rt::DecodeStatus::kOk);
  EXPECT_TRUE(s.drives_powered);
  EXPECT_FALSE(s.e_stopped);
  EXPECT_TRUE(s.in_motion);
  EXPECT_TRUE(s.play_mode);
  EXPECT_FALSE(s.motion_possible);
  EXPECT_TRUE(s.error);
  EXPECT_EQ(s.error_code, 3001);
  unsigned char out[rt::kRobotStateBytes];
  ASSERT_EQ(rt::encode(s, out, sizeof out), rt::kRobotStateBytes);
  EXPECT_EQ(Bytes(out, out + sizeof out), state);
  Bytes bad = state;
  bad[4] = 7;
  EXPECT_EQ(rt::decode(bad.data(), bad.size(), s), rt::DecodeStatus::kBadField);
}

TEST(MotoRos2Rt, GarbageIsRefusedWithItsReason) {
  const Bytes good = rt_command_bytes();
  rt::Command c;
  EXPECT_EQ(rt::decode(good.data(), good.size() - 1, c), rt::DecodeStatus::kWrongSize);
  Bytes v2 = good;
  v2[0] = 2;
  EXPECT_EQ(rt::decode(v2.data(), v2.size(), c), rt::DecodeStatus::kUnknownVersion);
  Bytes kind2 = good;
  kind2[4] = 2;  // 0 joint, 1 Cartesian increments
  EXPECT_EQ(rt::decode(kind2.data(), kind2.size(), c), rt::DecodeStatus::kBadField);
  Bytes tool64 = good;
  tool64[524] = 64;
  EXPECT_EQ(rt::decode(tool64.data(), tool64.size(), c), rt::DecodeStatus::kBadField);
  Bytes nan = good;
  nan[12 + 6] = 0xF8;
  nan[12 + 7] = 0x7F;  // delta[0][0] = NaN
  EXPECT_EQ(rt::decode(nan.data(), nan.size(), c), rt::DecodeStatus::kNonFinite);
  EXPECT_EQ(c.sequence, 0u) << "a refused datagram leaves the output untouched";

  unsigned char out[rt::kReplyBytes];
  rt::Command bad = rt_command();
  bad.delta[3][7] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(rt::encode(bad, out, sizeof out), 0u);
  bad = rt_command();
  bad.tool[7] = -1;
  EXPECT_EQ(rt::encode(bad, out, sizeof out), 0u);
  EXPECT_EQ(rt::encode(rt_command(), out, rt::kCommandBytes - 1), 0u);
}

TEST(MotoRos2Rt, SequenceDistanceIsWrapSafe) {
  EXPECT_EQ(rt::sequence_ahead(10, 11), 1);
  EXPECT_EQ(rt::sequence_ahead(10, 10), 0);
  EXPECT_EQ(rt::sequence_ahead(10, 9), -1);
  EXPECT_EQ(rt::sequence_ahead(0xFFFFFFFFU, 2), 3);  // across the wrap: three ahead
  EXPECT_EQ(rt::sequence_ahead(2, 0xFFFFFFFFU), -3);
}

TEST(MotoRos2Rt, EncodingAndDecodingDoNotAllocate) {
  unsigned char out[rt::kReplyBytes];
  rt::Command c;
  rt::Reply r;
  test::AllocationGuard guard;
  for (int i = 0; i < 50; ++i) {
    const std::size_t n = rt::encode(rt_command(), out, sizeof out);
    ASSERT_EQ(rt::decode(out, n, c), rt::DecodeStatus::kOk);
    const std::size_t m = rt::encode(r, out, sizeof out);
    ASSERT_EQ(rt::decode(out, m, r), rt::DecodeStatus::kOk);
  }
  EXPECT_EQ(guard.allocations(), 0u);
}

}  // namespace
}  // namespace deflex
