// Simple message frames written by hand for tests, independently of deflex's codec: 32-bit words
// packed byte by byte in the chosen order, floats by their IEEE bit patterns (std::bit_cast), and a
// reader that splits a captured byte stream into frames the same way. Only the protocol facts are
// used: int32 LENGTH (header + data), MSG_TYPE, COMM_TYPE, REPLY_CODE, then the data.
#pragma once

#include <bit>
#include <cstdint>
#include <vector>

namespace deflex::test {

using Bytes = std::vector<unsigned char>;

struct HandFrame {
  bool big = false;
  Bytes bytes;
  HandFrame& word(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) {
      const int shift = big ? 24 - 8 * i : 8 * i;
      bytes.push_back(static_cast<unsigned char>((v >> shift) & 0xffU));
    }
    return *this;
  }
  HandFrame& i32(std::int32_t v) { return word(static_cast<std::uint32_t>(v)); }
  HandFrame& f32(float v) { return word(std::bit_cast<std::uint32_t>(v)); }
};

inline std::uint32_t hand_word(bool big, const unsigned char* p) {
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i) {
    const int shift = big ? 24 - 8 * i : 8 * i;
    v |= static_cast<std::uint32_t>(p[i]) << shift;
  }
  return v;
}

/// A JOINT_TRAJ_PT frame: `comm` (2 request, 3 reply), `reply` code, sequence, joints (rad; the rest 0),
/// velocity, duration (s).
inline Bytes hand_traj_pt(bool big, std::int32_t comm, std::int32_t reply, std::int32_t sequence,
                          const std::vector<float>& joints, float velocity, float duration) {
  HandFrame f{big, {}};
  f.i32(64).i32(11).i32(comm).i32(reply).i32(sequence);
  for (std::size_t j = 0; j < 10; ++j) f.f32(j < joints.size() ? joints[j] : 0.0f);
  f.f32(velocity).f32(duration);
  return f.bytes;
}

/// A JOINT_POSITION topic (or, with comm 3, a reply carrying one) with the sequence and joints.
inline Bytes hand_joint_position(bool big, const std::vector<float>& joints, std::int32_t sequence = 0,
                                 std::int32_t comm = 1, std::int32_t reply = 0) {
  HandFrame f{big, {}};
  f.i32(56).i32(10).i32(comm).i32(reply).i32(sequence);
  for (std::size_t j = 0; j < 10; ++j) f.f32(j < joints.size() ? joints[j] : 0.0f);
  return f.bytes;
}

/// A header-only frame (ABB's replies): LENGTH 12.
inline Bytes hand_header(bool big, std::int32_t type, std::int32_t comm, std::int32_t reply) {
  HandFrame f{big, {}};
  f.i32(12).i32(type).i32(comm).i32(reply);
  return f.bytes;
}

/// ROBOT_STATUS topic: drives_powered, e_stopped, error_code, in_error, in_motion, mode, motion_possible.
inline Bytes hand_status(bool big, std::int32_t e_stopped, std::int32_t in_error, std::int32_t error_code = 0) {
  HandFrame f{big, {}};
  f.i32(40).i32(13).i32(1).i32(0).i32(1).i32(e_stopped).i32(error_code).i32(in_error).i32(0).i32(2).i32(1);
  return f.bytes;
}

/// One frame cut from a captured byte stream by hand: its header words and data.
struct HandParsed {
  std::int32_t length = 0, type = 0, comm = 0, reply = 0;
  Bytes data;
  [[nodiscard]] std::int32_t i32(bool big, std::size_t word) const {
    return static_cast<std::int32_t>(hand_word(big, data.data() + 4 * word));
  }
  [[nodiscard]] float f32(bool big, std::size_t word) const {
    return std::bit_cast<float>(hand_word(big, data.data() + 4 * word));
  }
};

/// Splits `stream` into whole frames (what is left over stays in `stream`).
inline std::vector<HandParsed> hand_split(bool big, Bytes& stream) {
  std::vector<HandParsed> out;
  std::size_t at = 0;
  while (stream.size() - at >= 16) {
    const auto length = static_cast<std::int32_t>(hand_word(big, stream.data() + at));
    if (length < 12 || stream.size() - at < 4 + static_cast<std::size_t>(length)) break;
    HandParsed p;
    p.length = length;
    p.type = static_cast<std::int32_t>(hand_word(big, stream.data() + at + 4));
    p.comm = static_cast<std::int32_t>(hand_word(big, stream.data() + at + 8));
    p.reply = static_cast<std::int32_t>(hand_word(big, stream.data() + at + 12));
    p.data.assign(stream.begin() + static_cast<long>(at) + 16, stream.begin() + static_cast<long>(at) + 4 + length);
    out.push_back(std::move(p));
    at += 4 + static_cast<std::size_t>(length);
  }
  stream.erase(stream.begin(), stream.begin() + static_cast<long>(at));
  return out;
}

}  // namespace deflex::test
