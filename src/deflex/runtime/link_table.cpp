// The table of controller links (see link_table.hpp).
#include "deflex/runtime/link_table.hpp"

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex::runtime {

const std::array<LinkKindInfo, 7>& link_kinds() {
  // Stop silences: EGM rides through outages up to 3 s (its controller holds the last target; the
  // generated RAPID's CommTimeout matches); RSI's controller stops itself long before (its Timeout of
  // late answers), so 1 s of silence means it stopped; simple message has its own state timeout.
  static const std::array<LinkKindInfo, 7> kinds{{
      {LinkKind::kEgmJoint, "egm-joint",
       "ABB EGM position guidance (EGMActJoint/EGMRunJoint): deflex streams --program", true, CommandForm::kJointTarget,
       0.004, 3.0},
      {LinkKind::kEgmPath, "egm-path",
       "ABB EGM path correction (EGMActMove + EGMMoveL/EGMMoveC): the controller runs its own program, deflex sends "
       "whole TCP offsets",
       false, CommandForm::kTcpOffset, 0.048, 3.0},
      {LinkKind::kRsi, "rsi",
       "KUKA RSI axis correction (RSI_ON(#ABSOLUTE), ETHERNET to AXISCORR): the controller runs its own KRL program, "
       "deflex answers each <Rob> with whole AK offsets",
       false, CommandForm::kJointOffset, 0.004, 1.0},
      {LinkKind::kSimpleMessage, "simple-message",
       "ROS-Industrial simple message over TCP to a robot program (ABB RAPID, Fanuc KAREL servers): deflex streams "
       "--program one point a cycle",
       true, CommandForm::kJointTarget, 0.1, 1.0},
      // FANUC's controller stops the stream itself once its queue of commands runs dry (MOTN-603): a
      // second's silence means it has stopped.
      {LinkKind::kFanucJ519, "fanuc-j519",
       "FANUC Stream Motion (J519) over UDP: deflex streams --program, one command a status, within the "
       "controller's velocity, acceleration and jerk limits",
       true, CommandForm::kJointTarget, 0.008, 1.0},
      // MotoROS2 answers each command once, and deflex sends a late one again every few cycles: half a
      // second without a reply is a controller that dropped its real-time session or stopped.
      {LinkKind::kMotoros2Rt, "motoros2-rt",
       "Yaskawa MotoROS2 real-time motion (joint increments) over UDP: deflex streams --program, one increment a "
       "reply, measured from the command position the controller reports",
       true, CommandForm::kJointTarget, 0.004, 0.5},
      // A UR controller sends its state every loop cycle over TCP, which loses nothing: half a second without a
      // package is a controller (or a connection) that stopped.
      {LinkKind::kUrRtde, "ur-rtde",
       "Universal Robots RTDE (TCP 30004): deflex streams --program as joint targets into input registers, a "
       "URScript program hands them to servoj every cycle (500 Hz e-Series, 125 Hz CB3)",
       true, CommandForm::kJointTarget, 0.002, 0.5},
  }};
  return kinds;
}

const LinkKindInfo& link_kind(LinkKind kind) { return link_kinds()[static_cast<std::size_t>(kind)]; }

std::string link_kind_names() {
  std::string names;
  for (const LinkKindInfo& k : link_kinds()) names += (names.empty() ? "" : ", ") + std::string(k.name);
  return names;
}

LinkKind parse_link_kind(const std::string& name) {
  for (const LinkKindInfo& k : link_kinds()) {
    if (name == k.name) return k.kind;
  }
  throw InputError(fmt::format("option --link: '{}' is not one of {}", name, link_kind_names()));
}

}  // namespace deflex::runtime
