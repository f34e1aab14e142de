// An in-memory stream connection for deterministic simulation, the stream twin of memory_network.hpp:
// two ends on a shared Clock; what one end writes the other can read `latency_s` later, in order, as a
// byte stream (a read may split one write or join several). Each direction holds at most
// `window_bytes` unread bytes, so a writer that outruns its reader sees partial writes exactly as on
// TCP. Either end may close: the other reads what was sent before, then kClosed, and its writes fail
// once the close has reached it. Nothing waits and nothing depends on the machine's speed.
// Preallocated: reading and writing never allocate. Single-threaded: one pair belongs to one simulation.
#pragma once

#include <cstdint>
#include <vector>

#include "deflex/transport/clock.hpp"
#include "deflex/transport/stream_transport.hpp"

namespace deflex {

class MemoryStreamPair;

/// One end of a MemoryStreamPair.
/// Thread safety: one thread at a time, together with its pair.
class MemoryStreamEnd final : public StreamTransport {
 public:
  bool wait_readable(double timeout_s) noexcept override;
  long read(unsigned char* buffer, std::size_t capacity) noexcept override;
  long write(const unsigned char* data, std::size_t size) noexcept override;
  void close() noexcept override;
  [[nodiscard]] bool is_open() const noexcept override;
  /// Bytes written here and not yet read by the peer (arrived or not).
  [[nodiscard]] std::size_t unread_by_peer() const noexcept;

 private:
  friend class MemoryStreamPair;
  MemoryStreamEnd(MemoryStreamPair& pair, int side) : pair_(pair), side_(side) {}
  MemoryStreamPair& pair_;
  int side_;  // 0: client, 1: server
  bool closed_ = false;
};

/// Thread safety: one thread at a time: the pair and both its ends belong to one simulation.
class MemoryStreamPair {
 public:
  /// `latency_s` >= 0 one way; `window_bytes` >= 1 unread bytes per direction; `max_writes` >= 1
  /// writes in flight per direction (writes at the same instant count once). Throws InputError.
  MemoryStreamPair(const Clock& clock, double latency_s, std::size_t window_bytes = 65536,
                   std::size_t max_writes = 4096);
  /// A temporary clock would dangle: it does not compile (docs/architecture.md, "Ownership").
  MemoryStreamPair(const Clock&& clock, double latency_s, std::size_t window_bytes = 65536,
                   std::size_t max_writes = 4096) = delete;
  MemoryStreamPair(const MemoryStreamPair&) = delete;
  MemoryStreamPair& operator=(const MemoryStreamPair&) = delete;

  /// The connecting end (deflex's link) and the accepting end (the controller's server program).
  [[nodiscard]] MemoryStreamEnd& client() { return client_; }
  [[nodiscard]] MemoryStreamEnd& server() { return server_; }
  [[nodiscard]] const Clock& clock() const { return clock_; }

 private:
  friend class MemoryStreamEnd;
  struct Chunk {
    double deliver_at_s = 0.0;
    std::uint64_t end = 0;  // stream offset one past this write's last byte
  };
  struct Direction {
    std::vector<unsigned char> ring;
    std::vector<Chunk> chunks;
    std::size_t chunk_head = 0, chunk_count = 0;
    std::uint64_t written = 0, read = 0;
    double writer_closed_at_s = -1.0;  // < 0: the writing end is open
    double reader_closed_at_s = -1.0;  // < 0: the reading end is open
  };
  // Direction d carries bytes written by end d (0: client to server, 1: server to client).
  Direction& outgoing(int side) { return dir_[side]; }
  Direction& incoming(int side) { return dir_[1 - side]; }

  const Clock& clock_;
  double latency_s_;
  Direction dir_[2];
  MemoryStreamEnd client_{*this, 0};
  MemoryStreamEnd server_{*this, 1};
};

}  // namespace deflex
