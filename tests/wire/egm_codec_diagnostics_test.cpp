// What the EGM codec says about packets protobuf alone would get wrong or be loud about: a sequence
// number wider than its uint32 field (protobuf keeps its low 32 bits) is refused, and a packet with a
// required field missing is refused with its own status and without a line on stderr (protobuf
// printed one per packet). Packets written by hand from the field numbers.
#include <cstring>
#include <vector>

#include <gtest/gtest.h>

#include "deflex/wire/egm_codec.hpp"

namespace deflex {
namespace {

using Bytes = std::vector<unsigned char>;

void varint(Bytes& b, std::uint64_t v) {
  while (v >= 0x80) {
    b.push_back(static_cast<unsigned char>(v | 0x80));
    v >>= 7;
  }
  b.push_back(static_cast<unsigned char>(v));
}
void len_field(Bytes& b, int field, const Bytes& body) {
  varint(b, static_cast<std::uint64_t>(field << 3 | 2));
  varint(b, body.size());
  b.insert(b.end(), body.begin(), body.end());
}
void fixed64(Bytes& b, double v) {
  unsigned char raw[8];
  std::memcpy(raw, &v, 8);
  b.insert(b.end(), raw, raw + 8);
}

// EgmRobot { header { seqno }, feedBack { joints {6}, cartesian { pos { x [, y, z] } } } }.
Bytes robot(std::uint64_t seqno, bool complete_position) {
  Bytes header, joints, pos, pose, feedback, out;
  varint(header, 1 << 3);
  varint(header, seqno);
  for (int i = 0; i < 6; ++i) {
    varint(joints, 1 << 3 | 1);
    fixed64(joints, 10.0 * i);
  }
  for (int f = 1; f <= (complete_position ? 3 : 1); ++f) {
    varint(pos, static_cast<std::uint64_t>(f << 3 | 1));
    fixed64(pos, 100.0 * f);
  }
  len_field(pose, 1, pos);
  len_field(feedback, 1, joints);
  len_field(feedback, 2, pose);
  len_field(out, 1, header);
  len_field(out, 2, feedback);
  return out;
}

TEST(EgmCodecDiagnostics, ASequenceNumberBeyond32BitsIsRefusedNotTruncated) {
  EgmCodec codec(6);
  EgmRobotMessage m;
  Bytes p = robot(0xFFFFFFFFULL, true);
  ASSERT_EQ(codec.decode_robot(p.data(), p.size(), m), EgmDecodeStatus::kOk);
  EXPECT_EQ(m.seqno, 0xFFFFFFFFu);
  p = robot((std::uint64_t{1} << 32) + 7, true);
  EXPECT_EQ(codec.decode_robot(p.data(), p.size(), m), EgmDecodeStatus::kSequenceOutOfRange);
}

TEST(EgmCodecDiagnostics, AMissingRequiredFieldIsCountedSilently) {
  EgmCodec codec(6);
  EgmRobotMessage m;
  const Bytes p = robot(5, false);  // EgmCartesian without its required y and z
  const std::uint64_t before = egm_protobuf_log_messages();
  testing::internal::CaptureStderr();
  for (int k = 0; k < 1000; ++k) EXPECT_EQ(codec.decode_robot(p.data(), p.size(), m), EgmDecodeStatus::kMissingRequired);
  const std::string printed = testing::internal::GetCapturedStderr();
  EXPECT_EQ(printed, "");
  EXPECT_EQ(egm_protobuf_log_messages(), before);  // nothing was even attempted to be printed
  const Bytes ok = robot(6, true);
  EXPECT_EQ(codec.decode_robot(ok.data(), ok.size(), m), EgmDecodeStatus::kOk);
}

}  // namespace
}  // namespace deflex
