// The order of one sender's numbered datagrams (EGM sequence numbers, RSI IPOC time stamps, deflex
// force samples): each number is the next one, a duplicate, late (out of order), or a jump. A jump
// must never let one stray datagram capture the stream: a number far ahead of the running one (or
// far behind it) is refused until `confirm` datagrams in a row continue it with no datagram of the
// running sequence between them; only then is it a new sequence (the sender restarted without a
// silence). A jump back to a small number (a sender that restarted from its first number) is taken
// at once, as the links always did. Numbers are 32 bits wide and wrap (EGM, force samples) or
// 64 bits wide (IPOC). Never allocates, locks or throws.
#pragma once

#include <cstdint>

namespace deflex {

struct SequenceRules {
  int bits = 32;                   ///< 32 (wraps at 2^32) or 64
  std::uint64_t max_ahead = 250;   ///< a step forward larger than this is a jump
  std::uint64_t restart_max = 16;  ///< a jump back to a number <= this is a restart (0: no such rule)
  int confirm = 3;                 ///< datagrams in a row that make a jump a new sequence
  /// 64-bit numbers that may still wrap at 2^32 (RSI's IPOC: the drivers read it as 64 bits, no public
  /// source states the controller's own width): while the running number and the new one both fit in
  /// 32 bits, a step across 2^32 to a small number is the next one, not a jump back.
  bool wraps_at_32 = false;
  /// Throws InputError when a value is out of its range.
  void validate() const;
};

enum class SequenceVerdict {
  kFirst,       ///< no number before (a new session): taken
  kNext,        ///< ahead of the running number by 1..max_ahead: taken
  kRestart,     ///< a jump back to a small number, or a jump confirmed: taken as a new sequence
  kDuplicate,   ///< the running number again: refused
  kOutOfOrder,  ///< behind the running number: refused
  kFarAhead,    ///< more than max_ahead ahead: refused (until confirmed)
};
/// True for the verdicts whose datagram is taken.
[[nodiscard]] inline bool accepted(SequenceVerdict v) {
  return v == SequenceVerdict::kFirst || v == SequenceVerdict::kNext || v == SequenceVerdict::kRestart;
}

/// Thread safety: one thread at a time (observe() changes it).
class SequenceTracker {
 public:
  explicit SequenceTracker(const SequenceRules& rules = {}) : rules_(rules) {}

  /// Classifies `number` and, when it is taken, makes it the running number.
  SequenceVerdict observe(std::uint64_t number) noexcept;
  /// Forgets the running number: the next one starts a new session (after a silence).
  void reset() noexcept { have_ = false, candidates_ = 0; }

  [[nodiscard]] bool started() const { return have_; }
  [[nodiscard]] std::uint64_t last() const { return last_; }
  /// How far `number` is ahead of the running one (negative: behind), in the numbers' own width.
  [[nodiscard]] std::int64_t distance(std::uint64_t number) const noexcept;
  /// How far `to` is ahead of `from` under these rules (the 32-bit wrap, wraps_at_32).
  [[nodiscard]] static std::int64_t distance(const SequenceRules& rules, std::uint64_t from, std::uint64_t to) noexcept;
  [[nodiscard]] const SequenceRules& rules() const { return rules_; }

 private:
  SequenceRules rules_;
  bool have_ = false;
  std::uint64_t last_ = 0;
  std::uint64_t candidate_ = 0;  // the newest number of a jump not yet confirmed
  int candidates_ = 0;           // how many in a row continued it
};

}  // namespace deflex
