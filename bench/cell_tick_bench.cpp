// What a servo tick and a tracker sample of the case study cost, and of what: a setup's runs of each
// kind (the cost a tick of the study's simulation has, deflex's side included online), and
// the parts a tick is made of, each alone (the true arm's solve unloaded and loaded, the coupled solve
// of the arm and the bar, the tracker's and the force sensor's 1 kHz samples, a normal draw of each
// noise engine). With the study's own counts (ticks, samples, link cycles: printed by case_study_bench)
// they give the floor the study's CPU time cannot go below without simulating less.
// Run: build/bench/cell_tick_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <boost/random/normal_distribution.hpp>
#include <memory>
#include <random>
#include <vector>

#include "deflex/cell/coupled_tick.hpp"
#include "deflex/cell/force_sensor.hpp"
#include "deflex/cell/laser_tracker.hpp"
#include "deflex/cell/ldbb_device.hpp"
#include "deflex/cell/noise_engine.hpp"
#include "deflex/cell/path_drift.hpp"
#include "deflex/cell/true_robot.hpp"
#include "deflex/paths/circle_path.hpp"
#include "deflex/paths/path_ik.hpp"
#include "deflex/study/case_config.hpp"
#include "deflex/study/case_study.hpp"

namespace {

using namespace deflex;

// The paper's case as the study's default (fast) computation runs it (case_study.cpp): the 1 kHz noise
// from xoshiro256+, the arm's fixed point to 1e-8 rad, a tick's arm and bar agreeing to 0.25 N.
const study::CaseConfig& paper() {
  static const study::CaseConfig c = [] {
    study::CaseConfig x = study::paper_case();
    x.cell.sensor.fast_noise = true;
    x.cell.tracker.fast_noise = true;
    x.cell.robot.fixed_point_step_rad = 1e-8;
    x.cell.robot.first_order_step_rad = 1e-5;
    x.coupled_tick.force_tolerance_n = 0.25;
    x.coupled_tick.moment_tolerance_nm = 5e-3;
    x.coupled_tick.settle_tolerance_m = 2e-8;
    return x;
  }();
  return c;
}

// One physical setup's share of the study, alone: its seed's calibration, then at 50 mm/s and its
// highest load the unloaded reference, the uncompensated and the compensated run (a lap each way),
// and their evaluation, on one thread in the study's default computation. CPU per servo tick of the
// unloaded and of the loaded runs (the controller stand-in and, online, deflex's session over EGM
// included) and per evaluated tracker sample.
void BM_SetupRuns(benchmark::State& state) {
  study::CaseConfig c = study::paper_case();
  const std::string name = state.range(0) != 0 ? "online" : "offline";
  std::vector<study::SetupConfig> keep;
  for (const auto& s : c.setups) {
    if (s.name == name) keep.push_back(s);
  }
  keep.front().loads_n = {keep.front().loads_n.back()};
  keep.front().paper_uc_mm.clear();
  keep.front().paper_c_mm.clear();
  c.setups = keep;
  c.speeds_m_s = {0.05};
  study::CaseStudyOptions options;
  options.quick = true;
  options.seeds = 1;
  options.threads = 1;
  options.speed_sweep = false;
  options.error_budget = false;
  // A run: the settling hold, then a lap each way; the tracker records from the laps' start.
  const double laps_s = 2.0 * 2.0 * kPi * c.radius_m() / 0.05;
  const double run_ticks = (c.cell.ldbb.settle_s + laps_s) / c.cell.controller.servo_period_s;
  const double run_samples = laps_s * c.cell.tracker.rate_hz;
  for (auto _ : state) {
    const study::CaseStudyOutput out = study::run_case_study(c, options);
    const study::StudyPhaseTimes& p = out.phases;
    state.counters["calibration_s"] = p.calibration_s;
    state.counters["unloaded_ns_per_tick"] = p.unloaded_s / run_ticks * 1e9;
    state.counters["loaded_ns_per_tick"] = p.loaded_s / (2.0 * run_ticks) * 1e9;
    state.counters["evaluation_ns_per_sample"] = p.evaluation_s / (2.0 * run_samples) * 1e9;
    state.counters["runs"] = out.runs;
  }
}
BENCHMARK(BM_SetupRuns)->ArgName("online")->Arg(0)->Arg(1)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

// The arm of the paper's cell (the first seed's true robot, offline: no sensor) and the configurations
// of its circle a servo tick apart at 50 mm/s, by the nominal kinematics.
const cell::TrueRobot& robot() {
  static const cell::TrueRobot r(paper().cell, false, 1);
  return r;
}

const std::vector<JointVector>& circle_q() {
  static const std::vector<JointVector> q = [] {
    CirclePath circle;
    circle.centre_m = paper().circle.center_m;
    circle.radius_m = paper().radius_m();
    circle.points = static_cast<int>(2.0 * kPi * circle.radius_m / (0.05 * paper().cell.controller.servo_period_s));
    const std::vector<Pose> poses = sample_circle(circle, Eigen::Quaterniond(paper().circle.tcp_orientation.linear()));
    IkRequest first;
    JointVector standing(6);  // the study's standing pose, in front of the robot
    standing << 0.0, deg_to_rad(20.0), deg_to_rad(10.0), 0.0, deg_to_rad(60.0), 0.0;
    first.seed = standing;
    return solve_path_ik(robot().nominal_model(), poses, first).q;
  }();
  return q;
}

// The true arm's solve of one tick at the next configuration of the circle: unloaded (the kinematics
// alone) or under a 650 N wrench (its fixed point: Jacobians, the gears' hardening, lost motion).
void BM_TrueRobotSolve(benchmark::State& state) {
  const cell::TrueRobot& robot = ::robot();
  const auto& q = circle_q();
  Workspace ws(robot.true_model());
  cell::TrueRobotState s = robot.initial_state(q.front());
  Wrench w = Wrench::Zero();
  if (state.range(0) != 0) w.head<3>() = Vector3(-450.0, 0.0, -470.0);
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(robot.solve(ws, q[i], w, s, 0.004));
    i = (i + 1) % q.size();
  }
}
BENCHMARK(BM_TrueRobotSolve)->ArgName("loaded")->Arg(0)->Arg(1);

