// The case file: the built-in paper case loads, errors name the file, line and field, and the
// effect switches switch off what they say.
#include "deflex/study/case_config.hpp"

#include <gtest/gtest.h>

#include "deflex/model/errors.hpp"

namespace deflex::study {
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
  EXPECT_EQ(c.circle.points, 81);
  EXPECT_DOUBLE_EQ(c.online.lowpass_hz, 25.0);  // the paper's filter
  // The online setups reach the controller through EGM position guidance; offline runs a program.
  EXPECT_EQ(c.setups[0].link, LinkKind::kProgram);
  EXPECT_EQ(c.setups[1].link, LinkKind::kEgmJoint);
  EXPECT_DOUBLE_EQ(c.cell.controller.egm_period_s, 0.004);
  EXPECT_DOUBLE_EQ(c.cell.controller.egm_dead_time_s, 0.048);
  // r = L cos(phi), pivot L sin(phi) below the centre.
  EXPECT_NEAR(c.radius_m(), c.cell.ldbb.bar_length_m * std::cos(c.cell.ldbb.inclination_rad), 1e-15);
  EXPECT_NEAR((c.circle.center_m - c.pivot_m()).norm(),
              c.cell.ldbb.bar_length_m * std::sin(c.cell.ldbb.inclination_rad), 1e-15);
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
  const std::string bad_link = error_of(paper_with("strategy: hybrid, link: egm-joint", "strategy: hybrid, link: egm-path"));
  EXPECT_NE(bad_link.find("hybrid strategy streams the offline program"), std::string::npos) << bad_link;
  const std::string offline_link = error_of(paper_with("strategy: offline, link: program", "strategy: offline, link: egm-joint"));
  EXPECT_NE(offline_link.find("setups[1].link"), std::string::npos) << offline_link;
  const std::string frame = error_of(paper_with("path_corr_frame: tool", "path_corr_frame: world"));
  EXPECT_NE(frame.find("controller.path_corr_frame"), std::string::npos) << frame;
  const std::string latency = error_of(paper_with("network_latency_ms: 0.2", "network_latency_ms: 3"));
  EXPECT_NE(latency.find("half a servo period"), std::string::npos) << latency;
  EXPECT_THROW((void)load_case("/nonexistent/case.yaml"), ModelError);
}

TEST(CaseConfig, EffectSwitchesTurnOffTheirEffect) {
  const CaseConfig c = paper_case();
  EXPECT_EQ(without_effect(c, Effect::kTrackerNoise).cell.tracker.noise_m, 0.0);
  EXPECT_EQ(without_effect(c, Effect::kLdbbForceError).cell.ldbb.force_bias, 0.0);
  EXPECT_EQ(without_effect(c, Effect::kSensorCompliance).cell.sensor.lateral_compliance_m_per_n, 0.0);
  const CaseConfig lat = without_effect(c, Effect::kLatency);
  EXPECT_EQ(lat.cell.controller.egm_dead_time_s, 0.0);
  EXPECT_EQ(lat.cell.controller.path_corr_dead_time_s, 0.0);
  const CaseConfig m = model_consistent(c, true);
  EXPECT_TRUE(m.exact_model);
  EXPECT_GT(m.cell.tracker.noise_m, 0.0);
  EXPECT_EQ(m.cell.robot.forearm_ei_nm2, 0.0);
  EXPECT_EQ(m.cell.robot.coupling_23, 0.0);
  for (double b : m.cell.robot.lost_motion_rad) EXPECT_EQ(b, 0.0);
  EXPECT_EQ(m.cell.sensor.noise_n, 0.0);
}

TEST(CaseConfig, NewEffectsAreSizedInThePaperCaseAndSwitchOff) {
  const CaseConfig c = paper_case();
  EXPECT_GT(c.cell.drift.offset_m, 0.0);
  EXPECT_GT(c.cell.drift.wander_m, 0.0);
  EXPECT_GT(c.cell.sensor.sensitivity_error, 0.0);
  EXPECT_GT(std::abs(c.cell.sensor.misalignment_rad), 0.0);
  ASSERT_EQ(c.cell.robot.hardening_softening.size(), 6u);
  const CaseConfig d = without_effect(c, Effect::kPathDrift);
  EXPECT_EQ(d.cell.drift.offset_m + d.cell.drift.rotation_rad + d.cell.drift.wander_m, 0.0);
  const CaseConfig h = without_effect(c, Effect::kGearHardening);
  for (double v : h.cell.robot.hardening_softening) EXPECT_EQ(v, 0.0);
  const CaseConfig s = without_effect(c, Effect::kSensorCalibration);
  EXPECT_EQ(s.cell.sensor.sensitivity_error, 0.0);
  EXPECT_EQ(s.cell.sensor.misalignment_rad, 0.0);
  // The model-consistent cell has none of them.
  const CaseConfig m = model_consistent(c, true);
  EXPECT_EQ(m.cell.drift.offset_m + m.cell.drift.rotation_rad + m.cell.drift.wander_m, 0.0);
  for (double v : m.cell.robot.hardening_softening) EXPECT_EQ(v, 0.0);
  EXPECT_EQ(m.cell.sensor.sensitivity_error, 0.0);
  EXPECT_EQ(m.cell.sensor.misalignment_rad, 0.0);
}



}  // namespace
}  // namespace deflex::study
