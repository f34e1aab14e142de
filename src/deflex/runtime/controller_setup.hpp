// The controller's side of a link, chosen by link kind: what `deflex controller-setup` writes (ABB EGM's
// RAPID module and UdpUc entry; KUKA RSI's Ethernet config, context and KRL; FANUC Stream Motion's TP
// program and settings sheet; MotoROS2's configuration keys and sheet; UR's URScript servo program), from the defaults
// a session uses (link_table.hpp), so the controller's side agrees with deflex's.
#pragma once

#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "deflex/link/controller_file.hpp"
#include "deflex/model/robot_model.hpp"
#include "deflex/model/types.hpp"
#include "deflex/runtime/link_table.hpp"

namespace deflex::runtime {

/// What a controller setup is made from, in the units the command line's options take (deg, mm, s, ms),
/// each defaulting as `deflex controller-setup` does. A NaN or zero field is the link kind's default
/// where its comment says so.
struct ControllerSetupSettings {
  // deflex online's defaults, held once (link_table.hpp): the files agree with a session started with the
  // same options.
  static constexpr SessionOptionDefaults kShared = kSessionOptionDefaults;
  std::string link, sensor_ip, sentype = kShared.rsi_sentype, context = "deflex_rsi", device = "DEFLEX",
                               egm_config = "default", module = "DeflexEgm", path_frame = kShared.path_frame,
                               tool = "tool0", program, robot;
  int egm_port = 6510, rsi_port = 49152,  // the ports ABB's and KUKA's examples use
      rsi_timeout = kShared.rsi_timeout, rsi_precision = 4;
  double period_ms = 0.0,  // 0: the link kind's period
      max_joint_deg = kShared.max_joint_correction_deg, max_tcp_mm = kShared.max_tcp_correction_mm,
         ramp_in_s = kShared.ramp_in_s, comm_timeout_s = kNaN, lowpass_hz = 20.0, convergence_deg = 0.1,
         cond_time_s = 10.0, max_pos_deviation_deg = kNaN, max_speed_deviation_deg_s = kNaN, monitor_factor = 1.2,
         max_rate_deg_s = kShared.max_rate_deg_s,
         stop_silence_s = kNaN;  // NaN: the link kind's (link_table.cpp)
  // FANUC Stream Motion.
  std::string tp_program = "DEFLEXSM", fanuc_limits = "120,265,1240";
  int fanuc_version = 1, robot_port = -1, uframe = 0, utool = 1;  // robot_port -1: the protocol's
  double fanuc_correction_share = 0.25, move_speed_pct = 10.0;
  // MotoROS2 real-time.
  int motoros2_group = 0, motoros2_max_truncations = 25;
  double motoros2_resend_ms = 12.0;
  // Universal Robots RTDE.
  double ur_lookahead_ms = 30.0, ur_gain = 2000.0;
  int ur_register_offset = 24;
};

/// A setting controller-setup shares with `deflex online`: its option (a row of the settings table,
/// session_settings.hpp), the field that holds it, and the value that means "unset: the link's" (none:
/// every value is checked; NaN: a NaN is unset).
struct ControllerSetupShared {
  const char* option;
  std::variant<double ControllerSetupSettings::*, int ControllerSetupSettings::*,
               std::string ControllerSetupSettings::*>
      field;
  std::optional<double> unset;
};
/// Every setting controller-setup shares with deflex online, once: the command line binds its options
/// to these fields, and controller_setup_files() checks their values through the settings table.
[[nodiscard]] std::span<const ControllerSetupShared> controller_setup_shared();
/// The shared setting named `option`; throws std::logic_error for one that is not shared.
[[nodiscard]] const ControllerSetupShared& controller_setup_shared(std::string_view option);

/// Reads the robot file `path` ("" or "builtin": the built-in IRB 6700), as the front end reads robots
/// (the command line prints the file's notes).
using RobotLoader = std::function<RobotModel(const std::string& path)>;

/// The files for `settings.link` (egm-joint, egm-path, rsi, fanuc-j519, motoros2-rt or ur-rtde). The robot is read
/// through `load_robot` only when the link needs it (egm: its joint speed limits; a program's joints); without a
/// loader, load_robot_or_builtin. Throws InputError naming the option at fault (as `deflex controller-setup` spells it)
/// for an unknown link or a setting that cannot work.
[[nodiscard]] std::vector<ControllerFile> controller_setup_files(const ControllerSetupSettings& settings,
                                                                 const RobotLoader& load_robot = {});

}  // namespace deflex::runtime