// The coupled solve of the arm and the LDBB one servo tick at a time (the bar's and the drift's
// advance included), as a loaded run steps it.
void BM_CoupledTick(benchmark::State& state) {
  const study::CaseConfig& c = paper();
  const cell::TrueRobot& robot = ::robot();
  const auto& q = circle_q();
  Workspace ws(robot.true_model());
  cell::TrueRobotState s = robot.initial_state(q.front());
  cell::LdbbDevice bar(c.cell.ldbb, c.pivot_m(), 625.0, 3);
  cell::PathDrift drift(c.cell.drift, 4);
  cell::CoupledTickSolver solver(c.coupled_tick);
  const cell::CoupledArm arm{robot, ws, s, drift, &bar};
  benchmark::DoNotOptimize(solver.at_rest(arm, q.front()));
  std::size_t i = 1;
  Wrench w;
  for (auto _ : state) {
    drift.advance(0.004);
    bar.advance(0.004);
    benchmark::DoNotOptimize(solver.tick(arm, q[i], 0.004, w));
    i = (i + 1) % q.size();
  }
  state.counters["arm_solves_per_tick"] =
      static_cast<double>(solver.counters().arm_solves) / static_cast<double>(solver.counters().ticks);
}
BENCHMARK(BM_CoupledTick);

// The laser tracker over one servo tick (4 ms: four 1 kHz samples, their noise and interpolation).
void BM_TrackerTick(benchmark::State& state) {
  cell::TrackerConfig tc = paper().cell.tracker;
  tc.fast_noise = state.range(0) != 0;
  cell::LaserTracker tracker(tc, 5, 0.0, 1e9, 0.0);
  TrackerTrace out;
  out.reserve(1 << 20);
  double t = 0.0;
  const Vector3 p(1.8, 0.0, 0.9);
  for (auto _ : state) {
    tracker.observe(t, p, t + 0.004, p, out);
    t += 0.004;
    if (out.size() > (1u << 20) - 8) out.clear();
  }
  state.counters["samples_per_tick"] = 4;
}
BENCHMARK(BM_TrackerTick)->ArgName("fast")->Arg(0)->Arg(1);

// One 1 kHz sample of the force sensor's DAQ (its noise, drift, crosstalk and sensitivities).
void BM_DaqSample(benchmark::State& state) {
  cell::SensorConfig sc = paper().cell.sensor;
  sc.fast_noise = state.range(0) != 0;
  cell::ForceSensorDaq daq(sc, paper().cell.tool, 6);
  const Vector3 f(-450.0, 0.0, -470.0);
  const Matrix3 r = Matrix3::Identity();
  double t = 0.0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(daq.sample(f, r, t));
    t += 1e-3;
  }
}
BENCHMARK(BM_DaqSample)->ArgName("fast")->Arg(0)->Arg(1);

// A standard normal draw from each of the cell's noise engines (the reference Mersenne Twister and
// the fast xoshiro256+), through Boost's ziggurat as the cell draws them.
void BM_NormalDraw(benchmark::State& state) {
  cell::NoiseEngine rng(9, state.range(0) != 0);
  boost::random::normal_distribution<double> normal(0.0, 1.0);
  for (auto _ : state) {
    benchmark::DoNotOptimize(normal(rng));
  }
}
BENCHMARK(BM_NormalDraw)->ArgName("fast")->Arg(0)->Arg(1);

}  // namespace

BENCHMARK_MAIN();
