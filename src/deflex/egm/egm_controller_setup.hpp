// The controller's side of deflex's ABB EGM links, written by `deflex controller-setup --link
// egm-joint|egm-path`: a RAPID module that sets EGM up against deflex (EGMGetId, EGMSetupUC with the
// UdpUc device, EGMActJoint + EGMRunJoint for position guidance, or EGMActMove with procedures around
// the program's EGMMoveL/EGMMoveC for path correction) and the UdpUc transmission-protocol entry of
// the controller's communication configuration (SIO.cfg) that points at deflex's address and port.
// Everything deflex also knows (its port, its period, its bounds, the correction frame, its ramp-in)
// comes from the same options `deflex online` takes, so the two sides cannot disagree.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "deflex/link/controller_file.hpp"

namespace deflex {

struct EgmSetupOptions {
  bool path_correction = false;           ///< false: egm-joint (EGMActJoint/EGMRunJoint); true: egm-path
  std::string sensor_ip;                  ///< deflex's IPv4 address as the controller reaches it
  std::uint16_t port = 6510;              ///< deflex online --egm-port
  std::string device = "DEFLEX";          ///< the UdpUc device (Transmission Protocol) name
  std::string egm_config = "default";     ///< the External Motion Interface Data entry EGMSetupUC names
  std::string module = "DeflexEgm";       ///< the RAPID module's name
  double period_ms = 4.0;                 ///< deflex online --period-ms: EGMActJoint/EGMActMove \SampleRate
  double max_joint_correction_deg = 0.5;  ///< deflex online --max-joint-correction-deg
  double max_tcp_correction_mm = 5.0;     ///< deflex online --max-tcp-correction-mm
  /// EGMSetupUC \CommTimeout: how long the controller waits for deflex before it stops EGM. NaN:
  /// deflex's own stop silence, so both sides give up on a silent partner after the same time.
  double comm_timeout_s = std::numeric_limits<double>::quiet_NaN();
  double stop_silence_s = 3.0;  ///< deflex online --stop-silence-s
  // Position guidance only.
  double lowpass_hz = 20.0;      ///< EGMActJoint \LpFilter
  double ramp_in_s = 1.0;        ///< deflex online --ramp-in-s: EGMRunJoint \RampInTime
  double convergence_deg = 0.1;  ///< the egm_minmax condition on every joint
  double cond_time_s = 10.0;     ///< EGMRunJoint \CondTime
  // Supervision, derived from deflex's own limits unless given (NaN): the controller stops EGM on a
  // reference deflex itself would never send, so a fault deflex does not catch the controller does.
  //   MaxSpeedDeviation = 1.25 x the fastest any joint's command may move: the program's peak speed, the
  //     ramp-in blend's (1.5 x the start tolerance over the ramp) and the correction's rate bound;
  //   MaxPosDeviation = the correction bound + the start tolerance + that program speed x the
  //     controller's follow lag (its dead time and filter: the arm trails the reference by as much).
  double max_pos_deviation_deg = std::numeric_limits<double>::quiet_NaN();      ///< EGMActJoint \MaxPosDeviation
  double max_speed_deviation_deg_s = std::numeric_limits<double>::quiet_NaN();  ///< EGMActJoint \MaxSpeedDeviation
  /// The program's peak speed per joint (deg/s, from deflex online's --program); empty: the robot's
  /// speed limits (`robot_max_speed_deg_s`) stand in, looser.
  std::vector<double> program_peak_speed_deg_s;
  std::vector<double> robot_max_speed_deg_s;
  double max_rate_deg_s = 3.0;       ///< deflex online --max-rate-deg-s
  double start_tolerance_deg = 1.0;  ///< the start tolerance of deflex's stream
  double follow_lag_s = 0.1;  ///< how far the arm trails its reference (EGM users: ~50 ms dead time, plus the filter)
  // Path correction only.
  std::string path_frame = "tool";  ///< deflex online --path-corr-frame: tool, flange or path
  std::string tool = "tool0";       ///< the tooldata the program moves with
  /// Throws InputError naming the option (as `deflex controller-setup` spells it) when a value
  /// cannot work on the controller or disagrees with deflex.
  void validate() const;
};

/// The supervision values the module will carry (MaxPosDeviation, MaxSpeedDeviation, CommTimeout),
/// derived or as given, and how (for the module's comment and for tests).
struct EgmSupervision {
  double max_pos_deviation_deg = 0.0, max_speed_deviation_deg_s = 0.0, comm_timeout_s = 0.0;
  double fastest_command_deg_s = 0.0;  ///< the fastest deflex's command may move (deg/s)
  std::string basis;                   ///< "the program's peak speeds" or "the robot's speed limits"
};
/// Throws InputError when a value given is below what deflex itself may send.
[[nodiscard]] EgmSupervision egm_supervision(const EgmSetupOptions& options);

/// The RAPID module (<module>.mod) and the UdpUc entry (<device>_udpuc.cfg). Throws InputError.
[[nodiscard]] std::vector<ControllerFile> egm_controller_setup(const EgmSetupOptions& options);

}  // namespace deflex
