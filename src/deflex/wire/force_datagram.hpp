// deflex's force-sample datagram (docs/online.md, "UDP force-sample format"): one sample a datagram,
// 64 bytes, little-endian,
//   0  char[4] magic "DFXF"     4  uint32 sequence number (increments by one a sample)
//   8  float64 t_s (sender's clock)   16  float64[6] Fx Fy Fz (N) Mx My Mz (Nm), sensor frame.
// Encoded and decoded field by field with memcpy (no casting onto packed structs). Both sides use it:
// a sensor's DAQ program (or the simulated cell's DAQ) sends, deflex's force source receives.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "deflex/model/types.hpp"

namespace deflex {

inline constexpr std::size_t kForceDatagramBytes = 64;

/// The sample a datagram carries: sensor time (s) and wrench in the sensor frame (N, Nm).
struct ForceDatagram {
  std::uint32_t sequence = 0;
  double t_s = 0.0;
  Vector6 wrench_sensor = Vector6::Zero();
};

/// Encodes one sample into a 64-byte datagram.
void encode_force_datagram(const ForceDatagram& sample, std::array<unsigned char, kForceDatagramBytes>& out) noexcept;
/// Decodes a datagram; false when the size or magic is wrong. Values are copied as they are
/// (non-finite ones included: the receiver decides what to do with them).
bool decode_force_datagram(const unsigned char* data, std::size_t size, ForceDatagram& out) noexcept;

}  // namespace deflex
