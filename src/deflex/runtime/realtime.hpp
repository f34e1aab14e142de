// Real-time execution of an online session's loop on Linux: SCHED_FIFO at a stated priority, all
// memory locked (no page fault in the cycle), the loop pinned to one CPU. What each needs from the
// system (CAP_SYS_NICE or an RLIMIT_RTPRIO, CAP_IPC_LOCK or an RLIMIT_MEMLOCK, an online CPU allowed
// to the process) is named when it is refused. docs/online.md "Real-time setup" says how to grant
// them and how to isolate a core on Debian's PREEMPT_RT kernel.
#pragma once

#include <string>

namespace deflex::runtime {

struct RealtimeOptions {
  bool enabled = false;
  int priority = 80;  ///< SCHED_FIFO priority, 1..99 (the kernel's own threads run at 50 on PREEMPT_RT)
  int cpu = -1;       ///< CPU the loop is pinned to; -1: not pinned
  bool lock_memory = true;
  /// Throws InputError naming the setting.
  void validate() const;
};

/// What was granted, for the start-up line ("SCHED_FIFO 80 on CPU 1, memory locked").
struct RealtimeGrant {
  bool scheduler = false, pinned = false, locked = false;
  std::string text;
};

/// Applies the options to the calling thread (and locks the process's memory). Throws InputError
/// naming the missing permission or the CPU when the system refuses; nothing is left half-applied
/// that would not also be undone by the process ending.
RealtimeGrant make_current_thread_realtime(const RealtimeOptions& options);

/// The number of CPUs this process may run on (for messages and tests).
[[nodiscard]] int allowed_cpu_count();

}  // namespace deflex::runtime
