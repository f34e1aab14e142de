// The controller's side of deflex's FANUC Stream Motion link, written by `deflex controller-setup --link
// fanuc-j519`: a TP program in FANUC's ASCII form (.LS) that moves to the program's start and waits in
// IBGN for deflex's stream, and a settings sheet with the system variables and options the stream needs,
// derived from the same values `deflex online` runs with (its interval, its protocol version, the
// limits it keeps the stream within), so the two sides agree. What FANUC's manual alone would settle is
// marked unconfirmed in the sheet (../shared/reference/fanuc_j519.md gives the sources).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "deflex/link/controller_file.hpp"
#include "deflex/model/types.hpp"
#include "deflex/wire/fanuc_j519.hpp"

namespace deflex {

struct FanucSetupOptions {
  std::string program_name = "DEFLEXSM";  ///< the TP program's name (1..8 of A-Z, 0-9, '_'; a letter first)
  double period_ms = 8.0;                 ///< deflex online --period-ms: $STMO.$COM_INT
  std::uint32_t version = 1;              ///< deflex online --fanuc-version
  int uframe = 0, utool = 1;              ///< the frames the TP program sets (the program is in joints)
  JointVector start_rad;         ///< the program's first point: the TP program moves there first (empty: no move)
  double move_speed_pct = 10.0;  ///< the joint move to the start, % of the joints' top speed
  /// deflex online --fanuc-limits and --fanuc-correction-share (the sheet says what deflex keeps to).
  std::array<fanuc_j519::AxisLimits, fanuc_j519::kAxes> limits{};
  double correction_share = 0.25;
  /// deflex's address as the controller sees it (for the sheet; the controller answers the start packet's sender).
  std::string pc_address;
  std::uint16_t robot_port = 60015;
};

/// The TP program (.LS) and the settings sheet. Throws InputError naming the option for a name,
/// interval, version or speed that cannot work.
[[nodiscard]] std::vector<ControllerFile> fanuc_controller_setup(const FanucSetupOptions& options);

}  // namespace deflex
