// `deflex controller-setup --link egm-joint|egm-path|rsi|fanuc-j519|motoros2-rt|ur-rtde`: writes what the robot
// controller needs to talk to `deflex online` over that link (a RAPID module and the UdpUc entry for ABB
// EGM; the Ethernet config, the RSI context and the KRL lines for KUKA RSI; FANUC's TP program and
// settings; MotoROS2's configuration keys; the URScript servo program for UR), from the same options and defaults as
// `deflex online` (ports, period, bounds, SENTYPE), so the controller's side agrees with deflex's.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>

#include <fmt/format.h>

#include "cli_util.hpp"
#include "command.hpp"
#include "deflex/egm/egm_controller_setup.hpp"
#include "deflex/fanuc/fanuc_controller_setup.hpp"
#include "deflex/fanuc/fanuc_j519_link.hpp"
#include "deflex/link/link_cycle.hpp"
#include "deflex/model/types.hpp"
#include "deflex/motoros2/motoros2_controller_setup.hpp"
#include "deflex/paths/joint_trajectory.hpp"
#include "deflex/rsi/rsi_controller_setup.hpp"
#include "deflex/rsi/rsi_link.hpp"
#include "deflex/runtime/link_table.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/output_file.hpp"
#include "deflex/ur/ur_controller_setup.hpp"

