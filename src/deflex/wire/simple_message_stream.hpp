// Simple message frames over a byte stream, for both sides of a TCP link: FrameReader puts together
// whole frames from whatever pieces the stream delivers (a read may hold half a frame or three), and
// FrameOutbox keeps what a write could not take yet, so a partial write never cuts a frame in two on
// the wire. Both own one buffer sized at construction; nothing allocates afterwards. Transport-free:
// the caller moves the bytes (read into space(), write from pending()).
#pragma once

#include <cstddef>
#include <vector>

#include "deflex/wire/simple_message.hpp"

namespace deflex::simple_message {

/// Thread safety: one thread at a time.
class FrameReader {
 public:
  /// Frames longer than `max_frame_bytes` (LENGTH) are out of step. Throws InputError when
  /// max_frame_bytes is below 12 or above 1 MiB.
  FrameReader(ByteOrder order, std::size_t max_frame_bytes = kDefaultMaxFrameBytes);

  /// Where the next read may put bytes, and how many fit (never 0 while next() can make room).
  [[nodiscard]] unsigned char* space() noexcept;
  [[nodiscard]] std::size_t space_bytes() const noexcept;
  /// `n` bytes were read into space().
  void commit(std::size_t n) noexcept;

  /// The next whole frame, consumed: kComplete with `frame` pointing into this reader's buffer (valid
  /// until the next call of space()). kIncomplete: wait for more bytes. kTooShort or kOversized: the
  /// stream is out of step, nothing after it can be trusted; `length()` says the LENGTH that was read.
  FrameStatus next(FrameView& frame) noexcept;
  [[nodiscard]] std::int64_t length() const noexcept { return length_; }
  /// Bytes held that are not yet part of a returned frame.
  [[nodiscard]] std::size_t buffered() const noexcept { return end_ - begin_; }
  [[nodiscard]] ByteOrder byte_order() const noexcept { return order_; }
  [[nodiscard]] std::size_t max_frame_bytes() const noexcept { return max_frame_; }
  void clear() noexcept { begin_ = end_ = 0; }

 private:
  ByteOrder order_;
  std::size_t max_frame_;
  std::vector<unsigned char> buffer_;
  std::size_t begin_ = 0, end_ = 0;
  std::int64_t length_ = 0;
};

/// Thread safety: one thread at a time.
class FrameOutbox {
 public:
  /// Holds up to `capacity` bytes not yet taken by the stream. Throws InputError when 0.
  explicit FrameOutbox(std::size_t capacity);

  /// Room for `bytes` more at the end: where to put them (then commit), or null when there is none
  /// (the peer has stopped reading).
  [[nodiscard]] unsigned char* reserve(std::size_t bytes) noexcept;
  void commit(std::size_t bytes) noexcept;
  /// Bytes waiting for the stream, oldest first.
  [[nodiscard]] const unsigned char* pending() const noexcept { return buffer_.data() + begin_; }
  [[nodiscard]] std::size_t pending_bytes() const noexcept { return end_ - begin_; }
  /// The stream took `bytes` of pending().
  void consume(std::size_t bytes) noexcept;
  void clear() noexcept { begin_ = end_ = 0; }

 private:
  std::vector<unsigned char> buffer_;
  std::size_t begin_ = 0, end_ = 0;
};

}  // namespace deflex::simple_message
