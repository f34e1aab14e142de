// Timing of a controller link from its messages' time stamps (see link_timing.hpp).
#include "deflex/link/link_timing.hpp"

#include <algorithm>
#include <cmath>

#include "deflex/text/errors.hpp"

namespace deflex {

LinkTiming::LinkTiming(double period_s) : period_s_(period_s) {
  if (!std::isfinite(period_s) || !(period_s > 0.0)) throw InputError("link timing: the period must be > 0 s");
}

void LinkTiming::on_message(double stamp_step_s, double receipt_s, std::uint64_t cycles_since_previous,
                            bool new_session, LinkCounters& counters, LinkArrival& arrival) noexcept {
  const bool first = new_session || !have_ || !std::isfinite(stamp_step_s);
  if (first) {
    have_ = true;
    stamp_s_ = 0.0;
    jitter_s_ = 0.0;
    blocks_used_ = 0;
    block_ = 0;
    cycles_since_previous = 1;
  } else {
    stamp_s_ += stamp_step_s;
  }
  const double offset = receipt_s - stamp_s_;
  // The windowed minimum of the offset: the current block's minimum, and the older blocks'.
  if (blocks_used_ == 0) {
    blocks_used_ = 1;
    block_start_s_ = receipt_s;
    block_min_[static_cast<std::size_t>(block_)] = offset;
  } else if (receipt_s - block_start_s_ >= kBlockS) {
    block_ = (block_ + 1) % kBlocks;
    blocks_used_ = std::min(blocks_used_ + 1, kBlocks);
    block_start_s_ = receipt_s;
    block_min_[static_cast<std::size_t>(block_)] = offset;
  } else {
    block_min_[static_cast<std::size_t>(block_)] = std::min(block_min_[static_cast<std::size_t>(block_)], offset);
  }
  double reference = offset;
  for (int i = 0; i < blocks_used_; ++i) reference = std::min(reference, block_min_[static_cast<std::size_t>(i)]);

  if (!first) jitter_s_ += (std::abs(offset - previous_offset_s_) - jitter_s_) / 16.0;
  previous_offset_s_ = offset;

  arrival.stamp_s = stamp_s_;
  arrival.arrival_delay_s = offset - reference;
  arrival.jitter_s = jitter_s_;
  arrival.missed_before = cycles_since_previous > 1 ? cycles_since_previous - 1 : 0;
  counters.missed += arrival.missed_before;
  if (arrival.arrival_delay_s > period_s_) ++counters.late;
  counters.max_arrival_delay_s = std::max(counters.max_arrival_delay_s, arrival.arrival_delay_s);
  counters.jitter_s = jitter_s_;
}

}  // namespace deflex
