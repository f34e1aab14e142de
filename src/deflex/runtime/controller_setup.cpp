// The controller's side of a link by link kind (controller_setup.hpp).
#include "deflex/runtime/controller_setup.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <memory>
#include <stdexcept>

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

/// The settings controller-setup shares with `deflex online`, as (option, value in the option's unit or
/// words); an unset one (a period of 0, a silence of NaN, a port of -1: the link's) is left out.
std::vector<std::pair<const char*, std::string>> shared_settings(const ControllerSetupSettings& o) {
  std::vector<std::pair<const char*, std::string>> out;
  // A NaN is passed on for the table to refuse, except where it means "unset" (the silence).
  const auto number = [&out](const char* option, double v, bool nan_is_unset = false) {
    if (!(nan_is_unset && std::isnan(v))) out.emplace_back(option, fmt::format("{:.17g}", v));
  };
  if (o.period_ms != 0.0) number("--period-ms", o.period_ms);
  number("--max-joint-correction-deg", o.max_joint_deg);
  number("--max-tcp-correction-mm", o.max_tcp_mm);
  number("--max-rate-deg-s", o.max_rate_deg_s);
  number("--ramp-in-s", o.ramp_in_s);
  number("--stop-silence-s", o.stop_silence_s, true);
  number("--egm-port", o.egm_port);
  number("--rsi-port", o.rsi_port);
  number("--rsi-timeout", o.rsi_timeout);
  out.emplace_back("--rsi-sentype", o.sentype);
  out.emplace_back("--path-corr-frame", o.path_frame);
  number("--fanuc-version", o.fanuc_version);
  out.emplace_back("--fanuc-limits", o.fanuc_limits);
  number("--fanuc-correction-share", o.fanuc_correction_share);
  if (o.robot_port != -1) number("--robot-port", o.robot_port);
  number("--motoros2-group", o.motoros2_group);
  number("--motoros2-resend-ms", o.motoros2_resend_ms);
  number("--motoros2-max-truncations", o.motoros2_max_truncations);
  number("--ur-lookahead-ms", o.ur_lookahead_ms);
  number("--ur-gain", o.ur_gain);
  number("--ur-register-offset", o.ur_register_offset);
  return out;
}

/// Checks the shared settings that apply to the link as `deflex online` checks them (the settings
/// table: the same ranges, the same sentence), so the controller's side is never written for a value
/// the session would refuse.
void check_shared_settings(const ControllerSetupSettings& o) {
  const LinkKind kind = parse_link_kind(o.link);
  std::vector<GivenSetting> given;
  for (const auto& [option, text] : shared_settings(o)) {
    const SessionSetting* s = find_session_setting(option);
    if (s == nullptr) throw std::logic_error(fmt::format("controller-setup: {} is not in the settings table", option));
    if ((s->links & link_bit(kind)) == 0) continue;
    given.push_back({s, option_value(*s, text)});
  }
  (void)make_session_config(o.link, "online", given);
}

}  // namespace

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
