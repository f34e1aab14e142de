// A minimal IPv4 UDP socket for the EGM link: bind, non-blocking receive with the sender's address
// and the true datagram size (to spot oversized packets), send to an address, wait with a timeout.
// Owns the descriptor; only the constructor throws.
#pragma once

#include <netinet/in.h>

#include <cstddef>
#include <cstdint>
#include <string>

namespace deflex {

class UdpSocket {
 public:
  /// Binds `address:port` (port 0: ephemeral). Throws Error naming the address on failure.
  UdpSocket(const std::string& address, std::uint16_t port);
  ~UdpSocket();
  UdpSocket(const UdpSocket&) = delete;
  UdpSocket& operator=(const UdpSocket&) = delete;

  [[nodiscard]] std::uint16_t port() const { return port_; }
  /// Waits until a datagram is readable or `timeout_s` passes. Returns true when readable.
  bool wait_readable(double timeout_s) noexcept;
  /// Non-blocking receive. Returns the datagram's full size (may exceed `capacity`: then the copy is
  /// cut), or -1 when nothing is waiting.
  long receive(unsigned char* buffer, std::size_t capacity, sockaddr_in& from) noexcept;
  bool send_to(const unsigned char* data, std::size_t size, const sockaddr_in& to) noexcept;

 private:
  int fd_ = -1;
  std::uint16_t port_ = 0;
};

/// "127.0.0.1", 6510 -> sockaddr_in. Throws InputError on a bad address.
sockaddr_in make_address(const std::string& address, std::uint16_t port);

}  // namespace deflex
