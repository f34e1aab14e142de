// The table of online settings (see session_settings.hpp).
#include "deflex/runtime/session_settings.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <vector>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"
#include "deflex/text/parse_number.hpp"
#include "deflex/wire/rsi_xml.hpp"

namespace deflex::runtime {
namespace {

using C = SessionConfig;
constexpr double kDegPerRad = 180.0 / kPi;

constexpr LinkMask kStreaming = link_bit(LinkKind::kEgmJoint) | link_bit(LinkKind::kSimpleMessage) |
                                link_bit(LinkKind::kFanucJ519) | link_bit(LinkKind::kUrRtde);
constexpr LinkMask kEgm = link_bit(LinkKind::kEgmJoint) | link_bit(LinkKind::kEgmPath);
constexpr LinkMask kPath = link_bit(LinkKind::kEgmPath);
constexpr LinkMask kRsi = link_bit(LinkKind::kRsi);
constexpr LinkMask kSm = link_bit(LinkKind::kSimpleMessage);
constexpr LinkMask kFanuc = link_bit(LinkKind::kFanucJ519);
constexpr LinkMask kMoto = link_bit(LinkKind::kMotoros2Rt);
constexpr LinkMask kUr = link_bit(LinkKind::kUrRtde);

// The getters and setters of a table row come from one accessor of the field (a lambda without
// captures: C++20 constructs one where it is needed).
template <typename Field>
double get_real(const C& c) {
  C copy = c;  // the accessor hands out a reference to change: never called on the cycle
  return static_cast<double>(Field{}(copy));
}
template <typename Field>
void put_real(C& c, double v) {
  Field{}(c) = v;
}
template <typename Field>
bool get_flag(const C& c) {
  C copy = c;
  return Field{}(copy);
}
template <typename Field>
void put_flag(C& c, bool v) {
  Field{}(c) = v;
}
template <typename Field>
double get_count(const C& c) {
  C copy = c;
  return static_cast<double>(Field{}(copy));
}
template <typename Field>
void put_count(C& c, double v) {
  using T = std::remove_reference_t<decltype(Field{}(c))>;
  Field{}(c) = static_cast<T>(v);
}

template <typename Field>
SessionSetting real(SessionSetting s, Field /*field*/) {
  s.type = SettingType::kReal;
  s.get_real = &get_real<Field>;
  if (s.set_real == nullptr) s.set_real = &put_real<Field>;  // one value for several fields sets them all
  return s;
}
template <typename Field>
SessionSetting count(SessionSetting s, Field /*field*/) {
  s.type = SettingType::kInteger;
  s.get_real = &get_count<Field>;
  s.set_real = &put_count<Field>;
  return s;
}
template <typename Field>
SessionSetting flag(SessionSetting s, Field /*field*/) {
  s.type = SettingType::kFlag;
  s.get_flag = &get_flag<Field>;
  s.set_flag = &put_flag<Field>;
  return s;
}
SessionSetting text(SessionSetting s, std::string (*get)(const C&), void (*set)(C&, const std::string&)) {
  s.type = SettingType::kText;
  s.get_text = get;
  s.set_text = set;
  return s;
}
template <typename Field>
SessionSetting words(SessionSetting s, Field /*field*/) {
  return text(
      s,
      [](const C& c) {
        C copy = c;
        return std::string(Field{}(copy));
      },
      [](C& c, const std::string& v) { Field{}(c) = v; });
}

// The controller's cycle and what every command is held to.
void bound_settings(std::vector<SessionSetting>& t) {
  t.push_back(
      real({.key = "period_s",
            .option = "--period-ms",
            .unit = "s",
            .option_unit = "ms",
            .option_per_unit = 1e3,
            .min = 5e-4,
            .max = 1.0,
            .help = "the controller's cycle",
            .why = "a controller's cycle is 0.5 ms to 1 s",
            .default_text =
                "the link's: egm-joint, rsi 4; egm-path 48 (EGMActMove's SampleRate); "
                "simple-message 100 (the paper's); fanuc-j519 8; motoros2-rt 4 (the period start_rt_mode returns); "
                "ur-rtde 2 (e-Series; CB3: 8)"},
           [](C& c) -> double& { return c.online.period_s; }));
  t.push_back(real({.key = "max_joint_correction_rad",
                    .option = "--max-joint-correction-deg",
                    .unit = "rad",
                    .option_unit = "deg",
                    .option_per_unit = kDegPerRad,
                    .min = 0.0,
                    .max = deg_to_rad(10.0),
                    .min_open = true,
                    .help = "bound on each joint's correction: no command leaves the nominal by more",
                    .why = "a compliance correction is a fraction of a degree"},
                   [](C& c) -> double& { return c.online.max_joint_correction_rad; }));
  t.push_back(real({.key = "max_tcp_correction_m",
                    .option = "--max-tcp-correction-mm",
                    .unit = "m",
                    .option_unit = "mm",
                    .option_per_unit = 1e3,
                    .min = 0.0,
                    .max = 0.05,
                    .min_open = true,
                    .help = "bound on the TCP displacement of the correction",
                    .why = "a compliance correction is a few millimetres"},
                   [](C& c) -> double& { return c.online.max_tcp_correction_m; }));
}

// How fast the correction may change, and where its Jacobian is taken.
void rate_settings(std::vector<SessionSetting>& t) {
  t.push_back(real({.key = "max_correction_rate_rad_s",
                    .option = "--max-rate-deg-s",
                    .unit = "rad/s",
                    .option_unit = "deg/s",
                    .option_per_unit = kDegPerRad,
                    .min = 0.0,
                    .max = deg_to_rad(30.0),
                    .min_open = true,
                    .help = "bound on each joint's correction rate (times the period: the correction's largest "
                            "step a cycle, which must fit in its bound)",
                    .why = "a correction follows a process force, not a motion"},
                   [](C& c) -> double& { return c.online.max_correction_rate_rad_s; }));
  t.push_back(real({.key = "max_tcp_rate_m_s",
                    .option = "--max-tcp-rate-mm-s",
                    .unit = "m/s",
                    .option_unit = "mm/s",
                    .option_per_unit = 1e3,
                    .min = 0.0,
                    .max = 0.5,
                    .min_open = true,
                    .help = "bound on the rate of the correction's TCP translation: a stale force ramps out at it "
                            "on every link (egm-path: the offset's largest step a cycle)",
                    .why = "a correction follows a process force, not a motion"},
                   [](C& c) -> double& { return c.online.max_tcp_rate_m_s; }));
  t.push_back(real({.key = "watchdog_s",
                    .option = "--watchdog-ms",
                    .unit = "s",
                    .option_unit = "ms",
                    .option_per_unit = 1e3,
                    .min = 1e-3,
                    .max = 10.0,
                    .help = "no valid force sample for this long: the correction ramps to zero"},
                   [](C& c) -> double& { return c.online.watchdog_s; }));
  t.push_back(text(
      {.key = "jacobian_at",
       .option = "--jacobian-at",
       .help = "where the Jacobian is taken: nominal (the configuration the command is for; 'planned' "
               "says the same) or feedback"},
      [](const C& c) { return std::string(c.online.jacobian_at == JacobianAt::kPlanned ? "nominal" : "feedback"); },
      [](C& c, const std::string& v) {
        if (v == "nominal" || v == "planned") {
          c.online.jacobian_at = JacobianAt::kPlanned;
        } else if (v == "feedback") {
          c.online.jacobian_at = JacobianAt::kFeedback;
        } else {
          throw InputError(fmt::format("'{}' is not nominal, planned or feedback", v));
        }
      }));
}

// When a session ends.
void stop_settings(std::vector<SessionSetting>& t) {
  t.push_back({.key = "stop_silence_s",
               .option = "--stop-silence-s",
               .type = SettingType::kReal,
               .unit = "s",
               .min = 0.0,
               .max = 60.0,
               .min_open = true,
               .help = "no usable controller message this long: the controller is gone and the session stops (exit "
                       "code 5); shorter silences are ridden through",
               .default_text = "the link's: egm-joint, egm-path 3; rsi, simple-message, fanuc-j519 1; motoros2-rt 0.5",
               .get_real = [](const C& c) { return c.stop_silence_s.value_or(0.0); },
               .set_real = [](C& c, double v) { c.stop_silence_s = v; }});
  t.push_back(real({.key = "end_silence_s",
                    .option = "--end-silence-s",
                    .unit = "s",
                    .min = 0.0,
                    .max = 60.0,
                    .min_open = true,
                    .links = kStreaming,
                    .help = "after the program's end, a controller silence this long ends the session (exit 0)"},
                   [](C& c) -> double& { return c.end_silence_s; }));
  t.push_back(flag({.key = "end_on_silence",
                    .option = "--end-on-silence",
                    .links = kPath | kRsi,
                    .help = "a silence longer than the stop silence after a healthy session is the planned end (the "
                            "program's EGMStop or RSI_OFF): exit 0 instead of 5"},
                   [](C& c) -> bool& { return c.end_on_silence; }));
  t.push_back(real({.key = "duration_s",
                    .option = "--duration-s",
                    .unit = "s",
                    .min = 0.0,
                    .max = 1e6,
                    .help = "stop after this long (0: run until stopped)"},
                   [](C& c) -> double& { return c.duration_s; }));
  t.push_back(real({.key = "stop_ramp_s",
                    .option = "--stop-ramp-s",
                    .unit = "s",
                    .min = 0.05,
                    .max = 10.0,
                    .help = "a planned stop while moving: streamed programs come to rest on their path over this "
                            "long, corrections ramp out at the rate bound; a second stop request stops at once"},
                   [](C& c) -> double& { return c.stop_ramp_s; }));
}

// What a session reports and writes while it runs, and how its loop is scheduled.
void report_settings(std::vector<SessionSetting>& t) {
  t.push_back(real({.key = "status_interval_s",
                    .option = "--status-interval-s",
                    .unit = "s",
                    .min = 0.0,
                    .max = 3600.0,
                    .help = "a status line this often (0: none)"},
                   [](C& c) -> double& { return c.status_interval_s; }));
  t.push_back(words({.key = "log_path", .option = "--log", .help = "CSV log of every cycle (written off the loop)"},
                    [](C& c) -> std::string& { return c.log_path; }));
  t.push_back(words({.key = "fault_dump_path",
                     .option = "--fault-dump",
                     .help = "CSV the last cycles are written to, once per fault episode and at a stop for a fault "
                             "(checked for writability at start)"},
                    [](C& c) -> std::string& { return c.fault_dump_path; }));
  t.push_back(real({.key = "monitor_window_s",
                    .option = "--monitor-window-s",
                    .unit = "s",
                    .min = 1.0,
                    .max = 3600.0,
                    .help = "the history the live monitor page keeps and shows"},
                   [](C& c) -> double& { return c.monitor_window_s; }));
  t.push_back(flag({.key = "realtime",
                    .option = "--realtime",
                    .help = "run the loop with SCHED_FIFO, memory locked (and pinned with the CPU setting); refused "
                            "(exit 2) naming the missing permission when the system does not allow it"},
                   [](C& c) -> bool& { return c.realtime.enabled; }));
  t.push_back(count({.key = "rt_priority",
                     .option = "--rt-priority",
                     .min = 1,
                     .max = 99,
                     .help = "with realtime: the SCHED_FIFO priority"},
                    [](C& c) -> int& { return c.realtime.priority; }));
  t.push_back(count({.key = "rt_cpu",
                     .option = "--rt-cpu",
                     .min = 0,
                     .max = 1023,
                     .help = "with realtime: the CPU the loop is pinned to (an isolated core)",
                     .default_text = "not pinned"},
                    [](C& c) -> int& { return c.realtime.cpu; }));
  t.push_back(flag({.key = "rt_lock_memory",
                    .option = "--rt-no-mlock",
                    .help = "with realtime: do not lock the process's memory (the key says the opposite: lock it)",
                    .flag_inverted = true},
                   [](C& c) -> bool& { return c.realtime.lock_memory; }));
}

// Where the controller is reached.
void network_settings(std::vector<SessionSetting>& t) {
  constexpr double kPort = 65535.0;
  t.push_back(words({.key = "bind_address",
                     .option = "--bind",
                     .help = "the address the link's and the UDP force port bind to (0.0.0.0 or the cell network's "
                             "on a real cell)"},
                    [](C& c) -> std::string& { return c.network.bind_address; }));
  t.push_back(count({.key = "egm_port",
                     .option = "--egm-port",
                     .min = 0,
                     .max = kPort,
                     .links = kEgm,
                     .help = "the UDP port the controller's EGM messages arrive on (ABB's examples: 6510; 0: any free "
                             "one)",
                     .default_text = "required"},
                    [](C& c) -> int& { return c.network.egm_port; }));
  t.push_back(count({.key = "rsi_port",
                     .option = "--rsi-port",
                     .min = 0,
                     .max = kPort,
                     .links = kRsi,
                     .help = "the UDP port the controller's <Rob> documents arrive on (its Ethernet config's <PORT>)",
                     .default_text = "required"},
                    [](C& c) -> int& { return c.network.rsi_port; }));
  t.push_back(words({.key = "robot_host",
                     .option = "--robot-host",
                     .links = kSm | kFanuc | kMoto | kUr,
                     .help = "the controller's address (simple-message: its motion and state servers listen there; "
                             "fanuc-j519, motoros2-rt: its IPv4 address; ur-rtde: its RTDE server's)"},
                    [](C& c) -> std::string& { return c.network.robot_host; }));
  t.push_back(count({.key = "robot_port",
                     .option = "--robot-port",
                     .min = 1,
                     .max = kPort,
                     .links = kFanuc | kMoto | kUr,
                     .help = "the controller's port (fanuc-j519: Stream Motion's UDP; motoros2-rt: its "
                             "rt_listener_udp_port_number; ur-rtde: RTDE's TCP)",
                     .default_text = "the protocol's: fanuc-j519 60015, motoros2-rt 22000, ur-rtde 30004"},
                    [](C& c) -> int& { return c.network.robot_port; }));
  t.push_back(count({.key = "motion_port",
                     .option = "--motion-port",
                     .min = 1,
                     .max = kPort,
                     .links = kSm,
                     .help = "the TCP port of the motion server (JOINT_TRAJ_PT)"},
                    [](C& c) -> int& { return c.network.motion_port; }));
  t.push_back(count({.key = "state_port",
                     .option = "--state-port",
                     .min = 1,
                     .max = kPort,
                     .links = kSm,
                     .help = "the TCP port of the state server (JOINT_POSITION)"},
                    [](C& c) -> int& { return c.network.state_port; }));
  t.push_back(real({.key = "connect_timeout_s",
                    .option = "--connect-timeout-s",
                    .unit = "s",
                    .min = 0.0,
                    .max = 600.0,
                    .min_open = true,
                    .links = kSm | kUr,
                    .help = "the wait for each connection"},
                   [](C& c) -> double& { return c.network.connect_timeout_s; }));
}

// ABB EGM's own settings (the ramp-in is the streaming links').
void egm_settings(std::vector<SessionSetting>& t) {
  t.push_back(real({.key = "ramp_in_s",
                    .option = "--ramp-in-s",
                    .unit = "s",
                    .min = 0.0,
                    .max = 60.0,
                    .links = kStreaming,
                    .help = "the blend from where the controller is to the program takes this long",
                    .set_real =
                        [](C& c, double v) {
                          c.egm_joint.stream.ramp_in_s = c.simple_message.stream.ramp_in_s = v;
                          c.fanuc_j519.stream.ramp_in_s = c.motoros2_rt.stream.ramp_in_s = v;
                          c.ur_rtde.stream.ramp_in_s = v;
                        }},
                   [](C& c) -> double& { return c.egm_joint.stream.ramp_in_s; }));
  t.push_back(flag({.key = "send_speed_reference",
                    .option = "--no-speed-reference",
                    .links = link_bit(LinkKind::kEgmJoint),
                    .help = "do not send the target's joint speeds (the key says the opposite: send them)",
                    .flag_inverted = true},
                   [](C& c) -> bool& { return c.egm_joint.send_speed_reference; }));
  t.push_back(text(
      {.key = "path_corr_frame",
       .option = "--path-corr-frame",
       .links = kPath,
       .help = "the frame EGMActMove was given: tool (tool.tframe), flange (tool0) or path (path "
               "coordinates)"},
      [](const C& c) { return std::string(to_string(c.egm_path.frame)); },
      [](C& c, const std::string& v) { c.egm_path.frame = parse_path_corr_frame(v); }));
  t.push_back(real({.key = "correction_latency_s",
                    .option = "--correction-latency-ms",
                    .unit = "s",
                    .option_unit = "ms",
                    .option_per_unit = 1e3,
                    .min = 0.0,
                    .max = 1.0,
                    .links = kPath,
                    .help = "predictive: the controller's correction latency beyond the measured servo delay"},
                   [](C& c) -> double& { return c.egm_path.correction_latency_s; }));
  t.push_back(real({.key = "rotation_warning_rad",
                    .option = "--rotation-warning-mrad",
                    .unit = "rad",
                    .option_unit = "mrad",
                    .option_per_unit = 1e3,
                    .min = 0.0,
                    .max = 1.0,
                    .links = kPath,
                    .help = "report when the model predicts a TCP rotation above this (path correction cannot "
                            "correct it)"},
                   [](C& c) -> double& { return c.egm_path.rotation_warning_rad; }));
}

// KUKA RSI's own settings.
void rsi_settings(std::vector<SessionSetting>& t) {
  t.push_back(text(
      {.key = "rsi_sentype",
       .option = "--rsi-sentype",
       .links = kRsi,
       .help = "the Type of every answer, the controller's <SENTYPE>"},
      [](const C& c) { return c.rsi.sentype; },
      [](C& c, const std::string& v) {
        if (!valid_rsi_sentype(v)) {
          throw InputError(fmt::format("'{}' must be 1..32 letters, digits, '_' or '-', starting with a letter", v));
        }
        c.rsi.sentype = v;
      }));
  t.push_back(real({.key = "rsi_correction_latency_s",
                    .option = "--rsi-correction-latency-ms",
                    .unit = "s",
                    .option_unit = "ms",
                    .option_per_unit = 1e3,
                    .min = 0.0,
                    .max = 1.0,
                    .links = kRsi,
                    .help = "predictive: AXISCORR's latency beyond the delay the link measures (ASPos to AIPos)"},
                   [](C& c) -> double& { return c.rsi.correction_latency_s; }));
  t.push_back(count({.key = "rsi_max_document_bytes",
                     .option = "--rsi-max-document-bytes",
                     .min = 64,
                     .max = 65507,
                     .links = kRsi,
                     .help = "larger datagrams are counted oversized and never answered",
                     .why = "a UDP datagram carries at most 65507 bytes"},
                    [](C& c) -> std::size_t& { return c.rsi.max_document_bytes; }));
  t.push_back(count({.key = "rsi_timeout",
                     .option = "--rsi-timeout",
                     .min = 1,
                     .max = 1e6,
                     .links = kRsi,
                     .help = "the ETHERNET object's Timeout on the controller (late answers before RSI stops; "
                             "controller-setup writes the same): with the <Delay> it reports, an RSI stopped by it "
                             "is recognised"},
                    [](C& c) -> int& { return c.rsi.controller_timeout; }));
}

void simple_message_settings(std::vector<SessionSetting>& t) {
  t.push_back(text(
      {.key = "byte_order",
       .option = "--byte-order",
       .links = kSm,
       .help = "the server's byte order: little (ABB RAPID, Motoman DX100/DX200/YRC1000) or big (Fanuc "
               "KAREL, Motoman FS100)"},
      [](const C& c) { return std::string(simple_message::to_string(c.simple_message.byte_order)); },
      [](C& c, const std::string& v) { c.simple_message.byte_order = simple_message::parse_byte_order(v); }));
  t.push_back(count({.key = "buffer_depth",
                     .option = "--buffer-depth",
                     .min = 1,
                     .max = 64,
                     .links = kSm,
                     .help = "points kept queued on the controller; each adds one cycle of lag (reported; the "
                             "predictive strategy leads by the measured delay)"},
                    [](C& c) -> int& { return c.simple_message.buffer_depth; }));
  t.push_back(real({.key = "reply_timeout_s",
                    .option = "--reply-timeout-s",
                    .unit = "s",
                    .min = 0.0,
                    .max = 60.0,
                    .min_open = true,
                    .links = kSm,
                    .help = "a point unanswered this long stops the motion"},
                   [](C& c) -> double& { return c.simple_message.reply_timeout_s; }));
  t.push_back(real({.key = "state_timeout_s",
                    .option = "--state-timeout-s",
                    .unit = "s",
                    .min = 0.0,
                    .max = 60.0,
                    .min_open = true,
                    .links = kSm,
                    .help = "no JOINT_POSITION this long stops the motion"},
                   [](C& c) -> double& { return c.simple_message.state_timeout_s; }));
  t.push_back(count({.key = "max_failures",
                     .option = "--max-failures",
                     .min = 1,
                     .max = 1000,
                     .links = kSm,
                     .help = "FAILURE replies in a row (buffer full, point refused) before the motion is stopped"},
                    [](C& c) -> int& { return c.simple_message.max_failures; }));
  t.push_back(count({.key = "max_frame_bytes",
                     .option = "--max-frame-bytes",
                     .min = 64,
                     .max = 1 << 20,
                     .links = kSm,
                     .help = "the largest frame LENGTH accepted; a larger one means the stream is out of step"},
                    [](C& c) -> std::size_t& { return c.simple_message.max_frame_bytes; }));
  t.push_back(real({.key = "max_behind_s",
                    .option = "--max-behind-s",
                    .unit = "s",
                    .min = 0.0,
                    .max = 600.0,
                    .min_open = true,
                    .links = kSm,
                    .help = "a controller that takes points slower than the program's cycle may fall this far "
                            "behind the program before the motion is stopped (exit code 8)"},
                   [](C& c) -> double& { return c.simple_message.max_behind_s; }));
}

std::string fanuc_limits_text(const C& c) {
  const auto& l = c.fanuc_j519.limits;
  const auto triple = [](const fanuc_j519::AxisLimits& a) {
    return fmt::format("{},{},{}", number_text(a.velocity), number_text(a.acceleration), number_text(a.jerk));
  };
  const bool same = std::all_of(l.begin(), l.end(), [&](const fanuc_j519::AxisLimits& a) {
    return a.velocity == l[0].velocity && a.acceleration == l[0].acceleration && a.jerk == l[0].jerk;
  });
  if (same) return triple(l[0]);
  std::string s;
  for (const auto& a : l) {
    if (!s.empty()) s += ';';
    s += triple(a);
  }
  return s;
}

void fanuc_settings(std::vector<SessionSetting>& t) {
  t.push_back(count({.key = "fanuc_version",
                     .option = "--fanuc-version",
                     .min = 1,
                     .max = 4,
                     .links = kFanuc,
                     .help = "the Stream Motion protocol version the controller speaks: 1 (float32 targets), 3 or 4 "
                             "(float64; R-30iB Plus V9.40P and later)"},
                    [](C& c) -> std::uint32_t& { return c.fanuc_j519.version; }));
  t.push_back(text({.key = "fanuc_limits",
                    .option = "--fanuc-limits",
                    .links = kFanuc,
                    .help = "the controller's limits on the stream, VEL,ACC,JERK in deg/s, deg/s^2, deg/s^3, for "
                            "every joint, or one triple a joint separated by ';' (its threshold tables' strictest "
                            "values or the pendant's $STMO_GRP limits; default a CRX-10iA/L's strictest)"},
                   &fanuc_limits_text,
                   [](C& c, const std::string& v) { c.fanuc_j519.limits = parse_fanuc_limits(v, "fanuc_limits"); }));
  t.push_back(real({.key = "fanuc_correction_share",
                    .option = "--fanuc-correction-share",
                    .min = 0.0,
                    .max = 1.0,
                    .min_open = true,
                    .max_open = true,
                    .links = kFanuc,
                    .help = "the share of the acceleration and jerk limits the correction may take (the program "
                            "keeps the rest); the correction is smoothed to stay within it (its delay is reported)"},
                   [](C& c) -> double& { return c.fanuc_j519.correction_share; }));
  t.push_back(count({.key = "fanuc_catch_up",
                     .option = "--fanuc-catch-up",
                     .min = 0,
                     .max = 9,
                     .links = kFanuc,
                     .help = "statuses lost or late in a row that deflex answers with one command each, in order, as "
                             "FANUC's driver does (more: the session stops, too slow); at most the controller's "
                             "queue"},
                    [](C& c) -> int& { return c.fanuc_j519.max_catch_up; }));
}

void motoros2_settings(std::vector<SessionSetting>& t) {
  t.push_back(count({.key = "motoros2_group",
                     .option = "--motoros2-group",
                     .min = 0,
                     .max = 7,
                     .links = kMoto,
                     .help = "the control group deflex streams (0: the first robot)"},
                    [](C& c) -> int& { return c.motoros2_rt.group; }));
  t.push_back(count({.key = "motoros2_tool",
                     .option = "--motoros2-tool",
                     .min = 0,
                     .max = 63,
                     .links = kMoto,
                     .help = "the tool number sent with every command"},
                    [](C& c) -> int& { return c.motoros2_rt.tool; }));
  t.push_back(real({.key = "motoros2_resend_s",
                    .option = "--motoros2-resend-ms",
                    .unit = "s",
                    .option_unit = "ms",
                    .option_per_unit = 1e3,
                    .min = 0.0,
                    .max = 1.0,
                    .min_open = true,
                    .links = kMoto,
                    .help = "a command whose reply has not come this long is sent again with the same number (the "
                            "controller applies it at most once)"},
                   [](C& c) -> double& { return c.motoros2_rt.resend_after_s; }));
  t.push_back(count({.key = "motoros2_max_truncations",
                     .option = "--motoros2-max-truncations",
                     .min = 0,
                     .max = 100000,
                     .links = kMoto,
                     .help = "replies in a row flagging an increment the controller's Functional Safety Unit "
                             "truncated before the session stops (the program is faster than its speed limit)"},
                    [](C& c) -> int& { return c.motoros2_rt.max_truncation_run; }));
  t.push_back(count({.key = "motoros2_status_port",
                     .option = "--motoros2-status-port",
                     .min = 1,
                     .max = 65535,
                     .links = kMoto,
                     .help = "read the controller's RobotState on this UDP port (its rt_status_udp_port_number, "
                             "22001): an e-stop, an error, the drives off end the session at once; without it they "
                             "show as the controller's silence",
                     .default_text = "not read"},
                    [](C& c) -> int& { return c.motoros2_rt.status_port; }));
}

// servoj's parameters go to the controller every cycle; the registers are the script's layout.
void ur_settings(std::vector<SessionSetting>& t) {
  t.push_back(real({.key = "ur_lookahead_s",
                    .option = "--ur-lookahead-ms",
                    .unit = "s",
                    .option_unit = "ms",
                    .option_per_unit = 1e3,
                    .min = 0.03,
                    .max = 0.2,
                    .links = kUr,
                    .help = "servoj's lookahead_time: it smooths the target by delaying it (command to motion takes "
                            "about this plus 1/gain and a cycle; the predictive strategy leads by the measured delay)"},
                   [](C& c) -> double& { return c.ur_rtde.lookahead_s; }));
  t.push_back(real({.key = "ur_gain",
                    .option = "--ur-gain",
                    .min = 100.0,
                    .max = 2000.0,
                    .links = kUr,
                    .help = "servoj's proportional gain (higher follows the target more closely)"},
                   [](C& c) -> double& { return c.ur_rtde.gain; }));
  t.push_back(count({.key = "ur_register_offset",
                     .option = "--ur-register-offset",
                     .min = 0,
                     .max = 24,
                     .links = kUr,
                     .help = "the first RTDE input and output register of deflex's layout: 0, or 24 (the upper "
                             "range, clear of fieldbus mappings); the script controller setup writes must agree"},
                    [](C& c) -> int& { return c.ur_rtde.register_offset; }));
}

// The force source and the tare (session_force.hpp opens it).
void force_settings(std::vector<SessionSetting>& t) {
  t.push_back(words({.key = "force_source",
                     .option = "--force-source",
                     .help = "where the force samples come from: udp:PORT, csv:FILE or rdt:HOST[:PORT]"},
                    [](C& c) -> std::string& { return c.force.source; }));
  t.push_back(flag({.key = "loop", .option = "--loop", .help = "with csv:FILE, replay the file again and again"},
                   [](C& c) -> bool& { return c.force.loop; }));
  t.push_back(words({.key = "rdt_calibration",
                     .option = "--rdt-calibration",
                     .help = "rdt: counts to N and Nm: sensor (its netftapi2.xml over HTTP), FILE.xml (a saved "
                             "page), http://URL, onrobot-hex, or counts:counts_per_force=C,counts_per_torque=C,"
                             "force_unit=U,torque_unit=U"},
                    [](C& c) -> std::string& { return c.force.rdt_calibration; }));
  t.push_back(real({.key = "rdt_rate_hz",
                    .option = "--rdt-rate-hz",
                    .unit = "Hz",
                    .min = 1.0,
                    .max = 1e5,
                    .help = "rdt: the sensor's RDT rate (required for counts:; OnRobot 1000/n)",
                    .default_text = "the sensor page's comrdtrate"},
                   [](C& c) -> double& { return c.force.rdt_rate_hz; }));
  t.push_back(flag({.key = "rdt_buffered",
                    .option = "--rdt-buffered",
                    .help = "rdt: buffered streaming (several records a datagram)"},
                   [](C& c) -> bool& { return c.force.rdt_buffered; }));
  t.push_back(flag({.key = "tare",
                    .option = "--tare",
                    .help = "rdt: take the sensor's offset at start, arm still, over the tare window (refused when it "
                            "moves); the sensor configuration's bias must then be zero"},
                   [](C& c) -> bool& { return c.force.tare; }));
  t.push_back(real({.key = "tare_window_s",
                    .option = "--tare-window-s",
                    .unit = "s",
                    .min = 1e-3,
                    .max = 3600.0,
                    .help = "with tare: the averaging window"},
                   [](C& c) -> double& { return c.force.tare_window_s; }));
  t.push_back(real({.key = "tare_max_std_N",
                    .option = "--tare-max-std-N",
                    .unit = "N",
                    .min = 1e-9,
                    .max = 1e6,
                    .help = "with tare: the largest standard deviation of a force axis over the window"},
                   [](C& c) -> double& { return c.force.tare_max_std_n; }));
  t.push_back(real({.key = "tare_max_std_Nm",
                    .option = "--tare-max-std-Nm",
                    .unit = "Nm",
                    .min = 1e-9,
                    .max = 1e6,
                    .help = "with tare: the largest standard deviation of a torque axis over the window"},
                   [](C& c) -> double& { return c.force.tare_max_std_nm; }));
  t.push_back(words({.key = "tare_pose_deg",
                     .option = "--tare-pose-deg",
                     .help = "with tare and a payload: the joints the arm holds during the tare, deg (default for "
                             "streaming links: the program's start), so that the payload's weight stays in the "
                             "reading"},
                    [](C& c) -> std::string& { return c.force.tare_pose_deg; }));
}

std::vector<SessionSetting> make_table() {
  std::vector<SessionSetting> t;
  bound_settings(t);
  rate_settings(t);
  stop_settings(t);
  report_settings(t);
  network_settings(t);
  egm_settings(t);
  rsi_settings(t);
  simple_message_settings(t);
  fanuc_settings(t);
  motoros2_settings(t);
  ur_settings(t);
  force_settings(t);
  return t;
}

std::string links_text(LinkMask links) {
  std::string s;
  for (const LinkKindInfo& k : link_kinds()) {
    if ((links & link_bit(k.kind)) != 0) s += fmt::format("{}{}", s.empty() ? "" : " or ", k.name);
  }
  return s;
}

// A value in the key's unit, and in the option's where that differs: "1 rad (57.3 deg)".
std::string value_text(const SessionSetting& s, double v) {
  std::string key = fmt::format("{:.6g}{}{}", v, s.unit.empty() ? "" : " ", s.unit);
  if (s.option_unit.empty() || s.option_unit == s.unit) return key;
  return fmt::format("{} ({:.6g} {})", key, v * s.option_per_unit, s.option_unit);
}

std::string range_text(const SessionSetting& s) {
  return fmt::format("{} {} value {} {}", value_text(s, s.min),
                     s.min_open ? "<" : "<=", s.max_open ? "<" : "<=", value_text(s, s.max));
}

void check_number(const SessionSetting& s, double v) {
  if (!std::isfinite(v)) throw InputError(fmt::format("{}: {} is not a finite number", setting_name(s), v));
  if (s.type == SettingType::kInteger && v != std::floor(v)) {
    throw InputError(fmt::format("{}: {} is not a whole number", setting_name(s), number_text(v)));
  }
  const bool below = s.min_open ? !(v > s.min) : !(v >= s.min);
  const bool above = s.max_open ? !(v < s.max) : !(v <= s.max);
  if (below || above) {
    throw InputError(fmt::format("{}: {} is outside {}{}{}", setting_name(s), value_text(s, v), range_text(s),
                                 s.why.empty() ? "" : ": ", s.why));
  }
}

void apply(C& c, const GivenSetting& g) {
  const SessionSetting& s = *g.setting;
  const char* expected = s.type == SettingType::kFlag   ? "True or False"
                         : s.type == SettingType::kText ? "words"
                                                        : "a number";
  const auto wrong = [&] { return InputError(fmt::format("{}: expects {}", setting_name(s), expected)); };
  switch (s.type) {
    case SettingType::kReal:
    case SettingType::kInteger: {
      const double* v = std::get_if<double>(&g.value);
      if (v == nullptr) throw wrong();
      check_number(s, *v);
      s.set_real(c, *v);
      return;
    }
    case SettingType::kFlag: {
      const bool* v = std::get_if<bool>(&g.value);
      if (v == nullptr) throw wrong();
      s.set_flag(c, *v);
      return;
    }
    case SettingType::kText: {
      const std::string* v = std::get_if<std::string>(&g.value);
      if (v == nullptr) throw wrong();
      try {
        s.set_text(c, *v);
      } catch (const InputError& e) {
        throw InputError(fmt::format("{}: {}", setting_name(s), e.what()));
      }
      return;
    }
  }
}

bool given(std::span<const GivenSetting> settings, std::string_view key) {
  return std::any_of(settings.begin(), settings.end(), [&](const GivenSetting& g) { return g.setting->key == key; });
}

// What one setting alone cannot say.
void check_together(const C& c, std::span<const GivenSetting> settings) {
  if (c.link == LinkKind::kSimpleMessage && !(c.online.period_s >= 0.02)) {
    throw InputError(fmt::format(
        "{}: simple-message sends one point a cycle to a robot program; give its cycle (the paper's: 100 ms), at "
        "least 20 ms (got {:g} ms)",
        setting_name(*find_session_setting("period_s")), c.online.period_s * 1e3));
  }
  if (!c.realtime.enabled) {
    for (std::string_view key : {"rt_priority", "rt_cpu", "rt_lock_memory"}) {
      if (given(settings, key)) {
        throw InputError(
            fmt::format("{}: applies with realtime (--realtime)", setting_name(*find_session_setting(key))));
      }
    }
  }
  const bool rdt = c.force.source.rfind("rdt:", 0) == 0;
  for (std::string_view key : {"rdt_calibration", "rdt_rate_hz", "rdt_buffered", "tare"}) {
    if (!rdt && given(settings, key)) {
      throw InputError(
          fmt::format("{}: applies to the force source rdt:HOST[:PORT]", setting_name(*find_session_setting(key))));
    }
  }
  for (std::string_view key : {"tare_window_s", "tare_max_std_N", "tare_max_std_Nm", "tare_pose_deg"}) {
    if (!c.force.tare && given(settings, key)) {
      throw InputError(fmt::format("{}: applies with tare (--tare)", setting_name(*find_session_setting(key))));
    }
  }
  try {
    c.fanuc_j519.validate();
  } catch (const InputError& e) {
    throw InputError(fmt::format("settings fanuc_* (--fanuc-*): {}", e.what()));
  }
  c.motoros2_rt.validate();  // its messages name the setting
  c.ur_rtde.validate();
}

}  // namespace

std::span<const SessionSetting> session_settings() {
  static const std::vector<SessionSetting> table = make_table();
  return table;
}

const SessionSetting* find_session_setting(std::string_view name) {
  for (const SessionSetting& s : session_settings()) {
    if (s.key == name || s.option == name) return &s;
  }
  return nullptr;
}

std::string setting_name(const SessionSetting& s) { return fmt::format("setting {} ({})", s.key, s.option); }

SettingValue option_value(const SessionSetting& s, const std::string& text) {
  switch (s.type) {
    case SettingType::kReal:
    case SettingType::kInteger: {
      const std::optional<double> v = parse_double(trim_view(text));
      if (!v) throw InputError(fmt::format("{}: {}", setting_name(s), not_a_number(text)));
      if (s.type == SettingType::kInteger && *v != std::floor(*v)) {
        throw InputError(fmt::format("{}: '{}' is not a whole number", setting_name(s), text));
      }
      return *v / s.option_per_unit;
    }
    case SettingType::kFlag:
      return text != "false";
    case SettingType::kText:
      break;
  }
  return text;
}

SessionConfig default_session_config(LinkKind link) {
  constexpr SessionOptionDefaults d = kSessionOptionDefaults;
  SessionConfig c;
  c.link = link;
  c.online.period_s = link_kind(link).default_period_s;
  c.online.max_joint_correction_rad = deg_to_rad(d.max_joint_correction_deg);
  c.online.max_tcp_correction_m = d.max_tcp_correction_mm * 1e-3;
  c.online.max_correction_rate_rad_s = deg_to_rad(d.max_rate_deg_s);
  c.online.max_tcp_rate_m_s = d.max_tcp_rate_mm_s * 1e-3;
  c.egm_joint.stream.ramp_in_s = c.simple_message.stream.ramp_in_s = d.ramp_in_s;
  c.egm_path.frame = parse_path_corr_frame(d.path_frame);
  c.rsi.sentype = d.rsi_sentype;
  c.rsi.controller_timeout = d.rsi_timeout;
  return c;
}

SessionConfig make_session_config(const std::string& link, const std::string& strategy,
                                  std::span<const GivenSetting> settings) {
  SessionConfig c = default_session_config(parse_link_kind(link));
  c.strategy = parse_strategy(strategy);
  for (const GivenSetting& g : settings) {
    if ((g.setting->links & link_bit(c.link)) == 0) {
      throw InputError(fmt::format("{}: applies to --link {}, not {}", setting_name(*g.setting),
                                   links_text(g.setting->links), link_kind(c.link).name));
    }
    apply(c, g);
  }
  check_together(c, settings);
  return c;
}

std::string option_help(const SessionSetting& s) {
  std::string h(s.help);
  if (s.links != kEveryLink) {
    h = fmt::format("{}: {}", links_text(s.links), h);
  } else if (!h.empty()) {
    h[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(h[0])));
  }
  if (s.type == SettingType::kReal || s.type == SettingType::kInteger) {
    const std::string_view unit = s.option_unit.empty() ? s.unit : s.option_unit;
    const double k = s.option_unit.empty() ? 1.0 : s.option_per_unit;
    h += fmt::format(" [{}{}{}{:.6g}..{}{:.6g}]", unit, unit.empty() ? "" : "; ", s.min_open ? ">" : "", s.min * k,
                     s.max_open ? "<" : "", s.max * k);
  }
  return h;
}

