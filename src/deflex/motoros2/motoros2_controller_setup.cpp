// MotoROS2 real-time's controller side (see motoros2_controller_setup.hpp).
#include "deflex/motoros2/motoros2_controller_setup.hpp"

#include <cmath>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"
#include "deflex/wire/motoros2_rt.hpp"

namespace deflex {
namespace {

void check(const Motoros2SetupOptions& o) {
  if (!std::isfinite(o.period_ms) || o.period_ms < 1.0 || o.period_ms > 100.0 ||
      std::abs(o.period_ms - std::round(o.period_ms)) > 1e-9) {
    throw InputError(fmt::format(
        "option --period-ms: MotoROS2's interpolation period is whole milliseconds, 4 for one arm (got {:g})",
        o.period_ms));
  }
  if (o.robot_port < 1 || o.robot_port > 65535) {
    throw InputError(fmt::format("option --robot-port: 1..65535 (got {})", o.robot_port));
  }
  if (o.group < 0 || o.group > 7) throw InputError(fmt::format("option --motoros2-group: 0..7 (got {})", o.group));
  if (!std::isfinite(o.resend_ms) || !(o.resend_ms > 0.0)) {
    throw InputError(fmt::format("option --motoros2-resend-ms: must be > 0 (got {:g})", o.resend_ms));
  }
  // The controller must keep the session while deflex waits for a late reply (it sends the command again
  // every resend interval).
  if (!std::isfinite(o.stop_silence_s) || o.stop_silence_s * 1e3 < 2.0 * o.resend_ms + o.period_ms) {
    throw InputError(fmt::format(
        "option --stop-silence-s: the controller's timeout_for_rt_msg follows it and must cover two resends "
        "(--motoros2-resend-ms {:g}) and a period: at least {:g} ms (got {:g} s)",
        o.resend_ms, 2.0 * o.resend_ms + o.period_ms, o.stop_silence_s));
  }
}

int timeout_ms(const Motoros2SetupOptions& o) { return static_cast<int>(std::ceil(o.stop_silence_s * 1e3 - 1e-9)); }

std::string config_fragment(const Motoros2SetupOptions& o) {
  return fmt::format(
      "# deflex - the real-time keys of MotoROS2's motoros2_config.yaml for `deflex online --link motoros2-rt`.\n"
      "# Merge them into the motoros2_config.yaml on the controller (the other keys stay as they are).\n\n"
      "# deflex online --robot-port {}: where deflex sends its commands.\n"
      "rt_listener_udp_port_number: {}\n"
      "# The status side channel (RobotState), the defaults: with deflex online --motoros2-status-port 22001\n"
      "# deflex reads it and an e-stop or an error ends its session at once.\n"
      "rt_status_udp_port_number: {}\n"
      "rt_status_sleep_period: 10\n"
      "# ms without a command before the controller ends the real-time session. deflex sends a command\n"
      "# every period, and a late one again every {:g} ms (--motoros2-resend-ms), so it never falls silent\n"
      "# while it runs; this follows deflex's own stop silence (--stop-silence-s {:g}), so a PC that\n"
      "# stalled or ended leaves the controller no longer than deflex would wait for it.\n"
      "timeout_for_rt_msg: {}\n"
      "# deflex never skips a command number (a lost command goes again with its own number): a jump of\n"
      "# more than one is not deflex's, so the controller may end the session at once.\n"
      "max_sequence_diff_for_rt_msg: 1\n",
      o.robot_port, o.robot_port, motoros2_rt::kDefaultStatusPort, o.resend_ms, o.stop_silence_s, timeout_ms(o));
}

std::string speed_lines(const Motoros2SetupOptions& o) {
  if (o.stream_speed_rad_s.size() == 0) {
    return "  (give deflex controller-setup --program P.csv for each joint's figure: the program's peak speed,\n"
           "  plus 1.5 x the start tolerance over --ramp-in-s, plus --max-rate-deg-s)\n";
  }
  std::string s;
  for (Eigen::Index j = 0; j < o.stream_speed_rad_s.size(); ++j) {
    s += fmt::format("  joint {}: above {:.3f} deg/s\n", j + 1, rad_to_deg(o.stream_speed_rad_s[j]));
  }
  return s;
}

std::string settings_sheet(const Motoros2SetupOptions& o) {
  return fmt::format(
      "deflex - MotoROS2 real-time settings for `deflex online --link motoros2-rt`\n"
      "===========================================================================\n\n"
      "The real-time interface is MotoROS2 pull request #449 (not yet in a release): check its\n"
      "doc/rt_control.md on your version before relying on a field.\n\n"
      "On the controller: MotoROS2 with the real-time interface, its INIT_ROS job for the arm's configuration\n"
      "(robot_jobs/), the controller in AUTO (remote) mode, no alarm. motoros2_config.yaml: the keys in\n"
      "deflex_motoros2_config.yaml (the usual configuration update of MotoROS2's README).\n\n"
      "On the PC, with the micro-ROS agent running:\n"
      "  1. call the service reset_error (clears alarms), then start_rt_mode\n"
      "     (motoros2_interfaces/srv/StartRtMode) with control_mode JOINT_ANGLES (1): result_code READY.\n"
      "     Its answer gives `period`: deflex online --period-ms must equal it ({:g} ms here;\n"
      "     4 for one manipulator, longer with more axes or groups).\n"
      "  2. deflex online --link motoros2-rt --robot-host <controller> --robot-port {} --motoros2-group {}\n"
      "     ...: it sends command 0 (no motion), anchors on the command position the reply reports (the arm\n"
      "     must be within the start tolerance of the program's start), and streams one increment a reply.\n"
      "  3. After deflex ends (the program's end, a stop, a fault) the controller holds the arm and ends the\n"
      "     session after timeout_for_rt_msg ({} ms); ros2 service call /stop_traj_mode ends it at once.\n"
      "     A new `deflex online` needs stop_traj_mode and start_rt_mode again (a new session starts at\n"
      "     command 0).\n\n"
      "The Functional Safety Unit: a speed limit below what deflex streams truncates increments (the reply\n"
      "flags it; deflex folds the lost motion into the next increments and stops after\n"
      "--motoros2-max-truncations {} flagged replies in a row). To stay clear of it, set each axis' limit:\n"
      "{}"
      "The controller ends the session on an increment above an axis' maximum increment per interpolation\n"
      "period (its maximum speed): the figures above must stay below the axes' maximum speeds too.\n\n"
      "What ends the session on the controller's side (deflex then reports the silence, exit 5): a command\n"
      "from a second address{}, a jump in the command numbers, an increment above an axis' maximum, a\n"
      "datagram of another size or version, timeout_for_rt_msg without a command, an e-stop or alarm.\n",
      o.period_ms, o.robot_port, o.group, timeout_ms(o), o.max_truncations, speed_lines(o),
      o.pc_address.empty() ? "" : fmt::format(" (deflex sends from {})", o.pc_address));
}

}  // namespace

std::vector<ControllerFile> motoros2_controller_setup(const Motoros2SetupOptions& options) {
  check(options);
  return {
      {"deflex_motoros2_config.yaml", config_fragment(options),
       "merge these keys into motoros2_config.yaml on the controller (MotoROS2 README, \"Updating the "
       "configuration\"), then restart MotoROS2"},
      {"deflex_motoros2_settings.txt", settings_sheet(options),
       "a sheet for the integrator: the service calls that start and end the real-time mode, the period, and "
       "the speed limits that keep the safety unit from truncating deflex's increments"},
  };
}

}  // namespace deflex
