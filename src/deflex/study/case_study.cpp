// The protocol runner of the simulated case study (see case_study.hpp).
#include "deflex/study/case_study.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <tuple>

#include <time.h>

#include "deflex/evaluate/iso9283_path.hpp"
#include "deflex/evaluate/lap_split.hpp"
#include "deflex/evaluate/path_metrics.hpp"
#include "deflex/model/tracker_trace.hpp"
#include "deflex/study/detail/simulated_run.hpp"
#include "deflex/text/errors.hpp"

namespace deflex::study {
namespace {

int mm_s(double speed_m_s) { return static_cast<int>(std::lround(speed_m_s * 1e3)); }

// This thread's CPU time (s): the phases are timed per thread, so a busy machine does not count.
double thread_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

struct Figures {
  double mean_mm = 0, std_mm = 0, max_mm = 0, sync_mm = NAN, iso_accuracy_mm = NAN, iso_repeatability_mm = NAN;
};

// The laps of a run, found in its tracker trace the way `deflex evaluate --split-laps` finds them
// (by the angle turned about the path's centre), not from the simulator's schedule.
std::vector<TrackerTrace> laps_of(const TrackerTrace& trace) { return split_laps(trace).laps; }

TrackerTrace thin(const TrackerTrace& lap, std::size_t max_points) {
  const std::size_t step = std::max<std::size_t>(1, lap.size() / max_points);
  TrackerTrace out;
  for (std::size_t i = 0; i < lap.size(); i += step) out.push_back(lap[i]);
  return out;
}

TrackerTrace thin_lap(const RunOutput& run, std::size_t max_points) {
  const auto laps = laps_of(run.trace);
  if (laps.empty()) return {};
  return thin(laps.back(), max_points);
}

// Points a plotted lap keeps: the path plots' laps, and each lap of the lap-by-lap plots.
constexpr std::size_t kPlotPoints = 1500;
constexpr std::size_t kPlotLapPoints = 720;

// An unloaded run prepared once for every loaded run compared with it: its raw trace (for the
// time-synchronous metric) and the mean of its laps, indexed (for the nearest-point metric: a dense,
// noisy reference would bias that distance low by its own noise). Once every run of its seed has been
// measured against it, the trace and the index are released (release_references()); what a plot
// needs of it is kept thinned.
struct Reference {
  RunOutput run;
  TrackerTrace mean;
  std::shared_ptr<const PolylineIndex> index;
  TrackerTrace plot_lap;  // its last lap, thinned (only the plotted runs' references)
};

Reference make_reference(RunOutput run, bool plotted) {
  Reference r;
  r.mean = mean_closed_path(run.trace);
  r.index = std::make_shared<const PolylineIndex>(r.mean);
  if (plotted) r.plot_lap = thin_lap(run, kPlotPoints);
  r.run = std::move(run);
  return r;
}

Figures evaluate_run(const RunOutput& loaded, const Reference& reference) {
  Figures f;
  const PathDeviationStats s = path_deviation(loaded.trace, *reference.index);
  f.mean_mm = s.mean_m * 1e3;
  f.std_mm = s.std_m * 1e3;
  f.max_mm = s.max_m * 1e3;
  f.sync_mm = time_synchronous_deviation(loaded.trace, reference.run.trace).mean_m * 1e3;
  const auto laps = laps_of(loaded.trace);
  if (!laps.empty()) {
    try {
      const Iso9283Path iso = iso9283_path(laps, reference.mean);
      f.iso_accuracy_mm = iso.accuracy_m * 1e3;
      f.iso_repeatability_mm = iso.repeatability_m * 1e3;
    } catch (const InputError&) {
      // A path ISO 9283 cannot evaluate leaves its figures empty; the paper's figure stands alone.
    }
  }
  return f;
}

// Every lap of a run, thinned, with its direction of travel.
std::vector<DirectedLap> plot_laps(const RunOutput& run, std::size_t max_points) {
  if (run.trace.size() < 2) return {};
  std::vector<DirectedLap> laps = directed_laps(run.trace);
  for (auto& lap : laps) lap.trace = thin(lap.trace, max_points);
  return laps;
}

// Runs that share a physical configuration and a way of driving the arm share their unloaded
// reference and their uncompensated runs: the offline setups (no sensor, the controller's own
// program), and the online setups per link (sensor mounted, deflex streaming uncorrected).
struct Family {
  bool sensor = false;
  LinkKind link = LinkKind::kProgram;
};

struct Progress {
  std::mutex mutex;
  double total = 0, done = 0;
  const CaseStudyOptions* options = nullptr;
  void add(double amount, const std::string& label) {
    if (!options || !options->progress) return;
    std::lock_guard<std::mutex> lock(mutex);
    done += amount;
    options->progress(total > 0 ? std::min(1.0, done / total) : 1.0, label);
  }
};

double run_cost(const CaseConfig& c, double speed_m_s, int laps) {
  return c.cell.ldbb.settle_s + 2.0 * kPi * c.radius_m() * laps / speed_m_s;
}

// Simulated seconds of a calibration: an unloaded and a loaded pass over every arc, each after a
// hold (the arcs' radii are at most the bar's length).
double calibration_cost(const CaseConfig& c) {
  if (c.exact_model) return 0.0;
  const double hold_s = std::max(1.5, 5.0 * c.cell.ldbb.time_constant_s);
  return 2.0 * c.calibration.arcs *
         (hold_s + c.calibration.arc_rad * c.cell.ldbb.bar_length_m / c.calibration.speed_m_s);
}

std::string describe(Strategy s, LinkKind link, double stream_period_s) {
  switch (s) {
    case Strategy::kOffline:
      return "offline compensation from the LDBB force model (paper, Figure 2): the controller runs the compensated "
             "program";
    case Strategy::kOnline:
      switch (link) {
        case LinkKind::kEgmPath:
          return "online compensation from the force sensor (paper, Figure 3) over ABB EGM path correction";
        case LinkKind::kSimpleMessage:
          return fmt::format(
              "online compensation from the force sensor (paper, Figure 3) streamed every {:g} ms over TCP to the "
              "robot program (simple message): the paper's own kind of link",
              stream_period_s * 1e3);
        case LinkKind::kRsi:
          return "online compensation from the force sensor (paper, Figure 3) over KUKA RSI axis correction";
        case LinkKind::kFanucJ519:
          return "online compensation from the force sensor (paper, Figure 3) streamed over FANUC Stream Motion (J519)";
        case LinkKind::kMotoros2Rt:
          return "online compensation from the force sensor (paper, Figure 3) streamed over Yaskawa MotoROS2 real-time";
        case LinkKind::kUrRtde:
          return "online compensation from the force sensor (paper, Figure 3) streamed over Universal Robots RTDE to "
                 "servoj";
        default:
          return "online compensation from the force sensor (paper, Figure 3) over ABB EGM position guidance";
      }
    case Strategy::kHybrid:
      return "hybrid: the offline program streamed, plus an online correction of measured minus modelled force";
    case Strategy::kPredictive:
      return "predictive: online, with the wrench predicted where the command will be executed";
  }
  return "";
}

// A loaded run of the study and what is kept of it: the uncompensated runs per family, load and
// speed; the compensated ones per setup, load and speed.
struct LoadedJob {
  int seed;
  int family;
  RunKind kind;
  Strategy strategy;
  double load_n;
  double speed;
  TrackerTrace plot_lap;                   // the plotted runs' last lap, thinned
  std::vector<DirectedLap> plot_all_laps;  // and every lap of theirs, thinned
  Figures figures;
  bool plot = false;
  bool write_trace = false;
  std::uint64_t link_cycles = 0, rejected = 0, guard_trips = 0, controller_events = 0;
  double max_deviation_rad = 0.0, max_tcp_m = 0.0, delay_s = 0.0, controller_peak = 0.0;
  cell::CoupledTickCounters coupled{};  // the run's coupled solves of the arm and the bar
};

// A run of the error budget: a setup's compensated run on a cell built without one effect, or
// (no effect named) without every effect at once.
struct BudgetJob {
  int setup;
  std::optional<Effect> off;
  double residual_mm = NAN;
  cell::CoupledTickCounters coupled;  // its calibration's and run's coupled solves
};

std::string budget_label(const BudgetJob& bj) { return bj.off ? to_string(*bj.off) : "every effect off"; }

// What the steps of one case study share: the case per seed, the physical setups and families of
// runs, the runs planned and their results, the cells, the unloaded references and the progress.
struct StudyContext {
  StudyContext(const CaseConfig& c, const CaseStudyOptions& o)
      : config(c),
        options(o),
        laps_cw(o.quick ? std::min(1, c.laps_cw) : c.laps_cw),
        laps_ccw(o.quick ? std::min(1, c.laps_ccw) : c.laps_ccw),
        laps(laps_cw + laps_ccw),
        n_seeds(o.seeds > 0 ? o.seeds : std::max(1, c.seeds)) {
    progress.options = &o;
  }

