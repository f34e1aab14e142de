// Force samples arriving as deflex force datagrams (wire/force_datagram.hpp) over any datagram
// transport: UDP from a sensor's DAQ program on a real cell, the in-memory network from the
// simulated cell's DAQ. Non-blocking; never allocates after construction.
#pragma once

#include <cstdint>

#include "deflex/online/force_sample.hpp"
#include "deflex/transport/datagram_transport.hpp"
#include "deflex/transport/sequence_tracker.hpp"
#include "deflex/wire/force_datagram.hpp"

namespace deflex {

struct ForceSourceCounters {
  std::uint64_t received = 0, accepted = 0, malformed = 0, out_of_order = 0;
  std::uint64_t far_ahead = 0;  ///< a sequence number far ahead of the running one (a stray): dropped
  std::uint64_t restarts = 0;   ///< the sender started a new sequence
};

/// How force samples are ordered: a sample more than 100 ahead of the running sequence number (0.1 s
/// at 1 kHz) is a stray until 3 samples in a row continue it; a jump back to a number <= 16 is a
/// restarted sender.
[[nodiscard]] SequenceRules force_sequence_rules();

/// Thread safety: one thread at a time (the loop's), with its transport.
class DatagramForceSource : public ForceSource {
 public:
  /// `transport` must outlive the source.
  explicit DatagramForceSource(DatagramTransport& transport) : transport_(transport) {}

  /// The next new sample, oldest first. Non-finite values arrive with valid = false (the pipeline
  /// rejects them). A sample not newer than the last one is dropped and counted, and so is one far
  /// ahead of it (a stray cannot make the source drop the real samples after it); a restarted sender
  /// (a jump back to a sequence number <= 16, or any jump that 3 samples in a row continue) is accepted.
  bool latest(ForceSample& out) noexcept override;
  [[nodiscard]] const ForceSourceCounters& counters() const { return counters_; }
  [[nodiscard]] ForceSourceStats stats() const noexcept override;

 private:
  DatagramTransport& transport_;
  SequenceTracker sequence_{force_sequence_rules()};
  ForceSourceCounters counters_;
};

}  // namespace deflex
