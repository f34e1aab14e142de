// The case file: the built-in paper case loads, errors name the file, line and field, and the
// effect switches switch off what they say.
#include "deflex/cell/case_config.hpp"

#include <gtest/gtest.h>

#include "deflex/model/errors.hpp"

namespace deflex::cell {
namespace {

std::string paper_with(const std::string& from, const std::string& to) {
  std::string text = paper_case_yaml();
  const auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  text.replace(pos, from.size(), to);
  return text;
}

std::string error_of(const std::string& text) {
  try {
    (void)load_case_text(text, "case.yaml");
  } catch (const ModelError& e) {
    return e.what();
  }
  return "";
}

TEST(CaseConfig, PaperCaseHasTheProtocolOfThePaper) {
  const CaseConfig c = paper_case();
  ASSERT_GE(c.setups.size(), 2u);
  EXPECT_EQ(c.setups[0].name, "offline");
  EXPECT_FALSE(c.setups[0].sensor_mounted);
  EXPECT_EQ(c.setups[0].loads_n, (std::vector<double>{125, 375, 625}));
  EXPECT_EQ(c.setups[1].loads_n, (std::vector<double>{150, 400, 650}));
  EXPECT_TRUE(c.setups[1].sensor_mounted);
  EXPECT_EQ(c.laps_cw, 3);
  EXPECT_EQ(c.laps_ccw, 3);
  ASSERT_EQ(c.speeds_m_s.size(), 3u);
  EXPECT_DOUBLE_EQ(c.speeds_m_s[2], 0.05);
  EXPECT_EQ(c.controller.program_points, 81);
  EXPECT_DOUBLE_EQ(c.online.cycle_s, 0.1);
  // r = L cos(phi), pivot L sin(phi) below the centre.
  EXPECT_NEAR(c.radius_m(), c.ldbb.bar_length_m * std::cos(c.ldbb.inclination_rad), 1e-15);
  EXPECT_NEAR((c.circle.center_m - c.pivot_m()).norm(), c.ldbb.bar_length_m * std::sin(c.ldbb.inclination_rad), 1e-15);
}

TEST(CaseConfig, ErrorsNameTheFileLineAndField) {
  EXPECT_NE(error_of(paper_with("stiffness_scale:", "stifness_scale:")).find("stifness_scale"), std::string::npos);
  const std::string bad_speed = error_of(paper_with("speeds_mm_s: [10, 30, 50]", "speeds_mm_s: [10, -30, 50]"));
  EXPECT_NE(bad_speed.find("case.yaml:"), std::string::npos) << bad_speed;
  EXPECT_NE(bad_speed.find("must be positive"), std::string::npos) << bad_speed;
  const std::string bad_strategy = error_of(paper_with("strategy: hybrid", "strategy: telepathy"));
  EXPECT_NE(bad_strategy.find("telepathy"), std::string::npos);
  const std::string nan = error_of(paper_with("bar_length_mm: 150", "bar_length_mm: .nan"));
  EXPECT_NE(nan.find("ldbb.bar_length_mm"), std::string::npos) << nan;
  EXPECT_THROW((void)load_case("/nonexistent/case.yaml"), ModelError);
}

TEST(CaseConfig, EffectSwitchesTurnOffTheirEffect) {
  const CaseConfig c = paper_case();
  EXPECT_EQ(without_effect(c, Effect::kTrackerNoise).tracker.noise_m, 0.0);
  EXPECT_EQ(without_effect(c, Effect::kLdbbForceError).ldbb.force_bias, 0.0);
  EXPECT_EQ(without_effect(c, Effect::kSensorCompliance).sensor.lateral_compliance_m_per_n, 0.0);
  const CaseConfig m = model_consistent(c, true);
  EXPECT_TRUE(m.exact_model);
  EXPECT_GT(m.tracker.noise_m, 0.0);
  EXPECT_EQ(m.robot.forearm_ei_nm2, 0.0);
  EXPECT_EQ(m.robot.coupling_23, 0.0);
  for (double b : m.robot.lost_motion_rad) EXPECT_EQ(b, 0.0);
  EXPECT_EQ(m.sensor.noise_n, 0.0);
}

}  // namespace
}  // namespace deflex::cell
