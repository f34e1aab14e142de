// FANUC Stream Motion's controller side (see fanuc_controller_setup.hpp).
#include "deflex/fanuc/fanuc_controller_setup.hpp"

#include <cctype>
#include <cmath>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

void check(const FanucSetupOptions& o) {
  const std::string& n = o.program_name;
  bool ok = !n.empty() && n.size() <= 8 && std::isupper(static_cast<unsigned char>(n[0])) != 0;
  for (const char c : n) {
    ok = ok && (std::isupper(static_cast<unsigned char>(c)) != 0 || std::isdigit(static_cast<unsigned char>(c)) != 0 ||
                c == '_');
  }
  if (!ok) {
    throw InputError(fmt::format(
        "option --tp-program: '{}' must be 1..8 upper-case letters, digits or '_', starting with a letter", n));
  }
  if (std::abs(o.period_ms - 8.0) > 1e-9 && std::abs(o.period_ms - 4.0) > 1e-9 && std::abs(o.period_ms - 1.0) > 1e-9) {
    throw InputError(
        fmt::format("option --period-ms: FANUC's communication interval is 8, 4 or 1 ms (got {:g})", o.period_ms));
  }
  if (!fanuc_j519::known_version(o.version)) {
    throw InputError(fmt::format("option --fanuc-version: {} is not 1, 3 or 4", o.version));
  }
  if (!(o.move_speed_pct > 0.0 && o.move_speed_pct <= 100.0)) {
    throw InputError(fmt::format("option --move-speed-pct: 0..100 % (got {:g})", o.move_speed_pct));
  }
  if (o.uframe < 0 || o.uframe > 9 || o.utool < 1 || o.utool > 10) {
    throw InputError("options --uframe, --utool: user frame 0..9, tool frame 1..10");
  }
  if (o.start_rad.size() > static_cast<Eigen::Index>(6)) {
    throw InputError("option --program: the TP program's start position is written for arms of up to 6 joints");
  }
}

std::string tp_program(const FanucSetupOptions& o) {
  const bool move = o.start_rad.size() > 0;
  std::vector<std::string> lines = {fmt::format("UFRAME_NUM={} ;", o.uframe), fmt::format("UTOOL_NUM={} ;", o.utool)};
  if (move) lines.push_back(fmt::format("J P[1] {:.0f}% FINE ;", o.move_speed_pct));
  lines.push_back("! deflex streams from here ;");
  lines.push_back("IBGN start[1] ;");
  lines.push_back("IBGN end[1] ;");
  std::string s = fmt::format(
      "/PROG  {}\n/ATTR\nCOMMENT\t\t= \"deflex J519 stream\";\nPROTECT\t\t= READ_WRITE;\n"
      "DEFAULT_GROUP\t= 1,*,*,*,*;\n/MN\n",
      o.program_name);
  for (std::size_t i = 0; i < lines.size(); ++i) s += fmt::format("{:4d}:  {}\n", i + 1, lines[i]);
  s += "/POS\n";
  if (move) {
    s += fmt::format("P[1]{{\n   GP1:\n\tUF : {}, UT : {},\n", o.uframe, o.utool);
    for (Eigen::Index j = 0; j < o.start_rad.size(); ++j) {
      s += fmt::format("\tJ{}= {:9.3f} deg{}", j + 1, rad_to_deg(o.start_rad[j]),
                       j + 1 == o.start_rad.size() ? "\n" : (j % 3 == 2 ? ",\n" : ",\t"));
    }
    s += "};\n";
  }
  s += "/END\n";
  return s;
}

