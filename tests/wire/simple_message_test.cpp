// The simple message wire format against frames written here by hand from the protocol facts
// (../shared/reference/simple_message.md): int32 LENGTH (header + data), MSG_TYPE, COMM_TYPE,
// REPLY_CODE, then the data, every int32 and IEEE float32 in the controller's byte order, the floats
// given here as their bit patterns (1.0f = 0x3F800000 ...). Both byte orders; framing on a stream cut
// into arbitrary pieces; truncated, too long, non-finite, too short and oversized frames; no
// allocation once running.
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "deflex/text/errors.hpp"
#include "deflex/wire/simple_message.hpp"
#include "deflex/wire/simple_message_stream.hpp"
#include "support/allocation_guard.hpp"

namespace deflex {
namespace {

namespace sm = simple_message;
using Bytes = std::vector<unsigned char>;

// Packs 32-bit words by hand, most significant byte first for big-endian.
struct Words {
  bool big;
  Bytes bytes;
  Words& w(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) {
      const int shift = big ? 24 - 8 * i : 8 * i;
      bytes.push_back(static_cast<unsigned char>((v >> shift) & 0xffU));
    }
    return *this;
  }
  Words& zeros(int n) {
    for (int i = 0; i < n; ++i) w(0);
    return *this;
  }
};

constexpr std::uint32_t kOneF = 0x3F800000;        // 1.0f
constexpr std::uint32_t kMinusHalfF = 0xBF000000;  // -0.5f
constexpr std::uint32_t kQuarterF = 0x3E800000;    // 0.25f
constexpr std::uint32_t kTenthF = 0x3DCCCCCD;      // 0.1f
constexpr std::uint32_t kTwoF = 0x40000000;        // 2.0f
constexpr std::uint32_t kNanF = 0x7FC00000;

// JOINT_TRAJ_PT service request: sequence 7, joints (1, -0.5, 2, 0 ...), velocity 0.25, duration 0.1.
Bytes traj_pt_request(bool big) {
  Words f{big, {}};
  f.w(64).w(11).w(2).w(0);  // LENGTH = 12 + 52; JOINT_TRAJ_PT; SERVICE_REQUEST; INVALID
  f.w(7).w(kOneF).w(kMinusHalfF).w(kTwoF).zeros(7).w(kQuarterF).w(kTenthF);
  return f.bytes;
}

TEST(SimpleMessageWire, JointTrajPtEncodesToTheHandWrittenFrameInBothByteOrders) {
  for (bool big : {false, true}) {
    const sm::ByteOrder order = big ? sm::ByteOrder::kBig : sm::ByteOrder::kLittle;
    sm::JointTrajPt p;
    p.sequence = 7;
    p.joints_rad[0] = 1.0f;
    p.joints_rad[1] = -0.5f;
    p.joints_rad[2] = 2.0f;
    p.velocity = 0.25f;
    p.duration_s = 0.1f;
    Bytes out(100, 0xAA);
    const std::size_t n =
        sm::encode(order, {sm::kJointTrajPt, sm::kServiceRequest, sm::kReplyInvalid}, p, out.data(), out.size());
    ASSERT_EQ(n, 68u);
    out.resize(n);
    EXPECT_EQ(out, traj_pt_request(big)) << (big ? "big" : "little");
    // No room: nothing written.
    Bytes small(67);
    EXPECT_EQ(sm::encode(order, {sm::kJointTrajPt, sm::kServiceRequest, 0}, p, small.data(), small.size()), 0u);
  }
  // The two orders are each other's byte reversal, word by word (LENGTH 64 = 0x40).
  const Bytes le = traj_pt_request(false), be = traj_pt_request(true);
  EXPECT_EQ(le[0], 0x40);
  EXPECT_EQ(be[3], 0x40);
  EXPECT_EQ(be[0], 0x00);
}

TEST(SimpleMessageWire, HandWrittenFramesDecodeInBothByteOrders) {
  for (bool big : {false, true}) {
    const sm::ByteOrder order = big ? sm::ByteOrder::kBig : sm::ByteOrder::kLittle;
    const Bytes frame = traj_pt_request(big);
    std::size_t bytes = 0;
    std::int64_t length = 0;
    ASSERT_EQ(sm::peek_frame(order, frame.data(), frame.size(), 1024, bytes, length), sm::FrameStatus::kComplete);
    EXPECT_EQ(bytes, 68u);
    EXPECT_EQ(length, 64);
    const sm::FrameView v = sm::view_frame(order, frame.data(), bytes);
    EXPECT_EQ(v.header.msg_type, 11);
    EXPECT_EQ(v.header.comm_type, 2);
    EXPECT_EQ(v.header.reply_code, 0);
    ASSERT_EQ(v.data_bytes, 52u);
    sm::JointTrajPt p;
    ASSERT_EQ(sm::decode(order, v.data, v.data_bytes, p), sm::DecodeStatus::kOk);
    EXPECT_EQ(p.sequence, 7);
    EXPECT_EQ(p.joints_rad[0], 1.0f);
    EXPECT_EQ(p.joints_rad[1], -0.5f);
    EXPECT_EQ(p.joints_rad[2], 2.0f);
    for (std::size_t j = 3; j < 10; ++j) EXPECT_EQ(p.joints_rad[j], 0.0f);
    EXPECT_EQ(p.velocity, 0.25f);
    EXPECT_EQ(p.duration_s, 0.1f);

    // JOINT_POSITION topic (what the state servers publish): sequence 0, joints (0.25, 1, -0.5 ...).
    Words jp{big, {}};
    jp.w(56).w(10).w(1).w(0).w(0).w(kQuarterF).w(kOneF).w(kMinusHalfF).zeros(7);
    sm::JointPosition q;
    ASSERT_EQ(sm::peek_frame(order, jp.bytes.data(), jp.bytes.size(), 1024, bytes, length), sm::FrameStatus::kComplete);
    const sm::FrameView vq = sm::view_frame(order, jp.bytes.data(), bytes);
    EXPECT_EQ(vq.header.msg_type, sm::kJointPosition);
    EXPECT_EQ(vq.header.comm_type, sm::kTopic);
    ASSERT_EQ(sm::decode(order, vq.data, vq.data_bytes, q), sm::DecodeStatus::kOk);
    EXPECT_EQ(q.joints_rad[0], 0.25f);
    EXPECT_EQ(q.joints_rad[1], 1.0f);
    EXPECT_EQ(q.joints_rad[2], -0.5f);

    // ROBOT_STATUS: drives_powered 1, e_stopped 0, error_code 42, in_error 0, in_motion 1, mode 2 (auto),
    // motion_possible 1.
    Words rs{big, {}};
    rs.w(40).w(13).w(1).w(0).w(1).w(0).w(42).w(0).w(1).w(2).w(1);
    ASSERT_EQ(sm::peek_frame(order, rs.bytes.data(), rs.bytes.size(), 1024, bytes, length), sm::FrameStatus::kComplete);
    const sm::FrameView vs = sm::view_frame(order, rs.bytes.data(), bytes);
    sm::RobotStatus s;
    ASSERT_EQ(sm::decode(order, vs.data, vs.data_bytes, s), sm::DecodeStatus::kOk);
    EXPECT_EQ(s.drives_powered, 1);
    EXPECT_EQ(s.e_stopped, 0);
    EXPECT_EQ(s.error_code, 42);
    EXPECT_EQ(s.in_motion, 1);
    EXPECT_EQ(s.mode, 2);
    EXPECT_EQ(s.motion_possible, 1);
    // And the encoder writes the same bytes.
    Bytes out(64);
    const std::size_t n = sm::encode(order, {sm::kRobotStatus, sm::kTopic, 0}, s, out.data(), out.size());
    out.resize(n);
    EXPECT_EQ(out, rs.bytes);

    // A header-only SUCCESS reply (ABB's RAPID server answers so): LENGTH 12.
    Words reply{big, {}};
    reply.w(12).w(11).w(3).w(1);
    Bytes enc(16);
    EXPECT_EQ(sm::encode_frame(order, {sm::kJointTrajPt, sm::kServiceReply, sm::kReplySuccess}, nullptr, 0, enc.data(),
                               enc.size()),
              16u);
    EXPECT_EQ(enc, reply.bytes);
  }
}

TEST(SimpleMessageWire, AFrameReadInTheWrongByteOrderIsOversizedNotMisread) {
  const Bytes le = traj_pt_request(false);
  std::size_t bytes = 0;
  std::int64_t length = 0;
  // 0x40000000 bytes: far beyond any sane frame, so the wrong setting is caught at the first frame.
  EXPECT_EQ(sm::peek_frame(sm::ByteOrder::kBig, le.data(), le.size(), 1024, bytes, length),
            sm::FrameStatus::kOversized);
  EXPECT_EQ(length, 0x40000000);
}

TEST(SimpleMessageWire, BadLengthsAndDataSizesAreStatusesThatNameWhatIsWrong) {
  const sm::ByteOrder le = sm::ByteOrder::kLittle;
  std::size_t bytes = 0;
  std::int64_t length = 0;
  const Bytes full = traj_pt_request(false);
  // Incomplete: fewer than 4 bytes, and a prefix whose frame has not all arrived.
  EXPECT_EQ(sm::peek_frame(le, full.data(), 3, 1024, bytes, length), sm::FrameStatus::kIncomplete);
  EXPECT_EQ(sm::peek_frame(le, full.data(), 67, 1024, bytes, length), sm::FrameStatus::kIncomplete);
  // LENGTH below the header, negative, above the maximum.
  for (std::uint32_t bad : {0u, 8u, 11u, 0xFFFFFFFFu}) {
    Words f{false, {}};
    f.w(bad).w(11).w(2).w(0);
    EXPECT_EQ(sm::peek_frame(le, f.bytes.data(), f.bytes.size(), 1024, bytes, length), sm::FrameStatus::kTooShort)
        << bad;
  }
  Words huge{false, {}};
  huge.w(1025);
  EXPECT_EQ(sm::peek_frame(le, huge.bytes.data(), 4, 1024, bytes, length), sm::FrameStatus::kOversized);
  EXPECT_EQ(length, 1025);
  EXPECT_EQ(sm::peek_frame(le, huge.bytes.data(), 4, 2048, bytes, length), sm::FrameStatus::kIncomplete);

  // Data of the wrong size or with a NaN.
  Words jp{false, {}};
  jp.w(0).w(kOneF).zeros(9);  // 44 bytes
  sm::JointPosition q;
  EXPECT_EQ(sm::decode(le, jp.bytes.data(), 43, q), sm::DecodeStatus::kTruncated);
  jp.w(0);
  EXPECT_EQ(sm::decode(le, jp.bytes.data(), 48, q), sm::DecodeStatus::kTooLong);
  EXPECT_EQ(sm::decode(le, jp.bytes.data(), 44, q), sm::DecodeStatus::kOk);
  Words nan{false, {}};
  nan.w(0).w(kOneF).w(kNanF).zeros(8);
  EXPECT_EQ(sm::decode(le, nan.bytes.data(), 44, q), sm::DecodeStatus::kNonFinite);
  sm::JointTrajPt p;
  EXPECT_EQ(sm::decode(le, full.data() + 16, 51, p), sm::DecodeStatus::kTruncated);
  sm::RobotStatus s;
  EXPECT_EQ(sm::decode(le, full.data() + 16, 24, s), sm::DecodeStatus::kTruncated);

  EXPECT_EQ(sm::parse_byte_order("big"), sm::ByteOrder::kBig);
  EXPECT_EQ(sm::parse_byte_order("little"), sm::ByteOrder::kLittle);
  try {
    (void)sm::parse_byte_order("network");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'network'"), std::string::npos) << e.what();
  }
}

TEST(SimpleMessageStream, FramesComeOutWholeAndInOrderHoweverTheStreamCutsThem) {
  for (bool big : {false, true}) {
    const sm::ByteOrder order = big ? sm::ByteOrder::kBig : sm::ByteOrder::kLittle;
    // Three frames: a JOINT_TRAJ_PT request, a header-only reply, a JOINT_POSITION; twenty times over.
    Bytes stream;
    for (int k = 0; k < 20; ++k) {
      Words f{big, {}};
      f.w(64).w(11).w(2).w(0).w(static_cast<std::uint32_t>(k)).w(kOneF).zeros(9).w(0).w(kTenthF);
      f.w(12).w(11).w(3).w(2);
      f.w(56).w(10).w(1).w(0).w(0).w(kTwoF).zeros(9);
      stream.insert(stream.end(), f.bytes.begin(), f.bytes.end());
    }
    sm::FrameReader reader(order, 1024);
    std::mt19937 rng(big ? 7 : 11);
    std::uniform_int_distribution<std::size_t> piece(1, 150);
    std::size_t at = 0;
    std::vector<int> types;
    std::vector<int> sequences;
    while (at < stream.size()) {
      const std::size_t n = std::min({piece(rng), stream.size() - at, reader.space_bytes()});
      std::copy_n(stream.data() + at, n, reader.space());
      reader.commit(n);
      at += n;
      sm::FrameView f;
      for (sm::FrameStatus s = reader.next(f); s != sm::FrameStatus::kIncomplete; s = reader.next(f)) {
        ASSERT_EQ(s, sm::FrameStatus::kComplete);
        types.push_back(f.header.msg_type * 10 + f.header.comm_type);
        if (f.header.msg_type == sm::kJointTrajPt && f.header.comm_type == sm::kServiceRequest) {
          sm::JointTrajPt p;
          ASSERT_EQ(sm::decode(order, f.data, f.data_bytes, p), sm::DecodeStatus::kOk);
          sequences.push_back(p.sequence);
          EXPECT_EQ(p.joints_rad[0], 1.0f);
          EXPECT_EQ(p.duration_s, 0.1f);
        }
        if (f.header.comm_type == sm::kServiceReply) {
          EXPECT_EQ(f.header.reply_code, sm::kReplyFailure);
          EXPECT_EQ(f.data_bytes, 0u);
        }
      }
    }
    ASSERT_EQ(types.size(), 60u);
    for (std::size_t i = 0; i < types.size(); i += 3) {
      EXPECT_EQ(types[i], 112);
      EXPECT_EQ(types[i + 1], 113);
      EXPECT_EQ(types[i + 2], 101);
    }
    ASSERT_EQ(sequences.size(), 20u);
    for (int k = 0; k < 20; ++k) EXPECT_EQ(sequences[static_cast<std::size_t>(k)], k);
    EXPECT_EQ(reader.buffered(), 0u);
  }
}

TEST(SimpleMessageStream, AnOutOfStepLengthIsReportedWithTheLengthRead) {
  sm::FrameReader reader(sm::ByteOrder::kLittle, 1024);
  Words f{false, {}};
  f.w(12).w(11).w(3).w(1).w(5000).w(0);
  std::copy(f.bytes.begin(), f.bytes.end(), reader.space());
  reader.commit(f.bytes.size());
  sm::FrameView v;
  EXPECT_EQ(reader.next(v), sm::FrameStatus::kComplete);
  EXPECT_EQ(reader.next(v), sm::FrameStatus::kOversized);
  EXPECT_EQ(reader.length(), 5000);
  EXPECT_THROW(sm::FrameReader(sm::ByteOrder::kLittle, 4), InputError);
}

TEST(SimpleMessageStream, TheOutboxKeepsWhatAPartialWriteLeft) {
  sm::FrameOutbox box(100);
  const Bytes frame = traj_pt_request(false);
  unsigned char* at = box.reserve(frame.size());
  ASSERT_NE(at, nullptr);
  std::copy(frame.begin(), frame.end(), at);
  box.commit(frame.size());
  EXPECT_EQ(box.reserve(40), nullptr);  // 68 + 40 > 100
  box.consume(30);                      // the stream took 30 bytes
  ASSERT_EQ(box.pending_bytes(), 38u);
  EXPECT_EQ(Bytes(box.pending(), box.pending() + 38), Bytes(frame.begin() + 30, frame.end()));
  EXPECT_NE(box.reserve(60), nullptr);  // room after moving the rest to the front
  EXPECT_EQ(Bytes(box.pending(), box.pending() + 38), Bytes(frame.begin() + 30, frame.end()));
  box.consume(38);
  EXPECT_EQ(box.pending_bytes(), 0u);
}

TEST(SimpleMessageStream, ReadingAndWritingFramesDoesNotAllocate) {
  sm::FrameReader reader(sm::ByteOrder::kBig, 1024);
  sm::FrameOutbox box(4096);
  const Bytes frame = traj_pt_request(true);
  sm::JointTrajPt p;
  test::AllocationGuard guard;
  for (int k = 0; k < 1000; ++k) {
    std::copy(frame.begin(), frame.end(), reader.space());
    reader.commit(frame.size());
    sm::FrameView v;
    ASSERT_EQ(reader.next(v), sm::FrameStatus::kComplete);
    ASSERT_EQ(sm::decode(sm::ByteOrder::kBig, v.data, v.data_bytes, p), sm::DecodeStatus::kOk);
    unsigned char* at = box.reserve(68);
    ASSERT_NE(at, nullptr);
    box.commit(sm::encode(sm::ByteOrder::kBig, v.header, p, at, 68));
    box.consume(68);
  }
  EXPECT_EQ(guard.allocations(), 0u);
}

}  // namespace
}  // namespace deflex
