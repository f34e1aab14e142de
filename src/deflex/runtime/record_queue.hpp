// How a session's cycles leave the loop's thread: a single-producer single-consumer ring of fixed
// size, lock-free (two atomic indices, acquire/release), allocated once. The loop pushes one entry per
// cycle (and a heartbeat while the controller is silent); the reporter thread (the cycle log, the
// fault dump, the status lines, the summary) pops them. A full ring drops the entry and counts it:
// the loop never waits for a slow disk or terminal.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "deflex/link/controller_link.hpp"

namespace deflex::runtime {

/// One entry from the loop to the reporter.
struct SessionEntry {
  enum class Kind : std::uint8_t {
    kCycle = 0,      ///< a cycle the link handled (record is valid)
    kHeartbeat = 1,  ///< nothing handled: the counters and state now (waiting, silent)
  };
  Kind kind = Kind::kHeartbeat;
  double t_s = 0.0;  ///< the session's clock
  LinkState state = LinkState::kWaiting;
  LinkCycleRecord record;
  LinkCounters counters;  ///< the link's counters after this entry
  CompensatorCounters compensator;
  ForceSourceStats force;  ///< the force source's counts after this entry (zero when the caller pushes samples)
};

/// Thread safety: push() from one producer thread while pop() runs on one consumer thread, without
/// locks; never two producers or two consumers.
template <class T>
class SpscRing {
 public:
  /// `capacity` is rounded up to a power of two; every slot is a copy of `prototype` (so entries
  /// holding vectors are sized once, here).
  SpscRing(std::size_t capacity, const T& prototype) {
    std::size_t n = 2;
    while (n < capacity) n <<= 1;
    slots_.assign(n, prototype);
    mask_ = n - 1;
  }
  /// Producer side. False (and nothing written) when the ring is full. Never allocates or locks.
  bool push(const T& value) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_.load(std::memory_order_acquire) > mask_) return false;
    slots_[head & mask_] = value;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }
  /// Consumer side. False when empty.
  bool pop(T& out) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_.load(std::memory_order_acquire)) return false;
    out = slots_[tail & mask_];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }
  [[nodiscard]] std::size_t capacity() const { return mask_ + 1; }

 private:
  std::vector<T> slots_;
  std::size_t mask_ = 1;
  alignas(64) std::atomic<std::size_t> head_{0};
  alignas(64) std::atomic<std::size_t> tail_{0};
};

}  // namespace deflex::runtime