  const CaseConfig& config;
  const CaseStudyOptions& options;
  const int laps_cw, laps_ccw, laps;
  const int n_seeds;
  // How many seeds a setup runs (its first ones), and a family (the most of its setups').
  [[nodiscard]] int seeds_of(const SetupConfig& s) const { return s.seeds > 0 ? std::min(s.seeds, n_seeds) : n_seeds; }
  std::vector<int> family_seeds;
  std::vector<CaseConfig> seed_config;  // each seed its own cell (true robot, sensor, calibrations) and runs
  bool need_cell[2] = {false, false};   // the physical setups: without, with the sensor
  std::vector<Family> families;
  std::vector<double> speeds;  // every speed run unloaded: the tables', the sweep's, the budget's
  std::vector<LoadedJob> loaded;
  std::vector<BudgetJob> budget_jobs;
  std::vector<int> budget_setups;
  std::vector<std::array<std::optional<SetupCell>, 2>> cells;
  std::map<std::tuple<int, int, int>, Reference> unloaded;  // by seed, family and speed (mm/s)
  double cal_cost = 0.0;                                    // simulated seconds of one calibration
  Progress progress;
  std::mutex sink_mutex;
  std::mutex phase_mutex;
  StudyPhaseTimes phases;

  // Adds the thread's CPU time since `since_s` to a phase; returns the time now.
  double charge(double StudyPhaseTimes::*phase, double since_s) {
    const double now = thread_cpu_s();
    std::lock_guard<std::mutex> lock(phase_mutex);
    phases.*phase += now - since_s;
    return now;
  }

  // The case of seed `si`.
  const CaseConfig& cfg_of(int si) const { return seed_config[static_cast<std::size_t>(si)]; }

  // The path plots show the first seed's runs at the first speed of the tables.
  bool plotted(int si, double v) const { return si == 0 && mm_s(v) == mm_s(config.speeds_m_s.front()); }

  // The family a setup's runs belong to, -1 before it is planned.
  int family_of(const SetupConfig& s) const {
    for (std::size_t i = 0; i < families.size(); ++i) {
      if (families[i].sensor == s.sensor_mounted && families[i].link == s.link) return static_cast<int>(i);
    }
    return -1;
  }

  // The sweep runs each setup at its load nearest to sweep_load_n.
  double sweep_load(const SetupConfig& s) const {
    return *std::min_element(s.loads_n.begin(), s.loads_n.end(), [&](double a, double b) {
      return std::abs(a - config.sweep_load_n) < std::abs(b - config.sweep_load_n);
    });
  }

  // The planned loaded run of this seed, family, kind, strategy (compensated runs), load and speed.
  const LoadedJob* find(int si, int fam, RunKind kind, Strategy st, double load, double v) const {
    for (const auto& j : loaded) {
      if (j.seed == si && j.family == fam && j.kind == kind && (kind != RunKind::kCompensated || j.strategy == st) &&
          j.load_n == load && mm_s(j.speed) == mm_s(v)) {
        return &j;
      }
    }
    return nullptr;
  }

  // The calibrated cell of seed `si` with or without the sensor.
  const SetupCell& cell_of(int si, bool sensor) const { return *cells[static_cast<std::size_t>(si)][sensor ? 1 : 0]; }

