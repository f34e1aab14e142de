// The controller's side of deflex's KUKA RSI link, written by `deflex controller-setup --link rsi`
// (KR C4, RSI 3.x file formats):
//   <context>_ethernet.xml  the ETHERNET object's config: deflex's IP_NUMBER and PORT, the SENTYPE,
//                           SEND (RIst, RSol, AIPos, ASPos, Delay) and RECEIVE (AK.A1..A6, HOLDON);
//   <context>.rsi.xml       the RSI context the controller runs: ETHERNET1's outputs 1..6 wired to
//                           AXISCORR1's inputs, whose LowerLimAi/UpperLimAi are deflex's joint bound,
//                           an AXISCORRMON1 whose MaxAi stops RSI just beyond it, and the ETHERNET
//                           Timeout (late answers before RSI stops);
//   <context>.src           the KRL lines that load the context and switch RSI on in absolute mode
//                           (RSI_ON(#ABSOLUTE, #IPO_FAST)), around the program's own motion.
// The port, SENTYPE, period and bound are the options `deflex online --link rsi` takes, so the two
// sides cannot disagree. RSIVisual's own files (.rsi, .rsi.diagram) and RSI 4.x's .rsix are not
// written: build the same wiring in RSIVisual for those (docs/online.md).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "deflex/link/controller_file.hpp"

namespace deflex {

struct RsiSetupOptions {
  std::string sensor_ip;                  ///< deflex's IPv4 address as the controller reaches it (<IP_NUMBER>)
  std::uint16_t port = 49152;             ///< deflex online --rsi-port (<PORT>)
  std::string sentype = "ImFree";         ///< deflex online --rsi-sentype (<SENTYPE>)
  std::string context = "deflex_rsi";     ///< base name of the files (and the KRL program's name)
  double period_ms = 4.0;                 ///< deflex online --period-ms: 4 (#IPO_FAST) or 12 (#IPO)
  double max_joint_correction_deg = 0.5;  ///< deflex online --max-joint-correction-deg: AXISCORR's limits
  /// AXISCORRMON MaxAi as a multiple of the bound: beyond what AXISCORR lets through, so it only
  /// trips when something other than deflex corrects the axes.
  double monitor_factor = 1.2;
  int timeout = 100;  ///< ETHERNET Timeout: late answers before RSI stops
  int precision = 4;  ///< ETHERNET Precision: decimals of the values the controller sends
  int axes = 6;
  /// The silence after which deflex starts a new session from zero correction (RsiLinkConfig); the
  /// Timeout must stop RSI before it, so a new session is always a new RSI_ON.
  double restart_silence_s = 0.5;
  /// Throws InputError naming the option (as `deflex controller-setup` spells it).
  void validate() const;
};

/// The three files. Throws InputError.
[[nodiscard]] std::vector<ControllerFile> rsi_controller_setup(const RsiSetupOptions& options);

}  // namespace deflex
