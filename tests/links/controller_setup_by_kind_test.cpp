// The controller setup chosen by link kind (runtime/controller_setup.hpp), as `deflex controller-setup`
// runs it: each kind's files with the link's own period where none is given (EGM's 4 ms sensor cycle,
// egm-path's 48 ms EGMActMove sample rate, RSI's #IPO_FAST 4 ms, FANUC's 8 ms interval), the robot read
// only where the link needs it, and settings that do not apply to a kind refused naming the option.
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "deflex/robotfile/robot_io.hpp"
#include "deflex/rsi/rsi_controller_setup.hpp"
#include "deflex/runtime/controller_setup.hpp"
#include "deflex/text/errors.hpp"
#include "support/error_of.hpp"

namespace deflex {
namespace {

using runtime::ControllerSetupSettings;

const ControllerFile& file_ending(const std::vector<ControllerFile>& files, const std::string& suffix) {
  for (const auto& f : files) {
    if (f.name.size() >= suffix.size() && f.name.compare(f.name.size() - suffix.size(), suffix.size(), suffix) == 0) {
      return f;
    }
  }
  throw std::runtime_error("no file ending " + suffix);
}

ControllerSetupSettings settings_for(const std::string& link) {
  ControllerSetupSettings s;
  s.link = link;
  s.sensor_ip = "10.0.0.2";
  return s;
}

/// A loader that counts its calls and hands out the built-in robot.
struct CountingLoader {
  int calls = 0;
  std::string last_path = "(none)";
  runtime::RobotLoader loader() {
    return [this](const std::string& path) {
      ++calls;
      last_path = path;
      return builtin_irb6700();
    };
  }
};

TEST(ControllerSetupByKind, EgmJointTakesTheSensorCycleAndReadsTheRobotOnce) {
  CountingLoader robot;
  ControllerSetupSettings s = settings_for("egm-joint");
  s.robot = "cell.yaml";
  const auto files = runtime::controller_setup_files(s, robot.loader());
  EXPECT_EQ(robot.calls, 1);
  EXPECT_EQ(robot.last_path, "cell.yaml");
  const std::string& mod = file_ending(files, ".mod").text;
  EXPECT_NE(mod.find("\\SampleRate:=4\\MaxPosDeviation"), std::string::npos) << mod;
  EXPECT_NE(mod.find("EGMActJoint"), std::string::npos);
  EXPECT_EQ(mod.find("EGMActMove"), std::string::npos);
}

TEST(ControllerSetupByKind, EgmPathTakesEgmActMovesSampleRateAndRefusesAProgram) {
  const std::string mod = file_ending(runtime::controller_setup_files(settings_for("egm-path")), ".mod").text;
  EXPECT_NE(mod.find("EGMActMove"), std::string::npos);
  EXPECT_NE(mod.find("\\SampleRate:=48;"), std::string::npos) << mod;
  ControllerSetupSettings s = settings_for("egm-path");
  s.program = "program.csv";
  EXPECT_NE(test::error_of([&] { (void)runtime::controller_setup_files(s); }).find("option --program"),
            std::string::npos);
}

TEST(ControllerSetupByKind, RsiIsTheRsiSetupWithDeflexsDefaultsAndNeedsNoRobot) {
  CountingLoader robot;
  const auto files = runtime::controller_setup_files(settings_for("rsi"), robot.loader());
  EXPECT_EQ(robot.calls, 0);
  RsiSetupOptions r;  // the documented defaults: port 49152, ImFree, 4 ms, 0.5 deg
  r.sensor_ip = "10.0.0.2";
  const auto expected = rsi_controller_setup(r);
  ASSERT_EQ(files.size(), expected.size());
  for (std::size_t i = 0; i < files.size(); ++i) {
    EXPECT_EQ(files[i].name, expected[i].name);
    EXPECT_EQ(files[i].text, expected[i].text);
  }
  EXPECT_NE(file_ending(files, ".src").text.find("#IPO_FAST"), std::string::npos);
  ControllerSetupSettings s = settings_for("rsi");
  s.robot = "cell.yaml";
  EXPECT_NE(test::error_of([&] { (void)runtime::controller_setup_files(s, robot.loader()); }).find("--robot"),
            std::string::npos);
  EXPECT_EQ(robot.calls, 0);
}

TEST(ControllerSetupByKind, FanucTakesItsEightMillisecondIntervalWithoutReadingTheRobot) {
  CountingLoader robot;
  const auto files = runtime::controller_setup_files(settings_for("fanuc-j519"), robot.loader());
  EXPECT_EQ(robot.calls, 0);
  ASSERT_EQ(files.size(), 2u);
  EXPECT_NE(files[1].text.find("$STMO.$COM_INT        = 8 "), std::string::npos) << files[1].text;
}

TEST(ControllerSetupByKind, AKindWithoutAControllerSetupIsRefusedNamingTheLink) {
  for (const std::string link : {"simple-message", "fanuc", ""}) {
    const std::string error = test::error_of([&] { (void)runtime::controller_setup_files(settings_for(link)); });
    EXPECT_NE(error.find("option --link: '" + link + "'"), std::string::npos) << error;
  }
  EXPECT_THROW((void)runtime::controller_setup_files(settings_for("simple-message")), InputError);
}

// The settings controller-setup shares with deflex online are checked by the settings table, so the
// controller's side is never written for a value the session would refuse, and the words are online's.
TEST(ControllerSetupByKind, SharedSettingsAreCheckedByTheSessionsTableWithItsWords) {
  ControllerSetupSettings s = settings_for("rsi");
  s.max_joint_deg = 57.0;
  EXPECT_EQ(test::error_of([&] { (void)runtime::controller_setup_files(s); }),
            "setting max_joint_correction_rad (--max-joint-correction-deg): 0.994838 rad (57 deg) is outside 0 rad (0 "
            "deg) < value <= 0.174533 rad (10 deg): a compliance correction is a fraction of a degree");
  s = settings_for("egm-joint");
  s.period_ms = 0.2;  // the table's cycles start at 0.5 ms
  EXPECT_NE(test::error_of([&] { (void)runtime::controller_setup_files(s); }).find("setting period_s (--period-ms)"),
            std::string::npos);
  s = settings_for("ur-rtde");
  s.ur_gain = 5.0;  // servoj's gain is 100..2000
  EXPECT_NE(test::error_of([&] {
              (void)runtime::controller_setup_files(s);
            }).find("setting ur_gain (--ur-gain): 5 is outside 100"),
            std::string::npos);
  s = settings_for("egm-joint");
  s.max_tcp_mm = std::numeric_limits<double>::quiet_NaN();  // NaN is never a bound
  EXPECT_NE(test::error_of([&] {
              (void)runtime::controller_setup_files(s);
            }).find("setting max_tcp_correction_m (--max-tcp-correction-mm)"),
            std::string::npos);
  // Another link's setting is not this link's business: an RSI value is not checked for egm-joint.
  s = settings_for("egm-joint");
  s.sentype = "9lives";
  EXPECT_NO_THROW((void)runtime::controller_setup_files(s));
}

}  // namespace
}  // namespace deflex
