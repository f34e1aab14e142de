// The case file: the built-in paper case loads, errors name the file, line and field, and the
// effect switches switch off what they say.
#include "deflex/study/case_config.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "deflex/text/errors.hpp"

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
  const std::string bad_link =
      error_of(paper_with("strategy: hybrid, link: egm-joint", "strategy: hybrid, link: egm-path"));
  EXPECT_NE(bad_link.find("hybrid strategy streams the offline program"), std::string::npos) << bad_link;
  const std::string offline_link =
      error_of(paper_with("strategy: offline, link: program", "strategy: offline, link: egm-joint"));
  EXPECT_NE(offline_link.find("setups[1].link"), std::string::npos) << offline_link;
  const std::string frame = error_of(paper_with("path_corr_frame: tool", "path_corr_frame: world"));
  EXPECT_NE(frame.find("controller.path_corr_frame"), std::string::npos) << frame;
  const std::string latency = error_of(paper_with("network_latency_ms: 0.2", "network_latency_ms: 3"));
  EXPECT_NE(latency.find("half a servo period"), std::string::npos) << latency;
  EXPECT_THROW((void)load_case("/nonexistent/case.yaml"), ModelError);
}

TEST(CaseConfig, ASetupMayNameEveryLinkOfTheRuntime) {
  // The paper's case runs one setup over each further controller link, at its highest load only.
  const CaseConfig c = paper_case();
  std::vector<LinkKind> links;
  for (const auto& s : c.setups) {
    links.push_back(s.link);
    if (s.link == LinkKind::kRsi || s.link == LinkKind::kFanucJ519 || s.link == LinkKind::kMotoros2Rt ||
        s.link == LinkKind::kUrRtde) {
      EXPECT_EQ(s.strategy, Strategy::kOnline) << s.name;
      EXPECT_TRUE(s.sensor_mounted) << s.name;
      EXPECT_EQ(s.loads_n, (std::vector<double>{650})) << s.name;
      EXPECT_TRUE(s.paper_uc_mm.empty()) << s.name;
    }
  }
  for (LinkKind k : kAllLinks) {
    EXPECT_NE(std::find(links.begin(), links.end(), k), links.end()) << to_string(k);
  }
  // Each name reads back as its link.
  for (const char* name : {"rsi", "fanuc-j519", "motoros2-rt", "ur-rtde"}) {
    const CaseConfig one =
        load_case_text(paper_with("name: online-100ms, strategy: online, link: simple-message",
                                  std::string("name: online-100ms, strategy: online, link: ") + name),
                       "case.yaml");
    EXPECT_STREQ(to_string(one.setups[5].link), name);
  }
}

TEST(CaseConfig, ASetupsSeedsAreOneToAThousandOrEverySeed) {
  // The paper's case runs its further links on the first seed only, every other setup on every seed.
  for (const auto& s : paper_case().setups) {
    const bool further_link = s.link == LinkKind::kRsi || s.link == LinkKind::kFanucJ519 ||
                              s.link == LinkKind::kMotoros2Rt || s.link == LinkKind::kUrRtde;
    EXPECT_EQ(s.seeds, further_link ? 1 : 0) << s.name;
  }
  const std::string from = "link: ur-rtde, sensor: true, loads_N: [650], seeds: 1}";
  EXPECT_EQ(load_case_text(paper_with(from, "link: ur-rtde, sensor: true, loads_N: [650], seeds: 3}"), "case.yaml")
                .setups.back()
                .seeds,
            3);
  const std::string zero = error_of(paper_with(from, "link: ur-rtde, sensor: true, loads_N: [650], seeds: 0}"));
  EXPECT_NE(zero.find("setups[10].seeds"), std::string::npos) << zero;
  EXPECT_NE(zero.find("1..1000"), std::string::npos) << zero;
}