namespace deflex::cli {
namespace {

struct ControllerSetupOpts {
  // deflex online's defaults, held once (runtime/link_table.hpp): the files agree with a session
  // started with the same options.
  static constexpr runtime::SessionOptionDefaults kShared = runtime::kSessionOptionDefaults;
  std::string link, sensor_ip, output_dir = ".", sentype = kShared.rsi_sentype, context = "deflex_rsi",
                               device = "DEFLEX", egm_config = "default", module = "DeflexEgm",
                               path_frame = kShared.path_frame, tool = "tool0", program, robot;
  int egm_port = 6510, rsi_port = 49152,  // the ports ABB's and KUKA's examples use
      rsi_timeout = kShared.rsi_timeout, rsi_precision = 4;
  double period_ms = 0.0, max_joint_deg = kShared.max_joint_correction_deg, max_tcp_mm = kShared.max_tcp_correction_mm,
         ramp_in_s = kShared.ramp_in_s, comm_timeout_s = kNaN, lowpass_hz = 20.0, convergence_deg = 0.1,
         cond_time_s = 10.0, max_pos_deviation_deg = kNaN, max_speed_deviation_deg_s = kNaN, monitor_factor = 1.2,
         max_rate_deg_s = kShared.max_rate_deg_s,
         stop_silence_s = kNaN;  // default: the link kind's (runtime/link_table.cpp)
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
  bool json = false;
};

/// The options of `deflex controller-setup`, in the order --help lists them.
void add_controller_setup_options(CLI::App& sub, ControllerSetupOpts& o) {
  sub.add_option("--link", o.link,
                 "egm-joint, egm-path, rsi, fanuc-j519, motoros2-rt or ur-rtde (as deflex online --link)")
      ->required();
  sub.add_option("--sensor-ip", o.sensor_ip,
                 "deflex's IPv4 address as the controller reaches it (the PC on the controller's network)")
      ->required();
  sub.add_option("-o,--output-dir", o.output_dir, "Directory the files are written to (made when missing)")
      ->capture_default_str();
  sub.add_option("--egm-port", o.egm_port, "EGM: deflex online --egm-port")->capture_default_str();
  sub.add_option("--rsi-port", o.rsi_port, "rsi: deflex online --rsi-port (the Ethernet config's PORT)")
      ->capture_default_str();
  sub.add_option("--rsi-sentype", o.sentype, "rsi: deflex online --rsi-sentype (the Ethernet config's SENTYPE)")
      ->capture_default_str();
  sub.add_option("--period-ms", o.period_ms,
                 "deflex online --period-ms: egm-joint 4; egm-path the EGMActMove SampleRate (default 48); rsi 4 "
                 "(#IPO_FAST) or 12 (#IPO)");
  sub.add_option("--max-joint-correction-deg", o.max_joint_deg,
                 "deflex online --max-joint-correction-deg (rsi: AXISCORR's limits on every axis)")
      ->capture_default_str();
  sub.add_option("--max-tcp-correction-mm", o.max_tcp_mm, "deflex online --max-tcp-correction-mm")
      ->capture_default_str();
  sub.add_option("--ramp-in-s", o.ramp_in_s, "egm-joint: deflex online --ramp-in-s (EGMRunJoint \\RampInTime)")
      ->capture_default_str();
  sub.add_option("--path-corr-frame", o.path_frame, "egm-path: deflex online --path-corr-frame (tool, flange, path)")
      ->capture_default_str();
  sub.add_option("--egm-device", o.device, "EGM: the UdpUc device's name")->capture_default_str();
  sub.add_option("--egm-config", o.egm_config, "EGM: the External Motion Interface Data entry EGMSetupUC names")
      ->capture_default_str();
  sub.add_option("--module", o.module, "EGM: the RAPID module's name")->capture_default_str();
  sub.add_option("--tool", o.tool, "EGM: the tooldata the program moves with")->capture_default_str();
  sub.add_option("--comm-timeout-s", o.comm_timeout_s,
                 "EGM: EGMSetupUC \\CommTimeout, s (default: --stop-silence-s, deflex's own)");
  sub.add_option("--stop-silence-s", o.stop_silence_s, "EGM: deflex online --stop-silence-s (default: the link's, 3)");
  sub.add_option("--max-rate-deg-s", o.max_rate_deg_s, "egm-joint: deflex online --max-rate-deg-s")
      ->capture_default_str();
  sub.add_option("--program", o.program,
                 "egm-joint: deflex online --program: its peak joint speeds make \\MaxSpeedDeviation and "
                 "\\MaxPosDeviation tight (without it the robot's speed limits stand in)");
  sub.add_option("--robot", o.robot, "Robot file (its joint speed limits); default: the built-in IRB 6700");
  sub.add_option("--lowpass-hz", o.lowpass_hz, "egm-joint: EGMActJoint \\LpFilter, Hz")->capture_default_str();
  sub.add_option("--convergence-deg", o.convergence_deg, "egm-joint: the joints' convergence condition, deg")
      ->capture_default_str();
  sub.add_option("--cond-time-s", o.cond_time_s, "egm-joint: EGMRunJoint \\CondTime, s")->capture_default_str();
  sub.add_option("--max-pos-deviation-deg", o.max_pos_deviation_deg,
                 "egm-joint: EGMActJoint \\MaxPosDeviation, deg (default: derived from deflex's bound, start tolerance "
                 "and the program's speed)");
  sub.add_option("--max-speed-deviation-deg-s", o.max_speed_deviation_deg_s,
                 "egm-joint: EGMActJoint \\MaxSpeedDeviation, deg/s (default: 1.25 x the fastest deflex's command may "
                 "move)");
  sub.add_option("--context", o.context, "rsi: base name of the files and the KRL program")->capture_default_str();
  sub.add_option("--rsi-timeout", o.rsi_timeout, "rsi: ETHERNET Timeout, late answers before RSI stops")
      ->capture_default_str();
  sub.add_option("--rsi-precision", o.rsi_precision, "rsi: ETHERNET Precision, decimals the controller sends")
      ->capture_default_str();
  sub.add_option("--rsi-monitor-factor", o.monitor_factor,
                 "rsi: AXISCORRMON's MaxAi as a multiple of --max-joint-correction-deg")
      ->capture_default_str();
  sub.add_option("--tp-program", o.tp_program, "fanuc-j519: the TP program's name")->capture_default_str();
  sub.add_option("--fanuc-version", o.fanuc_version, "fanuc-j519: deflex online --fanuc-version")
      ->capture_default_str();
  sub.add_option("--fanuc-limits", o.fanuc_limits, "fanuc-j519: deflex online --fanuc-limits (deg/s, deg/s^2, deg/s^3)")
      ->capture_default_str();
  sub.add_option("--fanuc-correction-share", o.fanuc_correction_share,
                 "fanuc-j519: deflex online --fanuc-correction-share")
      ->capture_default_str();
  sub.add_option("--robot-port", o.robot_port,
                 "fanuc-j519, motoros2-rt, ur-rtde: deflex online --robot-port (default 60015, 22000, 30004)");
  sub.add_option("--motoros2-group", o.motoros2_group, "motoros2-rt: deflex online --motoros2-group")
      ->capture_default_str();
  sub.add_option("--motoros2-resend-ms", o.motoros2_resend_ms, "motoros2-rt: deflex online --motoros2-resend-ms")
      ->capture_default_str();
  sub.add_option("--motoros2-max-truncations", o.motoros2_max_truncations,
                 "motoros2-rt: deflex online --motoros2-max-truncations")
      ->capture_default_str();
  sub.add_option("--ur-lookahead-ms", o.ur_lookahead_ms, "ur-rtde: deflex online --ur-lookahead-ms")
      ->capture_default_str();
  sub.add_option("--ur-gain", o.ur_gain, "ur-rtde: deflex online --ur-gain")->capture_default_str();
  sub.add_option("--ur-register-offset", o.ur_register_offset, "ur-rtde: deflex online --ur-register-offset")
      ->capture_default_str();
  sub.add_option("--uframe", o.uframe, "fanuc-j519: the user frame the TP program sets")->capture_default_str();
  sub.add_option("--utool", o.utool, "fanuc-j519: the tool frame the TP program sets")->capture_default_str();
  sub.add_option("--move-speed-pct", o.move_speed_pct,
                 "fanuc-j519: the TP program's joint move to --program's start, % of the joints' top speed")
      ->capture_default_str();
  sub.add_flag("--json", o.json, "Print one JSON document (the files written and where each goes) on stdout");
}

/// A port option's value as a port; outside 1..65535 an error naming the option.
std::uint16_t controller_setup_port(int p, const char* option) {
  if (p < 1 || p > 65535) throw InputError(fmt::format("option {}: must be 1..65535 (got {})", option, p));
  return static_cast<std::uint16_t>(p);
}

/// The files of --link egm-joint or egm-path: the RAPID module and the UdpUc entry.
std::vector<ControllerFile> egm_setup_files(const ControllerSetupOpts& o) {
  EgmSetupOptions e;
  e.path_correction = o.link == "egm-path";
  e.sensor_ip = o.sensor_ip;
  e.port = controller_setup_port(o.egm_port, "--egm-port");
  e.device = o.device;
  e.egm_config = o.egm_config;
  e.module = o.module;
  const runtime::LinkKindInfo& kind = runtime::link_kind(runtime::parse_link_kind(o.link));
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
  const RobotModel model = load_cli_robot("controller-setup", o.robot);
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

/// The files of --link rsi: the Ethernet config, the RSI context and the KRL program.
std::vector<ControllerFile> rsi_setup_files(const ControllerSetupOpts& o) {
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
  r.period_ms = o.period_ms > 0.0 ? o.period_ms : runtime::link_kind(runtime::LinkKind::kRsi).default_period_s * 1e3;
  if (o.period_ms < 0.0) throw InputError("option --period-ms: must be > 0");
  r.max_joint_correction_deg = o.max_joint_deg;
  r.monitor_factor = o.monitor_factor;
  r.timeout = o.rsi_timeout;
  r.precision = o.rsi_precision;
  r.restart_silence_s = RsiLinkConfig{}.restart_silence_s;
  return rsi_controller_setup(r);
}

/// The files of --link fanuc-j519: the TP program and the settings sheet.
std::vector<ControllerFile> fanuc_setup_files(const ControllerSetupOpts& o) {
  FanucSetupOptions f;
  f.program_name = o.tp_program;
  f.period_ms =
      o.period_ms > 0.0 ? o.period_ms : runtime::link_kind(runtime::LinkKind::kFanucJ519).default_period_s * 1e3;
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
    const RobotModel model = load_cli_robot("controller-setup", o.robot);
    f.start_rad = JointTrajectory::read_csv(o.program, model).points().front();
  }
  return fanuc_controller_setup(f);
}

/// The files of --link motoros2-rt: the motoros2_config.yaml keys and the settings sheet. With --program,
/// each joint's fastest stream (the link's per-cycle step limit over the period: the program's peak,
/// the ramp-in blend's and the correction's rate) for the safety unit's speed limits.
std::vector<ControllerFile> motoros2_setup_files(const ControllerSetupOpts& o) {
  const runtime::LinkKindInfo& kind = runtime::link_kind(runtime::LinkKind::kMotoros2Rt);
  Motoros2SetupOptions m;
  if (o.period_ms < 0.0) throw InputError("option --period-ms: must be > 0");
  m.period_ms = o.period_ms > 0.0 ? o.period_ms : kind.default_period_s * 1e3;
  m.robot_port = o.robot_port == -1 ? 22000 : o.robot_port;
  m.group = o.motoros2_group;
  m.stop_silence_s = std::isnan(o.stop_silence_s) ? kind.default_stop_silence_s : o.stop_silence_s;
  m.resend_ms = o.motoros2_resend_ms;
  m.max_truncations = o.motoros2_max_truncations;
  m.pc_address = o.sensor_ip;
  if (!o.program.empty()) {
    const RobotModel model = load_cli_robot("controller-setup", o.robot);
    const auto program = std::make_shared<const JointTrajectory>(JointTrajectory::read_csv(o.program, model));
    OnlineConfig online;
    online.period_s = m.period_ms * 1e-3;
    online.max_joint_correction_rad = deg_to_rad(o.max_joint_deg);
    online.max_correction_rate_rad_s = deg_to_rad(o.max_rate_deg_s);
    JointStreamConfig stream;
    stream.ramp_in_s = o.ramp_in_s;
    stream.validate();
    const CommandLimits l = command_limits(CommandForm::kJointTarget, online, model.dof(), program.get(), &stream);
    m.stream_speed_rad_s = l.joint_step_rad / online.period_s;
  }
  return motoros2_controller_setup(m);
}

/// The files of --link ur-rtde: the URScript servo program and the settings sheet. With --program, each
/// joint's fastest stream (as for motoros2-rt): the script checks every step against it and the sheet
/// gives the safety configuration's speed limits.
std::vector<ControllerFile> ur_setup_files(const ControllerSetupOpts& o) {
  const runtime::LinkKindInfo& kind = runtime::link_kind(runtime::LinkKind::kUrRtde);
  UrSetupOptions u;
  if (o.period_ms < 0.0) throw InputError("option --period-ms: must be > 0");
  u.period_ms = o.period_ms > 0.0 ? o.period_ms : kind.default_period_s * 1e3;
  u.robot_port = o.robot_port == -1 ? 30004 : o.robot_port;
  u.lookahead_s = o.ur_lookahead_ms * 1e-3;
  u.gain = o.ur_gain;
  u.register_offset = o.ur_register_offset;
  if (!o.program.empty()) {
    const RobotModel model = load_cli_robot("controller-setup", o.robot);
    const auto program = std::make_shared<const JointTrajectory>(JointTrajectory::read_csv(o.program, model));
    OnlineConfig online;
    online.period_s = u.period_ms * 1e-3;
    online.max_joint_correction_rad = deg_to_rad(o.max_joint_deg);
    online.max_correction_rate_rad_s = deg_to_rad(o.max_rate_deg_s);
    JointStreamConfig stream;
    stream.ramp_in_s = o.ramp_in_s;
    stream.validate();
    const CommandLimits l = command_limits(CommandForm::kJointTarget, online, model.dof(), program.get(), &stream);
    u.stream_speed_rad_s = l.joint_step_rad / online.period_s;
  }
  return ur_controller_setup(u);
}

/// Writes the files into --output-dir and lists them with where each goes (JSON with --json).
void write_controller_setup_files(const ControllerSetupOpts& o, const std::vector<ControllerFile>& files) {
  OutputFolder folder(o.output_dir, "option --output-dir");  // made when missing, as every output's folder
  write_controller_files(files, o.output_dir);
  folder.keep();
  if (o.json) {
    nlohmann::json list = nlohmann::json::array();
    for (const auto& f : files) {
      list.push_back({{"file", (std::filesystem::path(o.output_dir) / f.name).string()}, {"install", f.install}});
    }
    print_json({{"link", o.link}, {"files", list}});
  } else {
    std::cout << fmt::format("deflex controller-setup --link {}: wrote {} files to {}\n", o.link, files.size(),
                             o.output_dir);
    for (const auto& f : files) std::cout << fmt::format("  {}\n      {}\n", f.name, f.install);
    std::cout << "docs/online.md walks through installing them and names the controller's typical errors.\n";
  }
}

/// Makes the link's files and writes them.
void run_controller_setup(const ControllerSetupOpts& o, int& exit_code) {
  std::vector<ControllerFile> files;
  if (o.link == "egm-joint" || o.link == "egm-path") {
    files = egm_setup_files(o);
  } else if (o.link == "rsi") {
    files = rsi_setup_files(o);
  } else if (o.link == "fanuc-j519") {
    files = fanuc_setup_files(o);
  } else if (o.link == "motoros2-rt") {
    files = motoros2_setup_files(o);
  } else if (o.link == "ur-rtde") {
    files = ur_setup_files(o);
  } else {
    throw InputError(
        fmt::format("option --link: '{}' is not egm-joint, egm-path, rsi, fanuc-j519, motoros2-rt or ur-rtde", o.link));
  }
  write_controller_setup_files(o, files);
  exit_code = 0;
}

/// Registers the options; the command runs once they parse.
void setup_controller_setup(CLI::App& sub, int& exit_code) {
  auto o = std::make_shared<ControllerSetupOpts>();
  add_controller_setup_options(sub, *o);
  sub.callback([o, &exit_code] { run_controller_setup(*o, exit_code); });
}

}  // namespace

DEFLEX_COMMAND(
    "controller-setup",
    "Write the robot controller's side of a link (--link egm-joint|egm-path|rsi|fanuc-j519|motoros2-rt|ur-rtde): "
    "RAPID and UdpUc for ABB EGM, the Ethernet config, RSI context and KRL for KUKA RSI, the TP program "
    "and settings for FANUC Stream Motion, the motoros2_config.yaml keys for MotoROS2's real-time mode, the "
    "URScript servo program for Universal Robots, "
    "agreeing with deflex online's options",
    setup_controller_setup, 42);

}  // namespace deflex::cli
