// A setting as a session ran with it, for the people watching it: its command-line option and its
// value in the option's unit, as text ("--max-joint-correction-deg", "0.5"). The cycle log records one
// per "# setting: " line and the monitor's page lists them; the unit, the range and the help are looked
// up in the settings table (session_settings.hpp) by the option, so nothing describes a setting twice.
#pragma once

#include <string>

namespace deflex::runtime {

struct ShownSetting {
  std::string option;  ///< "--max-joint-correction-deg"
  std::string value;   ///< in the option's unit: "0.5"; flags "on" / "off"
};

}  // namespace deflex::runtime
