// The protocol runner of the simulated case study (see case_study.hpp).
#include "deflex/study/case_study.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <tuple>
#include <array>
#include <thread>

#include "deflex/evaluate/iso9283_path.hpp"
#include "deflex/evaluate/lap_split.hpp"
#include "deflex/model/tracker_trace.hpp"
#include "deflex/evaluate/path_metrics.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/study/detail/simulated_run.hpp"

namespace deflex::study {
namespace {

int mm_s(double speed_m_s) { return static_cast<int>(std::lround(speed_m_s * 1e3)); }

struct Figures {
  double mean_mm = 0, std_mm = 0, max_mm = 0, sync_mm = NAN, iso_accuracy_mm = NAN, iso_repeatability_mm = NAN;
};

// The laps of a run, found in its tracker trace the way `deflex evaluate --split-laps` finds them
// (by the angle turned about the path's centre), not from the simulator's schedule.
std::vector<TrackerTrace> laps_of(const TrackerTrace& trace) { return split_laps(trace).laps; }

// An unloaded run prepared once for every loaded run compared with it: its raw trace (for the
// time-synchronous metric) and the mean of its laps, indexed (for the nearest-point metric: a dense,
// noisy reference would bias that distance low by its own noise).
struct Reference {
  RunOutput run;
  TrackerTrace mean;
  std::shared_ptr<const PolylineIndex> index;
};

Reference make_reference(RunOutput run) {
  Reference r;
  r.mean = mean_closed_path(run.trace);
  r.index = std::make_shared<const PolylineIndex>(r.mean);
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
  return 2.0 * c.calibration.arcs * (hold_s + c.calibration.arc_rad * c.cell.ldbb.bar_length_m / c.calibration.speed_m_s);
}

const char* describe(Strategy s, LinkKind link) {
  switch (s) {
    case Strategy::kOffline:
      return "offline compensation from the LDBB force model (paper, Figure 2): the controller runs the compensated "
             "program";
    case Strategy::kOnline:
      switch (link) {
        case LinkKind::kEgmPath:
          return "online compensation from the force sensor (paper, Figure 3) over ABB EGM path correction";
        case LinkKind::kSimpleMessage:
          return "online compensation from the force sensor (paper, Figure 3) streamed every 100 ms over TCP to the "
                 "robot program (simple message): the paper's own kind of link";
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

}  // namespace

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
  const int laps_cw = options.quick ? std::min(1, config.laps_cw) : config.laps_cw;
  const int laps_ccw = options.quick ? std::min(1, config.laps_ccw) : config.laps_ccw;
  const int laps = laps_cw + laps_ccw;
  Progress progress;
  progress.options = &options;

  // The seeds: each one its own cell (true robot, sensor, calibrations) and runs.
  const int n_seeds = options.seeds > 0 ? options.seeds : std::max(1, config.seeds);
  std::vector<CaseConfig> seed_config(static_cast<std::size_t>(n_seeds), config);
  for (int si = 0; si < n_seeds; ++si) seed_config[static_cast<std::size_t>(si)].seed = config.seed + static_cast<std::uint64_t>(si);
  auto cfg_of = [&](int si) -> const CaseConfig& { return seed_config[static_cast<std::size_t>(si)]; };

  // The physical setups (with and without the sensor) and the families of runs.
  bool need_cell[2] = {false, false};
  std::vector<Family> families;
  auto family_of = [&](const SetupConfig& s) {
    for (std::size_t i = 0; i < families.size(); ++i) {
      if (families[i].sensor == s.sensor_mounted && families[i].link == s.link) return static_cast<int>(i);
    }
    families.push_back(Family{s.sensor_mounted, s.link});
    return static_cast<int>(families.size()) - 1;
  };
  for (const auto& s : config.setups) {
    need_cell[s.sensor_mounted ? 1 : 0] = true;
    (void)family_of(s);
  }
  std::vector<std::array<std::optional<SetupCell>, 2>> cells(static_cast<std::size_t>(n_seeds));
  std::vector<double> speeds = config.speeds_m_s;
  auto add_speed = [&](double v) {
    if (std::none_of(speeds.begin(), speeds.end(), [&](double u) { return mm_s(u) == mm_s(v); })) speeds.push_back(v);
  };
  if (options.speed_sweep) {
    for (double v : config.sweep_speeds_m_s) add_speed(v);
  }
  if (options.error_budget) add_speed(config.budget.speed_m_s);
  // The sweep runs each setup at its load nearest to sweep_load_n.
  auto sweep_load = [&](const SetupConfig& s) {
    return *std::min_element(s.loads_n.begin(), s.loads_n.end(), [&](double a, double b) {
      return std::abs(a - config.sweep_load_n) < std::abs(b - config.sweep_load_n);
    });
  };

  // Loaded jobs per seed: uncompensated per family, load and speed; compensated per setup, load and
  // speed.
  struct LoadedJob {
    int seed;
    int family;
    RunKind kind;
    Strategy strategy;
    double load_n;
    double speed;
    RunOutput keep;  // only for the plotted runs
    Figures figures;
    bool plot = false;
    bool write_trace = false;
    std::uint64_t link_cycles = 0, rejected = 0, guard_trips = 0;
    double max_deviation_rad = 0.0, max_tcp_m = 0.0, delay_s = 0.0;
  };
  std::vector<LoadedJob> loaded;
  auto find = [&](int si, int fam, RunKind kind, Strategy st, double load, double v) -> LoadedJob* {
    for (auto& j : loaded) {
      if (j.seed == si && j.family == fam && j.kind == kind && (kind != RunKind::kCompensated || j.strategy == st) &&
          j.load_n == load && mm_s(j.speed) == mm_s(v)) {
        return &j;
      }
    }
    return nullptr;
  };
  auto add_loaded = [&](int si, int fam, RunKind kind, Strategy strategy, double load, double speed) {
    if (find(si, fam, kind, strategy, load, speed) != nullptr) return;
    LoadedJob j{si, fam, kind, strategy, load, speed, {}, {}};
    loaded.push_back(std::move(j));
  };
  for (int si = 0; si < n_seeds; ++si) {
    for (const auto& s : config.setups) {
      const int fam = family_of(s);
      for (double load : s.loads_n) {
        for (double v : config.speeds_m_s) {
          add_loaded(si, fam, RunKind::kUncompensated, s.strategy, load, v);
          add_loaded(si, fam, RunKind::kCompensated, s.strategy, load, v);
        }
      }
      if (options.speed_sweep) {
        for (double v : config.sweep_speeds_m_s) {
          add_loaded(si, fam, RunKind::kUncompensated, s.strategy, sweep_load(s), v);
          add_loaded(si, fam, RunKind::kCompensated, s.strategy, sweep_load(s), v);
        }
      }
    }
  }
  if (options.error_budget) {
    for (const auto& s : config.setups) {
      const double load = s.loads_n[static_cast<std::size_t>(config.budget.load_index)];
      add_loaded(0, family_of(s), RunKind::kUncompensated, s.strategy, load, config.budget.speed_m_s);
      add_loaded(0, family_of(s), RunKind::kCompensated, s.strategy, load, config.budget.speed_m_s);
    }
  }
  // Plot: each setup's highest load at the first speed, first seed. Traces written: the first
  // seed's runs at the highest load and the budget's speed.
  for (auto& j : loaded) {
    if (j.seed != 0) continue;
    for (const auto& s : config.setups) {
      if (family_of(s) != j.family || j.load_n != s.loads_n.back()) continue;
      if (j.kind == RunKind::kUncompensated || j.strategy == s.strategy) {
        if (mm_s(j.speed) == mm_s(config.speeds_m_s.front())) j.plot = true;
        if (mm_s(j.speed) == mm_s(config.budget.speed_m_s) && options.trace_sink) j.write_trace = true;
      }
    }
  }

  // Error budget, first seed: the offline setup and the paper's online one (position guidance).
  // "Every effect" is the table's own run; each effect off is a cell built without it (its own
  // calibration) running the same runs with the same seeds.
  struct BudgetJob {
    int setup;
    Effect off;
    double residual_mm = NAN;
  };
  std::vector<BudgetJob> budget_jobs;
  std::vector<int> budget_setups;
  if (options.error_budget) {
    bool have_offline = false, have_online = false;
    for (std::size_t i = 0; i < config.setups.size(); ++i) {
      const auto& sc = config.setups[i];
      const bool offline = sc.strategy == Strategy::kOffline && !have_offline;
      const bool online = sc.strategy == Strategy::kOnline && sc.link == LinkKind::kEgmJoint && !have_online;
      if (!offline && !online) continue;
      have_offline = have_offline || offline;
      have_online = have_online || online;
      budget_setups.push_back(static_cast<int>(i));
      for (Effect e : kAllEffects) {
        if ((e == Effect::kSensorCompliance || e == Effect::kSensorDrift) && !sc.sensor_mounted) continue;
        if ((e == Effect::kSensorErrors || e == Effect::kSensorCalibration || e == Effect::kLatency) && offline) continue;
        budget_jobs.push_back(BudgetJob{static_cast<int>(i), e});
      }
    }
  }

  // Progress weights: simulated seconds.
  const double cal_cost = calibration_cost(config);
  for (int si = 0; si < n_seeds; ++si) {
    for (int f = 0; f < 2; ++f) {
      if (need_cell[f]) progress.total += cal_cost;
    }
    for (std::size_t f = 0; f < families.size(); ++f) {
      for (double v : speeds) progress.total += run_cost(config, v, laps);
    }
  }
  for (const auto& j : loaded) progress.total += run_cost(config, j.speed, laps);
  for (std::size_t i = 0; i < budget_jobs.size(); ++i) {
    progress.total += cal_cost + 2.0 * run_cost(config, config.budget.speed_m_s, laps);
  }

  // Phase 1: calibrations.
  {
    std::vector<std::function<void()>> jobs;
    for (int si = 0; si < n_seeds; ++si) {
      for (int f = 0; f < 2; ++f) {
        if (!need_cell[f]) continue;
        jobs.emplace_back([&, si, f] {
          cells[static_cast<std::size_t>(si)][static_cast<std::size_t>(f)].emplace(build_setup_cell(cfg_of(si), f == 1));
          progress.add(cal_cost, fmt::format("seed {}: calibration, {}", cfg_of(si).seed, f == 1 ? "sensor mounted" : "no sensor"));
        });
        ++out.calibrations;
      }
    }
    run_parallel(jobs, options.threads);
  }
  auto cell_of = [&](int si, bool sensor) -> const SetupCell& {
    return *cells[static_cast<std::size_t>(si)][sensor ? 1 : 0];
  };
  // The unloaded reference run of a seed, family and speed (the tables' and the budget's alike).
  auto unloaded_spec = [&](int si, const Family& fam, double v) {
    RunSpec spec;
    spec.kind = RunKind::kUnloaded;
    spec.link = fam.link;
    spec.speed_m_s = v;
    spec.laps_cw = laps_cw;
    spec.laps_ccw = laps_ccw;
    spec.seed = run_seed(cfg_of(si).seed, fam.sensor, RunKind::kUnloaded, Strategy::kOffline, 0.0, v,
                         static_cast<std::uint64_t>(fam.link));
    return spec;
  };
  auto loaded_spec = [&](int si, const Family& fam, RunKind kind, Strategy strategy, double load, double v) {
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
  };
  std::mutex sink_mutex;
  auto sink = [&](const std::string& name, const TrackerTrace& trace) {
    std::lock_guard<std::mutex> lock(sink_mutex);
    options.trace_sink(name, trace);
  };
  const char* kFamilyName[] = {"offline", "sensor"};
  auto family_label = [&](const Family& fam) {
    return fmt::format("{}-{}", kFamilyName[fam.sensor ? 1 : 0], to_string(fam.link));
  };

  // Phase 2: unloaded runs, the references (seed, family, speed).
  std::map<std::tuple<int, int, int>, Reference> unloaded;
  {
    for (int si = 0; si < n_seeds; ++si) {
      for (std::size_t f = 0; f < families.size(); ++f) {
        for (double v : speeds) unloaded[{si, static_cast<int>(f), mm_s(v)}];  // slots before the threads start
      }
    }
    std::vector<std::function<void()>> jobs;
    for (int si = 0; si < n_seeds; ++si) {
      for (std::size_t f = 0; f < families.size(); ++f) {
        for (double v : speeds) {
          jobs.emplace_back([&, si, f, v] {
            const Family& fam = families[f];
            RunOutput run = simulate_run(cfg_of(si), cell_of(si, fam.sensor), unloaded_spec(si, fam, v));
            if (si == 0 && options.trace_sink && mm_s(v) == mm_s(config.budget.speed_m_s)) {
              sink(fmt::format("{}_unloaded_{}mm_s", family_label(fam), mm_s(v)), run.trace);
            }
            unloaded.at({si, static_cast<int>(f), mm_s(v)}) = make_reference(std::move(run));
            progress.add(run_cost(config, v, laps), fmt::format("seed {}: unloaded {} mm/s", cfg_of(si).seed, mm_s(v)));
          });
        }
      }
    }
    run_parallel(jobs, options.threads);
  }
  // Phase 3: loaded runs (slowest first so both cores finish together) and the error budget's runs.
  {
    std::vector<std::size_t> order(loaded.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return loaded[a].speed < loaded[b].speed; });
    std::vector<std::function<void()>> jobs;
    for (std::size_t i : order) {
      jobs.emplace_back([&, i] {
        LoadedJob& j = loaded[i];
        const Family& fam = families[static_cast<std::size_t>(j.family)];
        const RunSpec spec = loaded_spec(j.seed, fam, j.kind, j.strategy, j.load_n, j.speed);
        RunOutput run = simulate_run(cfg_of(j.seed), cell_of(j.seed, fam.sensor), spec);
        j.figures = evaluate_run(run, unloaded.at({j.seed, j.family, mm_s(j.speed)}));
        j.link_cycles = run.link_cycles;
        j.rejected = run.link_counters.rejected();
        j.guard_trips = run.link_counters.guard_trips;
        j.max_deviation_rad = run.max_command_deviation_rad;
        j.max_tcp_m = run.max_tcp_correction_m;
        j.delay_s = run.measured_delay_s;
        if (j.write_trace) {
          sink(fmt::format("{}_{}_{:.0f}N_{}mm_s", family_label(fam),
                           j.kind == RunKind::kUncompensated ? "uc" : to_string(j.strategy), j.load_n, mm_s(j.speed)),
               run.trace);
        }
        if (j.plot) j.keep = std::move(run);
        progress.add(run_cost(config, j.speed, laps),
                     fmt::format("seed {}: {} {} N {} mm/s", cfg_of(j.seed).seed,
                                 j.kind == RunKind::kUncompensated ? "UC" : to_string(j.strategy), j.load_n,
                                 mm_s(j.speed)));
      });
    }
    for (auto& bj : budget_jobs) {
      jobs.emplace_back([&] {
        const SetupConfig& sc = config.setups[static_cast<std::size_t>(bj.setup)];
        const Family& fam = families[static_cast<std::size_t>(family_of(sc))];
        const CaseConfig cfg = without_effect(cfg_of(0), bj.off);
        const SetupCell cell = build_setup_cell(cfg, sc.sensor_mounted);
        const double load = sc.loads_n[static_cast<std::size_t>(config.budget.load_index)];
        const double v = config.budget.speed_m_s;
        const Reference reference = make_reference(simulate_run(cfg, cell, unloaded_spec(0, fam, v)));
        const RunSpec c_spec = loaded_spec(0, fam, RunKind::kCompensated, sc.strategy, load, v);
        bj.residual_mm = evaluate_run(simulate_run(cfg, cell, c_spec), reference).mean_mm;
        progress.add(cal_cost + 2.0 * run_cost(config, v, laps), fmt::format("budget: {}", to_string(bj.off)));
      });
    }
    run_parallel(jobs, options.threads);
  }

  // Assemble the study: per setup, load and speed the seeds' figures, their means and spread.
  StudyResult& study = out.study;
  study.case_name = config.name;
  study.seed = config.seed;
  for (int si = 0; si < n_seeds; ++si) study.seeds.push_back(cfg_of(si).seed);
  for (double v : config.speeds_m_s) study.speeds_mm_s.push_back(mm_s(v));
  auto mean_over_seeds = [&](const std::vector<double>& values) {
    double sum = 0.0;
    int n = 0;
    for (double x : values) {
      if (std::isfinite(x)) {
        sum += x;
        ++n;
      }
    }
    return n > 0 ? sum / n : NAN;
  };
  for (const auto& s : config.setups) {
    const int fam = family_of(s);
    SetupResult sr;
    sr.setup = s.name;
    sr.description = describe(s.strategy, s.link);
    LinkSummary ls;
    ls.setup = s.name;
    ls.link = to_string(s.link);
    ls.joint_commands = s.link != LinkKind::kEgmPath;
    ls.bound_rad = config.online.max_joint_correction_rad;
    int delay_runs = 0;
    for (const auto& j : loaded) {
      if (j.family != fam || j.kind != RunKind::kCompensated || j.strategy != s.strategy || s.link == LinkKind::kProgram)
        continue;
      ls.cycles += j.link_cycles;
      ls.rejected += j.rejected;
      ls.guard_trips += j.guard_trips;
      ls.max_command_deviation_rad = std::max(ls.max_command_deviation_rad, j.max_deviation_rad);
      ls.max_tcp_correction_m = std::max(ls.max_tcp_correction_m, j.max_tcp_m);
      if (std::isfinite(j.delay_s)) {
        ls.measured_delay_s += j.delay_s;
        ++delay_runs;
      }
    }
    if (s.link != LinkKind::kProgram) {
      ls.measured_delay_s = delay_runs > 0 ? ls.measured_delay_s / delay_runs : NAN;
      out.links.push_back(ls);
    }
    for (double load : s.loads_n) {
      LoadResult lr;
      lr.load_N = load;
      for (double v : config.speeds_m_s) {
        const int key = mm_s(v);
        std::vector<double> uc_std, uc_max, iso_uc, c_std, c_max, iso_c, iso_rep;
        for (int si = 0; si < n_seeds; ++si) {
          const LoadedJob* uc = find(si, fam, RunKind::kUncompensated, s.strategy, load, v);
          const LoadedJob* c = find(si, fam, RunKind::kCompensated, s.strategy, load, v);
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
      sr.loads.push_back(lr);
    }
    study.setups.push_back(sr);
    if (options.speed_sweep) {
      const double load = sweep_load(s);
      for (double v : config.sweep_speeds_m_s) {
        SweepPoint p;
        p.setup = s.name;
        p.load_N = load;
        p.speed_mm_s = v * 1e3;
        for (int si = 0; si < n_seeds; ++si) {
          const LoadedJob* uc = find(si, fam, RunKind::kUncompensated, s.strategy, load, v);
          const LoadedJob* c = find(si, fam, RunKind::kCompensated, s.strategy, load, v);
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
    // Path plot traces (first seed).
    const double v0 = config.speeds_m_s.front();
    const LoadedJob* uc = find(0, fam, RunKind::kUncompensated, s.strategy, s.loads_n.back(), v0);
    const LoadedJob* c = find(0, fam, RunKind::kCompensated, s.strategy, s.loads_n.back(), v0);
    if (uc && c && !uc->keep.trace.empty() && !c->keep.trace.empty()) {
      const Reference& ref = unloaded.at({0, fam, mm_s(v0)});
      PlotTraces pt;
      pt.setup = s.name;
      pt.load_n = s.loads_n.back();
      pt.speed_mm_s = mm_s(v0);
      pt.title = fmt::format("{}: {:.0f} N at {} mm/s (seed {})", s.name, s.loads_n.back(), mm_s(v0), config.seed);
      pt.unloaded = thin_lap(ref.run, 1500);
      pt.unloaded_mean = thin(ref.mean, 1500);
      pt.uc = thin_lap(uc->keep, 1500);
      pt.c = thin_lap(c->keep, 1500);
      pt.uc_laps = plot_laps(uc->keep, 720);
      pt.c_laps = plot_laps(c->keep, 720);
      out.plots.push_back(std::move(pt));
    }
  }
  for (int si : budget_setups) {
    const SetupConfig& sc = config.setups[static_cast<std::size_t>(si)];
    const int fam = family_of(sc);
    ErrorBudget b;
    b.setup = sc.name;
    b.load_N = sc.loads_n[static_cast<std::size_t>(config.budget.load_index)];
    b.speed_mm_s = mm_s(config.budget.speed_m_s);
    b.seed = config.seed;
    b.laps = laps;
    b.residual_mm_all = find(0, fam, RunKind::kCompensated, sc.strategy, b.load_N, config.budget.speed_m_s)->figures.mean_mm;
    b.uc_mm = find(0, fam, RunKind::kUncompensated, sc.strategy, b.load_N, config.budget.speed_m_s)->figures.mean_mm;
    for (const auto& bj : budget_jobs) {
      if (bj.setup != si) continue;
      b.entries.push_back(ErrorBudgetEntry{to_string(bj.off), effect_size(config, bj.off), bj.residual_mm,
                                           residual_share(b.residual_mm_all, bj.residual_mm)});
    }
    study.error_budgets.push_back(std::move(b));
  }

  // The cell in words (the first seed's).
  for (int f = 0; f < 2; ++f) {
    if (!need_cell[f]) continue;
    const SetupCell& cell = cell_of(0, f == 1);
    std::string k_true, k_id;
    const auto& kt = cell.robot->true_model().stiffness();
    const auto& ki = cell.calibration.identified.stiffness();
    for (int j = 0; j < kt.size(); ++j) {
      k_true += fmt::format("{}{:.3g}", j ? ", " : "", kt[j]);
      k_id += fmt::format("{}{:.3g}", j ? ", " : "", ki[j]);
    }
    out.setup_paragraphs.push_back(fmt::format(
        "Setup {} the force sensor (seed {}): true joint stiffness (diagonal, Nm/rad) [{}]; identified from {} "
        "calibration measurements taken while moving along {} arcs in the operating space [{}] (residual {:.1f} um "
        "RMS). The identified values absorb what the lumped model lacks ({}).",
        f == 1 ? "with" : "without", config.seed, k_true, cell.calibration.measurements, config.calibration.arcs, k_id,
        cell.calibration.estimate.residual_rms_m * 1e6,
        f == 1 ? "sensor compliance, joint coupling, link bending, base tilt, lost motion"
               : "joint coupling, link bending, base tilt, lost motion"));
    for (const auto& note : cell.calibration.notes) {
      if (note.find("kept the assumed") != std::string::npos || note.find("poorly") != std::string::npos) {
        out.setup_paragraphs.back() += " Calibration: " + note + ".";
      }
    }
    // How far the identified model is from the true arm on the circle, per seed (a diagnostic from
    // the simulator's truth; no strategy sees it).
    double load = 0.0;
    for (const auto& s : config.setups) {
      if (s.sensor_mounted == (f == 1)) load = std::max(load, s.loads_n.back());
    }
    std::vector<double> errors, scales;
    for (int si = 0; si < n_seeds; ++si) {
      double scale = NAN;
      errors.push_back(identified_model_error(cfg_of(si), cell_of(si, f == 1), load, &scale));
      scales.push_back(scale);
    }
    const Spread e = spread_of(errors), sc = spread_of(scales);
    out.setup_paragraphs.back() += fmt::format(
        " On the circle at {:.0f} N the identified model's static deflection is off the true arm's by {:.0f} % on "
        "average (its length {:.0f} % of the true one){}.",
        load, e.mean * 100, sc.mean * 100,
        n_seeds > 1 ? fmt::format("; over the {} seeds {:.0f}-{:.0f} % and {:.0f}-{:.0f} %", n_seeds, e.min * 100,
                                  e.max * 100, sc.min * 100, sc.max * 100)
                    : std::string());
  }
  const auto& k = config.cell.controller;
  out.setup_paragraphs.push_back(fmt::format(
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
      rad_to_deg(config.cell.ldbb.inclination_rad), laps_cw, laps_ccw, config.cell.tracker.rate_hz,
      config.cell.tracker.noise_m * 1e6, k.servo_period_s * 1e3, k.egm_period_s * 1e3, k.egm_dead_time_s * 1e3,
      k.egm_lowpass_hz, k.egm_position_gain_per_s, k.path_corr_period_s * 1e3, k.path_corr_dead_time_s * 1e3,
      config.online.stream_period_s * 1e3, config.online.stream_buffer_depth, n_seeds,
      n_seeds == 1 ? "" : "s", config.seed, n_seeds == 1 ? std::string() : fmt::format(" to {}", cfg_of(n_seeds - 1).seed)));
  out.runs = static_cast<int>(loaded.size()) + static_cast<int>(budget_jobs.size()) * 2;
  out.runs += n_seeds * static_cast<int>(families.size() * speeds.size());
  out.calibrations += static_cast<int>(budget_jobs.size());
  out.simulated_s = progress.total;
  study.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace deflex::study
