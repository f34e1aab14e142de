// What the EGM codec says about packets protobuf alone would get wrong or be loud about: a sequence
// number wider than its uint32 field (protobuf keeps its low 32 bits) is refused, and a packet with a
// required field missing is refused with its own status and without a line on stderr (protobuf
// printed one per packet). Packets written by hand from the field numbers.

#include <gtest/gtest.h>

#include "deflex/wire/egm_codec.hpp"
#include "wire/protobuf_bytes.hpp"

namespace deflex {
namespace {

using test::Bytes;
using test::len_field;

// EgmRobot { header { seqno }, feedBack { joints {6}, cartesian { pos { x [, y, z] } } } }.
Bytes robot(std::uint64_t seqno, bool complete_position) {
  Bytes header, joints, pos, pose, feedback, out;
  test::varint_field(header, 1, seqno);
  for (int i = 0; i < 6; ++i) test::double_field(joints, 1, 10.0 * i);
  for (int f = 1; f <= (complete_position ? 3 : 1); ++f) test::double_field(pos, f, 100.0 * f);
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
  for (int k = 0; k < 1000; ++k)
    EXPECT_EQ(codec.decode_robot(p.data(), p.size(), m), EgmDecodeStatus::kMissingRequired);
  const std::string printed = testing::internal::GetCapturedStderr();
  EXPECT_EQ(printed, "");
  EXPECT_EQ(egm_protobuf_log_messages(), before);  // nothing was even attempted to be printed
  const Bytes ok = robot(6, true);
  EXPECT_EQ(codec.decode_robot(ok.data(), ok.size(), m), EgmDecodeStatus::kOk);
}

}  // namespace
}  // namespace deflex
