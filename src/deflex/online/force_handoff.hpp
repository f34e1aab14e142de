// A force sensor driver on a thread of its own hands its samples to the compensation cycle through
// this queue: one producer (the driver's thread: push()), one consumer (the cycle's thread: the
// ForceSource the cycle drains, OnlineCompensator::drain/step(input, source)). Boost.Lockfree's
// single-producer single-consumer ring (Debian's libboost-dev): wait-free on both sides, no
// allocation after construction, never blocks. A full queue refuses the new sample and counts it (the
// driver sees false), so the cycle's samples stay in order and none is overwritten under the consumer.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>

#include "deflex/online/force_sample.hpp"

namespace deflex {

/// Thread safety: push() from one producer thread while latest() and stats() run on one consumer
/// thread, without locks; never two producers or two consumers.
class ForceHandoff final : public ForceSource {
 public:
  /// Holds `capacity` samples (1 to 1 << 24; two cycles at the sensor's rate is the compensator's own
  /// queue). Throws InputError otherwise. Allocates here only.
  explicit ForceHandoff(std::size_t capacity);
  ~ForceHandoff() override;
  ForceHandoff(const ForceHandoff&) = delete;
  ForceHandoff& operator=(const ForceHandoff&) = delete;

  /// The driver's thread: queues one sample; false (and counted) when the queue is full.
  bool push(const ForceSample& sample) noexcept;
  /// The cycle's thread: the oldest sample not yet taken; false when there is none.
  bool latest(ForceSample& out) noexcept override;
  /// Counts so far: received (pushed or refused), accepted (queued), lost (refused: the queue was full).
  /// Read from the cycle's thread.
  [[nodiscard]] ForceSourceStats stats() const noexcept override;
  [[nodiscard]] std::size_t capacity() const { return capacity_; }

 private:
  // Boost's ring behind a pointer made once here, so this header does not parse Boost.Lockfree's.
  struct Ring;
  std::size_t capacity_;
  std::unique_ptr<Ring> ring_;
  // Written by the producer, read by the consumer's stats(): relaxed counts, not synchronisation.
  alignas(64) std::atomic<std::uint64_t> pushed_{0};
  std::atomic<std::uint64_t> refused_{0};
};

}  // namespace deflex