  // The unloaded reference run of a seed, family and speed (the tables' and the budget's alike).
  RunSpec unloaded_spec(int si, const Family& fam, double v) const {
    RunSpec spec;
    spec.kind = RunKind::kUnloaded;
    spec.link = fam.link;
    spec.speed_m_s = v;
    spec.laps_cw = laps_cw;
    spec.laps_ccw = laps_ccw;
    spec.seed = run_seed(cfg_of(si).seed, fam.sensor, RunKind::kUnloaded, Strategy::kOffline, 0.0, v,
                         static_cast<std::uint64_t>(fam.link));
    return spec;
  }

  // A loaded run of a seed and family.
  RunSpec loaded_spec(int si, const Family& fam, RunKind kind, Strategy strategy, double load, double v) const {
    RunSpec spec;
    spec.kind = kind;
    spec.strategy = strategy;
    spec.link = fam.link;
    spec.load_n = load;
    spec.speed_m_s = v;
    spec.laps_cw = laps_cw;
    spec.laps_ccw = laps_ccw;
    spec.seed = run_seed(cfg_of(si).seed, fam.sensor, kind, strategy, load, v, static_cast<std::uint64_t>(fam.link));
    return spec;
  }

  // Hands a trace to the options' trace sink, one call at a time.
  void sink(const std::string& name, const TrackerTrace& trace) {
    std::lock_guard<std::mutex> lock(sink_mutex);
    options.trace_sink(name, trace);
  }
};

// The name a family's written traces start with.
std::string family_label(const Family& fam) {
  static const char* const kFamilyName[] = {"offline", "sensor"};
  return fmt::format("{}-{}", kFamilyName[fam.sensor ? 1 : 0], to_string(fam.link));
}

// The fast computation's changes to a seed's case: the tracker's and the sensor's 1 kHz noise from the
// faster generator (the draws that set a run's course, its drift, clock and zero drift, stay the
// reference's). The cell's sizes and what it shows the compensators stay as they are.
void use_fast_computation(CaseConfig& c) {
  c.cell.sensor.fast_noise = true;
  c.cell.tracker.fast_noise = true;
  // The arm's deflected configuration to 1e-8 rad (error left ~1e-11 rad; its kinematics within
  // 30 nm at the TCP), and a loaded tick's arm and bar agreeing to 0.25 N (0.25-0.4 um of TCP at the
  // arm's 1-1.6 um/N: 20 times below the tracker's 5 um noise, and below the bar's own 2 N of noise).
  c.cell.robot.fixed_point_step_rad = 1e-8;
  // And a first step below 1e-5 rad ends it (error left ~1.3e-8 rad, ~30 nm at the TCP), the end
  // poses moved along the Jacobian already taken: one forward kinematics a solve instead of two.
  c.cell.robot.first_order_step_rad = 1e-5;
  c.coupled_tick.force_tolerance_n = 0.25;
  c.coupled_tick.moment_tolerance_nm = 5e-3;
  // The bar settled against the arm's linear response to 20 nm (at most 11 mN of seal force, a
  // twentieth of the tolerance above) before each solve of the arm.
  c.coupled_tick.settle_tolerance_m = 2e-8;
}

// The seeds' cases, the physical setups and families the setups need, and every speed an unloaded
// reference is run at.
void plan_seeds_and_families(StudyContext& x) {
  const CaseConfig& config = x.config;
  x.seed_config.assign(static_cast<std::size_t>(x.n_seeds), config);
  for (int si = 0; si < x.n_seeds; ++si) {
    CaseConfig& c = x.seed_config[static_cast<std::size_t>(si)];
    c.seed = config.seed + static_cast<std::uint64_t>(si);
    if (!x.options.exact) use_fast_computation(c);
  }
  for (const auto& s : config.setups) {
    x.need_cell[s.sensor_mounted ? 1 : 0] = true;
    if (x.family_of(s) < 0) {
      x.families.push_back(Family{s.sensor_mounted, s.link});
      x.family_seeds.push_back(0);
    }
    int& fs = x.family_seeds[static_cast<std::size_t>(x.family_of(s))];
    fs = std::max(fs, x.seeds_of(s));
  }
  x.cells.resize(static_cast<std::size_t>(x.n_seeds));
  x.speeds = config.speeds_m_s;
  auto add_speed = [&](double v) {
    if (std::none_of(x.speeds.begin(), x.speeds.end(), [&](double u) { return mm_s(u) == mm_s(v); })) {
      x.speeds.push_back(v);
    }
  };
  if (x.options.speed_sweep) {
    for (double v : config.sweep_speeds_m_s) add_speed(v);
  }
  if (x.options.error_budget) add_speed(config.budget.speed_m_s);
}

// Plans a loaded run unless it is planned already (a family's setups share their uncompensated runs).
void add_loaded_run(StudyContext& x, int si, int fam, RunKind kind, Strategy strategy, double load, double speed) {
  if (x.find(si, fam, kind, strategy, load, speed) != nullptr) return;
  LoadedJob j{si, fam, kind, strategy, load, speed, {}, {}, {}};
  x.loaded.push_back(std::move(j));
}

// The loaded runs of every seed (the tables', the sweep's, the budget's) and which of the first
// seed's are plotted or have their traces written.
void plan_loaded_runs(StudyContext& x) {
  const CaseConfig& config = x.config;
  for (int si = 0; si < x.n_seeds; ++si) {
    for (const auto& s : config.setups) {
      if (si >= x.seeds_of(s)) continue;
      const int fam = x.family_of(s);
      for (double load : s.loads_n) {
        for (double v : config.speeds_m_s) {
          add_loaded_run(x, si, fam, RunKind::kUncompensated, s.strategy, load, v);
          add_loaded_run(x, si, fam, RunKind::kCompensated, s.strategy, load, v);
        }
      }
      if (x.options.speed_sweep) {
        for (double v : config.sweep_speeds_m_s) {
          add_loaded_run(x, si, fam, RunKind::kUncompensated, s.strategy, x.sweep_load(s), v);
          add_loaded_run(x, si, fam, RunKind::kCompensated, s.strategy, x.sweep_load(s), v);
        }
      }
    }
  }
  if (x.options.error_budget) {
    for (const auto& s : config.setups) {
      // A setup the budget does not run may have fewer loads (the case file checks only the budget's).
      if (static_cast<std::size_t>(config.budget.load_index) >= s.loads_n.size()) continue;
      const double load = s.loads_n[static_cast<std::size_t>(config.budget.load_index)];
      add_loaded_run(x, 0, x.family_of(s), RunKind::kUncompensated, s.strategy, load, config.budget.speed_m_s);
      add_loaded_run(x, 0, x.family_of(s), RunKind::kCompensated, s.strategy, load, config.budget.speed_m_s);
    }
  }
  // Plot: each setup's highest load at the first speed, first seed. Traces written: the first
  // seed's runs at the highest load and the budget's speed.
  for (auto& j : x.loaded) {
    if (j.seed != 0) continue;
    for (const auto& s : config.setups) {
      if (x.family_of(s) != j.family || j.load_n != s.loads_n.back()) continue;
      if (j.kind == RunKind::kUncompensated || j.strategy == s.strategy) {
        if (x.plotted(j.seed, j.speed)) j.plot = true;
        if (mm_s(j.speed) == mm_s(config.budget.speed_m_s) && x.options.trace_sink) j.write_trace = true;
      }
    }
  }
}

// Error budget, first seed: the offline setup and the paper's online one (position guidance).
// "Every effect" is the table's own run; each effect off is a cell built without it (its own
// calibration) running the same runs with the same seeds.
void plan_error_budget(StudyContext& x) {
  if (!x.options.error_budget) return;
  for (std::size_t i : budget_setups(x.config)) {
    const auto& sc = x.config.setups[i];
    const bool offline = sc.strategy == Strategy::kOffline;
    if (static_cast<std::size_t>(x.config.budget.load_index) >= sc.loads_n.size()) continue;
    x.budget_setups.push_back(static_cast<int>(i));
    for (Effect e : kAllEffects) {
      const bool sensor_only =
          e == Effect::kSensorCompliance || e == Effect::kSensorDrift || e == Effect::kSensorMoment;
      if (sensor_only && !sc.sensor_mounted) continue;
      if ((e == Effect::kSensorErrors || e == Effect::kSensorCalibration || e == Effect::kLatency) && offline) continue;
      x.budget_jobs.push_back(BudgetJob{static_cast<int>(i), e, NAN, {}});
    }
    // And every effect off at once, so the reader sees what the one-at-a-time figures do not add up to.
    x.budget_jobs.push_back(BudgetJob{static_cast<int>(i), std::nullopt, NAN, {}});
  }
}

// The progress's weights: the simulated seconds of every calibration and run.
void weigh_progress(StudyContext& x) {
  const CaseConfig& config = x.config;
  x.cal_cost = calibration_cost(config);
  for (int si = 0; si < x.n_seeds; ++si) {
    for (int f = 0; f < 2; ++f) {
      if (x.need_cell[f]) x.progress.total += x.cal_cost;
    }
    for (std::size_t f = 0; f < x.families.size(); ++f) {
      if (si >= x.family_seeds[f]) continue;
      for (double v : x.speeds) x.progress.total += run_cost(config, v, x.laps);
    }
  }
  for (const auto& j : x.loaded) x.progress.total += run_cost(config, j.speed, x.laps);
  for (std::size_t i = 0; i < x.budget_jobs.size(); ++i) {
    x.progress.total += x.cal_cost + 2.0 * run_cost(config, config.budget.speed_m_s, x.laps);
  }
}

// Phase 1: the calibrations, one per seed and physical setup. Returns how many.
int run_calibrations(StudyContext& x) {
  int calibrations = 0;
  std::vector<std::function<void()>> jobs;
  for (int si = 0; si < x.n_seeds; ++si) {
    for (int f = 0; f < 2; ++f) {
      if (!x.need_cell[f]) continue;
      jobs.emplace_back([&x, si, f] {
        const double start = thread_cpu_s();
        auto& slot = x.cells[static_cast<std::size_t>(si)][static_cast<std::size_t>(f)];
        slot.emplace(build_setup_cell(x.cfg_of(si), f == 1));
        x.charge(&StudyPhaseTimes::calibration_s, start);
        x.progress.add(x.cal_cost, fmt::format("seed {}: calibration, {}", x.cfg_of(si).seed,
                                               f == 1 ? "sensor mounted" : "no sensor"));
      });
      ++calibrations;
    }
  }
  run_parallel(jobs, x.options.threads);
  return calibrations;
}

// Phase 2 of a seed and family: its unloaded runs, the references at every speed (slowest first so
// both cores finish together).
void run_unloaded_references(StudyContext& x, int si, std::size_t f) {
  for (double v : x.speeds) x.unloaded[{si, static_cast<int>(f), mm_s(v)}];  // slots before the threads start
  std::vector<double> speeds = x.speeds;
  std::stable_sort(speeds.begin(), speeds.end());
  std::vector<std::function<void()>> jobs;
  for (double v : speeds) {
    jobs.emplace_back([&x, si, f, v] {
      const Family& fam = x.families[f];
      const double start = thread_cpu_s();
      RunOutput run = simulate_run(x.cfg_of(si), x.cell_of(si, fam.sensor), x.unloaded_spec(si, fam, v));
      const double simulated = x.charge(&StudyPhaseTimes::unloaded_s, start);
      if (si == 0 && x.options.trace_sink && mm_s(v) == mm_s(x.config.budget.speed_m_s)) {
        x.sink(fmt::format("{}_unloaded_{}mm_s", family_label(fam), mm_s(v)), run.trace);
      }
      x.unloaded.at({si, static_cast<int>(f), mm_s(v)}) = make_reference(std::move(run), x.plotted(si, v));
      x.charge(&StudyPhaseTimes::evaluation_s, simulated);
      x.progress.add(run_cost(x.config, v, x.laps),
                     fmt::format("seed {}: unloaded {} mm/s", x.cfg_of(si).seed, mm_s(v)));
    });
  }
  run_parallel(jobs, x.options.threads);
}

// After a family's runs of a seed: its references' traces and indexes are no longer needed (the
// tables keep figures, the plots thinned laps), so the study holds one family's references at a time.
void release_references(StudyContext& x, int si, std::size_t f) {
  for (auto& [key, ref] : x.unloaded) {
    if (std::get<0>(key) != si || std::get<1>(key) != static_cast<int>(f)) continue;
    ref.run.trace = TrackerTrace();
    ref.index.reset();
  }
}

// One loaded run: simulated, evaluated against its unloaded reference, what its link did kept, and
// its trace written or kept when planned so.
void run_loaded_job(StudyContext& x, LoadedJob& j) {
  const Family& fam = x.families[static_cast<std::size_t>(j.family)];
  const RunSpec spec = x.loaded_spec(j.seed, fam, j.kind, j.strategy, j.load_n, j.speed);
  const double start = thread_cpu_s();
  RunOutput run = simulate_run(x.cfg_of(j.seed), x.cell_of(j.seed, fam.sensor), spec);
  const double simulated = x.charge(&StudyPhaseTimes::loaded_s, start);
  j.figures = evaluate_run(run, x.unloaded.at({j.seed, j.family, mm_s(j.speed)}));
  j.link_cycles = run.link_cycles;
  j.rejected = run.link_counters.rejected();
  j.guard_trips = run.link_counters.guard_trips;
  j.max_deviation_rad = run.max_command_deviation_rad;
  j.max_tcp_m = run.max_tcp_correction_m;
  j.delay_s = run.measured_delay_s;
  j.controller_events = run.controller_events;
  j.controller_peak = run.controller_peak;
  j.coupled = run.coupled;
  if (j.write_trace) {
    x.sink(fmt::format("{}_{}_{:.0f}N_{}mm_s", family_label(fam),
                       j.kind == RunKind::kUncompensated ? "uc" : to_string(j.strategy), j.load_n, mm_s(j.speed)),
           run.trace);
  }
  if (j.plot) {
    j.plot_lap = thin_lap(run, kPlotPoints);
    j.plot_all_laps = plot_laps(run, kPlotLapPoints);
  }
  x.charge(&StudyPhaseTimes::evaluation_s, simulated);
  x.progress.add(
      run_cost(x.config, j.speed, x.laps),
      fmt::format("seed {}: {} {} N {} mm/s", x.cfg_of(j.seed).seed,
                  j.kind == RunKind::kUncompensated ? "UC" : to_string(j.strategy), j.load_n, mm_s(j.speed)));
}

// The first seed's case without the budget job's effect, or without every effect of the cell (the
// ones a setup's budget does not list act on no run of that setup). The calibration is kept: the
// compensators still get a model identified on that cell, not the exact one.
CaseConfig budget_case(const StudyContext& x, const BudgetJob& bj) {
  if (bj.off) return without_effect(x.cfg_of(0), *bj.off);
  CaseConfig cfg = x.cfg_of(0);
  for (Effect e : kAllEffects) cfg = without_effect(cfg, e);
  return cfg;
}

// One run of the error budget: a cell built without the effect (its own calibration), its unloaded
// reference and the setup's compensated run at the budget's load and speed.
void run_budget_job(StudyContext& x, BudgetJob& bj) {
  const double start = thread_cpu_s();
  const CaseConfig& config = x.config;
  const SetupConfig& sc = config.setups[static_cast<std::size_t>(bj.setup)];
  const Family& fam = x.families[static_cast<std::size_t>(x.family_of(sc))];
  const CaseConfig cfg = budget_case(x, bj);
  const SetupCell cell = build_setup_cell(cfg, sc.sensor_mounted);
  const double load = sc.loads_n[static_cast<std::size_t>(config.budget.load_index)];
  const double v = config.budget.speed_m_s;
  const Reference reference = make_reference(simulate_run(cfg, cell, x.unloaded_spec(0, fam, v)), false);
  const RunSpec c_spec = x.loaded_spec(0, fam, RunKind::kCompensated, sc.strategy, load, v);
  const RunOutput run = simulate_run(cfg, cell, c_spec);
  bj.residual_mm = evaluate_run(run, reference).mean_mm;
  bj.coupled = cell.calibration.coupled;
  bj.coupled.add(run.coupled);
  x.charge(&StudyPhaseTimes::budget_s, start);
  x.progress.add(x.cal_cost + 2.0 * run_cost(config, v, x.laps), fmt::format("budget: {}", budget_label(bj)));
}

// Phase 3 of a seed and family: its loaded runs (slowest first so both cores finish together) and,
// with `budget`, the error budget's runs (they make their own references).
void run_loaded_and_budget_runs(StudyContext& x, int si, std::size_t f, bool budget) {
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < x.loaded.size(); ++i) {
    if (x.loaded[i].seed == si && x.loaded[i].family == static_cast<int>(f)) order.push_back(i);
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return x.loaded[a].speed < x.loaded[b].speed; });
  std::vector<std::function<void()>> jobs;
  for (std::size_t i : order) jobs.emplace_back([&x, i] { run_loaded_job(x, x.loaded[i]); });
  if (budget) {
    for (auto& bj : x.budget_jobs) jobs.emplace_back([&x, &bj] { run_budget_job(x, bj); });
  }
  run_parallel(jobs, x.options.threads);
}

