// The timing a controller link can see from the messages themselves: each message carries the
// controller's time stamp (EGM header.tm, RSI IPOC, both whole ms of its clock) and arrives at a time
// of the link's clock. From the two, per message: how much later than the quickest recent message it
// came (the arrival delay: queueing in the network, the kernel or a late poll), the interarrival
// jitter (RFC 3550's running estimator), and the controller cycles missed before it (from its
// sequence). A message more than one period later than the quickest is counted late. The clocks
// need no synchronisation: only differences of their difference are used, and the reference (the
// quickest message) is the minimum over the last few seconds, so a drift between the clocks of 1e-4
// moves it by less than 1 ms. Never allocates, locks or throws.
#pragma once

#include <array>
#include <cstdint>

#include "deflex/link/link_record.hpp"

namespace deflex {

/// Thread safety: one thread at a time (the link's).
class LinkTiming {
 public:
  /// `period_s`: the controller's cycle (what "late" is measured in). Throws InputError unless > 0.
  explicit LinkTiming(double period_s);

  /// A message taken. `stamp_step_s`: how far its time stamp is ahead of the previous message taken
  /// (wrap-aware, s; ignored on a new session); `receipt_s`: the link's clock when it was received;
  /// `cycles_since_previous`: controller cycles since the previous message taken (1 when none was
  /// missed; ignored on a new session). Updates counters.missed, late, max_arrival_delay_s, jitter_s
  /// and fills `arrival`.
  void on_message(double stamp_step_s, double receipt_s, std::uint64_t cycles_since_previous, bool new_session,
                  LinkCounters& counters, LinkArrival& arrival) noexcept;

  [[nodiscard]] double period_s() const { return period_s_; }

 private:
  static constexpr int kBlocks = 8;       // the minimum is taken over kBlocks blocks ...
  static constexpr double kBlockS = 1.0;  // ... of this many seconds of receipt time
  double period_s_;
  bool have_ = false;
  double stamp_s_ = 0.0;  // the continuous time stamp of the session
  double previous_offset_s_ = 0.0;
  double jitter_s_ = 0.0;
  std::array<double, kBlocks> block_min_{};
  int block_ = 0, blocks_used_ = 0;
  double block_start_s_ = 0.0;
};

}  // namespace deflex
