// The controller's side of the EGM links (see egm_controller_setup.hpp). RAPID facts: ABB's EGM
// instructions as the public EGM examples use them (EGMSetupUC with \Joint or \PathCorr\APTR,
// EGMActJoint's \J1..\J6 conditions, \LpFilter, \SampleRate, \MaxPosDeviation, \MaxSpeedDeviation,
// EGMRunJoint's \CondTime, \RampInTime, \PosCorrGain, EGMActMove's sensor frame and \SampleRate).
#include "deflex/egm/egm_controller_setup.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"
#include "deflex/transport/datagram_transport.hpp"

namespace deflex {

namespace {

void positive(double v, double at_most, const char* option) {
  if (!std::isfinite(v) || !(v > 0.0) || v > at_most) {
    throw InputError(fmt::format("option {}: must be a number > 0 and <= {} (got {})", option, at_most, v));
  }
}

}  // namespace

void EgmSetupOptions::validate() const {
  (void)make_datagram_address(sensor_ip, port);  // InputError naming the text when it is not IPv4
  if (sensor_ip == "0.0.0.0") {
    throw InputError("option --sensor-ip: the controller must be given deflex's own address, not 0.0.0.0");
  }
  if (port == 0) throw InputError("option --egm-port: the controller needs deflex's port (1..65535)");
  for (const auto& [value, option] : {std::pair{&device, "--egm-device"}, std::pair{&egm_config, "--egm-config"},
                                      std::pair{&module, "--module"}, std::pair{&tool, "--tool"}}) {
    if (!plain_identifier(*value, 32)) {
      throw InputError(
          fmt::format("option {}: '{}' is not a RAPID name (a letter, then letters, digits or '_', at "
                      "most 32)",
                      option, *value));
    }
  }
  positive(period_ms, 1000.0, "--period-ms");
  const double cycles = period_ms / 4.0;
  if (std::abs(cycles - std::round(cycles)) > 1e-9) {
    throw InputError(
        fmt::format("option --period-ms: EGM's \\SampleRate is a multiple of the 4 ms cycle (got {})", period_ms));
  }
  if (!path_correction && std::abs(period_ms - 4.0) > 1e-9) {
    throw InputError(
        "option --period-ms: position guidance runs at EGM's 4 ms (deflex online --link egm-joint "
        "--period-ms 4)");
  }
  positive(max_joint_correction_deg, 10.0, "--max-joint-correction-deg");
  positive(max_tcp_correction_mm, 1000.0, "--max-tcp-correction-mm");
  if (!std::isnan(comm_timeout_s)) positive(comm_timeout_s, 3600.0, "--comm-timeout-s");
  positive(stop_silence_s, 3600.0, "--stop-silence-s");
  positive(max_rate_deg_s, 1e5, "--max-rate-deg-s");
  positive(start_tolerance_deg, 10.0, "the start tolerance");
  positive(follow_lag_s, 10.0, "the follow lag");
  positive(lowpass_hz, 1000.0, "--lowpass-hz");
  positive(ramp_in_s, 60.0, "--ramp-in-s");
  positive(convergence_deg, 180.0, "--convergence-deg");
  positive(cond_time_s, 3600.0, "--cond-time-s");
  if (!std::isnan(max_pos_deviation_deg)) positive(max_pos_deviation_deg, 1000.0, "--max-pos-deviation-deg");
  if (!std::isnan(max_speed_deviation_deg_s)) {
    positive(max_speed_deviation_deg_s, 10000.0, "--max-speed-deviation-deg-s");
  }
  if (!std::isnan(max_pos_deviation_deg) && max_pos_deviation_deg < max_joint_correction_deg) {
    throw InputError(
        "option --max-pos-deviation-deg: smaller than deflex's own --max-joint-correction-deg, so the "
        "controller would stop EGM on a correction deflex allows");
  }
  for (const auto* list : {&program_peak_speed_deg_s, &robot_max_speed_deg_s}) {
    for (double v : *list) {
      if (!std::isfinite(v) || v < 0.0)
        throw InputError("controller setup: joint speeds must be finite and >= 0 deg/s");
    }
  }
  if (path_frame != "tool" && path_frame != "flange" && path_frame != "path") {
    throw InputError(fmt::format("option --path-corr-frame: '{}' is not tool, flange or path", path_frame));
  }
}

EgmSupervision egm_supervision(const EgmSetupOptions& o) {
  EgmSupervision s;
  const std::vector<double>& speeds =
      !o.program_peak_speed_deg_s.empty() ? o.program_peak_speed_deg_s : o.robot_max_speed_deg_s;
  s.basis = !o.program_peak_speed_deg_s.empty() ? "the program's peak joint speeds"
            : !o.robot_max_speed_deg_s.empty()
                ? "the robot's joint speed limits (give --program for tighter values)"
                : "a 250 deg/s joint speed (give --program or --robot for tighter values)";
  double fastest_program = speeds.empty() ? 250.0 : 0.0;
  for (double v : speeds) fastest_program = std::max(fastest_program, v);
  const double blend = o.ramp_in_s > 0.0 ? 1.5 * o.start_tolerance_deg / o.ramp_in_s : 0.0;
  s.fastest_command_deg_s = fastest_program + blend + o.max_rate_deg_s;
  // Rounded up to what RAPID is given (0.01 deg, 1 deg/s), never below what deflex may send.
  const double derived_speed = std::ceil(1.25 * s.fastest_command_deg_s);
  const double derived_pos =
      std::ceil((o.max_joint_correction_deg + o.start_tolerance_deg + fastest_program * o.follow_lag_s) * 100.0) /
      100.0;
  s.max_speed_deviation_deg_s = std::isnan(o.max_speed_deviation_deg_s) ? derived_speed : o.max_speed_deviation_deg_s;
  s.max_pos_deviation_deg = std::isnan(o.max_pos_deviation_deg) ? derived_pos : o.max_pos_deviation_deg;
  s.comm_timeout_s = std::isnan(o.comm_timeout_s) ? o.stop_silence_s : o.comm_timeout_s;
  if (!o.path_correction && s.max_speed_deviation_deg_s < s.fastest_command_deg_s) {
    throw InputError(fmt::format(
        "option --max-speed-deviation-deg-s: {} deg/s is below the {:.1f} deg/s deflex's command may move ({}, the "
        "ramp-in and the correction's rate), so the controller would stop EGM on a command deflex allows",
        plain_number(s.max_speed_deviation_deg_s), s.fastest_command_deg_s, s.basis));
  }
  return s;
}

namespace {

// Position guidance: the procedure that hands the arm to deflex's stream, supervised from deflex's limits.
std::string egm_joint_procedure(const EgmSetupOptions& o, const EgmSupervision& sup) {
  std::string conditions, joints;
  for (int j = 1; j <= 6; ++j) {
    conditions += fmt::format("\\J{}:=deflex_converged", j);
    joints += fmt::format("\\J{}", j);
  }
  return fmt::format(
      "  ! EGMRunJoint returns once every joint stayed within this of deflex's target (deg) for \\CondTime; deflex\n"
      "  ! holds the program's last point when the program ends.\n"
      "  LOCAL CONST egm_minmax deflex_converged:=[{neg},{pos}];\n"
      "\n"
      "  ! Supervision from deflex's own limits ({basis}): deflex's command moves at most {fastest} deg/s\n"
      "  ! and stays within {joint} deg of its nominal, so the controller stops EGM beyond {maxspeed} deg/s or\n"
      "  ! {maxpos} deg from the arm; it gives up on a silent deflex after {timeout} s, as deflex gives up on it.\n"
      "  ! Position guidance: deflex streams the program. Call with the arm at the program's start (within 1 deg).\n"
      "  PROC deflex_egm_joint()\n"
      "    EGMReset deflex_egm_id;\n"
      "    EGMGetId deflex_egm_id;\n"
      "    EGMSetupUC ROB_1,deflex_egm_id,\"{config}\",\"{device}\"\\Joint\\CommTimeout:={timeout};\n"
      "    EGMActJoint deflex_egm_id\\Tool:={tool}\\WObj:=wobj0{conditions}\n"
      "      \\LpFilter:={lp}\\SampleRate:={period}\\MaxPosDeviation:={maxpos}\\MaxSpeedDeviation:={maxspeed};\n"
      "    EGMRunJoint deflex_egm_id,EGM_STOP_HOLD{joints}\\CondTime:={cond}\\RampInTime:={ramp}\\PosCorrGain:=1;\n"
      "    EGMReset deflex_egm_id;\n"
      "  ENDPROC\n",
      fmt::arg("neg", plain_number(-o.convergence_deg)), fmt::arg("pos", plain_number(o.convergence_deg)),
      fmt::arg("config", o.egm_config), fmt::arg("device", o.device),
      fmt::arg("timeout", plain_number(sup.comm_timeout_s)), fmt::arg("basis", sup.basis),
      fmt::arg("fastest", plain_number(std::round(sup.fastest_command_deg_s * 10.0) / 10.0)),
      fmt::arg("joint", plain_number(o.max_joint_correction_deg)), fmt::arg("tool", o.tool),
      fmt::arg("conditions", conditions), fmt::arg("lp", plain_number(o.lowpass_hz)),
      fmt::arg("period", plain_number(o.period_ms)), fmt::arg("maxpos", plain_number(sup.max_pos_deviation_deg)),
      fmt::arg("maxspeed", plain_number(sup.max_speed_deviation_deg_s)), fmt::arg("joints", joints),
      fmt::arg("cond", plain_number(o.cond_time_s)), fmt::arg("ramp", plain_number(o.ramp_in_s)));
}

// Path correction: the procedures around the program's own corrected moves, in deflex's frame.
std::string egm_path_procedures(const EgmSetupOptions& o, const EgmSupervision& sup) {
  std::string text;
  // The frame EGMActMove is given is the frame deflex expresses its offsets in.
  std::string frame = o.tool + ".tframe";
  std::string frame_note = "deflex's offsets are in the tool frame (--path-corr-frame tool)";
  if (o.path_frame == "flange") {
    text += "  LOCAL CONST pose deflex_flange_frame:=[[0,0,0],[1,0,0,0]];\n";
    frame = "deflex_flange_frame";
    frame_note = "deflex's offsets are in the flange frame, tool0 (--path-corr-frame flange)";
  } else if (o.path_frame == "path") {
    frame_note = "deflex's offsets are in path coordinates: x along the travel (--path-corr-frame path)";
  }
  text += fmt::format(
      "\n"
      "  ! Path correction: the program's own EGMMoveL/EGMMoveC run, deflex sends whole offsets every {period} ms;\n"
      "  ! {frame_note}. Call before the corrected moves.\n"
      "  PROC deflex_egm_path_begin()\n"
      "    EGMReset deflex_egm_id;\n"
      "    EGMGetId deflex_egm_id;\n"
      "    EGMSetupUC ROB_1,deflex_egm_id,\"{config}\",\"{device}\"\\PathCorr\\APTR\\CommTimeout:={timeout};\n"
      "    EGMActMove deflex_egm_id,{frame}\\SampleRate:={period};\n"
      "  ENDPROC\n"
      "\n"
      "  ! Call after the corrected moves.\n"
      "  PROC deflex_egm_path_end()\n"
      "    EGMStop deflex_egm_id,EGM_STOP_HOLD;\n"
      "    EGMReset deflex_egm_id;\n"
      "  ENDPROC\n"
      "\n"
      "  ! How a program moves with the corrections (use your own targets, speeds and zones):\n"
      "  !   deflex_egm_path_begin;\n"
      "  !   EGMMoveL deflex_egm_id,p10,v50,z1,{tool}\\WObj:=wobj0;\n"
      "  !   EGMMoveC deflex_egm_id,p20,p30,v50,fine,{tool}\\WObj:=wobj0;\n"
      "  !   deflex_egm_path_end;\n",
      fmt::arg("period", plain_number(o.period_ms)), fmt::arg("frame_note", frame_note),
      fmt::arg("config", o.egm_config), fmt::arg("device", o.device),
      fmt::arg("timeout", plain_number(sup.comm_timeout_s)), fmt::arg("frame", frame), fmt::arg("tool", o.tool));
  return text;
}

}  // namespace

std::vector<ControllerFile> egm_controller_setup(const EgmSetupOptions& o) {
  o.validate();
  const EgmSupervision sup = egm_supervision(o);
  const std::string link = o.path_correction ? "egm-path" : "egm-joint";
  std::string mod = fmt::format(
      "MODULE {module}\n"
      "  ! Generated by deflex controller-setup --link {link}: the controller's side of deflex's EGM link.\n"
      "  ! deflex listens on {ip}:{port} (UdpUc device \"{device}\"); nothing it sends leaves the nominal by more\n"
      "  ! than {joint} deg a joint or {tcp} mm at the TCP. Start deflex first, with the same values:\n"
      "  !   deflex online --link {link} --bind {ip} --egm-port {port} --period-ms {period} --max-joint-correction-deg "
      "{joint} --max-tcp-correction-mm {tcp}{more}\n"
      "  LOCAL VAR egmident deflex_egm_id;\n",
      fmt::arg("module", o.module), fmt::arg("link", link), fmt::arg("ip", o.sensor_ip), fmt::arg("port", o.port),
      fmt::arg("device", o.device), fmt::arg("joint", plain_number(o.max_joint_correction_deg)),
      fmt::arg("tcp", plain_number(o.max_tcp_correction_mm)), fmt::arg("period", plain_number(o.period_ms)),
      fmt::arg("more", o.path_correction ? fmt::format(" --path-corr-frame {}", o.path_frame)
                                         : fmt::format(" --ramp-in-s {} --program P.csv", plain_number(o.ramp_in_s))));
  mod += o.path_correction ? egm_path_procedures(o, sup) : egm_joint_procedure(o, sup);
  mod += "ENDMODULE\n";

  const std::string cfg = fmt::format(
      "# Generated by deflex controller-setup --link {link}: the UdpUc device EGM reaches deflex through.\n"
      "# Merge into SIO.cfg (topic Communication, type Transmission Protocol), or enter the same values on the\n"
      "# FlexPendant or in RobotStudio: Name {device}, Type UDPUC, Remote Address {ip}, Remote port number {port}.\n"
      "# RobotWare 6 spells the address attribute RemoteAdress in SIO.cfg; the values are what matter.\n"
      "COM_TRP:\n"
      "\n"
      "      -Name \"{device}\" -Type \"UDPUC\" -RemoteAdress \"{ip}\"\\\n"
      "      -RemotePortNumber {port}\n",
      fmt::arg("link", link), fmt::arg("device", o.device), fmt::arg("ip", o.sensor_ip), fmt::arg("port", o.port));

  return {
      {o.module + ".mod", mod,
       "RAPID module: load it into the motion task (T_ROB1), e.g. FlexPendant Program Editor > Modules > Load "
       "Module, or copy it to HOME: and load it from your main module"},
      {o.device + "_udpuc.cfg", cfg,
       "UdpUc device: merge into SIO.cfg (Control Panel > Configuration > Communication > Transmission Protocol), "
       "then restart the controller"},
  };
}

}  // namespace deflex