std::string setting_value_text(const SessionSetting& s, const SessionConfig& config) {
  switch (s.type) {
    case SettingType::kReal:
    case SettingType::kInteger: {
      const double v = s.get_real(config);
      // Unset (a port of -1, a real of 0 where the range starts above it): what is used instead.
      const bool unset = v < 0.0 || (s.type == SettingType::kReal && v == 0.0);
      if (unset && !s.default_text.empty()) return std::string(s.default_text);
      return fmt::format("{:.6g}", v * (s.option_unit.empty() ? 1.0 : s.option_per_unit));
    }
    case SettingType::kFlag:
      return s.get_flag(config) != s.flag_inverted ? "on" : "off";
    case SettingType::kText:
      return s.get_text(config);
  }
  return {};
}

std::vector<ShownSetting> settings_shown(const SessionConfig& config) {
  std::vector<ShownSetting> out;
  for (const SessionSetting& s : session_settings()) {
    if ((s.links & link_bit(config.link)) == 0) continue;
    out.push_back({std::string(s.option), setting_value_text(s, config)});
  }
  return out;
}

std::string option_default(const SessionSetting& s) {
  if (!s.default_text.empty()) return std::string(s.default_text);
  return setting_value_text(s, default_session_config(LinkKind::kEgmJoint));
}

}  // namespace deflex::runtime
