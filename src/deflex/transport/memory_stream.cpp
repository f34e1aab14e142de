// In-memory stream connection (see memory_stream.hpp).
#include "deflex/transport/memory_stream.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex {

MemoryStreamPair::MemoryStreamPair(const Clock& clock, double latency_s, std::size_t window_bytes,
                                   std::size_t max_writes)
    : clock_(clock), latency_s_(latency_s) {
  if (!std::isfinite(latency_s) || latency_s < 0.0) {
    throw InputError(fmt::format("memory stream: latency must be finite and >= 0 s (got {})", latency_s));
  }
  if (window_bytes == 0 || window_bytes > (std::size_t{1} << 30) || max_writes == 0 || max_writes > 1'000'000) {
    throw InputError("memory stream: the window must be 1 byte..1 GiB and the writes in flight 1..1000000");
  }
  for (Direction& d : dir_) {
    d.ring.assign(window_bytes, 0);
    d.chunks.assign(max_writes, Chunk{});
  }
}

bool MemoryStreamEnd::wait_readable(double /*timeout_s*/) noexcept {
  if (closed_) return true;
  MemoryStreamPair::Direction& d = pair_.incoming(side_);
  const double now = pair_.clock_.now_s();
  if (d.chunk_count > 0 && d.chunks[d.chunk_head].deliver_at_s <= now) return true;
  return d.writer_closed_at_s >= 0.0 && now >= d.writer_closed_at_s + pair_.latency_s_ && d.read == d.written;
}

long MemoryStreamEnd::read(unsigned char* buffer, std::size_t capacity) noexcept {
  if (closed_) return kClosed;
  MemoryStreamPair::Direction& d = pair_.incoming(side_);
  const double now = pair_.clock_.now_s();
  // Everything in writes that have arrived by now may be read.
  std::uint64_t arrived = d.read;
  for (std::size_t i = 0; i < d.chunk_count; ++i) {
    const MemoryStreamPair::Chunk& c = d.chunks[(d.chunk_head + i) % d.chunks.size()];
    if (c.deliver_at_s > now) break;
    arrived = c.end;
  }
  const auto n = static_cast<std::size_t>(std::min<std::uint64_t>(capacity, arrived - d.read));
  if (n == 0) {
    const bool ended = d.writer_closed_at_s >= 0.0 && now >= d.writer_closed_at_s + pair_.latency_s_;
    return ended && d.read == d.written ? kClosed : 0;
  }
  const std::size_t size = d.ring.size();
  const auto at = static_cast<std::size_t>(d.read % size);
  const std::size_t first = std::min(n, size - at);
  std::memcpy(buffer, d.ring.data() + at, first);
  std::memcpy(buffer + first, d.ring.data(), n - first);
  d.read += n;
  while (d.chunk_count > 0 && d.chunks[d.chunk_head].end <= d.read) {
    d.chunk_head = (d.chunk_head + 1) % d.chunks.size();
    --d.chunk_count;
  }
  return static_cast<long>(n);
}

long MemoryStreamEnd::write(const unsigned char* data, std::size_t size) noexcept {
  if (closed_) return kClosed;
  MemoryStreamPair::Direction& d = pair_.outgoing(side_);
  const double now = pair_.clock_.now_s();
  // Like TCP, writing to a peer that has gone fails once its close has reached this end.
  if (d.reader_closed_at_s >= 0.0 && now >= d.reader_closed_at_s + pair_.latency_s_) return kClosed;
  const std::size_t window = d.ring.size();
  const auto unread = static_cast<std::size_t>(d.written - d.read);
  const std::size_t n = std::min(size, window - unread);
  if (n == 0) return 0;
  const double deliver_at = now + pair_.latency_s_;
  if (d.chunk_count > 0) {
    MemoryStreamPair::Chunk& last = d.chunks[(d.chunk_head + d.chunk_count - 1) % d.chunks.size()];
    if (last.deliver_at_s == deliver_at) {
      last.end += n;
    } else if (d.chunk_count == d.chunks.size()) {
      return 0;  // too many writes in flight: the window counts as full
    } else {
      d.chunks[(d.chunk_head + d.chunk_count) % d.chunks.size()] = {deliver_at, d.written + n};
      ++d.chunk_count;
    }
  } else {
    d.chunks[d.chunk_head] = {deliver_at, d.written + n};
    d.chunk_count = 1;
  }
  const auto at = static_cast<std::size_t>(d.written % window);
  const std::size_t first = std::min(n, window - at);
  std::memcpy(d.ring.data() + at, data, first);
  std::memcpy(d.ring.data(), data + first, n - first);
  d.written += n;
  return static_cast<long>(n);
}

void MemoryStreamEnd::close() noexcept {
  if (closed_) return;
  closed_ = true;
  const double now = pair_.clock_.now_s();
  pair_.outgoing(side_).writer_closed_at_s = now;
  pair_.incoming(side_).reader_closed_at_s = now;
}

bool MemoryStreamEnd::is_open() const noexcept { return !closed_; }

std::size_t MemoryStreamEnd::unread_by_peer() const noexcept {
  const MemoryStreamPair::Direction& d = pair_.outgoing(side_);
  return static_cast<std::size_t>(d.written - d.read);
}

}  // namespace deflex
