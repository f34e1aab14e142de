// Force samples streamed over UDP, one datagram a sample, in deflex's documented format
// (docs/online.md, "UDP force-sample format"): 64 bytes, little-endian,
//   0  char[4] magic "DFXF"     4  uint32 sequence number (increments by one a sample)
//   8  float64 t_s (sender's clock)   16  float64[6] Fx Fy Fz (N) Mx My Mz (Nm), sensor frame.
// Decoded field by field with memcpy (no casting onto packed structs).
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "deflex/online/force_sample.hpp"

namespace deflex {

inline constexpr std::size_t kForceDatagramBytes = 64;

/// Encodes a sample into a 64-byte datagram.
void encode_force_datagram(const ForceSample& sample, std::uint32_t sequence,
                           std::array<unsigned char, kForceDatagramBytes>& out) noexcept;
/// Decodes a datagram; false when the size or magic is wrong. Non-finite values decode with
/// valid = false (the pipeline rejects them).
bool decode_force_datagram(const unsigned char* data, std::size_t size, ForceSample& out,
                           std::uint32_t& sequence) noexcept;

struct UdpForceCounters {
  std::uint64_t received = 0, accepted = 0, malformed = 0, out_of_order = 0;
};

/// Receives the stream on a UDP port (loopback by default). Non-blocking; never allocates after
/// construction.
class UdpForceSource final : public ForceSource {
 public:
  /// Binds `bind_address:port` (port 0: an ephemeral port, read it back with port()). Throws Error.
  explicit UdpForceSource(std::uint16_t port, const std::string& bind_address = "127.0.0.1");
  ~UdpForceSource() override;
  UdpForceSource(const UdpForceSource&) = delete;
  UdpForceSource& operator=(const UdpForceSource&) = delete;

  bool latest(ForceSample& out) noexcept override;
  [[nodiscard]] std::uint16_t port() const { return port_; }
  [[nodiscard]] const UdpForceCounters& counters() const { return counters_; }

 private:
  int fd_ = -1;
  std::uint16_t port_ = 0;
  bool have_sequence_ = false;
  std::uint32_t last_sequence_ = 0;
  UdpForceCounters counters_;
};

}  // namespace deflex
