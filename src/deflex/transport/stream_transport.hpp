// How a controller link moves a byte stream (ROS-Industrial simple message over TCP), whatever carries
// it: a TCP connection on a real cell (tcp_stream.hpp) or an in-memory connection in a deterministic
// simulation (memory_stream.hpp). A stream has no message boundaries: a read may return part of a frame
// or several frames, and a write may take only part of what it is given (the peer's window is full), so
// the caller keeps the rest for later. deflex's links and the simulated controllers see only this
// interface, so the simulated cell exercises exactly the link code a real cell runs.
#pragma once

#include <cstddef>

namespace deflex {

/// Thread safety: one thread at a time (the thread of the link or simulation that owns the
/// connection), for every stream.
class StreamTransport {
 public:
  /// What read() and write() return once the connection is over (closed by either end, or broken).
  static constexpr long kClosed = -1;

  virtual ~StreamTransport() = default;

  /// Waits until bytes (or the end of the connection) are waiting, or `timeout_s` passes (NaN or
  /// negative: no wait); true when a read would return something other than 0. Simulated transports
  /// never wait: simulated time passes outside them.
  virtual bool wait_readable(double timeout_s) noexcept = 0;
  /// Non-blocking. Copies up to `capacity` waiting bytes into `buffer` and returns their count; 0 when
  /// none waits; kClosed once the connection is over and every byte sent before its end was read.
  virtual long read(unsigned char* buffer, std::size_t capacity) noexcept = 0;
  /// Non-blocking. Takes up to `size` bytes and returns how many it took (fewer than `size` when the
  /// window is full: the caller writes the rest later), or kClosed when the connection is over.
  virtual long write(const unsigned char* data, std::size_t size) noexcept = 0;
  /// Ends the connection from this side: the peer reads what was sent, then kClosed.
  virtual void close() noexcept = 0;
  [[nodiscard]] virtual bool is_open() const noexcept = 0;
  /// A descriptor poll(2) can wait on, or -1 (simulated streams).
  [[nodiscard]] virtual int descriptor() const noexcept { return -1; }

 protected:
  StreamTransport() = default;
  StreamTransport(const StreamTransport&) = default;
  StreamTransport& operator=(const StreamTransport&) = default;
};

/// Waits until either stream is readable or `timeout_s` passes (NaN or negative: no wait): one poll(2)
/// on both descriptors when both have one, otherwise each stream's own wait without waiting (a
/// simulation). True when either is readable.
bool wait_readable_any(StreamTransport& a, StreamTransport& b, double timeout_s) noexcept;

/// poll(2)'s millisecond timeout for a wait in seconds: NaN and negative give 0 (no wait), anything
/// beyond INT_MAX ms gives INT_MAX (a cast of a larger double to int is undefined).
[[nodiscard]] int poll_timeout_ms(double timeout_s) noexcept;

}  // namespace deflex
