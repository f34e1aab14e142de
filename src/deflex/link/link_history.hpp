// The last cycles of a controller link in a preallocated ring (libfranka keeps its last cycles the
// same way), for a post-mortem after a fault (the runtime writes them out, runtime/cycle_log.hpp).
// Recording never allocates.
#pragma once

#include <cstddef>
#include <vector>

#include "deflex/link/link_record.hpp"

namespace deflex {

/// Thread safety: one thread at a time (the link's).
class LinkHistory {
 public:
  /// `cycles` >= 1 records of `joints` joints each, allocated here once.
  LinkHistory(std::size_t cycles, int joints);

  void record(const LinkCycleRecord& r) noexcept;
  [[nodiscard]] std::size_t size() const { return count_; }
  [[nodiscard]] std::size_t capacity() const { return ring_.size(); }
  /// The k-th record kept, oldest first (k < size()).
  [[nodiscard]] const LinkCycleRecord& at(std::size_t k) const {
    return ring_[(head_ + ring_.size() - count_ + k) % ring_.size()];
  }
  /// Forgets every record (the ring keeps its storage).
  void clear() noexcept { head_ = count_ = 0; }
  /// A record with every joint vector sized for the robot (a link's starting value).
  [[nodiscard]] const LinkCycleRecord& blank() const { return blank_; }
  [[nodiscard]] int joints() const { return joints_; }

 private:
  std::vector<LinkCycleRecord> ring_;
  std::size_t head_ = 0, count_ = 0;
  LinkCycleRecord blank_;
  int joints_;
};

}  // namespace deflex
