// The UR RTDE link's controller side (see ur_controller_setup.hpp).
#include "deflex/ur/ur_controller_setup.hpp"

#include <cmath>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

void check(const UrSetupOptions& o) {
  if (std::abs(o.period_ms - 2.0) > 1e-9 && std::abs(o.period_ms - 8.0) > 1e-9) {
    throw InputError(fmt::format(
        "option --period-ms: a UR controller's loop is 2 ms (e-Series) or 8 ms (CB3) (got {:g})", o.period_ms));
  }
  if (!std::isfinite(o.lookahead_s) || o.lookahead_s < 0.03 - 1e-12 || o.lookahead_s > 0.2 + 1e-12) {
    throw InputError(fmt::format("option --ur-lookahead-ms: servoj takes 30..200 ms (got {:g})", o.lookahead_s * 1e3));
  }
  if (!std::isfinite(o.gain) || o.gain < 100.0 || o.gain > 2000.0) {
    throw InputError(fmt::format("option --ur-gain: servoj takes 100..2000 (got {:g})", o.gain));
  }
  if (o.register_offset != 0 && o.register_offset != 24) {
    throw InputError(fmt::format("option --ur-register-offset: 0 or 24 (got {})", o.register_offset));
  }
  if (o.robot_port < 1 || o.robot_port > 65535) {
    throw InputError(fmt::format("option --robot-port: 1..65535 (got {})", o.robot_port));
  }
  // The watchdog must let a few late packages through, and still stop the arm well within a second.
  if (!std::isfinite(o.watchdog_hz) || o.watchdog_hz < 1.0 || o.watchdog_hz > 1e3 / (5.0 * o.period_ms)) {
    throw InputError(fmt::format("watchdog: 1..{:g} Hz at a {:g} ms loop (got {:g})", 1e3 / (5.0 * o.period_ms),
                                 o.period_ms, o.watchdog_hz));
  }
}

std::string register_list(const char* function, int first, int count) {
  std::string s;
  for (int k = 0; k < count; ++k) s += fmt::format("{}{}({})", k == 0 ? "" : ", ", function, first + k);
  return s;
}

// With a program: every new target's step against the stream's per-cycle limit (1 % over it, for
// rounding), so a target deflex never sends halts the program before servoj takes it.
std::string step_check(const UrSetupOptions& o) {
  if (o.stream_speed_rad_s.size() == 0) return "";
  std::string limits;
  for (Eigen::Index j = 0; j < o.stream_speed_rad_s.size(); ++j) {
    limits += fmt::format("{}{:.9f}", j == 0 ? "" : ", ", 1.01 * o.stream_speed_rad_s[j] * o.period_ms * 1e-3);
  }
  return fmt::format(
      "    # deflex's per-cycle step limit for this program (rad): a larger step is not deflex's.\n"
      "    step_max = [{}]\n"
      "    j = 0\n"
      "    while j < 6:\n"
      "      if norm(q[j] - q_last[j]) > step_max[j]:\n"
      "        popup(\"deflex: a target beyond the stream's step limit\", error=True, blocking=False)\n"
      "        halt\n"
      "      end\n"
      "      j = j + 1\n"
      "    end\n",
      limits);
}

