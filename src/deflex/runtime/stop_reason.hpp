// Why an online session ended, and the exit code `deflex online` gives for it: one table, the one in
// docs/online.md ("Faults and exit codes"). 0 only for a planned end.
#pragma once

#include "deflex/link/controller_link.hpp"

namespace deflex::runtime {

enum class StopReason : int {
  kRunning = 0,            ///< not ended yet
  kProgramEnd = 1,         ///< the program ran to its end, or the controller ended the session as planned
  kUserStop = 2,           ///< SIGINT, SIGTERM, request_stop()
  kDuration = 3,           ///< the session's time limit
  kStartRefused = 4,       ///< the arm was not where the program starts: nothing was sent
  kControllerSilent = 5,   ///< no usable controller message for longer than the stop silence
  kControllerStopped = 6,  ///< the controller stopped or faulted (RSI Timeout, EGM ended early, motors off, e-stop,
                           ///< refused points, a closed connection)
  kProtocol = 7,           ///< the controller sent what its protocol does not allow
  kSafety = 8,             ///< deflex's final guard refused a command (bound, step limit, invalid cycle)
  kTooSlow = 9,            ///< the controller falls behind the program past the stated limit
  kOutputFailed = 10,      ///< an output of the session (the cycle log, the field log, a fault dump) could not be
                           ///< written: the session ramped down and ended, naming the file
};

[[nodiscard]] const char* to_string(StopReason r);
/// 0 planned end (program end, user stop, duration); 1 an output could not be written (the job failed);
/// 2 the controller's messages out of protocol (bad
/// input); 4 start refused; 5 controller silent; 6 controller stopped or faulted; 7 deflex's safety
/// guard; 8 controller too slow. (1 and 3 keep their meaning for every deflex command: the job failed,
/// an internal error.)
[[nodiscard]] int exit_code(StopReason r);
/// The reason a link's stop cause stands for.
[[nodiscard]] StopReason stop_reason_of(LinkStopCause cause);

}  // namespace deflex::runtime
