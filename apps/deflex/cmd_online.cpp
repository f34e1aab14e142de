// `deflex online`: deflex on a controller link (ABB EGM position guidance or path correction, KUKA RSI
// axis correction, ROS-Industrial simple message). This file only turns options into a session
// (runtime/session.hpp: the link by kind, the loop and its stop rules, the cycle log, the fault dump,
// the status, the summary) and prints what it says; the exit code is the session's stop reason's
// (docs/online.md, "Faults and exit codes").
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <thread>

#include <fmt/format.h>

#include "cli_util.hpp"
#include "command.hpp"
#include "deflex/force/force_spec.hpp"
#include "deflex/monitor/cycle_log_reader.hpp"
#include "deflex/monitor/monitor_server.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/runtime/session.hpp"
#include "deflex/sensors/force_source_spec.hpp"
#include "deflex/sensors/wrench_tare.hpp"
#include "deflex/text/errors.hpp"
#include "field_log.hpp"

namespace deflex::cli {
namespace {

using runtime::LinkKind;

// The session a stop signal goes to: request_stop() is an atomic counter, safe in a signal handler, so
// the loop sees the request at its next cycle (a planned stop ramps down first; a second signal ends
// the session at once).
std::atomic<runtime::Session*> g_session{nullptr};
extern "C" void on_stop_signal(int /*signal*/) {
  if (runtime::Session* s = g_session.load()) s->request_stop();
}

struct OnlineOpts {
  std::string link, robot, sensor, force_source, program, strategy = "online", force_model, log, fault_dump,
                                                          jacobian_at = "nominal";
  // The settings controller-setup writes into the controller's side come from one place.
  static constexpr runtime::SessionOptionDefaults kShared = runtime::kSessionOptionDefaults;
  double period_ms = 0.0, max_joint_deg = kShared.max_joint_correction_deg, max_tcp_mm = kShared.max_tcp_correction_mm,
         max_rate_deg_s = kShared.max_rate_deg_s, max_tcp_rate_mm_s = kShared.max_tcp_rate_mm_s, watchdog_ms = 50.0;
  double end_silence_s = 2.0, stop_silence_s = 0.0, duration_s = 0.0, status_s = 1.0, stop_ramp_s = 0.5;
  bool loop = false, json = false, end_on_silence = false;
  // The live monitor page.
  std::string monitor;
  bool monitor_remote = false, log_report = false;
  double monitor_window_s = 30.0, monitor_linger_s = 0.0;
  // Real time.
  bool realtime = false, rt_no_mlock = false;
  int rt_priority = 80, rt_cpu = -1;
  // Network.
  std::string bind = "127.0.0.1", robot_host;
  int egm_port = -1, rsi_port = -1, motion_port = 11000, state_port = 11002;
  double connect_timeout_s = 5.0;
  // EGM.
  double ramp_in_s = kShared.ramp_in_s, correction_latency_ms = 0.0, rotation_warning_mrad = 0.1;
  bool no_speed_ref = false;
  std::string path_frame = kShared.path_frame;
  // RSI.
  std::string sentype = kShared.rsi_sentype;
  double rsi_correction_latency_ms = 0.0;
  int rsi_max_document_bytes = 4096, rsi_timeout = kShared.rsi_timeout;
  // RDT force sensors and the tare.
  std::string rdt_calibration, tare_pose_deg;
  double rdt_rate_hz = 0.0, tare_window_s = 0.5, tare_max_std_n = 0.5, tare_max_std_nm = 0.05;
  bool rdt_buffered = false, tare = false;
  // Simple message.
  std::string byte_order = "little";
  int buffer_depth = 2, max_failures = 3, max_frame_bytes = 1024;
  double reply_timeout_s = 1.0, state_timeout_s = 1.0, max_behind_s = 2.0;
  // FANUC Stream Motion.
  int robot_port = -1, fanuc_version = 1, fanuc_catch_up = 8;
  std::string fanuc_limits = "120,265,1240";
  double fanuc_correction_share = 0.25;
  LogOptions log_options;
};

// Options that belong to some links only: given with another link they are refused, so a user
// never believes a setting took effect that the chosen link ignores.
struct LinkOption {
  const char* name;
  std::vector<LinkKind> links;
};
const std::vector<LinkOption>& link_options() {
  static const std::vector<LinkOption> options{
      {"--egm-port", {LinkKind::kEgmJoint, LinkKind::kEgmPath}},
      {"--ramp-in-s", {LinkKind::kEgmJoint, LinkKind::kSimpleMessage, LinkKind::kFanucJ519}},
      {"--no-speed-reference", {LinkKind::kEgmJoint}},
      {"--path-corr-frame", {LinkKind::kEgmPath}},
      {"--correction-latency-ms", {LinkKind::kEgmPath}},
      {"--rotation-warning-mrad", {LinkKind::kEgmPath}},
      {"--rsi-port", {LinkKind::kRsi}},
      {"--rsi-sentype", {LinkKind::kRsi}},
      {"--rsi-correction-latency-ms", {LinkKind::kRsi}},
      {"--rsi-max-document-bytes", {LinkKind::kRsi}},
      {"--rsi-timeout", {LinkKind::kRsi}},
      {"--robot-host", {LinkKind::kSimpleMessage, LinkKind::kFanucJ519}},
      {"--robot-port", {LinkKind::kFanucJ519}},
      {"--fanuc-version", {LinkKind::kFanucJ519}},
      {"--fanuc-limits", {LinkKind::kFanucJ519}},
      {"--fanuc-correction-share", {LinkKind::kFanucJ519}},
      {"--fanuc-catch-up", {LinkKind::kFanucJ519}},
      {"--motion-port", {LinkKind::kSimpleMessage}},
      {"--state-port", {LinkKind::kSimpleMessage}},
      {"--byte-order", {LinkKind::kSimpleMessage}},
      {"--buffer-depth", {LinkKind::kSimpleMessage}},
      {"--connect-timeout-s", {LinkKind::kSimpleMessage}},
      {"--reply-timeout-s", {LinkKind::kSimpleMessage}},
      {"--state-timeout-s", {LinkKind::kSimpleMessage}},
      {"--max-failures", {LinkKind::kSimpleMessage}},
      {"--max-frame-bytes", {LinkKind::kSimpleMessage}},
      {"--max-behind-s", {LinkKind::kSimpleMessage}},
      {"--end-on-silence", {LinkKind::kEgmPath, LinkKind::kRsi}},
      {"--end-silence-s", {LinkKind::kEgmJoint, LinkKind::kSimpleMessage, LinkKind::kFanucJ519}},
  };
  return options;
}

// The controller's cycle and what every command is held to: the correction's bounds and rates, the
// force watchdog, where the Jacobian is taken.
void add_bound_options(CLI::App& sub, OnlineOpts& o) {
  sub.add_option("--period-ms", o.period_ms,
                 "The controller's cycle in ms (default: egm-joint and rsi 4; egm-path 48, the EGMActMove SampleRate; "
                 "simple-message 100, the paper's)");
  sub.add_option("--max-joint-correction-deg", o.max_joint_deg,
                 "Bound on each joint's correction, degrees: no command leaves the nominal by more")
      ->capture_default_str();
  sub.add_option("--max-tcp-correction-mm", o.max_tcp_mm, "Bound on the TCP displacement of the correction, mm")
      ->capture_default_str();
  sub.add_option("--max-rate-deg-s", o.max_rate_deg_s,
                 "Bound on each joint's correction rate, deg/s (times the period: the correction's largest step a "
                 "cycle, which must fit in its bound)")
      ->capture_default_str();
  sub.add_option("--max-tcp-rate-mm-s", o.max_tcp_rate_mm_s,
                 "Bound on the rate of the correction's TCP translation, mm/s: a stale force ramps out at it on every "
                 "link (egm-path: the offset's largest step a cycle)")
      ->capture_default_str();
  sub.add_option("--watchdog-ms", o.watchdog_ms, "No valid force sample for this long: ramp the correction to zero")
      ->capture_default_str();
  sub.add_option("--jacobian-at", o.jacobian_at, "nominal (the configuration the command is for) or feedback")
      ->capture_default_str();
}

void add_link_options(CLI::App& sub, OnlineOpts& o) {
  sub.add_option("--egm-port", o.egm_port,
                 "EGM: UDP port the controller's EGM messages arrive on (ABB examples: 6510)");
  sub.add_option("--ramp-in-s", o.ramp_in_s,
                 "egm-joint, simple-message, fanuc-j519: blend from where the controller is to the program over this "
                 "time, s")
      ->capture_default_str();
  sub.add_flag("--no-speed-reference", o.no_speed_ref, "egm-joint: do not send the target's joint speeds");
  sub.add_option("--path-corr-frame", o.path_frame,
                 "egm-path: the frame EGMActMove was given: tool (tool.tframe), flange (tool0) or path (path "
                 "coordinates)")
      ->capture_default_str();
  sub.add_option("--correction-latency-ms", o.correction_latency_ms,
                 "egm-path, predictive: the controller's correction latency beyond the measured servo delay, ms")
      ->capture_default_str();
  sub.add_option("--rotation-warning-mrad", o.rotation_warning_mrad,
                 "egm-path: report when the model predicts a TCP rotation above this (it cannot be corrected), mrad")
      ->capture_default_str();
  sub.add_option("--rsi-port", o.rsi_port,
                 "rsi: UDP port the controller's <Rob> documents arrive on (its Ethernet config's <PORT>; ROS "
                 "examples: 49152 or 59152)");
  sub.add_option("--rsi-sentype", o.sentype,
                 "rsi: the Type of every answer, the controller's <SENTYPE> (letters, digits, '_', '-')")
      ->capture_default_str();
  sub.add_option("--rsi-correction-latency-ms", o.rsi_correction_latency_ms,
                 "rsi, predictive: AXISCORR's latency beyond the delay the link measures (ASPos to AIPos), ms")
      ->capture_default_str();
  sub.add_option("--rsi-max-document-bytes", o.rsi_max_document_bytes,
                 "rsi: larger datagrams are counted oversized and never answered")
      ->capture_default_str();
  sub.add_option("--rsi-timeout", o.rsi_timeout,
                 "rsi: the ETHERNET object's Timeout on the controller (late answers before RSI stops; deflex "
                 "controller-setup writes the same): with the <Delay> it reports, an RSI stopped by it is recognised")
      ->capture_default_str();
  sub.add_option("--robot-host", o.robot_host,
                 "simple-message: the controller's address (its motion and state servers listen there); "
                 "fanuc-j519: its IPv4 address");
  sub.add_option("--robot-port", o.robot_port, "fanuc-j519: the controller's Stream Motion UDP port (default 60015)");
  sub.add_option("--fanuc-version", o.fanuc_version,
                 "fanuc-j519: the Stream Motion protocol version the controller speaks: 1 (float32 targets), 3 or 4 "
                 "(float64; R-30iB Plus V9.40P and later)")
      ->capture_default_str();
  sub.add_option("--fanuc-limits", o.fanuc_limits,
                 "fanuc-j519: the controller's limits on the stream, VEL,ACC,JERK in deg/s, deg/s^2, deg/s^3, for "
                 "every joint, or one triple a joint separated by ';' (its threshold tables' strictest values or the "
                 "pendant's $STMO_GRP limits; default a CRX-10iA/L's strictest)")
      ->capture_default_str();
  sub.add_option("--fanuc-correction-share", o.fanuc_correction_share,
                 "fanuc-j519: the share of the acceleration and jerk limits the correction may take (0..1; the "
                 "program keeps the rest); the correction is smoothed to stay within it (its delay is reported)")
      ->capture_default_str();
  sub.add_option("--fanuc-catch-up", o.fanuc_catch_up,
                 "fanuc-j519: statuses lost or late in a row that deflex answers with one command each, in order, "
                 "as FANUC's driver does (more: the session stops, too slow); at most the controller's queue")
      ->capture_default_str();
  sub.add_option("--motion-port", o.motion_port, "simple-message: TCP port of the motion server (JOINT_TRAJ_PT)")
      ->capture_default_str();
  sub.add_option("--state-port", o.state_port, "simple-message: TCP port of the state server (JOINT_POSITION)")
      ->capture_default_str();
  sub.add_option("--byte-order", o.byte_order,
                 "simple-message: the server's byte order: little (ABB RAPID, Motoman DX100/DX200/YRC1000) or big "
                 "(Fanuc KAREL, Motoman FS100)")
      ->capture_default_str();
  sub.add_option("--buffer-depth", o.buffer_depth,
                 "simple-message: points kept queued on the controller; each adds one cycle of lag (reported; the "
                 "predictive strategy leads by the measured delay)")
      ->capture_default_str();
  sub.add_option("--connect-timeout-s", o.connect_timeout_s, "simple-message: wait this long for each connection, s")
      ->capture_default_str();
  sub.add_option("--reply-timeout-s", o.reply_timeout_s,
                 "simple-message: a point unanswered this long stops the motion, s")
      ->capture_default_str();
  sub.add_option("--state-timeout-s", o.state_timeout_s,
                 "simple-message: no JOINT_POSITION this long stops the motion, s")
      ->capture_default_str();
  sub.add_option("--max-failures", o.max_failures,
                 "simple-message: FAILURE replies in a row (buffer full, point refused) before the motion is stopped")
      ->capture_default_str();
  sub.add_option("--max-frame-bytes", o.max_frame_bytes,
                 "simple-message: the largest frame LENGTH accepted; a larger one means the stream is out of step")
      ->capture_default_str();
  sub.add_option("--max-behind-s", o.max_behind_s,
                 "simple-message: a controller that takes points slower than the program's cycle may fall this far "
                 "behind the program, s, before the motion is stopped (exit code 8)")
      ->capture_default_str();
}

void add_sensor_options(CLI::App& sub, OnlineOpts& o) {
  sub.add_option("--rdt-calibration", o.rdt_calibration,
                 "rdt: counts to N and Nm: sensor (its netftapi2.xml over HTTP), FILE.xml (a saved page), http://URL, "
                 "onrobot-hex, or counts:counts_per_force=C,counts_per_torque=C,force_unit=U,torque_unit=U");
  sub.add_option(
      "--rdt-rate-hz", o.rdt_rate_hz,
      "rdt: the sensor's RDT rate, Hz (default: its page's comrdtrate; required for counts:, OnRobot 1000/n)");
  sub.add_flag("--rdt-buffered", o.rdt_buffered, "rdt: buffered streaming (several records a datagram)");
  sub.add_flag("--tare", o.tare,
               "rdt: take the sensor's offset at start, arm still, over --tare-window-s (refused when it moves); "
               "the sensor configuration's bias must then be zero");
  sub.add_option("--tare-window-s", o.tare_window_s, "With --tare: the averaging window, s")->capture_default_str();
  sub.add_option("--tare-max-std-N", o.tare_max_std_n,
                 "With --tare: the largest standard deviation of a force axis over the window, N")
      ->capture_default_str();
  sub.add_option("--tare-max-std-Nm", o.tare_max_std_nm,
                 "With --tare: the largest standard deviation of a torque axis over the window, Nm")
      ->capture_default_str();
  sub.add_option("--tare-pose-deg", o.tare_pose_deg,
                 "With --tare and a payload: the joints the arm holds during the tare, deg (default for streaming "
                 "links: the program's start), so that the payload's weight stays in the reading");
}

void check_sensor_options(const CLI::App& sub, const OnlineOpts& o) {
  const bool rdt = o.force_source.rfind("rdt:", 0) == 0;
  for (const char* name : {"--rdt-calibration", "--rdt-rate-hz", "--rdt-buffered", "--tare"}) {
    if (!rdt && sub.get_option(name)->count() > 0) {
      throw InputError(fmt::format("option {}: applies to --force-source rdt:HOST[:PORT]", name));
    }
  }
  for (const char* name : {"--tare-window-s", "--tare-max-std-N", "--tare-max-std-Nm", "--tare-pose-deg"}) {
    if (!o.tare && sub.get_option(name)->count() > 0)
      throw InputError(fmt::format("option {}: applies with --tare", name));
  }
}

void check_link_options(const CLI::App& sub, LinkKind kind) {
  const runtime::LinkKindInfo& info = runtime::link_kind(kind);
  for (const LinkOption& lo : link_options()) {
    if (sub.get_option(lo.name)->count() == 0) continue;
    if (std::find(lo.links.begin(), lo.links.end(), kind) != lo.links.end()) continue;
    std::string links;
    for (LinkKind k : lo.links) links += fmt::format("{}{}", links.empty() ? "" : " or ", runtime::link_kind(k).name);
    throw InputError(fmt::format("option {}: applies to --link {}, not {}", lo.name, links, info.name));
  }
}

// The FANUC link's settings from its options.
void fanuc_settings(const OnlineOpts& o, FanucJ519LinkConfig& f) {
  f.version = o.fanuc_version < 0 ? 0U : static_cast<std::uint32_t>(o.fanuc_version);
  f.correction_share = o.fanuc_correction_share;
  f.max_catch_up = o.fanuc_catch_up;
  f.stream.ramp_in_s = o.ramp_in_s;
  f.limits = parse_fanuc_limits(o.fanuc_limits, "--fanuc-limits");
  try {
    f.validate();
  } catch (const InputError& e) {
    throw InputError(fmt::format("options --fanuc-*: {}", e.what()));
  }
}

runtime::SessionConfig session_config(const OnlineOpts& o, const CLI::App& sub) {
  runtime::SessionConfig c;
  c.link = runtime::parse_link_kind(o.link);
  check_link_options(sub, c.link);
  const runtime::LinkKindInfo& info = runtime::link_kind(c.link);
  c.strategy = parse_strategy(o.strategy);
  const auto positive = [](double v, const char* option) {
    if (!std::isfinite(v) || !(v > 0.0))
      throw InputError(fmt::format("option {}: must be a number > 0 (got {})", option, v));
  };
  const auto non_negative = [](double v, const char* option) {
    if (!std::isfinite(v) || v < 0.0)
      throw InputError(fmt::format("option {}: must be a number >= 0 (got {})", option, v));
  };
  const bool period_given = sub.get_option("--period-ms")->count() > 0;
  if (period_given) positive(o.period_ms, "--period-ms");
  positive(o.max_joint_deg, "--max-joint-correction-deg");
  positive(o.max_tcp_mm, "--max-tcp-correction-mm");
  positive(o.max_rate_deg_s, "--max-rate-deg-s");
  positive(o.max_tcp_rate_mm_s, "--max-tcp-rate-mm-s");
  positive(o.watchdog_ms, "--watchdog-ms");
  positive(o.status_s, "--status-interval-s");
  positive(o.end_silence_s, "--end-silence-s");
  non_negative(o.duration_s, "--duration-s");
  if (period_given && o.period_ms > 1000.0) throw InputError("option --period-ms: at most 1000 ms");
  if (o.max_joint_deg > 10.0) {
    throw InputError(
        "option --max-joint-correction-deg: at most 10 deg (a compliance correction is a fraction of one)");
  }
  c.online.period_s = period_given ? o.period_ms * 1e-3 : info.default_period_s;
  c.online.max_joint_correction_rad = deg_to_rad(o.max_joint_deg);
  c.online.max_tcp_correction_m = o.max_tcp_mm * 1e-3;
  c.online.max_correction_rate_rad_s = deg_to_rad(o.max_rate_deg_s);
  c.online.max_tcp_rate_m_s = o.max_tcp_rate_mm_s * 1e-3;
  c.online.watchdog_s = o.watchdog_ms * 1e-3;
  if (o.jacobian_at == "nominal" || o.jacobian_at == "planned") {
    c.online.jacobian_at = JacobianAt::kPlanned;
  } else if (o.jacobian_at == "feedback") {
    c.online.jacobian_at = JacobianAt::kFeedback;
  } else {
    throw InputError("option --jacobian-at: must be nominal or feedback");
  }
  if (sub.get_option("--stop-silence-s")->count() > 0) {
    positive(o.stop_silence_s, "--stop-silence-s");
    c.stop_silence_s = o.stop_silence_s;
  }
  c.end_silence_s = o.end_silence_s;
  c.end_on_silence = o.end_on_silence;
  c.duration_s = o.duration_s;
  c.stop_ramp_s = o.stop_ramp_s;
  c.status_interval_s = o.status_s;
  c.log_path = o.log;
  c.fault_dump_path = o.fault_dump;
  c.monitor = !o.monitor.empty();
  c.monitor_window_s = o.monitor_window_s;
  c.realtime.enabled = o.realtime;
  c.realtime.priority = o.rt_priority;
  c.realtime.cpu = o.rt_cpu;
  c.realtime.lock_memory = !o.rt_no_mlock;
  if (!o.realtime &&
      (sub.get_option("--rt-priority")->count() > 0 || sub.get_option("--rt-cpu")->count() > 0 || o.rt_no_mlock)) {
    throw InputError("options --rt-priority, --rt-cpu, --rt-no-mlock: apply with --realtime");
  }
  // Network.
  c.network.bind_address = o.bind;
  c.network.egm_port = o.egm_port;
  c.network.rsi_port = o.rsi_port;
  c.network.robot_host = o.robot_host;
  c.network.robot_port = o.robot_port;
  c.network.motion_port = o.motion_port;
  c.network.state_port = o.state_port;
  c.network.connect_timeout_s = o.connect_timeout_s;
  // Each link's own settings.
  non_negative(o.ramp_in_s, "--ramp-in-s");
  c.egm_joint.stream.ramp_in_s = o.ramp_in_s;
  c.egm_joint.send_speed_reference = !o.no_speed_ref;
  non_negative(o.correction_latency_ms, "--correction-latency-ms");
  non_negative(o.rotation_warning_mrad, "--rotation-warning-mrad");
  c.egm_path.frame = parse_path_corr_frame(o.path_frame);
  c.egm_path.correction_latency_s = o.correction_latency_ms * 1e-3;
  c.egm_path.rotation_warning_rad = o.rotation_warning_mrad * 1e-3;
  non_negative(o.rsi_correction_latency_ms, "--rsi-correction-latency-ms");
  if (!valid_rsi_sentype(o.sentype)) {
    throw InputError(fmt::format(
        "option --rsi-sentype: '{}' must be 1..32 letters, digits, '_' or '-', starting with a letter", o.sentype));
  }
  if (o.rsi_max_document_bytes < 64 || o.rsi_max_document_bytes > 65507) {
    throw InputError("option --rsi-max-document-bytes: must be 64..65507");
  }
  if (o.rsi_timeout < 1) throw InputError(fmt::format("option --rsi-timeout: at least 1 (got {})", o.rsi_timeout));
  c.rsi.sentype = o.sentype;
  c.rsi.correction_latency_s = o.rsi_correction_latency_ms * 1e-3;
  c.rsi.max_document_bytes = static_cast<std::size_t>(o.rsi_max_document_bytes);
  c.rsi.controller_timeout = o.rsi_timeout;
  if (c.link == LinkKind::kSimpleMessage && !(c.online.period_s >= 0.02)) {
    throw InputError(fmt::format(
        "option --period-ms: simple-message sends one point a cycle to a robot program; give its cycle (the paper's: "
        "100), at least 20 ms (got {:g} ms)",
        c.online.period_s * 1e3));
  }
  runtime::SessionConfig& s = c;
  try {
    s.simple_message.byte_order = simple_message::parse_byte_order(o.byte_order);
  } catch (const InputError& e) {
    throw InputError(fmt::format("option --byte-order: {}", e.what()));
  }
  if (o.buffer_depth < 1 || o.buffer_depth > 64) {
    throw InputError(fmt::format("option --buffer-depth: must be 1..64 points (got {})", o.buffer_depth));
  }
  if (o.max_failures < 1) throw InputError(fmt::format("option --max-failures: must be >= 1 (got {})", o.max_failures));
  if (o.max_frame_bytes < 64 || o.max_frame_bytes > (1 << 20)) {
    throw InputError(fmt::format("option --max-frame-bytes: must be 64..1048576 (got {})", o.max_frame_bytes));
  }
  positive(o.reply_timeout_s, "--reply-timeout-s");
  positive(o.state_timeout_s, "--state-timeout-s");
  positive(o.max_behind_s, "--max-behind-s");
  s.simple_message.buffer_depth = o.buffer_depth;
  s.simple_message.reply_timeout_s = o.reply_timeout_s;
  s.simple_message.state_timeout_s = o.state_timeout_s;
  s.simple_message.max_failures = o.max_failures;
  s.simple_message.max_frame_bytes = static_cast<std::size_t>(o.max_frame_bytes);
  s.simple_message.max_behind_s = o.max_behind_s;
  s.simple_message.stream.ramp_in_s = o.ramp_in_s;
  fanuc_settings(o, c.fanuc_j519);
  return c;
}

// --tare: the sensor's offset, averaged with the arm still, the payload's weight at the tare pose left
// in the reading (the pipeline's gravity compensation takes it out at every pose).
void tare_sensor(const OnlineOpts& o, const RobotModel& model, const SensorConfig& sensor,
                 const JointTrajectory* program, const OpenedForceSource& force, spdlog::logger& log) {
  if (sensor.bias_sensor.cwiseAbs().maxCoeff() > 0.0) {
    throw InputError(fmt::format(
        "option --tare: the sensor configuration {} gives a bias too ({:.3f} {:.3f} {:.3f} N ...): the offset would be "
        "taken out twice; set its bias to zero or leave --tare out",
        sensor.source, sensor.bias_sensor[0], sensor.bias_sensor[1], sensor.bias_sensor[2]));
  }
  TareSettings ts;
  ts.window_s = o.tare_window_s;
  ts.max_std_force_n = o.tare_max_std_n;
  ts.max_std_torque_nm = o.tare_max_std_nm;
  std::string pose_text = "no payload in the sensor configuration: the tare takes out all it reads";
  if (sensor.payload_mass_kg > 0.0) {
    JointVector q;
    if (!o.tare_pose_deg.empty()) {
      q = parse_joints_deg(o.tare_pose_deg, model, "--tare-pose-deg");
      pose_text = "the payload's weight at --tare-pose-deg kept in the reading";
    } else if (program != nullptr) {
      q = program->points().front();
      pose_text = "the payload's weight at the program's start kept in the reading";
    } else {
      throw InputError(
          "option --tare-pose-deg: the sensor configuration has a payload, and this link streams no program: give the "
          "joints the arm holds during the tare, so that its weight is not taken out as an offset");
    }
    Workspace ws(model);
    forward_kinematics(model, ws, q);
    const Matrix3 base_R_sensor = ws.base_T_flange.linear() * sensor.flange_T_sensor.linear();
    ts.expected_wrench_sensor = payload_wrench_sensor(sensor.payload_mass_kg, sensor.payload_cog_sensor_m,
                                                      sensor.gravity_base_m_s2, base_R_sensor);
  }
  log.info("tare: hold the arm still for {:g} s ({})", ts.window_s, pose_text);
  log.info("tare: {}", describe(force.rdt->tare(ts), ts));
}

// Where --log-report writes: beside the log, .html for its .csv.
std::string log_report_path(const std::string& log) {
  const std::string csv = ".csv";
  if (log.size() > csv.size() && log.compare(log.size() - csv.size(), csv.size(), csv) == 0) {
    return log.substr(0, log.size() - csv.size()) + ".html";
  }
  return log + ".html";
}

void run_online(const OnlineOpts& o, const CLI::App& sub, int& exit_code) {
  if (o.log_report && o.log.empty()) throw InputError("option --log-report: needs --log (the report draws the log)");
  if (!o.monitor.empty()) (void)monitor::parse_monitor_address(o.monitor, o.monitor_remote, "--monitor");
  if (o.monitor_remote && o.monitor.empty()) throw InputError("option --monitor-remote: only with --monitor");
  const runtime::SessionConfig config = session_config(o, sub);
  const runtime::LinkKindInfo& info = runtime::link_kind(config.link);
  const RobotModel model = load_cli_robot("online", o.robot);
  SensorConfig sensor = load_sensor_config_or_defaults(o.sensor);
  std::unique_ptr<ForceModel> force_model;
  if (!o.force_model.empty()) force_model = parse_force_spec(o.force_model);
  std::shared_ptr<const JointTrajectory> program;
  if (!o.program.empty())
    program = std::make_shared<const JointTrajectory>(JointTrajectory::read_csv(o.program, model));
  check_sensor_options(sub, o);
  const auto log_health = std::make_shared<FieldLogHealth>();
  const auto log = make_field_logger("online", o.log_options, log_health);
  ForceSourceOptions fo;
  fo.loop = o.loop;
  fo.bind_address = o.bind;
  fo.rdt_calibration.spec = o.rdt_calibration;
  fo.rdt_calibration.rate_hz = o.rdt_rate_hz;
  fo.rdt_stream.buffered = o.rdt_buffered;
  const OpenedForceSource force = open_force_source(o.force_source, fo);
  if (force.sample_rate_hz > 0.0 && std::abs(force.sample_rate_hz - sensor.sample_rate_hz) > 1e-9) {
    // The filter is designed for the rate the samples come at: the sensor's own.
    if (!o.sensor.empty()) {
      log->info(
          "the force source streams at {:g} Hz: the low-pass filter is designed for it (the sensor file says {:g} "
          "Hz)",
          force.sample_rate_hz, sensor.sample_rate_hz);
    }
    sensor.sample_rate_hz = force.sample_rate_hz;
  }
  if (o.tare) tare_sensor(o, model, sensor, program.get(), force, *log);
  SteadyClock clock;
  runtime::Session session(config, model, sensor, program, force_model.get(), force.source.get(), clock, {},
                           [log](runtime::LogLevel level, const std::string& text) {
                             switch (level) {
                               case runtime::LogLevel::kInfo:
                                 log->info("{}", text);
                                 break;
                               case runtime::LogLevel::kWarn:
                                 log->warn("{}", text);
                                 break;
                               case runtime::LogLevel::kError:
                                 log->error("{}", text);
                                 break;
                             }
                           });
  // The monitor binds before anything is answered: a port in use is an error now, not mid-session.
  std::unique_ptr<monitor::MonitorServer> monitor_server;
  if (config.monitor) {
    monitor_server = std::make_unique<monitor::MonitorServer>(
        session.monitor_feed(), monitor::parse_monitor_address(o.monitor, o.monitor_remote, "--monitor"));
    log->info("monitor on {} (the last {:g} s of the session, 10 updates a second)", monitor_server->url(),
              o.monitor_window_s);
  }
  if (info.streams_program && !model.has_max_speed()) {
    log->warn(
        "the robot file gives no joint speed limits, so the program's speeds were not checked (add max_speed "
        "to the robot file)");
  }
  log->info("deflex online: {}; robot {}; sensor {}; force from {}. Stop with Ctrl-C.", session.describe(),
            model.name(), sensor.source, force.description);

  g_session.store(&session);
  // A field log that cannot be written ends the session as the cycle log's failure does (exit 1).
  log_health->on_failure([](const std::string& text) {
    if (runtime::Session* s = g_session.load()) s->report_output_failure(text);
  });
  struct Unhook {  // the handlers never see a session that is gone, however this function is left
    ~Unhook() { g_session.store(nullptr); }
  } unhook;
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  (void)session.run(0.0);  // real time is asked for (and refused, exit 2) before anything is answered
  if (config.realtime.enabled) log->info("real time: {}", session.realtime_text());
  while (!session.ended()) (void)session.run(0.1);
  const runtime::SessionSummary& summary = session.finish();
  const bool planned = summary.exit_code == 0;
  for (std::string_view text = summary.text; !text.empty();) {
    const std::size_t eol = text.find('\n');
    const std::string_view line = text.substr(0, eol);
    if (planned) {
      log->info("{}", line);
    } else {
      log->error("{}", line);
    }
    text = eol == std::string_view::npos ? std::string_view() : text.substr(eol + 1);
  }
  if (o.json) {
    nlohmann::json doc = nlohmann::json::parse(summary.json_text);
    print_json(doc);
  }
  exit_code = summary.exit_code;
  // A session that ended as planned but whose cycle log could not be written failed all the same.
  if (!summary.output_error.empty() && exit_code == 0) exit_code = 1;
  if (log_health->failed()) {
    // The summary's lines may not have reached the file: say so where they did arrive.
    std::fprintf(stderr, "deflex online: %s: the lines after it are on stderr only\n", log_health->error().c_str());
    if (exit_code == 0) exit_code = 1;
  }
  if (o.log_report && summary.output_error.empty()) {
    const std::string report = log_report_path(o.log);
    write_output_file(report,
                      monitor::monitor_report(*monitor::read_cycle_log_feed(o.log),
                                              fmt::format("deflex online: {} ({})", o.log, summary.reason_text)),
                      "option --log-report");
    log->info("the session's charts: {}", report);
  }
  if (monitor_server && o.monitor_linger_s > 0.0) {
    log->info("monitor: the page stays up {:g} s more (--monitor-linger-s)", o.monitor_linger_s);
    std::this_thread::sleep_for(std::chrono::duration<double>(o.monitor_linger_s));
  }
}

void setup_online(CLI::App& sub, int& exit_code) {
  auto o = std::make_shared<OnlineOpts>();
  std::string link_help = "Controller link:";
  for (const runtime::LinkKindInfo& k : runtime::link_kinds()) link_help += fmt::format(" {} ({});", k.name, k.help);
  sub.add_option("--link", o->link, link_help)->required();
  sub.add_option("--robot", o->robot, kRobotHelp);
  sub.add_option("--sensor-config", o->sensor,
                 "Force-sensor YAML (docs/online.md); default: identity crosstalk, no payload, no bias, at the flange");
  sub.add_option("--bind", o->bind, "Address to bind the link's and the UDP force port to (0.0.0.0 for a real cell)")
      ->capture_default_str();
  sub.add_option("--force-source", o->force_source, force_source_kinds())->required();
  sub.add_flag("--loop", o->loop, "With csv:FILE, replay the file again and again");
  sub.add_option("--program", o->program,
                 "Streaming links: the nominal joint trajectory deflex streams, CSV t_s,q1_deg..qN_deg (deflex offline "
                 "--nominal-trajectory / --joint-trajectory write one)");
  sub.add_option("--strategy", o->strategy,
                 "online (the paper's), hybrid (--program is the offline-compensated one; corrects measured minus "
                 "--force), predictive (wrench predicted where the command is executed), none (stream only)")
      ->capture_default_str();
  sub.add_option("--force", o->force_model,
                 "Force model of the process, a pose model: ldbb:pivot_mm=X;Y;Z,force_N=F,mode=push|pull or "
                 "constant:fx_N=.. (hybrid: required; predictive: optional)");
  add_bound_options(sub, *o);
  sub.add_option("--stop-silence-s", o->stop_silence_s,
                 "No usable controller message this long: the controller is gone and the session stops (exit code 5); "
                 "shorter silences are ridden through. Default: egm-joint, egm-path 3; rsi 1");
  sub.add_option(
         "--end-silence-s", o->end_silence_s,
         "Streaming links: after the program's end, a controller silence this long ends the session (exit 0), s")
      ->capture_default_str();
  sub.add_flag("--end-on-silence", o->end_on_silence,
               "egm-path, rsi: a silence longer than --stop-silence-s after a healthy session is the planned end (the "
               "program's EGMStop or RSI_OFF): exit 0 instead of 5");
  sub.add_option("--log", o->log, "CSV log of every cycle (written off the loop's thread)");
  sub.add_flag("--log-report", o->log_report,
               "At the end, write the monitor's charts of the whole --log beside it (LOG with .html for .csv): a "
               "static page for a commissioning report");
  sub.add_option("--monitor", o->monitor,
                 "Serve a live page of the session at [ADDR:]PORT (default address 127.0.0.1; port 0 = any free one): "
                 "forces, corrections against their bounds, link health, 10 updates a second");
  sub.add_flag("--monitor-remote", o->monitor_remote,
               "Allow --monitor on an address other hosts can reach (the page shows the cell's data)");
  sub.add_option("--monitor-window-s", o->monitor_window_s, "The history the live page keeps, s (1..3600)")
      ->capture_default_str();
  sub.add_option("--monitor-linger-s", o->monitor_linger_s,
                 "Keep the live page up this long after the session ended, so its stop reason can be read, s");
  sub.add_option("--fault-dump", o->fault_dump,
                 "CSV the last cycles are written to, once per fault episode and at a stop for a fault (checked for "
                 "writability at start)");
  sub.add_flag("--json", o->json, "At the end, print one JSON document of the counters and timing on stdout");
  add_log_options(sub, o->log_options);
  sub.add_option("--stop-ramp-s", o->stop_ramp_s,
                 "A planned stop (SIGINT, SIGTERM, --duration-s) while moving: streamed programs come to rest on "
                 "their path over this long, corrections ramp out at the rate bound; a second signal stops at once, "
                 "0.05..10 s");
  sub.add_option("--duration-s", o->duration_s, "Stop after this many seconds (0: run until SIGINT/SIGTERM)")
      ->capture_default_str();
  sub.add_option("--status-interval-s", o->status_s, "Live status on stderr every this many seconds")
      ->capture_default_str();
  sub.add_flag("--realtime", o->realtime,
               "Run the loop with SCHED_FIFO, memory locked (and pinned with --rt-cpu); exit 2 naming the missing "
               "permission when the system refuses (docs/online.md \"Real-time setup\")");
  sub.add_option("--rt-priority", o->rt_priority, "With --realtime: the SCHED_FIFO priority, 1..99")
      ->capture_default_str();
  sub.add_option("--rt-cpu", o->rt_cpu, "With --realtime: the CPU to pin the loop to (an isolated core)");
  sub.add_flag("--rt-no-mlock", o->rt_no_mlock, "With --realtime: do not lock the process's memory");
  add_link_options(sub, *o);
  add_sensor_options(sub, *o);
  sub.callback([o, &sub, &exit_code] { run_online(*o, sub, exit_code); });
}

}  // namespace

DEFLEX_COMMAND("online",
               "Online compensation on a controller link (--link egm-joint|egm-path|rsi|simple-message|fanuc-j519): "
               "condition "
               "force samples and answer the controller, never beyond the bound of the nominal",
               setup_online, 40);

}  // namespace deflex::cli
