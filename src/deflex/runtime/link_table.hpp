// The controller links a session can run, as one explicit table (no static self-registration): each
// kind's name, what it needs and what its command is, and the defaults that differ between them. A
// further link is a row here and a case in Session::open_link.
#pragma once

#include <array>
#include <string>

#include "deflex/link/link_cycle.hpp"

namespace deflex::runtime {

enum class LinkKind : int {
  kEgmJoint = 0,
  kEgmPath = 1,
  kRsi = 2,
  kSimpleMessage = 3,
  kFanucJ519 = 4,
  kMotoros2Rt = 5,
  kUrRtde = 6
};

struct LinkKindInfo {
  LinkKind kind;
  const char* name;  ///< the --link value
  const char* help;
  bool streams_program;           ///< deflex is the motion source: needs a program (--program)
  CommandForm form;               ///< what goes on the wire
  double default_period_s;        ///< the controller's cycle when none is given
  double default_stop_silence_s;  ///< how long a silence is ridden through by default
};

/// The settings `deflex online` and `deflex controller-setup` share, held once: the controller's side a
/// setup writes (its bounds, ramp-in, SENTYPE) agrees with what the session does by default.
/// Units as the options take them (deg, mm, s, ms); the period and the stop silence come with the
/// link kind (LinkKindInfo). The ports have none: a session is told which port its controller uses.
struct SessionOptionDefaults {
  double max_joint_correction_deg = 0.5;  ///< --max-joint-correction-deg
  double max_tcp_correction_mm = 5.0;     ///< --max-tcp-correction-mm
  double max_rate_deg_s = 3.0;            ///< --max-rate-deg-s
  double max_tcp_rate_mm_s = 5.0;         ///< --max-tcp-rate-mm-s
  double ramp_in_s = 1.0;                 ///< --ramp-in-s (egm-joint, simple-message)
  const char* path_frame = "tool";        ///< --path-corr-frame (egm-path)
  const char* rsi_sentype = "ImFree";     ///< --rsi-sentype
  int rsi_timeout = 100;                  ///< --rsi-timeout: late answers before the RSI controller stops
};
inline constexpr SessionOptionDefaults kSessionOptionDefaults{};

[[nodiscard]] const std::array<LinkKindInfo, 7>& link_kinds();
[[nodiscard]] const LinkKindInfo& link_kind(LinkKind kind);
/// The kind named `name`; throws InputError naming it and listing the known names.
[[nodiscard]] LinkKind parse_link_kind(const std::string& name);
/// "egm-joint, egm-path, rsi, simple-message".
[[nodiscard]] std::string link_kind_names();

}  // namespace deflex::runtime
