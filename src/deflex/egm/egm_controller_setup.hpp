// The controller's side of deflex's ABB EGM links, written by `deflex controller-setup --link
// egm-joint|egm-path`: a RAPID module that sets EGM up against deflex (EGMGetId, EGMSetupUC with the
// UdpUc device, EGMActJoint + EGMRunJoint for position guidance, or EGMActMove with procedures around
// the program's EGMMoveL/EGMMoveC for path correction) and the UdpUc transmission-protocol entry of
// the controller's communication configuration (SIO.cfg) that points at deflex's address and port.
// Everything deflex also knows (its port, its period, its bounds, the correction frame, its ramp-in)
// comes from the same options `deflex online` takes, so the two sides cannot disagree.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "deflex/link/controller_file.hpp"

namespace deflex {

struct EgmSetupOptions {
  bool path_correction = false;     ///< false: egm-joint (EGMActJoint/EGMRunJoint); true: egm-path
  std::string sensor_ip;            ///< deflex's IPv4 address as the controller reaches it
  std::uint16_t port = 6510;        ///< deflex online --egm-port
  std::string device = "DEFLEX";    ///< the UdpUc device (Transmission Protocol) name
  std::string egm_config = "default";  ///< the External Motion Interface Data entry EGMSetupUC names
  std::string module = "DeflexEgm";    ///< the RAPID module's name
  double period_ms = 4.0;           ///< deflex online --period-ms: EGMActJoint/EGMActMove \SampleRate
  double max_joint_correction_deg = 0.5;  ///< deflex online --max-joint-correction-deg
  double max_tcp_correction_mm = 5.0;     ///< deflex online --max-tcp-correction-mm
  double comm_timeout_s = 1.0;      ///< EGMSetupUC \CommTimeout
  // Position guidance only.
  double lowpass_hz = 20.0;         ///< EGMActJoint \LpFilter
  double ramp_in_s = 1.0;           ///< deflex online --ramp-in-s: EGMRunJoint \RampInTime
  double convergence_deg = 0.1;     ///< the egm_minmax condition on every joint
  double cond_time_s = 10.0;        ///< EGMRunJoint \CondTime
  double max_pos_deviation_deg = 1000.0;    ///< EGMActJoint \MaxPosDeviation
  double max_speed_deviation_deg_s = 1000.0;  ///< EGMActJoint \MaxSpeedDeviation
  // Path correction only.
  std::string path_frame = "tool";  ///< deflex online --path-corr-frame: tool, flange or path
  std::string tool = "tool0";       ///< the tooldata the program moves with
  /// Throws InputError naming the option (as `deflex controller-setup` spells it) when a value
  /// cannot work on the controller or disagrees with deflex.
  void validate() const;
};

/// The RAPID module (<module>.mod) and the UdpUc entry (<device>_udpuc.cfg). Throws InputError.
[[nodiscard]] std::vector<ControllerFile> egm_controller_setup(const EgmSetupOptions& options);

}  // namespace deflex
