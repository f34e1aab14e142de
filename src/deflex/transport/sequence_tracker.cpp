// The order of one sender's numbered datagrams (see sequence_tracker.hpp).
#include "deflex/transport/sequence_tracker.hpp"

#include <cstdlib>

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
constexpr std::uint64_t k32 = std::uint64_t{1} << 32;
std::int64_t ahead32(std::uint64_t from, std::uint64_t to) {
  return static_cast<std::int32_t>(static_cast<std::uint32_t>(to) - static_cast<std::uint32_t>(from));
}
}  // namespace

std::int64_t SequenceTracker::distance(const SequenceRules& rules, std::uint64_t from, std::uint64_t to) noexcept {
  if (rules.bits == 32) return ahead32(from, to);
  const auto plain = static_cast<std::int64_t>(to - from);
  // A 32-bit counter read as 64 bits: across its wrap the plain difference is about -2^32.
  if (rules.wraps_at_32 && from < k32 && to < k32) {
    const std::int64_t wrapped = ahead32(from, to);
    if (std::llabs(wrapped) < std::llabs(plain)) return wrapped;
  }
  return plain;
}

std::int64_t SequenceTracker::distance(std::uint64_t number) const noexcept { return distance(rules_, last_, number); }

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
  const std::int64_t from_candidate = distance(rules_, candidate_, number);
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
