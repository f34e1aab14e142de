// Stop reasons and exit codes (see stop_reason.hpp).
#include "deflex/runtime/stop_reason.hpp"

namespace deflex::runtime {

const char* to_string(StopReason r) {
  switch (r) {
    case StopReason::kRunning:
      return "running";
    case StopReason::kProgramEnd:
      return "program-end";
    case StopReason::kUserStop:
      return "user-stop";
    case StopReason::kDuration:
      return "duration";
    case StopReason::kStartRefused:
      return "start-refused";
    case StopReason::kControllerSilent:
      return "controller-silent";
    case StopReason::kControllerStopped:
      return "controller-stopped";
    case StopReason::kProtocol:
      return "protocol";
    case StopReason::kSafety:
      return "safety";
    case StopReason::kTooSlow:
      return "too-slow";
    case StopReason::kOutputFailed:
      return "output-failed";
  }
  return "unknown";
}

int exit_code(StopReason r) {
  switch (r) {
    case StopReason::kRunning:
    case StopReason::kProgramEnd:
    case StopReason::kUserStop:
    case StopReason::kDuration:
      return 0;
    case StopReason::kProtocol:
      return 2;
    case StopReason::kStartRefused:
      return 4;
    case StopReason::kControllerSilent:
      return 5;
    case StopReason::kControllerStopped:
      return 6;
    case StopReason::kSafety:
      return 7;
    case StopReason::kTooSlow:
      return 8;
    case StopReason::kOutputFailed:
      return 1;
  }
  return 1;
}

StopReason stop_reason_of(LinkStopCause cause) {
  switch (cause) {
    case LinkStopCause::kNone:
      return StopReason::kRunning;
    case LinkStopCause::kRequested:
      return StopReason::kUserStop;
    case LinkStopCause::kEnded:
      return StopReason::kProgramEnd;
    case LinkStopCause::kProtocol:
      return StopReason::kProtocol;
    case LinkStopCause::kSilent:
      return StopReason::kControllerSilent;
    case LinkStopCause::kConnection:
    case LinkStopCause::kController:
      return StopReason::kControllerStopped;
    case LinkStopCause::kSafety:
      return StopReason::kSafety;
    case LinkStopCause::kTooSlow:
      return StopReason::kTooSlow;
  }
  return StopReason::kControllerStopped;
}

}  // namespace deflex::runtime
