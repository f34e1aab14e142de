// `deflex controller-setup --link egm-joint|egm-path|rsi|fanuc-j519|motoros2-rt|ur-rtde`: writes what the
// robot controller needs to talk to `deflex online` over that link (a RAPID module and the UdpUc entry
// for ABB EGM; the Ethernet config, the RSI context and the KRL lines for KUKA RSI; the TP program for
// FANUC; MotoROS2's configuration keys; UR's URScript servo program), made by the
// library by link kind (runtime/controller_setup.hpp) from the same defaults as `deflex online`.
#include <filesystem>
#include <iostream>
#include <memory>
#include <variant>

#include <fmt/format.h>

#include "cli_util.hpp"
#include "command.hpp"
#include "deflex/link/controller_file.hpp"
#include "deflex/runtime/controller_setup.hpp"
#include "deflex/runtime/session_settings.hpp"
#include "deflex/text/output_file.hpp"

namespace deflex::cli {
namespace {

// The settings and their defaults are the library's (runtime/controller_setup.hpp), which chooses the
// files by link kind; the command adds where they go and how they are listed.
struct ControllerSetupOpts : runtime::ControllerSetupSettings {
  std::string output_dir = ".";
  bool json = false;
};

// An option `deflex online` has too: bound to the field the library's list of shared settings names
// (runtime::controller_setup_shared), its help the settings table's (unit, range, the links it applies
// to) as online's --help gives it; the library checks its value as online does.
CLI::Option* add_shared(CLI::App& sub, ControllerSetupOpts& o, const char* option, const char* note = "") {
  const runtime::SessionSetting* s = runtime::find_session_setting(option);
  std::string help = "deflex online " + std::string(option);
  if (s != nullptr) help += ": " + runtime::option_help(*s);
  if (*note != '\0') help += fmt::format(" ({})", note);
  runtime::ControllerSetupSettings& settings = o;
  return std::visit([&](auto member) { return sub.add_option(option, settings.*member, help); },
                    runtime::controller_setup_shared(option).field);
}

// The link, where the files go, and the settings every link shares.
void add_controller_link_options(CLI::App& sub, ControllerSetupOpts& o) {
  sub.add_option("--link", o.link,
                 "egm-joint, egm-path, rsi, fanuc-j519, motoros2-rt or ur-rtde (as deflex online --link)")
      ->required();
  sub.add_option("--sensor-ip", o.sensor_ip,
                 "deflex's IPv4 address as the controller reaches it (the PC on the controller's network)")
      ->required();
  sub.add_option("-o,--output-dir", o.output_dir, "Directory the files are written to (made when missing)")
      ->capture_default_str();
  add_shared(sub, o, "--egm-port")->capture_default_str();
  add_shared(sub, o, "--rsi-port")->capture_default_str();
  add_shared(sub, o, "--rsi-sentype")->capture_default_str();
  add_shared(sub, o, "--period-ms", "egm-path: the EGMActMove SampleRate; rsi: 4 with #IPO_FAST, 12 with #IPO");
  add_shared(sub, o, "--max-joint-correction-deg", "rsi: AXISCORR's limits on every axis")->capture_default_str();
  add_shared(sub, o, "--max-tcp-correction-mm")->capture_default_str();
}

// ABB EGM's RAPID and UdpUc settings.
void add_controller_egm_options(CLI::App& sub, ControllerSetupOpts& o) {
  add_shared(sub, o, "--ramp-in-s", "egm-joint: EGMRunJoint \\RampInTime")->capture_default_str();
  add_shared(sub, o, "--path-corr-frame")->capture_default_str();
  sub.add_option("--egm-device", o.device, "EGM: the UdpUc device's name")->capture_default_str();
  sub.add_option("--egm-config", o.egm_config, "EGM: the External Motion Interface Data entry EGMSetupUC names")
      ->capture_default_str();
  sub.add_option("--module", o.module, "EGM: the RAPID module's name")->capture_default_str();
  sub.add_option("--tool", o.tool, "EGM: the tooldata the program moves with")->capture_default_str();
  sub.add_option("--comm-timeout-s", o.comm_timeout_s,
                 "EGM: EGMSetupUC \\CommTimeout, s (default: --stop-silence-s, deflex's own)");
  add_shared(sub, o, "--stop-silence-s");
  add_shared(sub, o, "--max-rate-deg-s")->capture_default_str();
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
}

// KUKA RSI, FANUC J519, MotoROS2 and UR RTDE settings.
void add_controller_other_options(CLI::App& sub, ControllerSetupOpts& o) {
  sub.add_option("--context", o.context, "rsi: base name of the files and the KRL program")->capture_default_str();
  add_shared(sub, o, "--rsi-timeout")->capture_default_str();
  sub.add_option("--rsi-precision", o.rsi_precision, "rsi: ETHERNET Precision, decimals the controller sends")
      ->capture_default_str();
  sub.add_option("--rsi-monitor-factor", o.monitor_factor,
                 "rsi: AXISCORRMON's MaxAi as a multiple of --max-joint-correction-deg")
      ->capture_default_str();
  sub.add_option("--tp-program", o.tp_program, "fanuc-j519: the TP program's name")->capture_default_str();
  add_shared(sub, o, "--fanuc-version")->capture_default_str();
  add_shared(sub, o, "--fanuc-limits")->capture_default_str();
  add_shared(sub, o, "--fanuc-correction-share")->capture_default_str();
  add_shared(sub, o, "--robot-port");
  add_shared(sub, o, "--motoros2-group")->capture_default_str();
  add_shared(sub, o, "--motoros2-resend-ms")->capture_default_str();
  add_shared(sub, o, "--motoros2-max-truncations")->capture_default_str();
  add_shared(sub, o, "--ur-lookahead-ms")->capture_default_str();
  add_shared(sub, o, "--ur-gain")->capture_default_str();
  add_shared(sub, o, "--ur-register-offset")->capture_default_str();
  sub.add_option("--uframe", o.uframe, "fanuc-j519: the user frame the TP program sets")->capture_default_str();
  sub.add_option("--utool", o.utool, "fanuc-j519: the tool frame the TP program sets")->capture_default_str();
  sub.add_option("--move-speed-pct", o.move_speed_pct,
                 "fanuc-j519: the TP program's joint move to --program's start, % of the joints' top speed")
      ->capture_default_str();
  sub.add_flag("--json", o.json, "Print one JSON document (the files written and where each goes) on stdout");
}

/// The options of `deflex controller-setup`, in the order --help lists them.
void add_controller_setup_options(CLI::App& sub, ControllerSetupOpts& o) {
  add_controller_link_options(sub, o);
  add_controller_egm_options(sub, o);
  add_controller_other_options(sub, o);
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
  const std::vector<ControllerFile> files = runtime::controller_setup_files(
      o, [](const std::string& path) { return load_cli_robot("controller-setup", path); });
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
    "URScript servo program for Universal Robots, agreeing with deflex online's options",
    setup_controller_setup, 42);

}  // namespace deflex::cli