std::string script(const UrSetupOptions& o) {
  const int r = o.register_offset;
  const double t = o.period_ms * 1e-3;
  const int hold_cycles = static_cast<int>(std::floor(0.5 / o.watchdog_hz / t));
  return fmt::format(
      "# deflex - servo program for `deflex online --link ur-rtde --ur-register-offset {r}`.\n"
      "# deflex writes, every {p:g} ms (RTDE input registers):\n"
      "#   input_int_register_{r}        a counter, one more every package (the watchdog watches it)\n"
      "#   input_int_register_{r1}        1 servo, 2 the stream has ended\n"
      "#   input_double_register_{r}..{r5} the six joint targets, rad\n"
      "#   input_double_register_{r6}     servoj's lookahead_time, s (0.03..0.2; --ur-lookahead-ms)\n"
      "#   input_double_register_{r7}     servoj's gain (100..2000; --ur-gain)\n"
      "# and reads output_int_register_{r}: the counter of the targets servoj took last.\n"
      "def deflex_servo():\n"
      "  write_output_integer_register({r}, 0)\n"
      "  textmsg(\"deflex: waiting for targets\")\n"
      "  while read_input_integer_register({r1}) != 1:\n"
      "    sync()\n"
      "  end\n"
      "  # deflex's counter must change at least {w:g} times a second, or the program stops (a stalled or\n"
      "  # lost PC never leaves the arm servoing to an old target).\n"
      "  rtde_set_watchdog(\"input_int_register_{r}\", {w:g}, \"stop\")\n"
      "  q_last = get_target_joint_positions()\n"
      "  lookahead = {la:g}\n"
      "  gain = {g:g}\n"
      "  mode = 1\n"
      "  while mode == 1:\n"
      "    mode = read_input_integer_register({r1})\n"
      "    q = [{qs}]\n"
      "    lookahead = read_input_float_register({r6})\n"
      "    gain = read_input_float_register({r7})\n"
      "    if lookahead < 0.03 or lookahead > 0.2 or gain < 100 or gain > 2000:\n"
      "      popup(\"deflex: servoj's lookahead or gain out of range\", error=True, blocking=False)\n"
      "      halt\n"
      "    end\n"
      "{step}"
      "    write_output_integer_register({r}, read_input_integer_register({r}))\n"
      "    # servoj blocks for one step ({t:g} s); its lookahead delays the target by about lookahead_time.\n"
      "    servoj(q, 0, 0, {t:g}, lookahead, gain)\n"
      "    q_last = q\n"
      "  end\n"
      "  # The stream ended: hold the last target while servoj reaches it (twice the lookahead, and less than\n"
      "  # the watchdog's period: deflex writes no more), then end.\n"
      "  k = 0\n"
      "  while k * {t:g} < 2 * lookahead and k < {hold}:\n"
      "    servoj(q_last, 0, 0, {t:g}, lookahead, gain)\n"
      "    k = k + 1\n"
      "  end\n"
      "  textmsg(\"deflex: the stream ended\")\n"
      "end\n"
      "deflex_servo()\n",
      fmt::arg("r", r), fmt::arg("r1", r + 1), fmt::arg("r5", r + 5), fmt::arg("r6", r + 6), fmt::arg("r7", r + 7),
      fmt::arg("p", o.period_ms), fmt::arg("w", o.watchdog_hz), fmt::arg("la", o.lookahead_s), fmt::arg("g", o.gain),
      fmt::arg("qs", register_list("read_input_float_register", r, 6)), fmt::arg("step", step_check(o)),
      fmt::arg("t", t), fmt::arg("hold", hold_cycles));
}

std::string speed_lines(const UrSetupOptions& o) {
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

std::string settings_sheet(const UrSetupOptions& o) {
  const double delay_ms = (o.lookahead_s + 1.0 / o.gain) * 1e3 + o.period_ms;
  return fmt::format(
      "deflex - Universal Robots settings for `deflex online --link ur-rtde`\n"
      "=====================================================================\n\n"
      "RTDE needs nothing enabled (port {}); the registers deflex uses ({} and up) must not be mapped\n"
      "to a fieldbus (EtherNet/IP, PROFINET) or written by another RTDE client (deflex then stops with\n"
      "IN_USE, naming --ur-register-offset).\n\n"
      "On the controller: load deflex_servo.script into a program (a Script node of a new program, or\n"
      "send it to the primary interface), arm at the program's start pose, and play it: it waits for\n"
      "deflex. Then, on the PC:\n"
      "  deflex online --link ur-rtde --robot-host <controller> --period-ms {:g} --ur-lookahead-ms {:g}\n"
      "    --ur-gain {:g} --ur-register-offset {} ...\n"
      "The rate: {:g} ms ({}).\n\n"
      "servoj's lookahead smooths the target by delaying it: command to motion takes about {:.1f} ms here\n"
      "(lookahead, 1/gain, one cycle). deflex measures it from actual_q and its predictive strategy leads by\n"
      "it; a shorter lookahead cuts it, at the price of a less smooth motion.\n\n"
      "The safety configuration's joint speed limits: a target faster than them is a protective stop,\n"
      "which ends deflex's session (exit 6). Set each joint's limit above what deflex streams:\n"
      "{}"
      "What ends the session: a protective stop, an e-stop or any safety mode but normal or reduced, the\n"
      "program stopped or paused (on the pendant, by its watchdog: deflex's counter unchanged for {:g} ms),\n"
      "an RTDE text message of error level, the connection closing.\n",
      o.robot_port, o.register_offset, o.period_ms, o.lookahead_s * 1e3, o.gain, o.register_offset, o.period_ms,
      o.period_ms < 5.0 ? "e-Series and later, 500 Hz" : "CB3, 125 Hz", delay_ms, speed_lines(o), 1e3 / o.watchdog_hz);
}

}  // namespace

std::vector<ControllerFile> ur_controller_setup(const UrSetupOptions& options) {
  check(options);
  return {
      {"deflex_servo.script", script(options),
       "the URScript program that hands deflex's targets to servoj: load it into a program on the controller "
       "and play it before deflex online starts"},
      {"deflex_ur_settings.txt", settings_sheet(options),
       "a sheet for the integrator: the registers, the rate, servoj's delay, and the joint speed limits that "
       "keep the safety system from stopping deflex's stream"},
  };
}

}  // namespace deflex
