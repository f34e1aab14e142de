// Force samples arriving as deflex force datagrams (wire/force_datagram.hpp) over any datagram
// transport: UDP from a sensor's DAQ program on a real cell, the in-memory network from the
// simulated cell's DAQ. Non-blocking; never allocates after construction.
#pragma once

#include <cstdint>

#include "deflex/online/force_sample.hpp"
#include "deflex/transport/datagram_transport.hpp"
#include "deflex/wire/force_datagram.hpp"

namespace deflex {

struct ForceSourceCounters {
  std::uint64_t received = 0, accepted = 0, malformed = 0, out_of_order = 0;
};

class DatagramForceSource : public ForceSource {
 public:
  /// `transport` must outlive the source.
  explicit DatagramForceSource(DatagramTransport& transport) : transport_(transport) {}

  /// The next new sample, oldest first. Non-finite values arrive with valid = false (the pipeline
  /// rejects them). A sample not newer than the last one is dropped and counted; a restarted sender
  /// (a jump back to a sequence number <= 16, or back by 1000 or more) is accepted.
  bool latest(ForceSample& out) noexcept override;
  [[nodiscard]] const ForceSourceCounters& counters() const { return counters_; }

 private:
  DatagramTransport& transport_;
  bool have_sequence_ = false;
  std::uint32_t last_sequence_ = 0;
  ForceSourceCounters counters_;
};

}  // namespace deflex
