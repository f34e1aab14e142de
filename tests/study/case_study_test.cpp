// Short cases of the protocol on the simulated cell (one speed, one lap): the tracker's noise
// statistics, the uncompensated deviation growing with the load, the model-consistent cell
// compensated down to the tracker's noise floor through every kind of link, the online strategies'
// lag at speed and the predictive strategy removing it, reproducibility from the seed, and the
// cell's independence from the strategies (it includes none of their code).
#include "deflex/study/case_study.hpp"

#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "deflex/cell/force_sensor.hpp"
#include "deflex/study/detail/simulated_run.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>
#include "deflex/evaluate/path_metrics.hpp"

namespace deflex::study {
namespace {

CaseConfig short_case(CaseConfig c) {
  c.laps_cw = 1;
  c.laps_ccw = 0;
  c.speeds_m_s = {0.05};
  c.sweep_speeds_m_s.clear();
  c.cell.ldbb.settle_s = 1.0;
  c.setups.resize(2);  // offline and online
  c.setups[0].loads_n = {150.0, 650.0};
  c.setups[1].loads_n = {150.0, 650.0};
  c.setups[0].paper_uc_mm.clear();
  c.setups[0].paper_c_mm.clear();
  c.setups[1].paper_uc_mm.clear();
  c.setups[1].paper_c_mm.clear();
  c.budget.load_index = 0;
  c.seeds = 1;
  return c;
}

RunSpec spec(RunKind kind, Strategy s, double load, std::uint64_t seed, LinkKind link = LinkKind::kProgram) {
  RunSpec r;
  r.kind = kind;
  r.strategy = s;
  r.link = link;
  r.load_n = load;
  r.speed_m_s = 0.05;
  r.laps_cw = 1;
  r.laps_ccw = 0;
  r.seed = seed;
  return r;
}

TEST(SensorSheet, TheBiasComesFromTheUsersTareNotFromTheSensor) {
  // The sheet holds no bias; the user tares with the arm still and the payload's weight predicted
  // from the sheet's mass. With no crosstalk or sheet errors but the mass, the tare's offset is the
  // true bias plus the weight the sheet gets wrong, as the sensor reads it at the tare pose: tool
  // down, sensor z along base -z, so (m_true - m_sheet) g on z.
  CaseConfig c = paper_case();
  cell::SensorConfig& s = c.cell.sensor;
  s.crosstalk = 0.0;
  s.crosstalk_calibration_residual = 0.0;
  s.sensitivity_error = 0.0;
  s.misalignment_rad = 0.0;
  s.moment_crosstalk = 0.0;
  s.zero_drift_n = 0.0;
  s.bias_n = Vector3(3.0, -2.0, 4.0);
  s.gravity_mass_error = 0.02;
  const SetupCell cell = build_setup_cell(c, true);
  cell::ForceSensorDaq sensor(s, c.cell.tool, 7, 8);
  const deflex::SensorConfig sheet = sensor_config_from_sheet(c, sensor.calibration());
  EXPECT_TRUE(sheet.bias_sensor.isZero());
  const JointVector& q = cell.nominal_path.q.front();
  const deflex::SensorConfig tared = tare_sensor(sheet, sensor, *cell.robot, q, tare_limit_n(s));
  const double weight_error_n = (c.cell.tool.ee_mass_kg - sheet.payload_mass_kg) * cell::kGravity;
  const Vector3 expected = s.bias_n + Vector3(0.0, 0.0, weight_error_n);
  // Noise 0.5 N over 500 samples: 0.02 N; the true flange is within a milliradian of the nominal.
  EXPECT_NEAR((tared.bias_sensor.head<3>() - expected).norm(), 0.0, 0.12)
      << tared.bias_sensor.head<3>().transpose() << " against " << expected.transpose();
  EXPECT_GT(std::abs(weight_error_n), 1.0);
}

TEST(SimulatedRun, TrackerNoiseHasTheConfiguredSigma) {
  CaseConfig c = short_case(paper_case());
  c.cell.tracker.noise_m = 8e-6;
  CaseConfig quiet = c;
  quiet.cell.tracker.noise_m = 0.0;
  const SetupCell noisy_cell = build_setup_cell(c, false);
  const SetupCell quiet_cell = build_setup_cell(quiet, false);
  const RunOutput a = simulate_run(c, noisy_cell, spec(RunKind::kUnloaded, Strategy::kOffline, 0.0, 3));
  const RunOutput b = simulate_run(quiet, quiet_cell, spec(RunKind::kUnloaded, Strategy::kOffline, 0.0, 3));
  ASSERT_EQ(a.trace.size(), b.trace.size());
  // 1 kHz for one lap at 50 mm/s: the program runs along the chords between the 81 points.
  const double lap_m = 80.0 * 2.0 * c.radius_m() * std::sin(kPi / 80.0);
  EXPECT_NEAR(static_cast<double>(a.trace.size()), lap_m / 0.05 * 1000.0, 2.0);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero(), sq = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < a.trace.size(); ++i) {
    const Vector3 d = a.trace[i].p_m - b.trace[i].p_m;
    sum += d;
    sq += d.cwiseProduct(d);
  }
  const double n = static_cast<double>(a.trace.size());
  for (int k = 0; k < 3; ++k) {
    const double mean = sum[k] / n;
    const double sigma = std::sqrt(sq[k] / n - mean * mean);
    EXPECT_NEAR(mean, 0.0, 4.0 * 8e-6 / std::sqrt(n));
    EXPECT_NEAR(sigma, 8e-6, 0.05 * 8e-6);  // 1600+ samples: the estimate is within a few %
  }
}

TEST(SimulatedRun, UncompensatedDeviationGrowsWithLoad) {
  const CaseConfig c = short_case(paper_case());
  for (bool sensor : {false, true}) {
    const SetupCell cell = build_setup_cell(c, sensor);
    const LinkKind link = sensor ? LinkKind::kEgmJoint : LinkKind::kProgram;
    const RunOutput unloaded = simulate_run(c, cell, spec(RunKind::kUnloaded, Strategy::kOffline, 0.0, 1, link));
    const double low = mean_distance_to_path_m(
        simulate_run(c, cell, spec(RunKind::kUncompensated, Strategy::kOffline, 150.0, 2, link)).trace, unloaded.trace);
    const double high = mean_distance_to_path_m(
        simulate_run(c, cell, spec(RunKind::kUncompensated, Strategy::kOffline, 650.0, 2, link)).trace, unloaded.trace);
    EXPECT_GT(high, 2.5 * low) << "sensor " << sensor;  // roughly proportional to the load
    EXPECT_GT(low, 5e-5);
  }
}

TEST(SimulatedRun, ModelConsistentCellIsCompensatedDownToTheTrackerNoise) {
  // Every extra effect off, the exact stiffness given to the compensators, no force error: what is
  // left after compensation must be the noise floor, i.e. what one unloaded run measures against
  // another, whichever way the correction reaches the controller (over the 100 ms simple message
  // link, whose buffer puts 0.3 s between a point and the motion, with the predictive strategy).
  CaseConfig c = model_consistent(short_case(paper_case()), true);
  c.speeds_m_s = {0.02};
  struct Way {
    bool sensor;
    LinkKind link;
    Strategy strategy;
    double allowed;  // of the floor
  };
  for (const Way& w :
       {Way{false, LinkKind::kProgram, Strategy::kOffline, 1.15},
        Way{true, LinkKind::kEgmJoint, Strategy::kOnline, 1.3}, Way{true, LinkKind::kEgmPath, Strategy::kOnline, 1.3},
        Way{true, LinkKind::kSimpleMessage, Strategy::kPredictive, 1.3}}) {
    const SetupCell cell = build_setup_cell(c, w.sensor);
    RunSpec r = spec(RunKind::kUnloaded, w.strategy, 0.0, 1, w.link);
    r.speed_m_s = 0.02;
    const RunOutput unloaded = simulate_run(c, cell, r);
    r.seed = 99;
    const RunOutput unloaded2 = simulate_run(c, cell, r);
    const double floor = mean_distance_to_path_m(unloaded2.trace, unloaded.trace);
    r.kind = RunKind::kUncompensated;
    r.load_n = 650.0;
    r.seed = 2;
    const double uc = mean_distance_to_path_m(simulate_run(c, cell, r).trace, unloaded.trace);
    r.kind = RunKind::kCompensated;
    const RunOutput compensated = simulate_run(c, cell, r);
    const double comp = mean_distance_to_path_m(compensated.trace, unloaded.trace);
    EXPECT_GT(uc, 20.0 * floor) << to_string(w.link);
    EXPECT_LT(comp, floor * w.allowed) << to_string(w.link) << " floor " << floor << " C " << comp;
    if (w.link != LinkKind::kProgram) {
      EXPECT_GT(compensated.link_cycles, 100u);
      EXPECT_EQ(compensated.link_counters.rejected(), 0u);
      EXPECT_EQ(compensated.link_counters.guard_trips, 0u);
    }
  }
}

TEST(SimulatedRun, OnlineLagGrowsWithSpeedAndThePredictiveStrategyRemovesIt) {
  // Noise-free, model-consistent cell: what is left of the online residual is the force measured
  // where the arm was one link delay (and the filter's lag) before the pose the command is for; it
  // grows with the TCP speed; predicting the wrench there removes most of it.
  CaseConfig c = model_consistent(short_case(paper_case()), false);
  const SetupCell cell = build_setup_cell(c, true);
  auto residual = [&](Strategy s, double speed) {
    RunSpec r = spec(RunKind::kUnloaded, s, 0.0, 5, LinkKind::kEgmJoint);
    r.speed_m_s = speed;
    const RunOutput unloaded = simulate_run(c, cell, r);
    r.kind = RunKind::kCompensated;
    r.load_n = 650.0;
    return mean_distance_to_path_m(simulate_run(c, cell, r).trace, unloaded.trace);
  };
  const double slow = residual(Strategy::kOnline, 0.02);
  const double fast = residual(Strategy::kOnline, 0.2);
  const double fast_predicted = residual(Strategy::kPredictive, 0.2);
  EXPECT_GT(fast, 3.0 * slow) << slow << " " << fast;
  EXPECT_LT(fast_predicted, 0.5 * fast) << fast_predicted << " " << fast;
}

TEST(CaseStudy, SameSeedGivesTheSameFiguresOnAnyNumberOfThreads) {
  CaseConfig c = short_case(paper_case());
  c.setups[0].loads_n = {650.0};
  c.setups[1].loads_n = {650.0};
  CaseStudyOptions o;
  o.speed_sweep = false;
  o.error_budget = false;
  o.threads = 2;
  const CaseStudyOutput a = run_case_study(c, o);
  o.threads = 1;
  const CaseStudyOutput b = run_case_study(c, o);
  ASSERT_EQ(a.study.setups.size(), 2u);
  for (std::size_t s = 0; s < 2; ++s) {
    EXPECT_EQ(a.study.setups[s].loads[0].uc_mm.at(50), b.study.setups[s].loads[0].uc_mm.at(50));
    EXPECT_EQ(a.study.setups[s].loads[0].c_mm.at(50), b.study.setups[s].loads[0].c_mm.at(50));
    EXPECT_GT(a.study.setups[s].loads[0].compensation.at(50), 0.5);
  }
  c.seed = 2;
  const CaseStudyOutput d = run_case_study(c, o);
  EXPECT_NE(a.study.setups[1].loads[0].c_mm.at(50), d.study.setups[1].loads[0].c_mm.at(50));
  // The online setup went through deflex's link, never beyond its bound.
  ASSERT_EQ(a.links.size(), 1u);
  EXPECT_GT(a.links[0].cycles, 1000u);
  EXPECT_EQ(a.links[0].guard_trips, 0u);
  EXPECT_LE(a.links[0].max_command_deviation_rad, a.links[0].bound_rad);
  EXPECT_GT(a.links[0].max_command_deviation_rad, 0.0);
}

TEST(CaseStudy, EveryFurtherControllerLinkCompensatesTheLoad) {
  // The paper's case's setups over RSI, FANUC Stream Motion, MotoROS2 and UR RTDE, one lap at 50 mm/s
  // and 650 N: each runs deflex's link against its simulated controller and the compensated path lies
  // clearly closer to the unloaded one than the uncompensated path of the same cell and seed does.
  const CaseConfig paper = paper_case();
  CaseConfig c = short_case(paper);
  c.setups.clear();
  for (const auto& s : paper.setups) {
    if (s.link == LinkKind::kRsi || s.link == LinkKind::kFanucJ519 || s.link == LinkKind::kMotoros2Rt ||
        s.link == LinkKind::kUrRtde) {
      c.setups.push_back(s);
    }
  }
  ASSERT_EQ(c.setups.size(), 4u);
  CaseStudyOptions o;
  o.speed_sweep = false;
  o.error_budget = false;
  o.threads = 2;
  const CaseStudyOutput out = run_case_study(c, o);
  ASSERT_EQ(out.links.size(), 4u);
  ASSERT_EQ(out.study.setups.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    const LinkSummary& l = out.links[i];
    const LoadResult& load = out.study.setups[i].loads.at(0);
    SCOPED_TRACE(l.link);
    EXPECT_EQ(l.link, to_string(c.setups[i].link));
    // One lap and its hold at 50 mm/s is ~10 s: at least one answer every 10 ms.
    EXPECT_GT(l.cycles, 1000u);
    EXPECT_EQ(l.rejected, 0u);
    EXPECT_EQ(l.guard_trips, 0u);
    EXPECT_GT(l.max_command_deviation_rad, 0.0);
    EXPECT_LE(l.max_command_deviation_rad, l.bound_rad);
    // Every link measures its delay from the controller's feedback. RSI's AIPos follows ASPos plus the
    // applied offset by the servo's following error (8 ms in the cell) and its report's age: a few
    // ms to a few tens, never the hundreds a mismatched reference gives.
    EXPECT_GT(l.measured_delay_s, 0.0);
    if (c.setups[i].link == LinkKind::kRsi) {
      EXPECT_GT(l.measured_delay_s, 0.004);
      EXPECT_LT(l.measured_delay_s, 0.05);
    }
    EXPECT_FALSE(l.controller_note.empty());
    // The row's figures are the setup's, and C is well under UC.
    EXPECT_DOUBLE_EQ(l.load_n, 650.0);
    EXPECT_DOUBLE_EQ(l.uc_mm, load.uc_mm.at(50));
    EXPECT_DOUBLE_EQ(l.c_mm, load.c_mm.at(50));
    EXPECT_GT(l.uc_mm, 0.3);
    EXPECT_LT(l.c_mm, 0.5 * l.uc_mm);
    EXPECT_NEAR(l.compensation, 1.0 - as_printed(l.c_mm) / as_printed(l.uc_mm), 1e-12);
  }
}

TEST(SimulatedRun, EachFurtherLinksCompensatedPathIsCloserThanTheSameCellsUncompensatedOne) {
  // Against the traces themselves (the evaluation's nearest-point distance, not the study's figures):
  // a run over each further link, compensated, against the uncompensated run of the same seed.
  const CaseConfig c = short_case(paper_case());
  const SetupCell cell = build_setup_cell(c, true);
  for (LinkKind link : {LinkKind::kRsi, LinkKind::kFanucJ519, LinkKind::kMotoros2Rt, LinkKind::kUrRtde}) {
    SCOPED_TRACE(to_string(link));
    const RunOutput unloaded = simulate_run(c, cell, spec(RunKind::kUnloaded, Strategy::kOnline, 0.0, 1, link));
    const RunOutput uc = simulate_run(c, cell, spec(RunKind::kUncompensated, Strategy::kOnline, 650.0, 2, link));
    const RunOutput comp = simulate_run(c, cell, spec(RunKind::kCompensated, Strategy::kOnline, 650.0, 2, link));
    const double uc_m = mean_distance_to_path_m(uc.trace, unloaded.trace);
    const double c_m = mean_distance_to_path_m(comp.trace, unloaded.trace);
    EXPECT_GT(uc_m, 3e-4);
    EXPECT_LT(c_m, 0.5 * uc_m) << "UC " << uc_m << " C " << c_m;
    EXPECT_GT(comp.link_cycles, 1000u);
    EXPECT_EQ(comp.link_counters.guard_trips, 0u);
  }
}

TEST(CaseStudy, SeveralSeedsGiveEachSeedsOwnFiguresTheirMeanAndSpread) {
  CaseConfig c = short_case(paper_case());
  c.setups[0].loads_n = {650.0};
  c.setups[1].loads_n = {650.0};
  CaseStudyOptions o;
  o.speed_sweep = false;
  o.error_budget = false;
  o.seeds = 2;
  const CaseStudyOutput both = run_case_study(c, o);
  EXPECT_EQ(both.study.seeds, (std::vector<std::uint64_t>{c.seed, c.seed + 1}));
  // Each seed's figure is the one a study of that seed alone gives.
  o.seeds = 1;
  const CaseStudyOutput first = run_case_study(c, o);
  CaseConfig second_case = c;
  second_case.seed = c.seed + 1;
  const CaseStudyOutput second = run_case_study(second_case, o);
  for (std::size_t s = 0; s < 2; ++s) {
    const LoadResult& l = both.study.setups[s].loads[0];
    ASSERT_EQ(l.c_mm_by_seed.at(50).size(), 2u);
    EXPECT_EQ(l.c_mm_by_seed.at(50)[0], first.study.setups[s].loads[0].c_mm.at(50));
    EXPECT_EQ(l.c_mm_by_seed.at(50)[1], second.study.setups[s].loads[0].c_mm.at(50));
    EXPECT_EQ(l.uc_mm_by_seed.at(50)[1], second.study.setups[s].loads[0].uc_mm.at(50));
    EXPECT_NEAR(l.c_mm.at(50), 0.5 * (l.c_mm_by_seed.at(50)[0] + l.c_mm_by_seed.at(50)[1]), 1e-15);
    const Spread sp = l.c_spread(50);
    EXPECT_EQ(sp.n, 2);
    EXPECT_NEAR(sp.sd, std::abs(l.c_mm_by_seed.at(50)[0] - l.c_mm_by_seed.at(50)[1]) / std::sqrt(2.0), 1e-12);
    EXPECT_NE(l.c_mm_by_seed.at(50)[0], l.c_mm_by_seed.at(50)[1]);  // two cells, two results
  }
  // A setup that runs the first seed only: its figures are that seed's, the other setup keeps both
  // seeds, and the study runs the setup's family (its unloaded, uncompensated and compensated runs) once.
  CaseConfig one_seed = c;
  one_seed.setups[1].seeds = 1;
  o.seeds = 2;
  const CaseStudyOutput mixed = run_case_study(one_seed, o);
  const LoadResult& kept = mixed.study.setups[0].loads[0];
  const LoadResult& first_only = mixed.study.setups[1].loads[0];
  ASSERT_EQ(kept.c_mm_by_seed.at(50).size(), 2u);
  EXPECT_EQ(kept.c_mm_by_seed.at(50), both.study.setups[0].loads[0].c_mm_by_seed.at(50));
  ASSERT_EQ(first_only.c_mm_by_seed.at(50).size(), 1u);
  EXPECT_EQ(first_only.c_mm.at(50), first.study.setups[1].loads[0].c_mm.at(50));
  EXPECT_EQ(first_only.uc_mm.at(50), first.study.setups[1].loads[0].uc_mm.at(50));
  // Each setup here is its own family: 1 unloaded, 1 uncompensated and 1 compensated run a seed.
  EXPECT_EQ(both.runs, 2 * 2 * 3);
  EXPECT_EQ(mixed.runs, 2 * 3 + 1 * 3);
}

TEST(CaseStudy, TheErrorBudgetsEveryEffectFigureIsTheTablesOwnRun) {
  CaseConfig c = short_case(paper_case());
  c.setups[0].loads_n = {650.0};
  c.setups[1].loads_n = {650.0};
  c.calibration.arcs = 3;  // a quicker calibration for each budget cell
  CaseStudyOptions o;
  o.speed_sweep = false;
  o.seeds = 1;
  const CaseStudyOutput out = run_case_study(c, o);
  ASSERT_EQ(out.study.error_budgets.size(), 2u);
  for (const auto& b : out.study.error_budgets) {
    const SetupResult* table = nullptr;
    for (const auto& s : out.study.setups) {
      if (s.setup == b.setup) table = &s;
    }
    ASSERT_NE(table, nullptr) << b.setup;
    EXPECT_EQ(b.residual_mm_all, table->loads[0].c_mm.at(50)) << b.setup;
    EXPECT_EQ(b.uc_mm, table->loads[0].uc_mm.at(50)) << b.setup;
    EXPECT_EQ(b.seed, c.seed);
    EXPECT_EQ(b.laps, 1);
    EXPECT_GT(b.entries.size(), 10u);
    // Every effect off at once, on a cell calibrated as the others are: far below C with every effect.
    EXPECT_TRUE(std::isfinite(b.residual_mm_all_off)) << b.setup;
    EXPECT_LT(b.residual_mm_all_off, b.residual_mm_all) << b.setup;
    bool tracker = false;
    for (const auto& e : b.entries) {
      EXPECT_TRUE(std::isfinite(e.residual_mm_without_it)) << e.effect;
      tracker = tracker || e.effect == to_string(Effect::kTrackerNoise);
    }
    EXPECT_TRUE(tracker);
  }
}

TEST(CellCalibration, WhileMovingItFindsTheTrueStiffnessOfAModelConsistentCell) {
  // No effect the lumped model lacks, no noise, the LDBB exact: what the moving calibration
  // identifies must be the true stiffness of the joints the arcs load (1, 2, 3 and 5).
  CaseConfig c = model_consistent(paper_case(), false);
  c.exact_model = false;
  c.cell.ldbb.ripple = 0.0;
  c.cell.ldbb.noise = 0.0;
  const SetupCell cell = build_setup_cell(c, false);
  const auto& k_true = cell.robot->true_model().stiffness();
  const auto& k_id = cell.calibration.identified.stiffness();
  for (int j : {0, 1, 2, 4}) {
    EXPECT_NEAR(k_id[j] / k_true[j], 1.0, 0.03) << "joint " << j + 1;
  }
  EXPECT_GT(cell.calibration.measurements, 6 * 10);
  EXPECT_LT(cell.calibration.estimate.residual_rms_m, 5e-6);
  // The same calibration on the full cell (drift, lost motion, link bending ...) leaves a residual
  // the model cannot explain, and still finds the stiffness within a plausible band.
  const CaseConfig full = paper_case();
  const SetupCell real = build_setup_cell(full, false);
  EXPECT_GT(real.calibration.estimate.residual_rms_m, 3.0 * cell.calibration.estimate.residual_rms_m);
  for (int j : {1, 2}) {
    const double ratio = real.calibration.identified.stiffness()[j] / real.robot->true_model().stiffness()[j];
    EXPECT_GT(ratio, 0.5) << "joint " << j + 1;
    EXPECT_LT(ratio, 2.0) << "joint " << j + 1;
  }
}

TEST(CellCalibration, ItKnowsOnlyTheForceTheBarReports) {
  // A model-consistent cell with the sensor mounted and a bar whose seal holds up to 20 % of its
  // force against the piston's last motion. The piston slides out as the arm yields to the load and
  // back and forth with the deflection along each arc, so the force the bar applies is off its
  // set-point by up to 20 %, differently along each arc. Taking the bar's report, the calibration is
  // given exactly the set-point (500 N along the nominal bar) and the stiffness it finds is off the
  // truth; taking the sensor's force, it finds the truth.
  CaseConfig c = model_consistent(paper_case(), false);
  c.exact_model = false;
  c.cell.ldbb.seal_friction = 0.20;
  c.cell.ldbb.seal_friction_spread = 0.0;
  c.cell.ldbb.ripple = 0.0;
  c.cell.ldbb.noise = 0.0;
  c.cell.sensor.noise_n = 0.0;
  c.cell.sensor.lateral_compliance_m_per_n = 0.0;
  c.cell.sensor.axial_compliance_m_per_n = 0.0;
  c.cell.sensor.rotational_compliance_rad_per_nm = 0.0;
  for (const bool from_sensor : {true, false}) {
    c.calibration.force_from_sensor = from_sensor;
    const SetupCell cell = build_setup_cell(c, true);
    double worst = 0.0;
    for (int j : {0, 1, 2, 4}) {
      const double ratio = cell.calibration.identified.stiffness()[j] / cell.robot->true_model().stiffness()[j];
      worst = std::max(worst, std::abs(ratio - 1.0));
      if (from_sensor) {
        EXPECT_NEAR(ratio, 1.0, 0.03) << "joint " << j + 1 << " (sensor)";
      }
    }
    if (from_sensor) {
      // The sensor reads what the bar applies: not the set-point.
      EXPECT_GT(std::abs(cell.calibration.mean_force_n - c.calibration.load_n), 5.0);
    } else {
      EXPECT_NEAR(cell.calibration.mean_force_n, c.calibration.load_n, 1e-9);
      EXPECT_GT(worst, 0.05) << "the bar's friction did not reach the identified stiffness";
    }
  }
}

TEST(CellCalibration, AJointTheIdentificationCallsUnusableIsMeasuredAgainOrKeptAtItsPrior) {
  // Two arcs instead of six: the identification flags some joints (a relative standard error over
  // its limit, a compliance at the c >= 0 bound); joint 6, whose axis runs through the TCP ball, no
  // force there ever turns. The calibration measures the flagged joints again at the planner's poses
  // where those can turn them, and gives the compensators the assumed stiffness for every joint its
  // final estimate still flags, never the flagged value.
  CaseConfig c = paper_case();
  c.calibration.arcs = 2;
  for (const bool sensor : {false, true}) {
    const SetupCell cell = build_setup_cell(c, sensor);
    const CellCalibration& cal = cell.calibration;
    const StiffnessEstimate& e = cal.estimate;
    const auto& k = cal.identified.stiffness();
    const auto& prior = cell.robot->nominal_model().stiffness();
    ASSERT_FALSE(cal.remeasured_joints.empty()) << "sensor " << sensor;
    EXPECT_GT(cal.measurements, 2 * c.calibration.points_per_arc) << "the planner's poses were measured";
    EXPECT_EQ(std::count(cal.remeasured_joints.begin(), cal.remeasured_joints.end(), 6), 0);
    EXPECT_EQ(std::count(cal.kept_joints.begin(), cal.kept_joints.end(), 6), 1);
    for (int j = 0; j < 6; ++j) {
      const auto ju = static_cast<std::size_t>(j);
      const bool kept = std::count(cal.kept_joints.begin(), cal.kept_joints.end(), j + 1) > 0;
      const bool flagged = std::count(e.unidentifiable_joints.begin(), e.unidentifiable_joints.end(), j + 1) > 0;
      const double rel = e.std_error_nm_per_rad[ju] / e.stiffness_nm_per_rad[ju];
      if (kept) {
        EXPECT_EQ(k[j], prior[j]) << "joint " << j + 1;
        EXPECT_TRUE(flagged || !std::isfinite(e.stiffness_nm_per_rad[ju])) << "joint " << j + 1;
        const std::string mark = fmt::format("joint {}: ", j + 1);
        EXPECT_EQ(std::count_if(cal.notes.begin(), cal.notes.end(),
                                [&](const std::string& n) {
                                  return n.rfind(mark, 0) == 0 && n.find("kept the assumed") != std::string::npos;
                                }),
                  1)
            << "joint " << j + 1;
      } else {
        EXPECT_FALSE(flagged) << "joint " << j + 1;
        EXPECT_LE(rel, IdentificationOptions{}.max_relative_std_error) << "joint " << j + 1;
        EXPECT_EQ(k[j], e.stiffness_nm_per_rad[ju]) << "joint " << j + 1;
      }
    }
  }
}

TEST(CellModule, IncludesNothingOfTheStrategiesOrTheirLinks) {
  // The simulated cell is hardware: it may speak the links' wire formats, never run their code.
  namespace fs = std::filesystem;
  int files = 0;
  for (const auto& entry : fs::directory_iterator(fs::path(DEFLEX_SOURCE_DIR) / "src/deflex/cell")) {
    std::ifstream in(entry.path());
    std::stringstream text;
    text << in.rdbuf();
    for (const char* forbidden :
         {"deflex/online/", "deflex/offline/", "deflex/link/", "deflex/egm/", "deflex/study/", "deflex/identify/"}) {
      EXPECT_EQ(text.str().find(forbidden), std::string::npos) << entry.path() << " includes " << forbidden;
    }
    ++files;
  }
  EXPECT_GT(files, 10);
}

}  // namespace
}  // namespace deflex::study
