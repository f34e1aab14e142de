// Fixed-period online loop (see periodic_loop.hpp).
#include "deflex/online/detail/periodic_loop.hpp"

#include <chrono>
#include <cmath>
#include <thread>

#include "deflex/text/errors.hpp"

namespace deflex {

LoopStats run_periodic(OnlineCompensator& compensator, ForceSource* source, double period_s,
                       const std::atomic<bool>& stop, const StateCallback& read_state,
                       const CommandCallback& send_command) {
  if (!std::isfinite(period_s) || !(period_s > 0.0)) {
    throw InputError("run_periodic: period_s must be finite and > 0");
  }
  using clock = std::chrono::steady_clock;
  const auto period = std::chrono::duration_cast<clock::duration>(std::chrono::duration<double>(period_s));
  const auto start = clock::now();
  auto next = start;
  LoopStats stats;
  CycleInput in;
  in.q_planned = JointVector::Zero(compensator.model().dof());
  in.q_feedback = in.q_planned;
  while (!stop.load(std::memory_order_relaxed)) {
    const auto begin = clock::now();
    in.t_s = std::chrono::duration<double>(begin - start).count();
    if (!read_state(in)) {
      break;
    }
    const CycleOutput out = source != nullptr ? compensator.step(in, *source) : compensator.step(in);
    if (send_command) {
      send_command(out);
    }
    ++stats.cycles;
    const double work_s = std::chrono::duration<double>(clock::now() - begin).count();
    stats.max_cycle_work_s = std::max(stats.max_cycle_work_s, work_s);
    next += period;
    const auto now = clock::now();
    if (now > next) {
      // Late: count it and restart the schedule from now instead of bursting to catch up.
      ++stats.overruns;
      next = now;
    } else {
      std::this_thread::sleep_until(next);
    }
  }
  return stats;
}

}  // namespace deflex
