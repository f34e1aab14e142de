// The controller's side of a link by link kind (controller_setup.hpp).
#include "deflex/runtime/controller_setup.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <memory>
#include <stdexcept>
#include <type_traits>

#include <fmt/format.h>

#include "deflex/egm/egm_controller_setup.hpp"
#include "deflex/fanuc/fanuc_controller_setup.hpp"
#include "deflex/fanuc/fanuc_j519_link.hpp"
#include "deflex/link/link_cycle.hpp"
#include "deflex/motoros2/motoros2_controller_setup.hpp"
#include "deflex/paths/joint_trajectory.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/rsi/rsi_controller_setup.hpp"
#include "deflex/rsi/rsi_link.hpp"
#include "deflex/runtime/session_settings.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/ur/ur_controller_setup.hpp"

namespace deflex::runtime {
namespace {

/// A port option's value as a port; outside 1..65535 an error naming the option.
std::uint16_t controller_setup_port(int p, const char* option) {
  if (p < 1 || p > 65535) throw InputError(fmt::format("option {}: must be 1..65535 (got {})", option, p));
  return static_cast<std::uint16_t>(p);
}

RobotModel read_robot(const RobotLoader& load_robot, const std::string& path) {
  return load_robot ? load_robot(path) : load_robot_or_builtin(path == "builtin" ? std::string() : path);
}

/// The files of egm-joint or egm-path: the RAPID module and the UdpUc entry.
std::vector<ControllerFile> egm_setup_files(const ControllerSetupSettings& o, const RobotLoader& load_robot) {
  EgmSetupOptions e;
  e.path_correction = o.link == "egm-path";
  e.sensor_ip = o.sensor_ip;
  e.port = controller_setup_port(o.egm_port, "--egm-port");
  e.device = o.device;
  e.egm_config = o.egm_config;
  e.module = o.module;
  const LinkKindInfo& kind = link_kind(parse_link_kind(o.link));
  e.period_ms = o.period_ms > 0.0 ? o.period_ms : kind.default_period_s * 1e3;
  if (o.period_ms < 0.0) throw InputError("option --period-ms: must be > 0");
  e.max_joint_correction_deg = o.max_joint_deg;
  e.max_tcp_correction_mm = o.max_tcp_mm;
  e.comm_timeout_s = o.comm_timeout_s;
  e.lowpass_hz = o.lowpass_hz;
  e.ramp_in_s = o.ramp_in_s;
  e.convergence_deg = o.convergence_deg;
  e.cond_time_s = o.cond_time_s;
  e.max_pos_deviation_deg = o.max_pos_deviation_deg;
  e.max_speed_deviation_deg_s = o.max_speed_deviation_deg_s;
  e.max_rate_deg_s = o.max_rate_deg_s;
  e.stop_silence_s = std::isnan(o.stop_silence_s) ? kind.default_stop_silence_s : o.stop_silence_s;
  const RobotModel model = read_robot(load_robot, o.robot);
  if (model.has_max_speed()) {
    for (int j = 0; j < model.dof(); ++j) e.robot_max_speed_deg_s.push_back(rad_to_deg(model.max_speed()[j]));
  }
  if (!o.program.empty()) {
    if (e.path_correction) throw InputError("option --program: egm-path corrects the controller's own program");
    const JointTrajectory program = JointTrajectory::read_csv(o.program, model);
    for (int j = 0; j < program.dof(); ++j) e.program_peak_speed_deg_s.push_back(rad_to_deg(program.peak_speed()[j]));
  }
  e.path_frame = o.path_frame;
  e.tool = o.tool;
  return egm_controller_setup(e);
}

/// The files of rsi: the Ethernet config, the RSI context and the KRL program.
std::vector<ControllerFile> rsi_setup_files(const ControllerSetupSettings& o) {
  if (!o.program.empty() || !o.robot.empty()) {
    throw InputError(
        "options --program, --robot: apply to --link egm-joint and egm-path (the RSI limits come from "
        "--max-joint-correction-deg)");
  }
  RsiSetupOptions r;
  r.sensor_ip = o.sensor_ip;
  r.port = controller_setup_port(o.rsi_port, "--rsi-port");
  r.sentype = o.sentype;
  r.context = o.context;
  r.period_ms = o.period_ms > 0.0 ? o.period_ms : link_kind(LinkKind::kRsi).default_period_s * 1e3;
  if (o.period_ms < 0.0) throw InputError("option --period-ms: must be > 0");
  r.max_joint_correction_deg = o.max_joint_deg;
  r.monitor_factor = o.monitor_factor;
  r.timeout = o.rsi_timeout;
  r.precision = o.rsi_precision;
  r.restart_silence_s = RsiLinkConfig{}.restart_silence_s;
  return rsi_controller_setup(r);
}

/// The files of fanuc-j519: the TP program and the settings sheet.
std::vector<ControllerFile> fanuc_setup_files(const ControllerSetupSettings& o, const RobotLoader& load_robot) {
  FanucSetupOptions f;
  f.program_name = o.tp_program;
  f.period_ms = o.period_ms > 0.0 ? o.period_ms : link_kind(LinkKind::kFanucJ519).default_period_s * 1e3;
  if (o.period_ms < 0.0) throw InputError("option --period-ms: must be > 0");
  if (o.fanuc_version < 0) throw InputError("option --fanuc-version: 1, 3 or 4");
  f.version = static_cast<std::uint32_t>(o.fanuc_version);
  f.uframe = o.uframe;
  f.utool = o.utool;
  f.move_speed_pct = o.move_speed_pct;
  f.limits = parse_fanuc_limits(o.fanuc_limits, "--fanuc-limits");
  if (!(o.fanuc_correction_share > 0.0 && o.fanuc_correction_share < 1.0)) {
    throw InputError("option --fanuc-correction-share: must be in (0, 1)");
  }
  f.correction_share = o.fanuc_correction_share;
  f.robot_port = controller_setup_port(o.robot_port == -1 ? 60015 : o.robot_port, "--robot-port");
  f.pc_address = o.sensor_ip;
  if (!o.program.empty()) {
    const RobotModel model = read_robot(load_robot, o.robot);
    f.start_rad = JointTrajectory::read_csv(o.program, model).points().front();
  }
  return fanuc_controller_setup(f);
}

/// Each joint's fastest stream of the program (its own speed, the blend's and the correction's, as the
/// link's step limit holds them), rad/s: for a controller's speed limits (MotoROS2's safety unit, UR's
/// safety configuration).
JointVector stream_speed_rad_s(const ControllerSetupSettings& o, double period_ms, const RobotLoader& load_robot) {
  const RobotModel model = read_robot(load_robot, o.robot);
  const auto program = std::make_shared<const JointTrajectory>(JointTrajectory::read_csv(o.program, model));
  OnlineConfig online;
  online.period_s = period_ms * 1e-3;
  online.max_joint_correction_rad = deg_to_rad(o.max_joint_deg);
  online.max_correction_rate_rad_s = deg_to_rad(o.max_rate_deg_s);
  JointStreamConfig stream;
  stream.ramp_in_s = o.ramp_in_s;
  stream.validate();
  const CommandLimits l = command_limits(CommandForm::kJointTarget, online, model.dof(), program.get(), &stream);
  return l.joint_step_rad / online.period_s;
}

/// The files of motoros2-rt: the motoros2_config.yaml keys and the settings sheet. With a program, the
/// sheet gives each joint's fastest stream (its speed and the correction's), for the safety unit's
/// speed limits.
std::vector<ControllerFile> motoros2_setup_files(const ControllerSetupSettings& o, const RobotLoader& load_robot) {
  const LinkKindInfo& kind = link_kind(LinkKind::kMotoros2Rt);
  Motoros2SetupOptions m;
  if (o.period_ms < 0.0) throw InputError("option --period-ms: must be > 0");
  m.period_ms = o.period_ms > 0.0 ? o.period_ms : kind.default_period_s * 1e3;
  m.robot_port = o.robot_port == -1 ? 22000 : o.robot_port;
  m.group = o.motoros2_group;
  m.stop_silence_s = std::isnan(o.stop_silence_s) ? kind.default_stop_silence_s : o.stop_silence_s;
  m.resend_ms = o.motoros2_resend_ms;
  m.max_truncations = o.motoros2_max_truncations;
  m.pc_address = o.sensor_ip;
  if (!o.program.empty()) m.stream_speed_rad_s = stream_speed_rad_s(o, m.period_ms, load_robot);
  return motoros2_controller_setup(m);
}

/// The files of ur-rtde: the URScript servo program and the settings sheet. With a program, each joint's
/// fastest stream (as for motoros2-rt): the script checks every step against it and the sheet gives the
/// safety configuration's speed limits.
std::vector<ControllerFile> ur_setup_files(const ControllerSetupSettings& o, const RobotLoader& load_robot) {
  const LinkKindInfo& kind = link_kind(LinkKind::kUrRtde);
  UrSetupOptions u;
  if (o.period_ms < 0.0) throw InputError("option --period-ms: must be > 0");
  u.period_ms = o.period_ms > 0.0 ? o.period_ms : kind.default_period_s * 1e3;
  u.robot_port = o.robot_port == -1 ? 30004 : o.robot_port;
  u.lookahead_s = o.ur_lookahead_ms * 1e-3;
  u.gain = o.ur_gain;
  u.register_offset = o.ur_register_offset;
  if (!o.program.empty()) u.stream_speed_rad_s = stream_speed_rad_s(o, u.period_ms, load_robot);
  return ur_controller_setup(u);
}

/// Checks the shared settings that apply to the link as `deflex online` checks them (the settings
/// table: the same ranges, the same sentence), so the controller's side is never written for a value
/// the session would refuse.
void check_shared_settings(const ControllerSetupSettings& o) {
  const LinkKind kind = parse_link_kind(o.link);
  std::vector<GivenSetting> given;
  for (const ControllerSetupShared& shared : controller_setup_shared()) {
    const SessionSetting* s = find_session_setting(shared.option);
    if (s == nullptr) {
      throw std::logic_error(fmt::format("controller-setup: {} is not in the settings table", shared.option));
    }
    if ((s->links & link_bit(kind)) == 0) continue;
    // The value as its option's text, for the table to read as the command line's: a number in full
    // (a NaN included, for the table to refuse), unless it is the field's "unset".
    const std::optional<std::string> text = std::visit(
        [&](auto member) -> std::optional<std::string> {
          const auto& value = o.*member;
          if constexpr (std::is_same_v<std::decay_t<decltype(value)>, std::string>) {
            return value;
          } else {
            const auto v = static_cast<double>(value);
            if (shared.unset && (std::isnan(*shared.unset) ? std::isnan(v) : v == *shared.unset)) return std::nullopt;
            return fmt::format("{:.17g}", v);
          }
        },
        shared.field);
    if (text) given.push_back({s, option_value(*s, *text)});
  }
  (void)make_session_config(o.link, "online", given);
}

}  // namespace

std::span<const ControllerSetupShared> controller_setup_shared() {
  using S = ControllerSetupSettings;
  static const ControllerSetupShared table[] = {
      {"--egm-port", &S::egm_port, {}},
      {"--rsi-port", &S::rsi_port, {}},
      {"--rsi-sentype", &S::sentype, {}},
      {"--period-ms", &S::period_ms, 0.0},  // 0: the link kind's
      {"--max-joint-correction-deg", &S::max_joint_deg, {}},
      {"--max-tcp-correction-mm", &S::max_tcp_mm, {}},
      {"--ramp-in-s", &S::ramp_in_s, {}},
      {"--path-corr-frame", &S::path_frame, {}},
      {"--stop-silence-s", &S::stop_silence_s, kNaN},  // NaN: the link kind's
      {"--max-rate-deg-s", &S::max_rate_deg_s, {}},
      {"--rsi-timeout", &S::rsi_timeout, {}},
      {"--fanuc-version", &S::fanuc_version, {}},
      {"--fanuc-limits", &S::fanuc_limits, {}},
      {"--fanuc-correction-share", &S::fanuc_correction_share, {}},
      {"--robot-port", &S::robot_port, -1.0},  // -1: the protocol's
      {"--motoros2-group", &S::motoros2_group, {}},
      {"--motoros2-resend-ms", &S::motoros2_resend_ms, {}},
      {"--motoros2-max-truncations", &S::motoros2_max_truncations, {}},
      {"--ur-lookahead-ms", &S::ur_lookahead_ms, {}},
      {"--ur-gain", &S::ur_gain, {}},
      {"--ur-register-offset", &S::ur_register_offset, {}},
  };
  return table;
}

const ControllerSetupShared& controller_setup_shared(std::string_view option) {
  for (const ControllerSetupShared& shared : controller_setup_shared()) {
    if (option == shared.option) return shared;
  }
  throw std::logic_error(fmt::format("controller-setup: {} is not a setting it shares with deflex online", option));
}

std::vector<ControllerFile> controller_setup_files(const ControllerSetupSettings& settings,
                                                   const RobotLoader& load_robot) {
  const std::string& link = settings.link;
  constexpr const char* kLinks[] = {"egm-joint", "egm-path", "rsi", "fanuc-j519", "motoros2-rt", "ur-rtde"};
  if (std::find(std::begin(kLinks), std::end(kLinks), link) == std::end(kLinks)) {
    throw InputError(
        fmt::format("option --link: '{}' is not egm-joint, egm-path, rsi, fanuc-j519, motoros2-rt or ur-rtde", link));
  }
  check_shared_settings(settings);
  if (link == "egm-joint" || link == "egm-path") return egm_setup_files(settings, load_robot);
  if (link == "rsi") return rsi_setup_files(settings);
  if (link == "fanuc-j519") return fanuc_setup_files(settings, load_robot);
  if (link == "motoros2-rt") return motoros2_setup_files(settings, load_robot);
  return ur_setup_files(settings, load_robot);
}

}  // namespace deflex::runtime
