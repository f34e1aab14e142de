// Simple message frames over a byte stream (see simple_message_stream.hpp).
#include "deflex/wire/simple_message_stream.hpp"

#include <algorithm>
#include <cstring>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex::simple_message {

FrameReader::FrameReader(ByteOrder order, std::size_t max_frame_bytes) : order_(order), max_frame_(max_frame_bytes) {
  if (max_frame_bytes < kHeaderBytes || max_frame_bytes > (std::size_t{1} << 20)) {
    throw InputError(
        fmt::format("simple message: the largest frame must be 12 bytes..1 MiB (got {})", max_frame_bytes));
  }
  // Two whole frames and their prefixes: a frame that straddles the end always fits after compaction.
  buffer_.assign(2 * (max_frame_bytes + kLengthBytes), 0);
}

unsigned char* FrameReader::space() noexcept {
  if (begin_ > 0) {
    // Move the unfinished frame to the front (at most one frame's bytes: cheap), so space() and
    // space_bytes() agree in whichever order a caller evaluates them.
    std::memmove(buffer_.data(), buffer_.data() + begin_, end_ - begin_);
    end_ -= begin_;
    begin_ = 0;
  }
  return buffer_.data() + end_;
}

std::size_t FrameReader::space_bytes() const noexcept { return buffer_.size() - (end_ - begin_); }

void FrameReader::commit(std::size_t n) noexcept { end_ = std::min(buffer_.size(), end_ + n); }

FrameStatus FrameReader::next(FrameView& frame) noexcept {
  std::size_t bytes = 0;
  const FrameStatus s = peek_frame(order_, buffer_.data() + begin_, end_ - begin_, max_frame_, bytes, length_);
  if (s == FrameStatus::kComplete) {
    frame = view_frame(order_, buffer_.data() + begin_, bytes);
    begin_ += bytes;
  }
  return s;
}

FrameOutbox::FrameOutbox(std::size_t capacity) {
  if (capacity == 0) throw InputError("simple message: the outbox needs room for at least one byte");
  buffer_.assign(capacity, 0);
}

unsigned char* FrameOutbox::reserve(std::size_t bytes) noexcept {
  if (buffer_.size() - end_ < bytes && begin_ > 0) {
    std::memmove(buffer_.data(), buffer_.data() + begin_, end_ - begin_);
    end_ -= begin_;
    begin_ = 0;
  }
  return buffer_.size() - end_ >= bytes ? buffer_.data() + end_ : nullptr;
}

void FrameOutbox::commit(std::size_t bytes) noexcept { end_ = std::min(buffer_.size(), end_ + bytes); }

void FrameOutbox::consume(std::size_t bytes) noexcept {
  begin_ = std::min(end_, begin_ + bytes);
  if (begin_ == end_) begin_ = end_ = 0;
}

}  // namespace deflex::simple_message
