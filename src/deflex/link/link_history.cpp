// Ring of a link's last cycles (see link_history.hpp).
#include "deflex/link/link_history.hpp"

#include <algorithm>

namespace deflex {

LinkHistory::LinkHistory(std::size_t cycles, int joints) : joints_(joints) {
  blank_.q_nominal = blank_.q_blend = blank_.q_feedback = blank_.q_command = blank_.dtheta = JointVector::Zero(joints);
  ring_.assign(std::max<std::size_t>(cycles, 1), blank_);
}

void LinkHistory::record(const LinkCycleRecord& r) noexcept {
  ring_[head_] = r;
  head_ = (head_ + 1) % ring_.size();
  count_ = std::min(count_ + 1, ring_.size());
}

}  // namespace deflex