// The mean of the finite values (a figure a seed could not give is left out); NaN when none is.
double mean_over_seeds(const std::vector<double>& values) {
  double sum = 0.0;
  int n = 0;
  for (double v : values) {
    if (std::isfinite(v)) {
      sum += v;
      ++n;
    }
  }
  return n > 0 ? sum / n : NAN;
}

// What a setup's controller counted of deflex's stream, in words (see LinkSummary::controller_note).
std::string controller_note(LinkKind link, std::uint64_t events, double peak) {
  switch (link) {
    case LinkKind::kRsi:
      return fmt::format("{} late cycles (RSI's Delay)", events);
    case LinkKind::kFanucJ519:
      return fmt::format("peak jerk {:.0f} % of the controller's limit, no limit stop", peak * 100.0);
    case LinkKind::kMotoros2Rt:
      return fmt::format("{} increments truncated by the safety unit", events);
    case LinkKind::kUrRtde:
      return "no protective stop";
    default:
      return "";
  }
}

// What the link of a setup did over its compensated runs, and the compensation it reached at its
// highest load (`top`, the setup's figures there); none for a setup that runs a program.
std::optional<LinkSummary> summarize_link(const StudyContext& x, const SetupConfig& s, int fam, const LoadResult& top) {
  if (s.link == LinkKind::kProgram) return std::nullopt;
  LinkSummary ls;
  ls.setup = s.name;
  ls.link = to_string(s.link);
  ls.joint_commands = s.link != LinkKind::kEgmPath;
  ls.bound_rad = x.config.online.max_joint_correction_rad;
  int delay_runs = 0;
  std::uint64_t events = 0;
  double peak = 0.0;
  for (const auto& j : x.loaded) {
    if (j.family != fam || j.kind != RunKind::kCompensated || j.strategy != s.strategy) continue;
    ls.cycles += j.link_cycles;
    ls.rejected += j.rejected;
    ls.guard_trips += j.guard_trips;
    ls.max_command_deviation_rad = std::max(ls.max_command_deviation_rad, j.max_deviation_rad);
    ls.max_tcp_correction_m = std::max(ls.max_tcp_correction_m, j.max_tcp_m);
    events += j.controller_events;
    peak = std::max(peak, j.controller_peak);
    if (std::isfinite(j.delay_s)) {
      ls.measured_delay_s += j.delay_s;
      ++delay_runs;
    }
  }
  ls.measured_delay_s = delay_runs > 0 ? ls.measured_delay_s / delay_runs : NAN;
  ls.controller_note = controller_note(s.link, events, peak);
  ls.load_n = top.load_N;
  ls.uc_mm = top.uc_mean_mm();
  std::vector<double> c;
  for (const auto& [speed, value] : top.c_mm) c.push_back(value);
  ls.c_mm = mean_over_seeds(c);
  std::vector<int> speeds;
  for (double v : x.config.speeds_m_s) speeds.push_back(mm_s(v));
  ls.compensation = printed_compensation_spread(top, speeds).mean;
  return ls;
}

