// Force samples streamed over UDP in deflex's force-datagram format (wire/force_datagram.hpp,
// docs/online.md): a bound UDP port feeding a DatagramForceSource.
#pragma once

#include <cstdint>
#include <string>

#include "deflex/sensors/datagram_force_source.hpp"
#include "deflex/transport/udp_transport.hpp"

namespace deflex {

class UdpForceSource final : public ForceSource {
 public:
  /// Binds `bind_address:port` (port 0: an ephemeral port, read it back with port()). Throws Error.
  explicit UdpForceSource(std::uint16_t port, const std::string& bind_address = "127.0.0.1")
      : transport_(bind_address, port), source_(transport_) {}

  bool latest(ForceSample& out) noexcept override { return source_.latest(out); }
  [[nodiscard]] std::uint16_t port() const { return transport_.port(); }
  [[nodiscard]] const ForceSourceCounters& counters() const { return source_.counters(); }
  [[nodiscard]] ForceSourceStats stats() const noexcept override { return source_.stats(); }

 private:
  UdpTransport transport_;
  DatagramForceSource source_;
};

}  // namespace deflex