std::string settings_sheet(const FanucSetupOptions& o) {
  const fanuc_j519::AxisLimits& l = o.limits[0];
  std::string s = fmt::format(
      "deflex - FANUC Stream Motion (J519) settings for `deflex online --link fanuc-j519`\n"
      "====================================================================================\n\n"
      "Options on the controller: J519 Stream Motion (or S636 External Control Package){}.\n\n"
      "System variables (Menu > System > Variables; a cold start after changing them):\n"
      "  $STMO.$COM_INT        = {:g}      the communication interval, ms: deflex online --period-ms {:g}\n"
      "  $STMO.$PKT_STACK      = 10     commands the controller queues (2..10; unconfirmed in FANUC's text)\n"
      "  $PARAM_GROUP[1].$SV_OFF_ENB[1..9] = FALSE   brake control off (else MOTN-615); R-50iA: Brake Control\n"
      "                                              screen DISABLE; power cycle\n"
      "  $STMO_GRP[1].$FLTR_LN = 1      no extra filter on the stream (a user's program sets it; unconfirmed)\n\n"
      "Protocol version: {} (deflex online --fanuc-version {}){}.\n"
      "Port: the controller listens on UDP {} (deflex online --robot-port {}); it answers the start packet's\n"
      "sender{}.\n\n"
      "Limits deflex keeps the stream within (deflex online --fanuc-limits; the pendant shows the\n"
      "controller's as $STMO_GRP[1].$JNT_VEL_LIM / $JNT_ACC_LIM / $JNT_JRK_LIM). Before its start packet\n"
      "deflex reads the controller's threshold tables and keeps, per joint, to the stricter of a table's\n"
      "strictest value and these; a controller that does not answer (older software): these alone:\n"
      "  velocity {:g} deg/s, acceleration {:g} deg/s^2, jerk {:g} deg/s^3 (joint 1; every joint is checked);\n"
      "  the correction takes {:.0f} % of the acceleration and jerk (--fanuc-correction-share), the program the\n"
      "  rest; deflex refuses a program that alone exceeds its share before sending anything.\n\n"
      "Running it:\n"
      "  1. Load {}.LS (the ASCII Program Loader, or convert it with ROBOGUIDE) and run it in AUTO at\n"
      "     100 % override: it moves to the program's start and waits in IBGN start[1].\n"
      "  2. Start deflex online --link fanuc-j519 --robot-host <controller> ...: it sends the start packet,\n"
      "     streams one command per status, and ends with a last-data command (the program goes past\n"
      "     IBGN end[1]) and the stop packet.\n\n"
      "Alarms you may see: MOTN-603 (receiving interval over: deflex's PC missed its send windows; use\n"
      "deflex online --realtime), MOTN-601 (sequence error), MOTN-607 (protocol version mismatch: set\n"
      "--fanuc-version), MOTN-609..611 / 720..722 (a joint's velocity, acceleration or jerk: the limits\n"
      "deflex was given are above the controller's), MOTN-615 (brake control not disabled).\n",
      o.period_ms < 2.0 ? "; S647 STMO/HSPD COMM ADD-ON for the 1 ms interval (High Speed Communication ENABLE)" : "",
      o.period_ms, o.period_ms, o.version, o.version,
      o.version == 1 ? " (float32 targets; 3 and 4 need R-30iB Plus V9.40P/81+, Mini Plus V9.40P/77+ or R-50iA)"
                     : " (float64 targets)",
      o.robot_port, o.robot_port, o.pc_address.empty() ? "" : fmt::format(" ({})", o.pc_address), l.velocity,
      l.acceleration, l.jerk, 100.0 * o.correction_share, o.program_name);
  return s;
}

}  // namespace

std::vector<ControllerFile> fanuc_controller_setup(const FanucSetupOptions& options) {
  check(options);
  return {
      {options.program_name + ".LS", tp_program(options),
       "the controller's TP programs (the ASCII Program Loader loads .LS; or convert it in ROBOGUIDE): run it in AUTO "
       "before deflex online"},
      {"deflex_j519_settings.txt", settings_sheet(options),
       "a sheet for the integrator: the options and system variables to set on the controller, and the matching "
       "deflex online options"},
  };
}

}  // namespace deflex
