// The order of one sender's numbered datagrams (see sequence_tracker.hpp).
#include "deflex/transport/sequence_tracker.hpp"

#include "deflex/text/errors.hpp"

namespace deflex {

void SequenceRules::validate() const {
  if (bits != 32 && bits != 64) throw InputError("sequence rules: numbers are 32 or 64 bits wide");
  if (max_ahead < 1 || (bits == 32 && max_ahead >= (std::uint64_t{1} << 31))) {
    throw InputError("sequence rules: max_ahead must be at least 1 and less than half the number range");
  }
  if (confirm < 1 || confirm > 1000) throw InputError("sequence rules: confirm must be 1..1000");
}

namespace {
// How far `to` is ahead of `from` (negative: behind), wrapping in the numbers' width.
std::int64_t ahead(int bits, std::uint64_t from, std::uint64_t to) {
  if (bits == 32) return static_cast<std::int32_t>(static_cast<std::uint32_t>(to) - static_cast<std::uint32_t>(from));
  return static_cast<std::int64_t>(to - from);
}
}  // namespace

std::int64_t SequenceTracker::distance(std::uint64_t number) const noexcept {
  return ahead(rules_.bits, last_, number);
}

SequenceVerdict SequenceTracker::observe(std::uint64_t number) noexcept {
  if (!have_) {
    have_ = true;
    last_ = number;
    candidates_ = 0;
    return SequenceVerdict::kFirst;
  }
  const std::int64_t d = distance(number);
  if (d > 0 && static_cast<std::uint64_t>(d) <= rules_.max_ahead) {
    last_ = number;
    candidates_ = 0;  // the running sequence goes on: any half-confirmed jump was a stray
    return SequenceVerdict::kNext;
  }
  if (d == 0) return SequenceVerdict::kDuplicate;
  if (d < 0 && rules_.restart_max > 0 && number <= rules_.restart_max && last_ > number + rules_.restart_max) {
    last_ = number;
    candidates_ = 0;
    return SequenceVerdict::kRestart;
  }
  // A jump: does it continue the previous jump?
  const std::int64_t from_candidate = ahead(rules_.bits, candidate_, number);
  if (candidates_ > 0 && from_candidate > 0 && static_cast<std::uint64_t>(from_candidate) <= rules_.max_ahead) {
    ++candidates_;
  } else {
    candidates_ = 1;
  }
  candidate_ = number;
  if (candidates_ >= rules_.confirm) {
    last_ = number;
    candidates_ = 0;
    return SequenceVerdict::kRestart;
  }
  return d > 0 ? SequenceVerdict::kFarAhead : SequenceVerdict::kOutOfOrder;
}

}  // namespace deflex
