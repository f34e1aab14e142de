// How a controller link moves datagrams, whatever carries them: UDP sockets on a real cell
// (udp_transport.hpp) or an in-memory network in a deterministic simulation (memory_network.hpp).
// The links and the simulated controllers talk through this interface only, so the simulated cell
// exercises exactly the link code a real cell runs.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>

namespace deflex {

/// An IPv4 address and port, both in host byte order.
struct DatagramAddress {
  std::uint32_t ipv4 = 0;
  std::uint16_t port = 0;
  friend bool operator==(const DatagramAddress&, const DatagramAddress&) = default;
};

/// "127.0.0.1", 6510 -> address. Throws InputError naming the text when it is not an IPv4 address.
[[nodiscard]] DatagramAddress make_datagram_address(const std::string& ipv4, std::uint16_t port);
/// "127.0.0.1:6510".
[[nodiscard]] std::string to_string(const DatagramAddress& address);

/// Thread safety: one thread at a time (the thread of the link or simulation that owns the
/// endpoint), for every transport.
class DatagramTransport {
 public:
  virtual ~DatagramTransport() = default;

  /// Waits until a datagram is waiting or `timeout_s` passes (NaN or negative: no wait); true when
  /// one is waiting. Simulated transports never wait: simulated time passes outside them.
  virtual bool wait_readable(double timeout_s) noexcept = 0;
  /// Non-blocking receive of the next datagram into `buffer`. Returns its full size (larger than
  /// `capacity` when it was cut, so the caller can count it as oversized), or -1 when none waits.
  virtual long receive(unsigned char* buffer, std::size_t capacity, DatagramAddress& from) noexcept = 0;
  /// Sends one datagram; false when it could not be sent.
  virtual bool send_to(const unsigned char* data, std::size_t size, const DatagramAddress& to) noexcept = 0;
  /// The address datagrams to this transport are sent to.
  [[nodiscard]] virtual DatagramAddress local_address() const noexcept = 0;
  /// How long ago (s) the datagram last returned by receive() reached this host: for UDP the
  /// kernel's receive time stamp (SO_TIMESTAMPNS), so it includes every scheduling delay before the
  /// program read it; NaN when the transport cannot tell. The answer time of a link is this, taken
  /// when its answer is sent.
  [[nodiscard]] virtual double since_receipt_s() const noexcept { return std::numeric_limits<double>::quiet_NaN(); }

 protected:
  DatagramTransport() = default;
  DatagramTransport(const DatagramTransport&) = default;
  DatagramTransport& operator=(const DatagramTransport&) = default;
};

}  // namespace deflex
