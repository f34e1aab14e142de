// EGM's two joint-mode messages coded by hand, beside protoc's generated classes (egm_codec.cpp).
// Written here because it is measurably better for deflex: protobuf's generated code takes 130-240 ns
// a message (bench/egm_bench, BM_EgmCodec), four of them a 4 ms cycle: a sixth of a simulated EGM
// cycle, controller and deflex together. These take 40-85 ns. Protobuf stays the reference:
// - the encoders write the bytes protobuf writes for the same message, to the byte (tested against
//   the generated classes on random messages);
// - the decoders take only the shape deflex and the cell's stand-in send and a controller sends in
//   joint mode (header, joints, the three states, the convergence flag), each field at most once,
//   and say "not mine" (false) for anything else, good or bad: the caller then decodes it with
//   protobuf, so every refusal and its reason stays protobuf's (tested on random and mutated bytes).
// Nothing here allocates or throws.
#pragma once

#include <cstddef>
#include <cstdint>

#include "deflex/wire/egm_codec.hpp"

namespace deflex::egm_fast {

// Protobuf's varint at p (moved past it). False when it runs past `end` (truncated); `bad` set when
// it is longer than 10 bytes or wider than 64 bits. The one reader of both coders (egm_codec.cpp too).
inline bool read_varint(const unsigned char*& p, const unsigned char* end, std::uint64_t& v, bool& bad) noexcept {
  v = 0;
  for (int shift = 0; shift < 70; shift += 7) {
    if (p >= end) {
      return false;
    }
    const unsigned char b = *p++;
    if (shift == 63 && b > 1) {
      bad = true;
      return true;
    }
    v |= static_cast<std::uint64_t>(b & 0x7f) << shift;
    if ((b & 0x80) == 0) {
      return true;
    }
  }
  bad = true;
  return true;
}

/// EgmRobot as protobuf serialises EgmCodec::encode_robot's message; 0 when it needs more than
/// `capacity` bytes.
[[nodiscard]] std::size_t encode_robot(const EgmRobotMessage& msg, unsigned char* out, std::size_t capacity) noexcept;

/// EgmSensor (position guidance) as protobuf serialises EgmCodec::encode_sensor's message;
/// `empty_speed_ref`: no speed reference this time but one was sent before (the reused message then
/// keeps an empty speedRef.joints). 0 when it needs more than `capacity` bytes.
[[nodiscard]] std::size_t encode_sensor(const EgmSensorMessage& msg, bool empty_speed_ref, unsigned char* out,
                                        std::size_t capacity) noexcept;

/// True and `out` filled when the bytes are a well-formed EgmRobot of the common shape that
/// EgmCodec::decode_robot would accept; false (and `out` untouched) for anything else.
[[nodiscard]] bool decode_robot(const unsigned char* data, std::size_t size, int expected_joints,
                                EgmRobotMessage& out) noexcept;

/// The same for EgmSensor and EgmCodec::decode_sensor.
[[nodiscard]] bool decode_sensor(const unsigned char* data, std::size_t size, int expected_joints,
                                 EgmSensorMessage& out) noexcept;

}  // namespace deflex::egm_fast
