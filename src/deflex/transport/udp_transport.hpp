// A datagram transport over an IPv4 UDP socket: bind, non-blocking receive with the sender's address,
// the true datagram size (so oversized packets are seen) and the kernel's receive time stamp (so the
// time from a datagram's arrival to its answer is known, scheduling included), send to an address,
// wait with a timeout. Owns the descriptor; only the constructor throws.
#pragma once

#include <cstdint>
#include <string>

#include "deflex/transport/datagram_transport.hpp"

namespace deflex {

/// Thread safety: one thread at a time (receive() keeps the time stamp since_receipt_s() reads).
class UdpTransport final : public DatagramTransport {
 public:
  /// Binds `address:port` (port 0: ephemeral, read it back with port()). Throws Error naming the
  /// address on failure, InputError when `address` is not IPv4.
  UdpTransport(const std::string& address, std::uint16_t port);
  ~UdpTransport() override;
  UdpTransport(const UdpTransport&) = delete;
  UdpTransport& operator=(const UdpTransport&) = delete;

  bool wait_readable(double timeout_s) noexcept override;
  long receive(unsigned char* buffer, std::size_t capacity, DatagramAddress& from) noexcept override;
  bool send_to(const unsigned char* data, std::size_t size, const DatagramAddress& to) noexcept override;
  [[nodiscard]] DatagramAddress local_address() const noexcept override { return local_; }
  [[nodiscard]] double since_receipt_s() const noexcept override;
  [[nodiscard]] std::uint16_t port() const { return local_.port; }

 private:
  int fd_ = -1;
  DatagramAddress local_;
  bool stamped_ = false;       // the kernel time-stamps datagrams (SO_TIMESTAMPNS)
  long long receipt_ns_ = -1;  // CLOCK_REALTIME of the last datagram received, ns (-1: unknown)
};

}  // namespace deflex
