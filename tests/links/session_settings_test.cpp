// The online settings table (runtime/session_settings.hpp): every setting's range, held at both ends,
// its link, the unit conversion of its option, and the defaults controller-setup shares. The command
// line and Python build their sessions through it; python/tests/test_runtime.py drives both front
// ends with the same bad values and compares their words.
#include <cmath>
#include <set>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "deflex/runtime/session_settings.hpp"
#include "deflex/text/errors.hpp"
#include "support/error_of.hpp"

namespace deflex::runtime {
namespace {

using test::error_of;

// The first link a setting applies to.
std::string link_for(const SessionSetting& s) {
  for (const LinkKindInfo& k : link_kinds()) {
    if ((s.links & link_bit(k.kind)) != 0) return k.name;
  }
  return "";
}

// A session of `link` given this one setting (and what it needs: a sensor over RDT with its tare, real
// time): the library's words, or "" when it is accepted.
std::string refusal(const std::string& link, const SessionSetting& s, const SettingValue& v) {
  std::vector<GivenSetting> given{{&s, v}};
  const std::string key(s.key);
  if (key.rfind("rdt_", 0) == 0 || key.rfind("tare", 0) == 0) {
    given.push_back({find_session_setting("force_source"), std::string("rdt:192.168.1.1")});
    if (key != "tare") given.push_back({find_session_setting("tare"), true});
  }
  if (key.rfind("rt_", 0) == 0) given.push_back({find_session_setting("realtime"), true});
  try {
    (void)make_session_config(link, "online", given);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(SessionSettings, EveryKeyAndOptionIsNamedOnceWithItsUnit) {
  std::set<std::string> names;
  for (const SessionSetting& s : session_settings()) {
    EXPECT_TRUE(names.insert(std::string(s.key)).second) << s.key;
    EXPECT_TRUE(names.insert(std::string(s.option)).second) << s.option;
    EXPECT_EQ(s.option.substr(0, 2), "--") << s.option;
    EXPECT_FALSE(s.help.empty()) << s.key;
    EXPECT_EQ(find_session_setting(s.key), &s);
    EXPECT_EQ(find_session_setting(s.option), &s);
    if (s.type == SettingType::kReal && !s.unit.empty()) {
      // A key in SI names its unit at its end (period_s, max_tcp_correction_m, tare_max_std_N).
      const std::string key(s.key);
      std::string tail(s.unit);
      for (char& c : tail) c = c == '/' ? '_' : c;
      if (tail == "Hz") tail = "hz";
      EXPECT_TRUE(key.size() > tail.size() && key.compare(key.size() - tail.size(), tail.size(), tail) == 0)
          << key << " in " << s.unit;
    }
  }
}

TEST(SessionSettings, EveryNumberIsHeldAtBothEndsOfItsRangeNamingTheSetting) {
  for (const SessionSetting& s : session_settings()) {
    if (s.type != SettingType::kReal && s.type != SettingType::kInteger) continue;
    SCOPED_TRACE(std::string(s.key));
    const double step = s.type == SettingType::kInteger ? 1.0 : std::max(1e-9, 1e-6 * std::abs(s.max));
    if (s.min_open) {
      EXPECT_NE(refusal(link_for(s), s, s.min), "") << "the minimum is excluded";
    } else {
      EXPECT_EQ(refusal(link_for(s), s, s.min), "");
    }
    if (s.max_open) {
      EXPECT_NE(refusal(link_for(s), s, s.max), "") << "the maximum is excluded";
      EXPECT_EQ(refusal(link_for(s), s, s.max - step), "");
    } else {
      EXPECT_EQ(refusal(link_for(s), s, s.max), "");
    }
    const std::string above = refusal(link_for(s), s, s.max + step);
    EXPECT_NE(above.find(setting_name(s)), std::string::npos) << above;
    EXPECT_NE(above.find("is outside"), std::string::npos) << above;
    EXPECT_NE(refusal(link_for(s), s, s.min - step), "");
    EXPECT_NE(refusal(link_for(s), s, std::nan("")).find("not a finite number"), std::string::npos);
    EXPECT_NE(refusal(link_for(s), s, std::string("5")).find("expects a number"), std::string::npos);
    if (s.type == SettingType::kInteger) {
      EXPECT_NE(refusal(link_for(s), s, s.max - 0.5).find("not a whole number"), std::string::npos);
    }
  }
}

TEST(SessionSettings, ASettingOfAnotherLinkIsRefusedNamingTheLinksItAppliesTo) {
  int checked = 0;
  for (const SessionSetting& s : session_settings()) {
    if (s.links == kEveryLink) continue;
    for (const LinkKindInfo& k : link_kinds()) {
      if ((s.links & link_bit(k.kind)) != 0) continue;
      const SettingValue v = s.type == SettingType::kFlag   ? SettingValue(true)
                             : s.type == SettingType::kText ? SettingValue(std::string("x"))
                                                            : SettingValue(s.max);
      const std::string words = refusal(k.name, s, v);
      EXPECT_NE(words.find(fmt::format("applies to --link {}", link_for(s))), std::string::npos) << words;
      EXPECT_NE(words.find(fmt::format("not {}", k.name)), std::string::npos) << words;
      ++checked;
    }
  }
  EXPECT_GT(checked, 40);
}

// The bounds a user meets first, written out here rather than read from the table.
TEST(SessionSettings, TheBoundsAreTheDocumentedOnesInTheOptionsUnits) {
  const SessionSetting& joint = *find_session_setting("--max-joint-correction-deg");
  // 10 deg is the largest bound: 10.001 deg is refused, 10 deg taken, both as the option gives them.
  EXPECT_EQ(refusal("egm-joint", joint, option_value(joint, "10")), "");
  const std::string words = refusal("egm-joint", joint, option_value(joint, "10.001"));
  EXPECT_NE(words.find("setting max_joint_correction_rad (--max-joint-correction-deg): 0.17455 rad (10.001 deg) is "
                       "outside 0 rad (0 deg) < value <= 0.174533 rad (10 deg)"),
            std::string::npos)
      << words;
  // The option's unit: 0.5 deg is pi/360 rad, 48 ms is 0.048 s, 5 mm is 0.005 m.
  EXPECT_DOUBLE_EQ(std::get<double>(option_value(joint, "0.5")), std::acos(-1.0) / 360.0);
  EXPECT_DOUBLE_EQ(std::get<double>(option_value(*find_session_setting("--period-ms"), "48")), 0.048);
  EXPECT_DOUBLE_EQ(std::get<double>(option_value(*find_session_setting("--max-tcp-correction-mm"), "5")), 0.005);
  EXPECT_NE(error_of([&] { (void)option_value(joint, "half"); }).find("'half' is not a number"), std::string::npos);
  // What controller-setup writes on the controller's side is what a session does by default.
  const SessionConfig d = default_session_config(LinkKind::kEgmJoint);
  EXPECT_DOUBLE_EQ(d.online.max_joint_correction_rad,
                   kSessionOptionDefaults.max_joint_correction_deg * std::acos(-1.0) / 180.0);
  EXPECT_DOUBLE_EQ(d.online.max_tcp_correction_m, kSessionOptionDefaults.max_tcp_correction_mm / 1000.0);
  EXPECT_DOUBLE_EQ(d.egm_joint.stream.ramp_in_s, kSessionOptionDefaults.ramp_in_s);
  EXPECT_EQ(d.rsi.controller_timeout, kSessionOptionDefaults.rsi_timeout);
  EXPECT_DOUBLE_EQ(default_session_config(LinkKind::kEgmPath).online.period_s, 0.048);
}

TEST(SessionSettings, SettingsThatOnlyWorkTogetherAreRefusedNamingTheMissingOne) {
  const auto words = [](const std::string& link, std::vector<GivenSetting> given) {
    return error_of([&] { (void)make_session_config(link, "online", given); });
  };
  const SessionSetting* period = find_session_setting("period_s");
  EXPECT_NE(words("simple-message", {{period, 0.004}}).find("at least 20 ms (got 4 ms)"), std::string::npos);
  EXPECT_NE(words("egm-joint", {{find_session_setting("rt_cpu"), 1.0}})
                .find("setting rt_cpu (--rt-cpu): applies with realtime (--realtime)"),
            std::string::npos);
  EXPECT_NE(words("egm-joint", {{find_session_setting("force_source"), std::string("csv:f.csv")},
                                {find_session_setting("tare"), true}})
                .find("setting tare (--tare): applies to the force source rdt:HOST[:PORT]"),
            std::string::npos);
  EXPECT_NE(words("egm-joint", {{find_session_setting("tare_window_s"), 1.0}}).find("applies with tare (--tare)"),
            std::string::npos);
  EXPECT_NE(words("egm-joint", {{find_session_setting("jacobian_at"), std::string("sideways")}})
                .find("setting jacobian_at (--jacobian-at): 'sideways' is not nominal, planned or feedback"),
            std::string::npos);
  // One value for every streaming link's blend; the strategy and the link by name.
  const SessionConfig c = make_session_config("fanuc-j519", "predictive",
                                              std::vector<GivenSetting>{{find_session_setting("ramp_in_s"), 2.5}});
  EXPECT_EQ(c.link, LinkKind::kFanucJ519);
  EXPECT_EQ(c.strategy, StrategyKind::kPredictive);
  EXPECT_DOUBLE_EQ(c.fanuc_j519.stream.ramp_in_s, 2.5);
  EXPECT_DOUBLE_EQ(c.simple_message.stream.ramp_in_s, 2.5);
  EXPECT_NE(words("fanuc", {}).find("'fanuc' is not one of"), std::string::npos);
}

// What the cycle log records and the monitor lists: the link's settings alone, each in its option's
// unit (the values below converted by hand), an unset one as its default's words.
TEST(SessionSettings, ASessionsSettingsAreShownInTheOptionsUnitsForItsLinkAlone) {
  const SessionConfig c =
      make_session_config("rsi", "online",
                          std::vector<GivenSetting>{{find_session_setting("max_joint_correction_rad"), 0.01},
                                                    {find_session_setting("period_s"), 0.012},
                                                    {find_session_setting("rsi_sentype"), std::string("ImFree")}});
  const std::vector<ShownSetting> shown = settings_shown(c);
  const auto value = [&shown](const std::string& option) -> std::string {
    for (const ShownSetting& s : shown) {
      if (s.option == option) return s.value;
    }
    return "(not shown)";
  };
  EXPECT_EQ(value("--max-joint-correction-deg"), "0.572958");  // 0.01 rad x 180/pi
  EXPECT_EQ(value("--period-ms"), "12");
  EXPECT_EQ(value("--rsi-sentype"), "ImFree");
  EXPECT_EQ(value("--rt-cpu"), "not pinned");
  EXPECT_EQ(value("--realtime"), "off");
  EXPECT_EQ(value("--egm-port"), "(not shown)");  // EGM's
  EXPECT_EQ(value("--fanuc-limits"), "(not shown)");
  // Every row that applies to RSI, once, in the table's order.
  std::size_t rows = 0;
  for (const SessionSetting& s : session_settings()) {
    if ((s.links & link_bit(LinkKind::kRsi)) == 0) continue;
    ASSERT_LT(rows, shown.size());
    EXPECT_EQ(shown[rows].option, s.option);
    ++rows;
  }
  EXPECT_EQ(rows, shown.size());
}

}  // namespace
}  // namespace deflex::runtime
