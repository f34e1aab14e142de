// The EGM schema against the wire format written by hand from the protocol facts (field numbers and
// types): EgmRobot with packed and unpacked joints, with and without planned joints; EgmSensor with
// its speed reference; EgmSensorPathCorr both ways; and the truncated/malformed distinction.
#include <cmath>
#include <cstring>
#include <vector>

#include <gtest/gtest.h>

#include "deflex/wire/egm_codec.hpp"
#include "wire/protobuf_bytes.hpp"

namespace deflex {
namespace {

using test::Bytes;
using test::len_field;
using test::varint;
void tag(Bytes& b, int field, int wire) { varint(b, static_cast<std::uint64_t>(field << 3 | wire)); }
void fixed64(Bytes& b, double v) {
  unsigned char raw[8];
  std::memcpy(raw, &v, 8);
  b.insert(b.end(), raw, raw + 8);
}

// EgmJoints { repeated double joints = 1; } unpacked (one tag per value, wire type 1) or packed.
Bytes joints(const std::vector<double>& q, bool packed) {
  Bytes j;
  if (packed) {
    Bytes body;
    for (double v : q) {
      fixed64(body, v);
    }
    len_field(j, 1, body);
  } else {
    for (double v : q) {
      tag(j, 1, 1);
      fixed64(j, v);
    }
  }
  return j;
}

// EgmRobot: header = 1 {seqno = 1, tm = 2}, feedBack = 2 {joints = 1}, planned = 3 {joints = 1}.
Bytes robot_packet(std::uint32_t seqno, const std::vector<double>& fb, const std::vector<double>& pl, bool packed) {
  Bytes header;
  tag(header, 1, 0);
  varint(header, seqno);
  tag(header, 2, 0);
  varint(header, 4242);
  Bytes feedback, planned, msg;
  len_field(feedback, 1, joints(fb, packed));
  len_field(planned, 1, joints(pl, packed));
  len_field(msg, 1, header);
  len_field(msg, 2, feedback);
  len_field(msg, 3, planned);
  tag(msg, 10, 1);  // utilizationRate, a double
  fixed64(msg, 12.5);
  return msg;
}

TEST(EgmCodec, DecodesHandWrittenPacketsPackedAndUnpacked) {
  EgmCodec codec(6);
  const std::vector<double> fb{1, 2, 3, 4, 5, 6}, pl{-10, 20.5, -30, 40, -50, 60.25};
  for (bool packed : {false, true}) {
    const Bytes p = robot_packet(77, fb, pl, packed);
    EgmRobotMessage m;
    ASSERT_EQ(codec.decode_robot(p.data(), p.size(), m), EgmDecodeStatus::kOk) << packed;
    EXPECT_EQ(m.seqno, 77u);
    EXPECT_EQ(m.tm_ms, 4242u);
    EXPECT_EQ(m.feedback_joints_deg[5], 6.0);
    EXPECT_EQ(m.planned_joints_deg[1], 20.5);
    EXPECT_EQ(m.planned_joints_deg[5], 60.25);
  }
}

TEST(EgmCodec, EncodedSensorMessageHasTheSchemaFieldNumbers) {
  EgmCodec codec(6);
  EgmSensorMessage s;
  s.seqno = 5;
  s.tm_ms = 9;
  s.planned_joints_deg = JointVector::Zero(6);
  s.planned_joints_deg[0] = 1.5;
  unsigned char buf[512];
  const std::size_t n = codec.encode_sensor(s, buf, sizeof(buf));
  ASSERT_GT(n, 0u);
  // EgmSensor: header = 1 (LEN) first: tag byte 0x0A; planned = 2 (LEN): tag 0x12 follows the header.
  EXPECT_EQ(buf[0], 0x0A);
  const std::size_t header_len = buf[1];
  EXPECT_EQ(buf[2], 0x08);  // seqno = 1, varint
  EXPECT_EQ(buf[3], 5);
  EXPECT_EQ(buf[4], 0x10);  // tm = 2
  EXPECT_EQ(buf[5], 9);
  EXPECT_EQ(buf[6], 0x18);  // mtype = 3
  EXPECT_EQ(buf[7], 3);     // MSGTYPE_CORRECTION
  EXPECT_EQ(buf[2 + header_len], 0x12);
  EgmSensorMessage back;
  ASSERT_TRUE(codec.decode_sensor(buf, n, back));
  EXPECT_EQ(back.planned_joints_deg[0], 1.5);
  s.planned_joints_deg[2] = std::nan("");
  EXPECT_EQ(codec.encode_sensor(s, buf, sizeof(buf)), 0u);  // a NaN correction is never encoded
}

TEST(EgmCodec, RejectsBadPacketsWithTheRightReason) {
  EgmCodec codec(6);
  EgmRobotMessage m;
  const std::vector<double> q{1, 2, 3, 4, 5, 6};
  const Bytes good = robot_packet(1, q, q, false);
  // Every cut is rejected except the two that end exactly before a whole field: before the trailing
  // utilizationRate (9 bytes) and before the planned joints (2 + 6 x 9 + 2 bytes). Protobuf cannot
  // tell those from shorter complete messages, which is harmless: they carry the header and the
  // feedback whole (the second one without planned joints, and says so).
  const std::size_t before_planned = good.size() - 9 - (2 + 2 + 6 * 9);
  for (std::size_t cut = 1; cut < good.size(); ++cut) {
    if (cut == good.size() - 9) {
      EXPECT_EQ(codec.decode_robot(good.data(), cut, m), EgmDecodeStatus::kOk);
      EXPECT_TRUE(m.has_planned);
      continue;
    }
    if (cut == before_planned) {
      EXPECT_EQ(codec.decode_robot(good.data(), cut, m), EgmDecodeStatus::kOk);
      EXPECT_FALSE(m.has_planned);
      continue;
    }
    const EgmDecodeStatus s = codec.decode_robot(good.data(), cut, m);
    EXPECT_LT(static_cast<int>(s), 0) << "cut at " << cut;
  }
  EXPECT_EQ(codec.decode_robot(good.data(), good.size() - 3, m), EgmDecodeStatus::kTruncated);
  const unsigned char garbage[] = {0xFF, 0xFF, 0xFF, 0x07, 0x00};
  EXPECT_EQ(codec.decode_robot(garbage, sizeof(garbage), m), EgmDecodeStatus::kMalformed);
  EXPECT_EQ(codec.decode_robot(good.data(), 0, m), EgmDecodeStatus::kEmpty);
  const std::vector<double> five{1, 2, 3, 4, 5};
  const Bytes short_joints = robot_packet(1, five, five, false);
  EXPECT_EQ(codec.decode_robot(short_joints.data(), short_joints.size(), m), EgmDecodeStatus::kMissingJoints);
  const std::vector<double> with_nan{1, 2, std::nan(""), 4, 5, 6};
  const Bytes nan_packet = robot_packet(1, q, with_nan, true);
  EXPECT_EQ(codec.decode_robot(nan_packet.data(), nan_packet.size(), m), EgmDecodeStatus::kNonFinite);
  Bytes no_header;
  Bytes fbody;
  len_field(fbody, 1, joints(q, false));
  len_field(no_header, 2, fbody);
  len_field(no_header, 3, fbody);
  EXPECT_EQ(codec.decode_robot(no_header.data(), no_header.size(), m), EgmDecodeStatus::kMissingHeader);
  Bytes only_header;
  Bytes h;
  tag(h, 1, 0);
  varint(h, 3);
  len_field(only_header, 1, h);
  EXPECT_EQ(codec.decode_robot(only_header.data(), only_header.size(), m), EgmDecodeStatus::kMissingJoints);
}

TEST(EgmCodec, PlannedJointsAreOptionalButMustBeWholeWhenThere) {
  EgmCodec codec(6);
  const std::vector<double> q{1, 2, 3, 4, 5, 6};
  Bytes header, fb, msg;
  tag(header, 1, 0);
  varint(header, 9);
  len_field(fb, 1, joints(q, false));
  len_field(msg, 1, header);
  len_field(msg, 2, fb);
  EgmRobotMessage m;
  ASSERT_EQ(codec.decode_robot(msg.data(), msg.size(), m), EgmDecodeStatus::kOk);
  EXPECT_FALSE(m.has_planned);
  EXPECT_EQ(m.feedback_joints_deg[3], 4.0);
  const Bytes both = robot_packet(10, q, q, false);
  ASSERT_EQ(codec.decode_robot(both.data(), both.size(), m), EgmDecodeStatus::kOk);
  EXPECT_TRUE(m.has_planned);
  const std::vector<double> five{1, 2, 3, 4, 5};
  const Bytes short_planned = robot_packet(11, q, five, true);
  EXPECT_EQ(codec.decode_robot(short_planned.data(), short_planned.size(), m), EgmDecodeStatus::kMissingJoints);
}

TEST(EgmCodec, SpeedReferenceGoesInSpeedRefJoints) {
  EgmCodec codec(6);
  EgmSensorMessage s;
  s.planned_joints_deg = JointVector::Constant(6, 2.0);
  s.speed_ref_joints_deg_s = JointVector::Zero(6);
  s.speed_ref_joints_deg_s[4] = -7.25;
  unsigned char buf[512];
  const std::size_t n = codec.encode_sensor(s, buf, sizeof(buf));
  ASSERT_GT(n, 0u);
  // Walk the top level: header (1), planned (2), speedRef (3) {joints (1) {joints...}}.
  std::size_t i = 0;
  int speed_ref_at = -1;
  while (i < n) {
    const int key = buf[i];
    const std::size_t len = buf[i + 1];  // every field here is shorter than 128 bytes
    if (key == 0x1A) speed_ref_at = static_cast<int>(i);
    i += 2 + len;
  }
  ASSERT_GE(speed_ref_at, 0) << "no field 3 (speedRef) of wire type 2";
  const auto at = static_cast<std::size_t>(speed_ref_at);
  EXPECT_EQ(buf[at + 2], 0x0A);  // speedRef.joints = 1, an EgmJoints
  EgmSensorMessage back;
  ASSERT_TRUE(codec.decode_sensor(buf, n, back));
  ASSERT_EQ(back.speed_ref_joints_deg_s.size(), 6);
  EXPECT_EQ(back.speed_ref_joints_deg_s[4], -7.25);
  // Without a speed reference nothing of field 3 is sent.
  s.speed_ref_joints_deg_s.resize(0);
  const std::size_t m = codec.encode_sensor(s, buf, sizeof(buf));
  ASSERT_TRUE(codec.decode_sensor(buf, m, back));
  EXPECT_EQ(back.speed_ref_joints_deg_s.size(), 0);
}

TEST(EgmCodec, PathCorrectionAgainstTheHandWrittenWireFormat) {
  // EgmSensorPathCorr: header = 1 {seqno = 1, tm = 2, mtype = 3}, pathCorr = 2 {pos = 1 {x, y, z:
  // doubles 1..3}, age = 2 (uint32)}.
  Bytes header, pos, corr, msg;
  tag(header, 1, 0);
  varint(header, 12);
  tag(header, 3, 0);
  varint(header, 4);  // MSGTYPE_PATH_CORRECTION
  for (int f = 1; f <= 3; ++f) {
    tag(pos, f, 1);
    fixed64(pos, 0.5 * f);
  }
  len_field(corr, 1, pos);
  tag(corr, 2, 0);
  varint(corr, 36);
  len_field(msg, 1, header);
  len_field(msg, 2, corr);
  EgmCodec codec(6);
  EgmPathCorrMessage back;
  ASSERT_TRUE(codec.decode_path_corr(msg.data(), msg.size(), back));
  EXPECT_EQ(back.seqno, 12u);
  EXPECT_EQ(back.pos_mm, Vector3(0.5, 1.0, 1.5));
  EXPECT_EQ(back.age_ms, 36u);
  // The codec's own encoding carries the same fields, mtype PATH_CORRECTION.
  EgmPathCorrMessage out;
  out.seqno = 12;
  out.pos_mm = Vector3(0.5, 1.0, 1.5);
  out.age_ms = 36;
  unsigned char buf[256];
  const std::size_t n = codec.encode_path_corr(out, buf, sizeof(buf));
  ASSERT_GT(n, 0u);
  EXPECT_EQ(buf[0], 0x0A);
  EXPECT_EQ(buf[2], 0x08);
  EXPECT_EQ(buf[3], 12);
  EXPECT_EQ(buf[buf[1] + 2 - 1], 4);  // the header's last field: mtype = 4
  ASSERT_TRUE(codec.decode_path_corr(buf, n, back));
  EXPECT_EQ(back.pos_mm, out.pos_mm);
  // Without the required age, or with a NaN, the correction is refused.
  Bytes corr_no_age, msg_no_age;
  len_field(corr_no_age, 1, pos);
  len_field(msg_no_age, 1, header);
  len_field(msg_no_age, 2, corr_no_age);
  EXPECT_FALSE(codec.decode_path_corr(msg_no_age.data(), msg_no_age.size(), back));
  out.pos_mm.x() = std::nan("");
  EXPECT_EQ(codec.encode_path_corr(out, buf, sizeof(buf)), 0u);
}

TEST(EgmCodec, TimeStampWrapsLikeTheUint32Field) {
  EXPECT_EQ(egm_time_stamp_ms(0.0), 0u);
  EXPECT_EQ(egm_time_stamp_ms(1.2345), 1234u);             // whole milliseconds, truncated
  EXPECT_EQ(egm_time_stamp_ms(4294967.295), 4294967295u);  // the largest value before the wrap
  // 2^32 ms = 4294967.296 s: the field wraps to 0 and counts on (49.7 days of uptime).
  EXPECT_EQ(egm_time_stamp_ms(4294967.296 + 10.0), 10000u);
  EXPECT_EQ(egm_time_stamp_ms(3.0 * 4294967.296 + 0.5), 500u);
  EXPECT_EQ(egm_time_stamp_ms(-1.0), 0u);
  EXPECT_EQ(egm_time_stamp_ms(std::nan("")), 0u);
  EXPECT_EQ(egm_time_stamp_ms(1e12), 2764472320u);  // 1e15 ms mod 2^32
}

}  // namespace
}  // namespace deflex