// A setup's figures at one load: per speed the seeds' figures and their means.
LoadResult load_result(const StudyContext& x, const SetupConfig& s, int fam, double load) {
  LoadResult lr;
  lr.load_N = load;
  for (double v : x.config.speeds_m_s) {
    const int key = mm_s(v);
    std::vector<double> uc_std, uc_max, iso_uc, c_std, c_max, iso_c, iso_rep;
    for (int si = 0; si < x.seeds_of(s); ++si) {
      const LoadedJob* uc = x.find(si, fam, RunKind::kUncompensated, s.strategy, load, v);
      const LoadedJob* c = x.find(si, fam, RunKind::kCompensated, s.strategy, load, v);
      lr.uc_mm_by_seed[key].push_back(uc->figures.mean_mm);
      lr.c_mm_by_seed[key].push_back(c->figures.mean_mm);
      lr.uc_sync_mm_by_seed[key].push_back(uc->figures.sync_mm);
      lr.c_sync_mm_by_seed[key].push_back(c->figures.sync_mm);
      uc_std.push_back(uc->figures.std_mm);
      uc_max.push_back(uc->figures.max_mm);
      iso_uc.push_back(uc->figures.iso_accuracy_mm);
      c_std.push_back(c->figures.std_mm);
      c_max.push_back(c->figures.max_mm);
      iso_c.push_back(c->figures.iso_accuracy_mm);
      iso_rep.push_back(c->figures.iso_repeatability_mm);
    }
    lr.uc_std_mm[key] = mean_over_seeds(uc_std);
    lr.uc_max_mm[key] = mean_over_seeds(uc_max);
    lr.iso_accuracy_uc_mm[key] = mean_over_seeds(iso_uc);
    lr.c_std_mm[key] = mean_over_seeds(c_std);
    lr.c_max_mm[key] = mean_over_seeds(c_max);
    lr.iso_accuracy_c_mm[key] = mean_over_seeds(iso_c);
    lr.iso_repeatability_mm[key] = mean_over_seeds(iso_rep);
  }
  lr.fill_means();
  return lr;
}

