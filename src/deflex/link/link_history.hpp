// The last cycles of a controller link in a preallocated ring (libfranka keeps its last cycles the
// same way), written out as CSV for a post-mortem after a fault. Recording never allocates.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "deflex/link/controller_link.hpp"

namespace deflex {

class LinkHistory {
 public:
  /// `cycles` >= 1 records of `joints` joints each, allocated here once.
  LinkHistory(std::size_t cycles, int joints);

  void record(const LinkCycleRecord& r) noexcept;
  [[nodiscard]] std::size_t size() const { return count_; }
  /// A record with every joint vector sized for the robot (a link's starting value).
  [[nodiscard]] const LinkCycleRecord& blank() const { return blank_; }
  /// Oldest first: t_s, sequence, status, replied, then q_nominal, q_feedback, q_command, dtheta in
  /// degrees, the TCP correction in mm, the wrenches in N and Nm, the delay and compute time in ms,
  /// then how the message arrived (arrival delay and jitter in ms, cycles missed before it).
  /// Throws Error naming the path when it cannot be written.
  void write_csv(const std::string& path) const;

 private:
  std::vector<LinkCycleRecord> ring_;
  std::size_t head_ = 0, count_ = 0;
  LinkCycleRecord blank_;
  int joints_;
};

}  // namespace deflex
