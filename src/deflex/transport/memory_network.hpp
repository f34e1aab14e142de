// An in-memory datagram network for deterministic simulation: the simulated cell's controller, its
// force-sensor DAQ and deflex's links each get an endpoint with an address, and datagrams reach
// their destination a fixed latency after they were sent, by a shared Clock that the simulation
// advances. Nothing waits and nothing depends on the machine's speed, so a run gives the same
// figures on any number of threads. Preallocated: sending and receiving never allocate.
// Single-threaded: one network belongs to one simulation.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <limits>
#include <memory>
#include <vector>

#include "deflex/transport/clock.hpp"
#include "deflex/transport/datagram_transport.hpp"

namespace deflex {

class MemoryNetwork;

struct MemoryNetworkCounters {
  std::uint64_t delivered = 0;          ///< datagrams handed to a receiver
  std::uint64_t dropped_full = 0;       ///< the destination's queue was full (a lost datagram)
  std::uint64_t dropped_no_route = 0;   ///< no endpoint has the destination address
  std::uint64_t dropped_oversized = 0;  ///< larger than the network's datagram size (send_to fails)
  std::uint64_t dropped_outage = 0;     ///< sent during an outage (add_outage): lost
};

/// One endpoint of a MemoryNetwork. Datagrams come out in the order they were sent to it, each once
/// its delivery time has come.
/// Thread safety: one thread at a time, together with its network (one network belongs to one
/// simulation).
class MemoryTransport final : public DatagramTransport {
 public:
  /// True when the oldest waiting datagram has arrived by the clock's time (never waits).
  bool wait_readable(double timeout_s) noexcept override;
  long receive(unsigned char* buffer, std::size_t capacity, DatagramAddress& from) noexcept override;
  bool send_to(const unsigned char* data, std::size_t size, const DatagramAddress& to) noexcept override;
  [[nodiscard]] DatagramAddress local_address() const noexcept override { return address_; }
  /// The simulated clock since the last datagram received was delivered.
  [[nodiscard]] double since_receipt_s() const noexcept override;
  /// Datagrams queued here, arrived or not.
  [[nodiscard]] std::size_t queued() const { return count_; }

 private:
  friend class MemoryNetwork;
  struct Slot {
    double deliver_at_s = 0.0;
    DatagramAddress from;
    std::size_t size = 0;
    std::vector<unsigned char> bytes;
  };
  MemoryTransport(MemoryNetwork& network, const DatagramAddress& address, double latency_s, std::size_t depth,
                  std::size_t max_bytes);
  bool enqueue(const unsigned char* data, std::size_t size, const DatagramAddress& from, double deliver_at_s) noexcept;

  MemoryNetwork& network_;
  DatagramAddress address_;
  double latency_s_;
  std::vector<Slot> slots_;
  std::size_t head_ = 0, count_ = 0;
  double receipt_s_ = std::numeric_limits<double>::quiet_NaN();
};

/// Thread safety: one thread at a time: the network, its endpoints and its clock belong to one
/// simulation.
class MemoryNetwork {
 public:
  explicit MemoryNetwork(const Clock& clock, std::size_t max_datagram_bytes = 2048, std::size_t queue_depth = 512);
  /// A temporary clock would dangle: it does not compile (docs/architecture.md, "Ownership").
  explicit MemoryNetwork(const Clock&& clock, std::size_t max_datagram_bytes = 2048,
                         std::size_t queue_depth = 512) = delete;
  MemoryNetwork(const MemoryNetwork&) = delete;
  MemoryNetwork& operator=(const MemoryNetwork&) = delete;

  /// A new endpoint at `address`; what it sends arrives `latency_s` (>= 0) later. The endpoint lives
  /// as long as the network. Throws InputError when the address is taken or the latency is bad.
  MemoryTransport& add_endpoint(const DatagramAddress& address, double latency_s = 0.0);

  /// Faults for tests: every datagram sent in [from_s, to_s) from or to `address` (any address when
  /// it is the default, 0.0.0.0:0) is lost, as with a pulled cable or a switch that reboots.
  /// Throws InputError on an empty or non-finite window.
  void add_outage(double from_s, double to_s, const DatagramAddress& address = {});

  /// A fault for tests: the next `count` datagrams `from` sends at or after `from_s` are overtaken in
  /// the network by the one sent after them: it arrives first, they arrive right behind it, in order
  /// (what a switch with several paths, or a Wi-Fi bridge, does). Throws InputError unless count >= 1.
  void add_reordering(double from_s, int count, const DatagramAddress& from);

  [[nodiscard]] const Clock& clock() const { return clock_; }
  [[nodiscard]] const MemoryNetworkCounters& counters() const { return counters_; }

 private:
  friend class MemoryTransport;
  bool route(const unsigned char* data, std::size_t size, const DatagramAddress& from, const DatagramAddress& to,
             double latency_s) noexcept;

  const Clock& clock_;
  std::size_t max_bytes_;
  std::size_t depth_;
  std::deque<std::unique_ptr<MemoryTransport>> endpoints_;
  struct Outage {
    double from_s, to_s;
    DatagramAddress address;
  };
  std::vector<Outage> outages_;
  struct Held {
    std::vector<unsigned char> bytes;
    DatagramAddress from, to;
    double latency_s;
  };
  struct Reordering {
    double from_s = 0.0;
    int count = 0;  // datagrams still to hold back
    DatagramAddress from;
    std::vector<Held> held;
  };
  std::vector<Reordering> reorderings_;
  bool deliver(const unsigned char* data, std::size_t size, const DatagramAddress& from, const DatagramAddress& to,
               double latency_s) noexcept;
  MemoryNetworkCounters counters_;
};

}  // namespace deflex
