// The controller's side of deflex's UR RTDE link, written by `deflex controller-setup --link ur-rtde`:
// the URScript program that hands deflex's targets to servoj (its register layout, the lookahead and
// gain deflex sends, the RTDE watchdog on deflex's counter, and, given a program, a check of every
// target's step against the stream's own per-cycle limit, a second guard on the controller), and a
// settings sheet: where the program goes, the rate, and the joint speed limits the safety configuration
// must stay above so it does not protective-stop deflex's stream. Facts and sources:
// ../shared/reference/ur_rtde.md.
#pragma once

#include <string>
#include <vector>

#include "deflex/link/controller_file.hpp"
#include "deflex/model/types.hpp"

namespace deflex {

struct UrSetupOptions {
  double period_ms = 2.0;     ///< deflex online --period-ms: 2 (e-Series) or 8 (CB3)
  double lookahead_s = 0.03;  ///< deflex online --ur-lookahead-ms (the script takes what deflex sends)
  double gain = 2000.0;       ///< deflex online --ur-gain
  int register_offset = 24;   ///< deflex online --ur-register-offset
  int robot_port = 30004;     ///< deflex online --robot-port
  double watchdog_hz = 10.0;  ///< rtde_set_watchdog's minimum frequency of deflex's counter
  /// The fastest each joint's stream may go (rad/s): program peak + blend + correction rate; empty: no
  /// program given (the script then checks no step, the sheet says how to work it out).
  JointVector stream_speed_rad_s;
};

/// The URScript program and the settings sheet. Throws InputError naming the option for a period,
/// lookahead, gain, register offset or watchdog that cannot work.
[[nodiscard]] std::vector<ControllerFile> ur_controller_setup(const UrSetupOptions& options);

}  // namespace deflex