// The speed sweep of a setup, at its load nearest to the sweep's: per speed the seeds' figures.
void add_sweep_points(const StudyContext& x, const SetupConfig& s, int fam, StudyResult& study) {
  const double load = x.sweep_load(s);
  for (double v : x.config.sweep_speeds_m_s) {
    SweepPoint p;
    p.setup = s.name;
    p.load_N = load;
    p.speed_mm_s = v * 1e3;
    for (int si = 0; si < x.seeds_of(s); ++si) {
      const LoadedJob* uc = x.find(si, fam, RunKind::kUncompensated, s.strategy, load, v);
      const LoadedJob* c = x.find(si, fam, RunKind::kCompensated, s.strategy, load, v);
      p.uc_mm_by_seed.push_back(uc->figures.mean_mm);
      p.c_mm_by_seed.push_back(c->figures.mean_mm);
      p.c_sync_mm_by_seed.push_back(c->figures.sync_mm);
    }
    p.uc_mm = mean_over_seeds(p.uc_mm_by_seed);
    p.c_mm = mean_over_seeds(p.c_mm_by_seed);
    p.c_sync_mm = mean_over_seeds(p.c_sync_mm_by_seed);
    p.compensation = compensation_ratio(p.uc_mm, p.c_mm);
    study.speed_sweep.push_back(p);
  }
}

// The path plot of a setup: its first seed's runs at its highest load and the first speed.
void add_plot_traces(const StudyContext& x, const SetupConfig& s, int fam, CaseStudyOutput& out) {
  const double v0 = x.config.speeds_m_s.front();
  const LoadedJob* uc = x.find(0, fam, RunKind::kUncompensated, s.strategy, s.loads_n.back(), v0);
  const LoadedJob* c = x.find(0, fam, RunKind::kCompensated, s.strategy, s.loads_n.back(), v0);
  if (!uc || !c || uc->plot_lap.empty() || c->plot_lap.empty()) return;
  const Reference& ref = x.unloaded.at({0, fam, mm_s(v0)});
  PlotTraces pt;
  pt.setup = s.name;
  pt.load_n = s.loads_n.back();
  pt.speed_mm_s = mm_s(v0);
  pt.title = fmt::format("{}: {:.0f} N at {} mm/s (seed {})", s.name, s.loads_n.back(), mm_s(v0), x.config.seed);
  pt.unloaded = ref.plot_lap;
  pt.unloaded_mean = thin(ref.mean, kPlotPoints);
  pt.uc = uc->plot_lap;
  pt.c = c->plot_lap;
  pt.uc_laps = uc->plot_all_laps;
  pt.c_laps = c->plot_all_laps;
  out.plots.push_back(std::move(pt));
}