TEST(CaseConfig, AnUnknownOrRefusedLinkNamesTheSetupAndTheLinks) {
  const std::string unknown = error_of(paper_with("name: online-ur, strategy: online, link: ur-rtde",
                                                  "name: online-ur, strategy: online, link: ur-rtdx"));
  EXPECT_NE(unknown.find("setups[10].link"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("setup 'online-ur'"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("unknown link 'ur-rtdx'"), std::string::npos) << unknown;
  for (const char* name :
       {"program", "egm-joint", "egm-path", "rsi", "simple-message", "fanuc-j519", "motoros2-rt", "ur-rtde"}) {
    EXPECT_NE(unknown.find(name), std::string::npos) << name << ": " << unknown;
  }
  // The hybrid strategy streams the offline program: not over RSI, where the KRL program runs itself.
  const std::string hybrid = error_of(
      paper_with("name: hybrid, strategy: hybrid, link: egm-joint", "name: hybrid, strategy: hybrid, link: rsi"));
  EXPECT_NE(hybrid.find("setup 'hybrid'"), std::string::npos) << hybrid;
  EXPECT_NE(hybrid.find("hybrid strategy streams the offline program"), std::string::npos) << hybrid;
  EXPECT_NE(hybrid.find("fanuc-j519"), std::string::npos) << hybrid;
  // Over FANUC the hybrid strategy is a setup like any other.
  EXPECT_EQ(error_of(paper_with("name: hybrid, strategy: hybrid, link: egm-joint",
                                "name: hybrid, strategy: hybrid, link: fanuc-j519")),
            "");
}

TEST(CaseConfig, SettingsTheRuntimeRefusesForALinkAreRefusedNamingTheSetup) {
  // deflex online bounds a joint's correction rate at 30 deg/s (0.52 rad/s); the case's own check takes
  // any positive rate, the runtime's refuses 1 rad/s for the first setup that runs over a link.
  const std::string fast = error_of(paper_with("max_rate_mrad_s: 50", "max_rate_mrad_s: 1000"));
  EXPECT_NE(fast.find("setups[2]"), std::string::npos) << fast;
  EXPECT_NE(fast.find("setup 'online'"), std::string::npos) << fast;
  EXPECT_NE(fast.find("--link egm-joint"), std::string::npos) << fast;
  EXPECT_NE(fast.find("max_correction_rate_rad_s"), std::string::npos) << fast;
}

TEST(CaseConfig, TheBudgetsLoadIndexIsCheckedOnTheSetupsTheBudgetRuns) {
  // A setup the budget does not run may have one load; the budget's own setups must have the index.
  EXPECT_EQ(error_of(paper_case_yaml()), "");  // the links' setups have one load, the index is 2
  const std::string short_online = error_of(paper_with(
      "name: online, strategy: online, link: egm-joint, sensor: true, loads_N: [150, 400, 650],\n     paper_uc_mm: "
      "[0.23, 0.65, 1.10],\n     paper_c_mm: [[0.07, 0.07, 0.08], [0.16, 0.15, 0.15], [0.25, 0.19, 0.21]]",
      "name: online, strategy: online, link: egm-joint, sensor: true, loads_N: [650]"));
  EXPECT_NE(short_online.find("out of range for setup 'online'"), std::string::npos) << short_online;
}

TEST(CaseConfig, EffectSwitchesTurnOffTheirEffect) {
  const CaseConfig c = paper_case();
  EXPECT_EQ(without_effect(c, Effect::kTrackerNoise).cell.tracker.noise_m, 0.0);
  EXPECT_EQ(without_effect(c, Effect::kLdbbForceError).cell.ldbb.pivot_error_m.norm(), 0.0);
  EXPECT_EQ(without_effect(c, Effect::kLdbbSealFriction).cell.ldbb.seal_friction, 0.0);
  EXPECT_GT(c.cell.ldbb.seal_friction, 0.0);
  EXPECT_EQ(without_effect(c, Effect::kSensorMoment).cell.sensor.moment_crosstalk, 0.0);
  EXPECT_EQ(without_effect(c, Effect::kTrackerClock).cell.tracker.trigger_jitter_s, 0.0);
  EXPECT_EQ(without_effect(c, Effect::kTrackerClock).cell.tracker.clock_rate_error, 0.0);
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

TEST(CaseConfig, TheTwinsFurtherEffectsAreSizedCheckedAndSwitchOff) {
  const CaseConfig c = paper_case();
  const auto& r = c.cell.robot;
  EXPECT_GT(r.upper_arm_ei_nm2, 0.0);
  EXPECT_GT(r.base_tilt_compliance_rad_per_nm, 0.0);
  EXPECT_GT(r.speed_stiffening, 0.0);
  EXPECT_GT(r.direction_asymmetry, 0.0);
  EXPECT_GT(r.servo_following_s, 0.0);
  EXPECT_GT(r.servo_compliance_fraction, 0.0);
  EXPECT_GT(c.cell.sensor.zero_drift_n, 0.0);
  EXPECT_GT(c.cell.drift.load_offset_m, 0.0);
  EXPECT_GT(c.cell.ldbb.stick_slip, 0.0);
  EXPECT_GE(c.seeds, 2);
  // The units at the edge: mm, ms, %, nrad/Nm in the file; SI inside.
  EXPECT_NEAR(r.servo_following_s, 0.008, 1e-12);
  EXPECT_NEAR(r.base_tilt_compliance_rad_per_nm, 0.3e-9, 1e-18);
  EXPECT_NEAR(c.cell.ldbb.stick_slip_travel_m, 0.0005, 1e-12);
  EXPECT_NEAR(c.cell.drift.load_offset_m, 15e-6, 1e-12);
  // Each switch turns its own effect off and leaves the rest.
  EXPECT_EQ(without_effect(c, Effect::kLinkBending).cell.robot.upper_arm_ei_nm2, 0.0);
  EXPECT_EQ(without_effect(c, Effect::kBaseCompliance).cell.robot.base_tilt_compliance_rad_per_nm, 0.0);
  const CaseConfig m = without_effect(c, Effect::kMotionStiffness);
  EXPECT_EQ(m.cell.robot.speed_stiffening + m.cell.robot.direction_asymmetry, 0.0);
  EXPECT_GT(m.cell.robot.servo_following_s, 0.0);
  const CaseConfig sv = without_effect(c, Effect::kServo);
  EXPECT_EQ(sv.cell.robot.servo_following_s + sv.cell.robot.servo_compliance_fraction, 0.0);
  EXPECT_EQ(without_effect(c, Effect::kSensorDrift).cell.sensor.zero_drift_n, 0.0);
  EXPECT_EQ(without_effect(c, Effect::kThermalLoadDrift).cell.drift.load_offset_m, 0.0);
  EXPECT_GT(without_effect(c, Effect::kThermalLoadDrift).cell.drift.offset_m, 0.0);
  EXPECT_EQ(without_effect(c, Effect::kLdbbStickSlip).cell.ldbb.stick_slip, 0.0);
  for (Effect e : kAllEffects) {
    EXPECT_STRNE(to_string(e), "?");
    EXPECT_FALSE(effect_size(c, e).empty()) << to_string(e);
  }
  const CaseConfig mc = model_consistent(c, true);
  EXPECT_EQ(mc.cell.robot.upper_arm_ei_nm2 + mc.cell.robot.base_tilt_compliance_rad_per_nm, 0.0);
  EXPECT_EQ(mc.cell.robot.servo_compliance_fraction + mc.cell.robot.speed_stiffening, 0.0);
  EXPECT_EQ(mc.cell.sensor.zero_drift_n + mc.cell.drift.load_offset_m + mc.cell.ldbb.stick_slip, 0.0);
}

TEST(CaseConfig, OutOfRangeEffectSizesAndSeedsAreRefusedByName) {
  const std::string stiff = error_of(paper_with("speed_stiffening_pct: 5", "speed_stiffening_pct: 80"));
  EXPECT_NE(stiff.find("true_robot.speed_stiffening_pct"), std::string::npos) << stiff;
  EXPECT_NE(stiff.find("0..50 %"), std::string::npos) << stiff;
  const std::string follow = error_of(paper_with("servo_following_ms: 8", "servo_following_ms: 500"));
  EXPECT_NE(follow.find("servo_following_ms"), std::string::npos) << follow;
  const std::string tilt =
      error_of(paper_with("base_tilt_compliance_nrad_per_Nm: 0.3", "base_tilt_compliance_nrad_per_Nm: -1"));
  EXPECT_NE(tilt.find("base_tilt_compliance_nrad_per_Nm"), std::string::npos) << tilt;
  const std::string drift = error_of(paper_with("zero_drift_N_per_10min: 0.4", "zero_drift_N_per_10min: .nan"));
  EXPECT_NE(drift.find("zero_drift_N_per_10min"), std::string::npos) << drift;
  const std::string slip = error_of(paper_with("stick_slip_travel_mm: 0.5", "stick_slip_travel_mm: 0"));
  EXPECT_NE(slip.find("stick_slip_travel_mm"), std::string::npos) << slip;
  const std::string from = error_of(paper_with("  force_from: ldbb", "  force_from: tracker"));
  EXPECT_NE(from.find("calibration.force_from"), std::string::npos) << from;
  EXPECT_NE(from.find("ldbb or sensor"), std::string::npos) << from;
  // The keys of the tuned bar bias are gone, and a file that still has them is told what replaced them.
  const std::string bias = error_of(paper_with("  force_from: ldbb", "  force_from: ldbb\n  ldbb_force_bias_pct: -15"));
  EXPECT_NE(bias.find("calibration.ldbb_force_bias_pct"), std::string::npos) << bias;
  EXPECT_NE(bias.find("seal_friction_pct"), std::string::npos) << bias;
  const std::string old_bias =
      error_of(paper_with("  seal_friction_pct: 25", "  force_bias_pct: -15\n  seal_friction_pct: 25"));
  EXPECT_NE(old_bias.find("ldbb.force_bias_pct"), std::string::npos) << old_bias;
  const std::string seal = error_of(paper_with("  seal_friction_pct: 25", "  seal_friction_pct: 70"));
  EXPECT_NE(seal.find("ldbb.seal_friction_pct"), std::string::npos) << seal;
  const std::string moment = error_of(paper_with("  nominal_moment_Nm: 50", "  nominal_moment_Nm: 0"));
  EXPECT_NE(moment.find("sensor.nominal_moment_Nm"), std::string::npos) << moment;
  const std::string clock = error_of(paper_with("  clock_rate_ppm: 50", "  clock_rate_ppm: -5"));
  EXPECT_NE(clock.find("tracker.clock_rate_ppm"), std::string::npos) << clock;
  const std::string seeds = error_of(paper_with("seeds: 4", "seeds: 0"));
  EXPECT_NE(seeds.find("protocol.seeds"), std::string::npos) << seeds;
  const std::string old_budget = error_of(paper_with("  load_index: 2", "  load_index: 2\n  laps_each_way: 1"));
  EXPECT_NE(old_budget.find("laps_each_way"), std::string::npos) << old_budget;
}

TEST(CaseConfig, TheStiffnessBandIsReadPerJointAndRefusedByNameWhenMalformed) {
  const CaseConfig c = paper_case();
  ASSERT_EQ(c.cell.robot.stiffness_band_min_nm_per_rad.size(), 6U);
  EXPECT_DOUBLE_EQ(c.cell.robot.stiffness_band_min_nm_per_rad[0], 1.0e6);
  EXPECT_DOUBLE_EQ(c.cell.robot.stiffness_band_max_nm_per_rad[5], 1.0e6);
  const std::string min_line = "  stiffness_band_min_Nm_per_rad: [1.0e6, 1.0e6, 1.0e6, 2.0e5, 2.0e5, 2.0e5]\n";
  const std::string alone = error_of(paper_with(min_line, ""));
  EXPECT_NE(alone.find("true_robot.stiffness_band_max_Nm_per_rad"), std::string::npos) << alone;
  EXPECT_NE(alone.find("both"), std::string::npos) << alone;
  const std::string inverted =
      error_of(paper_with(min_line, "  stiffness_band_min_Nm_per_rad: [1.0e6, 1.0e6, 1.0e6, 2.0e5, 2.0e5, 2.0e6]\n"));
  EXPECT_NE(inverted.find("stiffness_band_max_Nm_per_rad"), std::string::npos) << inverted;
  const std::string short_list = error_of(paper_with(min_line, "  stiffness_band_min_Nm_per_rad: [1.0e6, 1.0e6]\n"));
  EXPECT_NE(short_list.find("stiffness_band_min_Nm_per_rad"), std::string::npos) << short_list;
  const std::string negative =
      error_of(paper_with(min_line, "  stiffness_band_min_Nm_per_rad: [1.0e6, 1.0e6, 1.0e6, 2.0e5, 2.0e5, -1]\n"));
  EXPECT_NE(negative.find("stiffness_band_min_Nm_per_rad"), std::string::npos) << negative;
}

}  // namespace
}  // namespace deflex::study
