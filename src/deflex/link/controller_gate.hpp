// Which of a link's decoded messages may be taken, the same rule for every controller link (EGM, RSI):
// one controller (address and port) owns the link, and another sender is refused until the controller
// has been silent for the restart silence, measured from its last datagram of any kind (usable or
// not: while it keeps sending it has not gone away); the sequence numbers are ordered by the
// SequenceTracker (duplicates, late ones and strays far ahead refused); a silence, a change of sender
// or a jump confirmed by the messages after it begins a new session; every message taken is timed
// against its time stamp (LinkTiming). Counts what it refuses. Never allocates, locks or throws.
//
// A restart is told from reordering by the time stamp: a message a little behind the running number
// (within the reorder window) whose time stamp is not newer than the newest taken was overtaken in the
// network and is refused as late, however many such come in a row; a controller that restarted numbers
// from its first again but its clock goes on, so its message is newer. A time stamp that goes back, or
// moves by far more than the cycles the sequence says passed, is a jump of the controller's clock: the
// timing starts afresh (counted in clock_jumps) instead of reading the jump as delay or jitter.
#pragma once

#include <cstdint>

#include "deflex/link/link_record.hpp"
#include "deflex/link/link_timing.hpp"
#include "deflex/transport/datagram_transport.hpp"
#include "deflex/transport/sequence_tracker.hpp"

namespace deflex {

struct ControllerGateConfig {
  SequenceRules sequence;
  double restart_silence_s = 0.5;  ///< a silence this long ends the session
  double period_s = 0.004;         ///< the controller's cycle (for the timing)
  /// How far the sequence number moves in one cycle: 1 for a counter (EGM seqno), the period in ms
  /// for a millisecond time stamp (RSI IPOC). Gives the cycles missed between two messages.
  double numbers_per_cycle = 1.0;
  int stamp_bits = 32;  ///< width of the millisecond time stamp: 32 wraps (EGM tm), 64 (IPOC)
  /// Messages this many numbers behind the running one, or fewer, whose time stamp is not newer than
  /// the newest taken, are late (overtaken), never the start of a new sequence.
  std::uint64_t reorder_window = 32;
  /// Throws InputError naming the setting.
  void validate() const;
};

/// Thread safety: one thread at a time (the link's).
class ControllerGate {
 public:
  /// Throws InputError on a bad configuration.
  explicit ControllerGate(const ControllerGateConfig& config);

  /// Every datagram as it is read, before anything else is known of it.
  void heard(const DatagramAddress& from, double now_s) noexcept;
  /// A decoded message the link could use: `number` its sequence number, `stamp_ms` its time stamp.
  /// True when it is taken; then `session_start` tells whether it begins a new session (counted in
  /// restarts after the first) and `arrival` how it arrived. A refused message is counted
  /// (foreign_sender, duplicate, out_of_order, far_ahead).
  bool take(const DatagramAddress& from, std::uint64_t number, std::uint64_t stamp_ms, double now_s,
            LinkCounters& counters, bool& session_start, LinkArrival& arrival) noexcept;

  [[nodiscard]] bool has_controller() const { return have_sender_; }
  [[nodiscard]] const DatagramAddress& controller() const { return sender_; }

 private:
  ControllerGateConfig config_;
  SequenceTracker sequence_;
  LinkTiming timing_;
  bool have_sender_ = false;
  bool resync_ = false;  // the controller fell silent: the next message taken begins a session
  DatagramAddress sender_;
  double last_heard_s_ = 0.0;
  std::uint64_t last_stamp_ms_ = 0;
  [[nodiscard]] std::int64_t stamp_step_ms(std::uint64_t stamp_ms) const noexcept;
};

}  // namespace deflex