// Per setup: what its link did, its figures per load and speed, its speed sweep and its path plot.
void assemble_setups(const StudyContext& x, CaseStudyOutput& out) {
  for (const auto& s : x.config.setups) {
    const int fam = x.family_of(s);
    SetupResult sr;
    sr.setup = s.name;
    sr.description = describe(s.strategy, s.link, x.config.online.stream_period_s);
    // Online compensation streamed over TCP is the paper's own kind of link: its Table 2 is what such
    // a setup compares with, beside the EGM setup that carries the table's figures.
    if (s.strategy == Strategy::kOnline && s.link == LinkKind::kSimpleMessage && s.sensor_mounted &&
        s.paper_uc_mm.empty() && paper_reference().table_for(s.name) == nullptr) {
      sr.paper_table = "online";
      sr.paper_label =
          fmt::format("simple message, {:g} ms (the paper's kind of link)", x.config.online.stream_period_s * 1e3);
    }
    for (double load : s.loads_n) sr.loads.push_back(load_result(x, s, fam, load));
    if (const auto ls = summarize_link(x, s, fam, sr.loads.back())) out.links.push_back(*ls);
    out.study.setups.push_back(sr);
    if (x.options.speed_sweep) add_sweep_points(x, s, fam, out.study);
    add_plot_traces(x, s, fam, out);
  }
}

// The error budgets: per budget setup the table's own residual and the residual with each effect off.
void assemble_error_budgets(const StudyContext& x, StudyResult& study) {
  const CaseConfig& config = x.config;
  for (int si : x.budget_setups) {
    const SetupConfig& sc = config.setups[static_cast<std::size_t>(si)];
    const int fam = x.family_of(sc);
    ErrorBudget b;
    b.setup = sc.name;
    b.load_N = sc.loads_n[static_cast<std::size_t>(config.budget.load_index)];
    b.speed_mm_s = mm_s(config.budget.speed_m_s);
    b.seed = config.seed;
    b.laps = x.laps;
    b.residual_mm_all =
        x.find(0, fam, RunKind::kCompensated, sc.strategy, b.load_N, config.budget.speed_m_s)->figures.mean_mm;
    b.uc_mm = x.find(0, fam, RunKind::kUncompensated, sc.strategy, b.load_N, config.budget.speed_m_s)->figures.mean_mm;
    for (const auto& bj : x.budget_jobs) {
      if (bj.setup != si) continue;
      if (!bj.off) {
        b.residual_mm_all_off = bj.residual_mm;
        continue;
      }
      b.entries.push_back(ErrorBudgetEntry{to_string(*bj.off), effect_size(config, *bj.off), bj.residual_mm,
                                           one_at_a_time_sensitivity(b.residual_mm_all, bj.residual_mm)});
    }
    study.error_budgets.push_back(std::move(b));
  }
}

// The physical setup without (f = 0) or with (f = 1) the sensor in words: the first seed's true and
// identified stiffness and calibration, and how far the identified model is off the true arm.
std::string describe_cell(const StudyContext& x, int f) {
  const CaseConfig& config = x.config;
  const SetupCell& cell = x.cell_of(0, f == 1);
  std::string k_true, k_id;
  const auto& kt = cell.robot->true_model().stiffness();
  const auto& ki = cell.calibration.identified.stiffness();
  for (int j = 0; j < kt.size(); ++j) {
    k_true += fmt::format("{}{:.3g}", j ? ", " : "", kt[j]);
    k_id += fmt::format("{}{:.3g}", j ? ", " : "", ki[j]);
  }
  std::string text = fmt::format(
      "Setup {} the force sensor (seed {}): true joint stiffness (diagonal, Nm/rad) [{}]; identified from {} "
      "calibration measurements taken while moving along {} arcs in the operating space [{}] (residual {:.1f} um "
      "RMS). The identified values are the lumped joint model's best fit to those measurements: what the cell has "
      "beyond that model (the error budget lists its effects) is folded into them or left in the residual.",
      f == 1 ? "with" : "without", config.seed, k_true, cell.calibration.measurements, config.calibration.arcs, k_id,
      cell.calibration.estimate.residual_rms_m * 1e6);
  // What the calibration did about joints it could not identify: measured again, or kept at the
  // assumed stiffness (and why); the identification's own warnings stay in the calibration's notes.
  for (const auto& note : cell.calibration.notes) {
    if (note.find("kept the assumed") != std::string::npos || note.find("measured again") != std::string::npos ||
        note.find("no load the bar") != std::string::npos) {
      text += " Calibration: " + note + ".";
    }
  }
  // How far the identified model is from the true arm on the circle, per seed (a diagnostic from
  // the simulator's truth; no strategy sees it).
  double load = 0.0;
  for (const auto& s : config.setups) {
    if (s.sensor_mounted == (f == 1)) load = std::max(load, s.loads_n.back());
  }
  std::vector<double> errors, scales;
  for (int si = 0; si < x.n_seeds; ++si) {
    double scale = NAN;
    errors.push_back(identified_model_error(x.cfg_of(si), x.cell_of(si, f == 1), load, &scale));
    scales.push_back(scale);
  }
  const Spread e = spread_of(errors), sc = spread_of(scales);
  text += fmt::format(
      " On the circle at {:.0f} N the identified model's static deflection is off the true arm's by {:.0f} % on "
      "average (its length {:.0f} % of the true one){}.",
      load, e.mean * 100, sc.mean * 100,
      x.n_seeds > 1 ? fmt::format("; over the {} seeds {:.0f}-{:.0f} % and {:.0f}-{:.0f} %", x.n_seeds, e.min * 100,
                                  e.max * 100, sc.min * 100, sc.max * 100)
                    : std::string());
  return text;
}

