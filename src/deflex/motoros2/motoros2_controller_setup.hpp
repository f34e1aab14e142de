// The controller's side of deflex's MotoROS2 real-time link, written by `deflex controller-setup --link
// motoros2-rt`: the keys of MotoROS2's motoros2_config.yaml the real-time mode reads, with the values
// deflex's own settings imply (the port it sends to, how long a silent PC keeps the session, the
// sequence gap deflex never exceeds), and a settings sheet: the ROS 2 service calls that start and end
// the mode, the interpolation period deflex must run at, and, when a program is given, the speed each
// joint's stream may reach (the program's peak, the ramp-in blend's and the correction's rate bound),
// which a Functional Safety Unit speed limit must stay above or it truncates increments. The real-time
// mode is an open pull request of MotoROS2 (not in a release): ../shared/reference/motoros2_rt.md gives
// the sources; what they leave open is marked unconfirmed in the sheet.
#pragma once

#include <string>
#include <vector>

#include "deflex/link/controller_file.hpp"
#include "deflex/model/types.hpp"

namespace deflex {

struct Motoros2SetupOptions {
  double period_ms = 4.0;       ///< deflex online --period-ms: start_rt_mode's period (4 ms for one arm)
  int robot_port = 22000;       ///< deflex online --robot-port: rt_listener_udp_port_number
  int group = 0;                ///< deflex online --motoros2-group
  double stop_silence_s = 0.5;  ///< deflex online --stop-silence-s: timeout_for_rt_msg follows it
  double resend_ms = 12.0;      ///< deflex online --motoros2-resend-ms
  int max_truncations = 25;     ///< deflex online --motoros2-max-truncations
  /// The fastest each joint's stream may go (rad/s): program peak + blend + correction rate; empty: no
  /// program given (the sheet then says how to work it out).
  JointVector stream_speed_rad_s;
  std::string pc_address;  ///< deflex's address as the controller sees it (for the sheet)
};

/// The configuration fragment and the settings sheet. Throws InputError naming the option for a period,
/// port, group or silence that cannot work.
[[nodiscard]] std::vector<ControllerFile> motoros2_controller_setup(const Motoros2SetupOptions& options);

}  // namespace deflex
