// The force sensor driver's hand-off to the cycle (force_handoff.hpp).
#include "deflex/online/force_handoff.hpp"

#include <fmt/format.h>
#include <boost/lockfree/spsc_queue.hpp>

#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

std::size_t checked_capacity(std::size_t capacity) {
  if (capacity < 1 || capacity > (std::size_t{1} << 24)) {
    throw InputError(fmt::format("force hand-off queue: a capacity of {} samples is not 1..16777216", capacity));
  }
  return capacity;
}

}  // namespace

struct ForceHandoff::Ring {
  explicit Ring(std::size_t capacity) : queue(capacity) {}
  boost::lockfree::spsc_queue<ForceSample> queue;
};

ForceHandoff::ForceHandoff(std::size_t capacity)
    : capacity_(checked_capacity(capacity)), ring_(std::make_unique<Ring>(capacity)) {}

ForceHandoff::~ForceHandoff() = default;

bool ForceHandoff::push(const ForceSample& sample) noexcept {
  pushed_.fetch_add(1, std::memory_order_relaxed);
  if (ring_->queue.push(sample)) return true;
  refused_.fetch_add(1, std::memory_order_relaxed);
  return false;
}

bool ForceHandoff::latest(ForceSample& out) noexcept { return ring_->queue.pop(out); }

ForceSourceStats ForceHandoff::stats() const noexcept {
  ForceSourceStats s;
  s.received = pushed_.load(std::memory_order_relaxed);
  s.lost = refused_.load(std::memory_order_relaxed);
  s.accepted = s.received - s.lost;
  return s;
}

}  // namespace deflex