// The circle, the laps, the tracker, the controller's links and the seeds in words.
std::string describe_protocol(const StudyContext& x) {
  const CaseConfig& config = x.config;
  const int n_seeds = x.n_seeds;
  const auto& k = config.cell.controller;
  return fmt::format(
      "Circle of radius {:.1f} mm around ({:.0f}, {:.0f}, {:.0f}) mm in the base XY plane, tool pointing down, "
      "{} programmed configurations; LDBB bar {:.0f} mm inclined by {:.0f} deg (pivot below the centre); {} clockwise "
      "+ {} anticlockwise laps per run; tracker at {:.0f} Hz with {:.1f} um noise; servo {:.0f} ms. The online setups "
      "reach the controller through deflex's own links over the cell's network: EGM position guidance (deflex streams "
      "the program every {:.0f} ms; the controller follows after {:.0f} ms of dead time through a {:.0f} Hz filter, "
      "gain {:.0f}/s plus deflex's speed reference), EGM path correction (the controller asks every {:.0f} ms and "
      "applies an offset {:.0f} ms later) or ROS-Industrial simple message (deflex streams a joint point every {:.0f} "
      "ms over TCP to the robot program's streaming server, {} queued, each run as a joint move with a zone). {} "
      "seed{} ({}{}): each its own true robot, sensor and calibration; the tables give the mean over them and their "
      "spread.",
      config.radius_m() * 1e3, config.circle.center_m.x() * 1e3, config.circle.center_m.y() * 1e3,
      config.circle.center_m.z() * 1e3, config.circle.points, config.cell.ldbb.bar_length_m * 1e3,
      rad_to_deg(config.cell.ldbb.inclination_rad), x.laps_cw, x.laps_ccw, config.cell.tracker.rate_hz,
      config.cell.tracker.noise_m * 1e6, k.servo_period_s * 1e3, k.egm_period_s * 1e3, k.egm_dead_time_s * 1e3,
      k.egm_lowpass_hz, k.egm_position_gain_per_s, k.path_corr_period_s * 1e3, k.path_corr_dead_time_s * 1e3,
      config.online.stream_period_s * 1e3, config.online.stream_buffer_depth, n_seeds, n_seeds == 1 ? "" : "s",
      config.seed, n_seeds == 1 ? std::string() : fmt::format(" to {}", x.cfg_of(n_seeds - 1).seed));
}
}  // namespace

std::string describe_coupled_solves(const cell::CoupledTickCounters& c, const cell::CoupledTickOptions& o) {
  std::string text = fmt::format(
      "Every loaded servo tick of the cell solves the arm and the bar's force together (Newton's method: the force "
      "the bar gives where the arm then stands within {:g} N of the force the arm was solved under, at most {} "
      "solves of the arm a tick), so no force lags the arm by a tick: {} loaded ticks, {:.2f} solves of the arm a "
      "tick, at most {} in one tick; ",
      o.force_tolerance_n, o.max_arm_solves, c.ticks,
      c.ticks > 0 ? static_cast<double>(c.arm_solves) / static_cast<double>(c.ticks) : 0.0, c.most_arm_solves);
  text += c.unconverged == 0 ? std::string("every one converged.")
                             : fmt::format("{} reached the cap without converging (the worst left {:.3f} N apart).",
                                           c.unconverged, c.worst_mismatch_n);
  return text;
}

void run_parallel(std::vector<std::function<void()>>& jobs, int threads) {
  if (threads <= 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  threads = std::min<int>(threads, static_cast<int>(jobs.size()));
  std::atomic<std::size_t> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto worker = [&] {
    for (std::size_t i = next++; i < jobs.size(); i = next++) {
      try {
        jobs[i]();
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

CaseStudyOutput run_case_study(const CaseConfig& config, const CaseStudyOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  CaseStudyOutput out;
  StudyContext x(config, options);
  plan_seeds_and_families(x);
  plan_loaded_runs(x);
  plan_error_budget(x);
  weigh_progress(x);
  out.calibrations = run_calibrations(x);
  // Seed by seed and family by family, so that only one family's unloaded references (the long
  // traces) are held at a time; the budget's runs go with the first seed's last family. Every run's
  // seed comes from what it is, never from when it runs, so the order moves no figure.
  for (int si = 0; si < x.n_seeds; ++si) {
    std::size_t last = 0;
    for (std::size_t f = 0; f < x.families.size(); ++f) {
      if (si < x.family_seeds[f]) last = f;
    }
    for (std::size_t f = 0; f < x.families.size(); ++f) {
      if (si >= x.family_seeds[f]) continue;
      run_unloaded_references(x, si, f);
      run_loaded_and_budget_runs(x, si, f, si == 0 && f == last);
      release_references(x, si, f);
    }
  }

  // Assemble the study: per setup, load and speed the seeds' figures, their means and spread.
  const double assembly_start = thread_cpu_s();
  StudyResult& study = out.study;
  study.case_name = config.name;
  study.seed = config.seed;
  for (int si = 0; si < x.n_seeds; ++si) study.seeds.push_back(x.cfg_of(si).seed);
  for (double v : config.speeds_m_s) study.speeds_mm_s.push_back(mm_s(v));
  assemble_setups(x, out);
  assemble_error_budgets(x, study);

  // The cells (the first seed's) and the protocol in words.
  for (int f = 0; f < 2; ++f) {
    if (x.need_cell[f]) out.setup_paragraphs.push_back(describe_cell(x, f));
  }
  out.setup_paragraphs.push_back(describe_protocol(x));
  out.runs = static_cast<int>(x.loaded.size()) + static_cast<int>(x.budget_jobs.size()) * 2;
  for (int fs : x.family_seeds) out.runs += fs * static_cast<int>(x.speeds.size());
  out.calibrations += static_cast<int>(x.budget_jobs.size());
  out.simulated_s = x.progress.total;
  for (const auto& j : x.loaded) out.coupled.add(j.coupled);
  for (const auto& bj : x.budget_jobs) out.coupled.add(bj.coupled);
  for (const auto& seed_cells : x.cells) {
    for (const auto& cell : seed_cells) {
      if (cell) out.coupled.add(cell->calibration.coupled);
    }
  }
  out.coupled_options = x.cfg_of(0).coupled_tick;
  out.setup_paragraphs.push_back(describe_coupled_solves(out.coupled, out.coupled_options));
  x.charge(&StudyPhaseTimes::assembly_s, assembly_start);
  out.phases = x.phases;
  study.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace deflex::study
