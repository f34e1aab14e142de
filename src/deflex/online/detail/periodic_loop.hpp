// The online cycle run by the library at a fixed period, callback style (libfranka's control loop):
// each period the library reads the robot state through your callback, drains the force source, runs
// the compensator and hands you the command to send. For controllers that do not drive the timing
// themselves (EGM does: use EgmSensorEndpoint there).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>

#include "deflex/online/online_compensator.hpp"

namespace deflex {

struct LoopStats {
  std::uint64_t cycles = 0;
  std::uint64_t overruns = 0;     ///< cycles that started later than one period after the previous one
  double max_cycle_work_s = 0.0;  ///< longest time spent in callbacks + compensator in one cycle
};

/// Fills q_planned and q_feedback (rad) of the input (t_s is set by the loop). Return false to stop.
using StateCallback = std::function<bool(CycleInput&)>;
/// Receives every cycle's output; send q_command to the robot when status >= 0.
using CommandCallback = std::function<void(const CycleOutput&)>;

/// Runs until `stop` is set or the state callback returns false. The loop itself does not allocate,
/// lock or throw; the callbacks must not either if the whole cycle is to be real-time. `source` may
/// be null. Throws InputError if period_s is not positive.
LoopStats run_periodic(OnlineCompensator& compensator, ForceSource* source, double period_s,
                       const std::atomic<bool>& stop, const StateCallback& read_state,
                       const CommandCallback& send_command);

}  // namespace deflex
