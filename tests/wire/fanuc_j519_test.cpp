// FANUC Stream Motion datagrams against images written here by hand from the protocol's tables
// (../shared/reference/fanuc_j519.md: the v1 layout of FANUC's manual as the Wireshark dissector
// reads it, the v3/v4 layout of FANUC's ROS 2 driver's packets), every field big-endian, floats
// given as their IEEE bit patterns (10.0f = 41200000, -90.5f = C2B50000, 10.0 = 4024000000000000,
// -90.5 = C056A00000000000). Both directions, every version; wrong sizes, types and versions,
// non-finite values and out-of-range fields refused; no allocation.
#include <cmath>
#include <cstdint>
#include <limits>

#include <gtest/gtest.h>

#include "deflex/wire/fanuc_j519.hpp"
#include "hex_bytes.hpp"
#include "support/allocation_guard.hpp"

namespace deflex {
namespace {

namespace j519 = fanuc_j519;
using test::Bytes;
using test::hex;

j519::Command sample_command() {
  j519::Command c;
  c.sequence = 0x01020304;
  c.last = true;
  c.target[0] = 10.0;
  c.target[2] = -90.5;
  return c;
}

TEST(FanucJ519, VersionOneCommandIsTheManualsSixtyFourBytes) {
  const Bytes expected =
      hex("00000001 00000001 01020304"                 // type 1 (command), version 1, sequence
          "01 00 0000 0000 01 00 0000 0000 0000 0000"  // last, read I/O none, joint style, write I/O none, unused
          "41200000 00000000 C2B50000 00000000 00000000 00000000 00000000 00000000 00000000");
  ASSERT_EQ(expected.size(), j519::kCommandV1Bytes);
  unsigned char out[j519::kMaxDatagramBytes];
  ASSERT_EQ(j519::encode(1, sample_command(), out, sizeof out), j519::kCommandV1Bytes);
  EXPECT_EQ(Bytes(out, out + j519::kCommandV1Bytes), expected);

  j519::Command back;
  std::uint32_t version = 0;
  ASSERT_EQ(j519::decode(expected.data(), expected.size(), back, version), j519::DecodeStatus::kOk);
  EXPECT_EQ(version, 1u);
  EXPECT_EQ(back.sequence, 0x01020304u);
  EXPECT_TRUE(back.last);
  EXPECT_TRUE(back.joint_style);
  EXPECT_EQ(back.target[0], 10.0);
  EXPECT_EQ(back.target[2], -90.5);
}

TEST(FanucJ519, VersionThreeCommandCarriesDoublesAndAZeroIoBlock) {
  Bytes expected =
      hex("000000C9 00000003 01020304"  // type 201, version 3, sequence
          "01 01 FFFF"                  // last, motion control, unused (0xFFFF as FANUC's driver writes)
          "4024000000000000 0000000000000000 C056A00000000000");
  expected = test::zeros_after(expected, 6 * 8 + j519::kIoBytes);
  ASSERT_EQ(expected.size(), j519::kCommandV3Bytes);
  unsigned char out[j519::kMaxDatagramBytes];
  ASSERT_EQ(j519::encode(3, sample_command(), out, sizeof out), j519::kCommandV3Bytes);
  EXPECT_EQ(Bytes(out, out + j519::kCommandV3Bytes), expected);

  // The float64 target keeps what float32 rounds: 60 deg + 1e-6 deg survives version 3 only.
  j519::Command fine = sample_command();
  fine.target[1] = 60.000001;
  for (const std::uint32_t v : {1u, 3u}) {
    const std::size_t n = j519::encode(v, fine, out, sizeof out);
    j519::Command back;
    std::uint32_t version = 0;
    ASSERT_EQ(j519::decode(out, n, back, version), j519::DecodeStatus::kOk);
    EXPECT_EQ(version, v);
    if (v == 3) {
      EXPECT_EQ(back.target[1], 60.000001);
    } else {
      EXPECT_NE(back.target[1], 60.000001);
      EXPECT_NEAR(back.target[1], 60.000001, 4e-6);
    }
  }
}

TEST(FanucJ519, StartAndStopPackets) {
  unsigned char out[16];
  ASSERT_EQ(j519::encode_start(1, out, sizeof out), 8u);
  EXPECT_EQ(Bytes(out, out + 8), hex("00000000 00000001"));
  ASSERT_EQ(j519::encode_start(3, out, sizeof out), 8u);
  EXPECT_EQ(Bytes(out, out + 8), hex("000000C8 00000003"));
  ASSERT_EQ(j519::encode_stop(1, out, sizeof out), 8u);
  EXPECT_EQ(Bytes(out, out + 8), hex("00000002 00000001"));
  EXPECT_EQ(j519::encode_start(2, out, sizeof out), 0u) << "version 2 is not sourced";
  EXPECT_EQ(j519::encode_stop(1, out, 7), 0u);
}

Bytes version_one_status() {
  return hex(
      "00000000 00000001 00000007"  // type 0 (status), version 1, sequence 7
      "05 00 0000 0000 0000"        // ready + servo ready; read I/O echo
      "00001234"                    // time stamp, ms
      "3F800000 00000000 00000000 00000000 00000000 00000000 00000000 00000000 00000000"    // Cartesian
      "00000000 00000000 C2B50000 00000000 00000000 00000000 00000000 00000000 00000000"    // joints
      "00000000 00000000 00000000 00000000 00000000 00000000 00000000 00000000 3E800000");  // currents
}

TEST(FanucJ519, VersionOneStatusFieldsAtTheirOffsets) {
  const Bytes bytes = version_one_status();
  ASSERT_EQ(bytes.size(), j519::kStatusV1Bytes);
  j519::Status s;
  ASSERT_EQ(j519::decode(bytes.data(), bytes.size(), s), j519::DecodeStatus::kOk);
  EXPECT_EQ(s.version, 1u);
  EXPECT_EQ(s.sequence, 7u);
  EXPECT_TRUE(s.ready());
  EXPECT_FALSE(s.in_motion());
  EXPECT_FALSE(s.in_error());
  EXPECT_EQ(s.time_stamp_ms, 0x1234u);
  EXPECT_EQ(s.cartesian[0], 1.0f);
  EXPECT_EQ(s.joints_deg[2], -90.5f);
  EXPECT_EQ(s.currents_a[8], 0.25f);
  EXPECT_FALSE(s.has_wrench);

  unsigned char out[j519::kMaxDatagramBytes];
  ASSERT_EQ(j519::encode(1, s, out, sizeof out), j519::kStatusV1Bytes);
  EXPECT_EQ(Bytes(out, out + j519::kStatusV1Bytes), bytes);
}

TEST(FanucJ519, VersionFourStatusCarriesTheRobotStatusAndTheWrench) {
  Bytes bytes =
      hex("000000CC 00000004 00000009"             // type 204, version 4, sequence 9
          "09 05 02 00"                            // ready + in motion; in error + e-stopped; contact stop STOP
          "00000010");                             // time stamp
  bytes = test::zeros_after(bytes, 36 + 36 + 36);  // Cartesian, joints, currents
  const Bytes tail =
      hex("3F400000"                                               // safety scale 0.75
          "41200000 00000000 C2B50000 00000000 00000000 3E800000"  // Fx 10 N, Fz -90.5 N, Mz 0.25 Nm
          "00000002");                                             // external sensor
  bytes.insert(bytes.end(), tail.begin(), tail.end());
  bytes = test::zeros_after(bytes, j519::kIoBytes);
  ASSERT_EQ(bytes.size(), j519::kStatusV4Bytes);

  j519::Status s;
  ASSERT_EQ(j519::decode(bytes.data(), bytes.size(), s), j519::DecodeStatus::kOk);
  EXPECT_EQ(s.version, 4u);
  EXPECT_TRUE(s.ready());
  EXPECT_TRUE(s.in_motion());
  EXPECT_TRUE(s.in_error());
  EXPECT_EQ(s.contact_stop, 2);
  EXPECT_EQ(s.safety_scale, 0.75f);
  ASSERT_TRUE(s.has_wrench);
  EXPECT_EQ(s.wrench[0], 10.0f);
  EXPECT_EQ(s.wrench[2], -90.5f);
  EXPECT_EQ(s.wrench[5], 0.25f);
  EXPECT_EQ(s.sensor_type, 2u);

  unsigned char out[j519::kMaxDatagramBytes];
  ASSERT_EQ(j519::encode(4, s, out, sizeof out), j519::kStatusV4Bytes);
  EXPECT_EQ(Bytes(out, out + j519::kStatusV4Bytes), bytes);
  // Version 3 is the same up to the safety scale, then the I/O block (no wrench).
  ASSERT_EQ(j519::encode(3, s, out, sizeof out), j519::kStatusV3Bytes);
  EXPECT_EQ(Bytes(out + 8, out + 132), Bytes(bytes.begin() + 8, bytes.begin() + 132));
  EXPECT_EQ(Bytes(out, out + 4), hex("000000CA"));
}

TEST(FanucJ519, ThresholdRequestAndReply) {
  unsigned char out[j519::kMaxDatagramBytes];
  ASSERT_EQ(j519::encode(j519::ThresholdRequest{2, j519::LimitKind::kJerk}, out, sizeof out), 16u);
  EXPECT_EQ(Bytes(out, out + 16), hex("00000003 00000001 00000002 00000002"));

  // Axis 2's jerk table: 2000 mm/s, 8 ms; no load 1860 deg/s^3 at every speed but 1240 at 100 %.
  Bytes reply = hex("00000003 00000001 00000002 00000002 000007D0 00000008");
  for (int i = 0; i < 19; ++i) {
    const Bytes v = hex("44E88000");  // 1860.0f
    reply.insert(reply.end(), v.begin(), v.end());
  }
  const Bytes last = hex("449B0000");  // 1240.0f
  reply.insert(reply.end(), last.begin(), last.end());
  for (int i = 0; i < 20; ++i) {
    const Bytes v = hex("44FA0000");  // 2000.0f
    reply.insert(reply.end(), v.begin(), v.end());
  }
  ASSERT_EQ(reply.size(), j519::kThresholdReplyBytes);
  j519::ThresholdReply r;
  ASSERT_EQ(j519::decode(reply.data(), reply.size(), r), j519::DecodeStatus::kOk);
  EXPECT_EQ(r.axis, 2u);
  EXPECT_EQ(r.kind, j519::LimitKind::kJerk);
  EXPECT_EQ(r.max_cartesian_speed_mm_s, 2000u);
  EXPECT_EQ(r.interval_ms, 8u);
  EXPECT_EQ(r.no_load[0], 1860.0f);
  EXPECT_EQ(r.no_load[19], 1240.0f);
  EXPECT_EQ(r.full_load[7], 2000.0f);
  EXPECT_EQ(r.strictest(), 1240.0f);
  ASSERT_EQ(j519::encode(r, out, sizeof out), j519::kThresholdReplyBytes);
  EXPECT_EQ(Bytes(out, out + j519::kThresholdReplyBytes), reply);

  // A zero limit would make every motion a violation: not a table to trust.
  Bytes zero = reply;
  zero[24] = zero[25] = zero[26] = zero[27] = 0;
  EXPECT_EQ(j519::decode(zero.data(), zero.size(), r), j519::DecodeStatus::kBadField);
  Bytes axis10 = reply;
  axis10[11] = 10;
  EXPECT_EQ(j519::decode(axis10.data(), axis10.size(), r), j519::DecodeStatus::kBadField);
  j519::ThresholdRequest q;
  const Bytes kind3 = hex("00000003 00000001 00000001 00000003");
  EXPECT_EQ(j519::decode(kind3.data(), kind3.size(), q), j519::DecodeStatus::kBadField);
}

TEST(FanucJ519, CapabilityExchange) {
  const Bytes reply = hex("00000007 00000003 00000001 00000004 00000002 00000003 00000001");
  j519::Capability c;
  ASSERT_EQ(j519::decode(reply.data(), reply.size(), c), j519::DecodeStatus::kOk);
  EXPECT_EQ(c.sampling_rate_ms, 4u);
  EXPECT_EQ(c.start_move, 2u);
  EXPECT_EQ(c.available_version, 3u);
  EXPECT_EQ(c.status_uses_tcp, 1u);
  unsigned char out[j519::kCapabilityBytes];
  ASSERT_EQ(j519::encode(c, out, sizeof out), j519::kCapabilityBytes);
  EXPECT_EQ(Bytes(out, out + sizeof out), reply);
  Bytes bad = reply;
  bad[19] = 10;  // start_move 0..9
  EXPECT_EQ(j519::decode(bad.data(), bad.size(), c), j519::DecodeStatus::kBadField);
}

TEST(FanucJ519, GarbageIsRefusedWithItsReason) {
  j519::Status s;
  const Bytes good = version_one_status();
  EXPECT_EQ(j519::decode(good.data(), 7, s), j519::DecodeStatus::kWrongSize);
  EXPECT_EQ(j519::decode(good.data(), good.size() - 1, s), j519::DecodeStatus::kWrongSize);
  Bytes longer = good;
  longer.push_back(0);
  EXPECT_EQ(j519::decode(longer.data(), longer.size(), s), j519::DecodeStatus::kWrongSize);
  // The start packet shares type 0 with the v1 status: told apart by its size.
  const Bytes start = hex("00000000 00000001");
  EXPECT_EQ(j519::decode(start.data(), start.size(), s), j519::DecodeStatus::kWrongSize);
  Bytes v2 = good;
  v2[7] = 2;
  EXPECT_EQ(j519::decode(v2.data(), v2.size(), s), j519::DecodeStatus::kUnknownVersion);
  Bytes command_type = good;
  command_type[3] = 1;
  EXPECT_EQ(j519::decode(command_type.data(), command_type.size(), s), j519::DecodeStatus::kWrongType);
  Bytes nan = good;
  nan[60] = 0x7F;
  nan[61] = 0xC0;  // joint 1 = quiet NaN
  EXPECT_EQ(j519::decode(nan.data(), nan.size(), s), j519::DecodeStatus::kNonFinite);
  Bytes inf = good;
  inf[24] = 0x7F;
  inf[25] = 0x80;  // X = +inf
  EXPECT_EQ(j519::decode(inf.data(), inf.size(), s), j519::DecodeStatus::kNonFinite);
  EXPECT_EQ(s.sequence, 0u) << "a refused datagram leaves the output untouched";

  j519::Command c;
  std::uint32_t version = 0;
  unsigned char out[j519::kMaxDatagramBytes];
  std::size_t n = j519::encode(1, sample_command(), out, sizeof out);
  out[12] = 2;  // last-data is 0 or 1
  EXPECT_EQ(j519::decode(out, n, c, version), j519::DecodeStatus::kBadField);
  n = j519::encode(3, sample_command(), out, sizeof out);
  EXPECT_EQ(j519::decode(out, n - 1, c, version), j519::DecodeStatus::kWrongSize);
}

TEST(FanucJ519, NothingToSendFromANonFiniteOrUnrepresentableTarget) {
  unsigned char out[j519::kMaxDatagramBytes];
  j519::Command c = sample_command();
  c.target[4] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(j519::encode(1, c, out, sizeof out), 0u);
  EXPECT_EQ(j519::encode(3, c, out, sizeof out), 0u);
  c.target[4] = 1e300;  // finite as a double, infinite as the v1 float32
  EXPECT_EQ(j519::encode(1, c, out, sizeof out), 0u);
  EXPECT_EQ(j519::encode(3, c, out, sizeof out), j519::kCommandV3Bytes);
  EXPECT_EQ(j519::encode(3, sample_command(), out, j519::kCommandV3Bytes - 1), 0u);
  c = sample_command();
  c.joint_style = false;  // v3 commands carry joints only
  EXPECT_EQ(j519::encode(3, c, out, sizeof out), 0u);
}

// The controller's check by hand: from rest at 8 ms, a step of d deg is a velocity d/T, an
// acceleration d/T^2 and a jerk d/T^3; 0.001 deg is 1953.125 deg/s^3, over a CRX's 1240.
TEST(FanucJ519, MotionCheckIsTheStreamsFiniteDifferences) {
  std::array<j519::AxisLimits, j519::kAxes> limits{};
  limits.fill({10.0, 1000.0, 1240.0});
  j519::MotionCheck check(0.008, 6, limits);
  check.reset({});
  std::array<double, j519::kAxes> target{};
  target[3] = 0.001;
  std::size_t axis = 99;
  double value = 0.0;
  ASSERT_EQ(check.push(target, axis, value), j519::LimitExceeded::kJerk);
  EXPECT_EQ(axis, 3u);
  EXPECT_NEAR(value, 1953.125, 1e-9);
  EXPECT_NEAR(check.peak().velocity, 0.125, 1e-12);
  EXPECT_NEAR(check.peak().acceleration, 15.625, 1e-9);

  // A ramp at constant velocity has no acceleration or jerk once going: 0.01 deg a cycle (1.25 deg/s)
  // started with a jerk limit it may exceed only at the start.
  limits.fill({10.0, 1000.0, 1e9});
  j519::MotionCheck ramp(0.008, 6, limits);
  ramp.reset({});
  for (int k = 1; k <= 10; ++k) {
    target.fill(0.01 * k);
    ASSERT_EQ(ramp.push(target, axis, value), j519::LimitExceeded::kNone) << k;
  }
  EXPECT_NEAR(ramp.peak().velocity, 1.25, 1e-9);
  // ... and a jump of 0.1 deg on axis 6 where the ramp would have stopped (12.5 deg/s) trips the
  // velocity limit, reported as such.
  target[5] += 0.1;
  ASSERT_EQ(ramp.push(target, axis, value), j519::LimitExceeded::kVelocity);
  EXPECT_EQ(axis, 5u);
  EXPECT_NEAR(value, 12.5, 1e-9);
  // Axes past the checked count are not the controller's (a six-axis arm's E1..E3).
  j519::MotionCheck six(0.008, 6, limits);
  six.reset({});
  target.fill(0.0);
  target[8] = 100.0;
  EXPECT_EQ(six.push(target, axis, value), j519::LimitExceeded::kNone);
}

TEST(FanucJ519, EncodingAndDecodingDoNotAllocate) {
  unsigned char out[j519::kMaxDatagramBytes];
  const Bytes status = version_one_status();
  j519::Status s;
  j519::Command c;
  std::uint32_t version = 0;
  test::AllocationGuard guard;
  for (int i = 0; i < 100; ++i) {
    const std::size_t n = j519::encode(3, sample_command(), out, sizeof out);
    ASSERT_EQ(j519::decode(out, n, c, version), j519::DecodeStatus::kOk);
    ASSERT_EQ(j519::decode(status.data(), status.size(), s), j519::DecodeStatus::kOk);
  }
  EXPECT_EQ(guard.allocations(), 0u);
}

}  // namespace
}  // namespace deflex
