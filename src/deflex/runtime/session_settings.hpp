// Every setting of an online session, once: its Python and case-file key (SI units), its command-line
// option (the unit users expect there), its range, its default, its help, and the links it applies
// to. `deflex online` makes its options from this table and Python's deflex.Session and
// deflex.StandIn take its keys; both hand what they were given to make_session_config(), which
// checks every value here, so the two front ends refuse the same values with the same words:
//   setting max_joint_correction_rad (--max-joint-correction-deg): 1 rad (57.3 deg) is outside
//   0 < value <= 0.1745 rad (10 deg): a compliance correction is a fraction of a degree
// A further link's settings are rows here.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "deflex/runtime/session_config.hpp"
#include "deflex/runtime/shown_setting.hpp"

namespace deflex::runtime {

enum class SettingType { kReal, kInteger, kFlag, kText };

/// The links a setting applies to: a bit per LinkKind.
using LinkMask = std::uint32_t;
[[nodiscard]] constexpr LinkMask link_bit(LinkKind kind) { return LinkMask{1} << static_cast<int>(kind); }
inline constexpr LinkMask kEveryLink = ~LinkMask{0};

struct SessionSetting {
  std::string_view key{};     ///< Python's keyword and the case file's key, SI: "max_joint_correction_rad"
  std::string_view option{};  ///< the command line's: "--max-joint-correction-deg"
  SettingType type = SettingType::kReal;
  std::string_view unit{};         ///< the key's unit: "rad", "m", "s", "" (counts, words)
  std::string_view option_unit{};  ///< the option's: "deg", "mm", "ms"
  double option_per_unit = 1.0;    ///< an option's value is the key's times this (deg per rad ...)
  double min = 0.0, max = 0.0;     ///< reals and integers: the range, in the key's unit
  bool min_open = false;           ///< a real's range excludes its minimum (> 0)
  bool max_open = false;           ///< and its maximum (< 1)
  LinkMask links = kEveryLink;
  std::string_view help{};          ///< what it does (without unit, range and default: option_help() adds them)
  std::string_view why{};           ///< why the range is what it is ("" when the unit says it)
  bool flag_inverted = false;       ///< the option says the opposite of the key (--no-speed-reference)
  std::string_view default_text{};  ///< shown instead of the configuration's default ("the link's")
  // Access, by type: reals and integers (in the key's unit), flags, words (set_text parses them and
  // throws InputError with the reason, without the name).
  double (*get_real)(const SessionConfig&) = nullptr;
  void (*set_real)(SessionConfig&, double) = nullptr;
  bool (*get_flag)(const SessionConfig&) = nullptr;
  void (*set_flag)(SessionConfig&, bool) = nullptr;
  std::string (*get_text)(const SessionConfig&) = nullptr;
  void (*set_text)(SessionConfig&, const std::string&) = nullptr;
};

/// Every setting, in the order `deflex online --help` shows them.
[[nodiscard]] std::span<const SessionSetting> session_settings();
/// The setting whose key or option is `name` (null when none).
[[nodiscard]] const SessionSetting* find_session_setting(std::string_view name);
/// "setting max_joint_correction_rad (--max-joint-correction-deg)": how every message names it.
[[nodiscard]] std::string setting_name(const SessionSetting& s);

/// A value as a front end was given it: a number in the key's unit (SI), a flag, or words.
using SettingValue = std::variant<double, bool, std::string>;
struct GivenSetting {
  const SessionSetting* setting = nullptr;
  SettingValue value;
};
/// An option's text in the option's unit as the key's value ("0.5" deg -> 0.008727 rad). Throws
/// InputError naming the setting for a text that is not a (whole, for integers) number.
[[nodiscard]] SettingValue option_value(const SessionSetting& s, const std::string& text);

/// The configuration a session of `link` starts from: the link's cycle and stop silence, and the
/// bounds controller-setup writes into the controller's side (kSessionOptionDefaults).
[[nodiscard]] SessionConfig default_session_config(LinkKind link);
/// The configuration from a link's name, a strategy's, and the settings a user gave, every value
/// checked against the table (its type, its range, its link), then the settings against each other
/// (a step limit that fits its bound, realtime options without --realtime ...). Throws InputError
/// naming the setting (setting_name()) and saying why.
[[nodiscard]] SessionConfig make_session_config(const std::string& link, const std::string& strategy,
                                                std::span<const GivenSetting> given);

/// A setting's value in `config`, in the option's unit, as text ("0.5", "on", "nominal"); one that
/// `config` leaves unset (a port of -1, a real of 0) shows its default_text ("not read").
[[nodiscard]] std::string setting_value_text(const SessionSetting& s, const SessionConfig& config);
/// Every setting that applies to `config.link`, in the table's order, with its value in `config`: what
/// the cycle log records and the monitor lists.
[[nodiscard]] std::vector<ShownSetting> settings_shown(const SessionConfig& config);

/// The help an option shows: the setting's, its unit, range and the links it applies to.
[[nodiscard]] std::string option_help(const SessionSetting& s);
/// Its default as the option shows it ("0.5", "nominal", "the link's").
[[nodiscard]] std::string option_default(const SessionSetting& s);

}  // namespace deflex::runtime
