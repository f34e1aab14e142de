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
#include <thread>

#include "deflex/evaluate/iso9283_path.hpp"
#include "deflex/evaluate/lap_split.hpp"
#include "deflex/evaluate/path_metrics.hpp"
#include "deflex/model/errors.hpp"
#include "deflex/study/simulated_run.hpp"

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

TrackerTrace thin_lap(const RunOutput& run, std::size_t max_points) {
  const auto laps = laps_of(run.trace);
  if (laps.empty()) return {};
  const TrackerTrace& lap = laps.back();
  const std::size_t step = std::max<std::size_t>(1, lap.size() / max_points);
  TrackerTrace out;
  for (std::size_t i = 0; i < lap.size(); i += step) out.push_back(lap[i]);
  return out;
}

// Runs that share a physical configuration and a way of driving the arm share their unloaded
// reference and their uncompensated runs: the offline setups (no sensor, the controller's own
// program), and the online setups per link (sensor mounted, deflex streaming uncorrected).
struct Family {
  bool sensor = false;
  LinkKind link = LinkKind::kProgram;
  std::map<int, Reference> unloaded;  // by speed mm/s
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

const char* describe(Strategy s, LinkKind link) {
  switch (s) {
    case Strategy::kOffline:
      return "offline compensation from the LDBB force model (paper, Figure 2): the controller runs the compensated "
             "program";
    case Strategy::kOnline:
      return link == LinkKind::kEgmPath
                 ? "online compensation from the force sensor (paper, Figure 3) over ABB EGM path correction"
                 : "online compensation from the force sensor (paper, Figure 3) over ABB EGM position guidance";
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

  // The physical setups (with and without the sensor) and the families of runs.
  std::optional<SetupCell> cells[2];
  bool need_cell[2] = {false, false};
  std::vector<Family> families;
  auto family_of = [&](const SetupConfig& s) {
    for (std::size_t i = 0; i < families.size(); ++i) {
      if (families[i].sensor == s.sensor_mounted && families[i].link == s.link) return static_cast<int>(i);
    }
    families.push_back(Family{s.sensor_mounted, s.link, {}});
    return static_cast<int>(families.size()) - 1;
  };
  for (const auto& s : config.setups) {
    need_cell[s.sensor_mounted ? 1 : 0] = true;
    (void)family_of(s);
  }
  std::vector<double> speeds = config.speeds_m_s;
  if (options.speed_sweep) {
    for (double v : config.sweep_speeds_m_s) {
      if (std::none_of(speeds.begin(), speeds.end(), [&](double u) { return mm_s(u) == mm_s(v); })) speeds.push_back(v);
    }
  }
  // The sweep runs each setup at its load nearest to sweep_load_n.
  auto sweep_load = [&](const SetupConfig& s) {
    return *std::min_element(s.loads_n.begin(), s.loads_n.end(), [&](double a, double b) {
      return std::abs(a - config.sweep_load_n) < std::abs(b - config.sweep_load_n);
    });
  };

  // Loaded jobs: uncompensated per family, load and speed; compensated per setup, load and speed.
  struct LoadedJob {
    int family;
    RunKind kind;
    Strategy strategy;
    double load_n;
    double speed;
    RunOutput keep;  // only for the plotted runs
    Figures figures;
    bool plot = false;
    std::uint64_t link_cycles = 0, rejected = 0, guard_trips = 0;
    double max_deviation_rad = 0.0, max_tcp_m = 0.0, delay_s = 0.0;
  };
  std::vector<LoadedJob> loaded;
  auto add_loaded = [&](int fam, RunKind kind, Strategy strategy, double load, double speed) {
    for (const auto& j : loaded) {
      if (j.family == fam && j.kind == kind && (kind != RunKind::kCompensated || j.strategy == strategy) &&
          j.load_n == load && mm_s(j.speed) == mm_s(speed)) {
        return;
      }
    }
    loaded.push_back(LoadedJob{fam, kind, strategy, load, speed, {}, {}, false});
  };
  for (const auto& s : config.setups) {
    const int fam = family_of(s);
    for (double load : s.loads_n) {
      for (double v : config.speeds_m_s) {
        add_loaded(fam, RunKind::kUncompensated, s.strategy, load, v);
        add_loaded(fam, RunKind::kCompensated, s.strategy, load, v);
      }
    }
    if (options.speed_sweep) {
      for (double v : config.sweep_speeds_m_s) {
        add_loaded(fam, RunKind::kUncompensated, s.strategy, sweep_load(s), v);
        add_loaded(fam, RunKind::kCompensated, s.strategy, sweep_load(s), v);
      }
    }
  }
  // Plot: each setup's highest load at the first speed.
  for (auto& j : loaded) {
    for (const auto& s : config.setups) {
      if (family_of(s) == j.family && j.load_n == s.loads_n.back() &&
          mm_s(j.speed) == mm_s(config.speeds_m_s.front()) &&
          (j.kind == RunKind::kUncompensated || j.strategy == s.strategy)) {
        j.plot = true;
      }
    }
  }

  // Error budget cells: the offline setup and the paper's online one (position guidance), all
  // effects on plus each effect off.
  struct BudgetJob {
    int setup;
    std::optional<Effect> off;
    double residual_mm = NAN, uc_mm = NAN;
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
      budget_jobs.push_back(BudgetJob{static_cast<int>(i), std::nullopt});
      for (Effect e : kAllEffects) {
        if (e == Effect::kSensorCompliance && !sc.sensor_mounted) continue;
        if ((e == Effect::kSensorErrors || e == Effect::kSensorCalibration || e == Effect::kLatency) && offline) continue;
        budget_jobs.push_back(BudgetJob{static_cast<int>(i), e});
      }
    }
  }
  const int budget_laps = 2 * config.budget.laps_each_way;

  // Progress weights: simulated seconds.
  for (int f = 0; f < 2; ++f) {
    if (need_cell[f]) progress.total += 5.0;  // calibration
  }
  for (std::size_t f = 0; f < families.size(); ++f) {
    for (double v : speeds) progress.total += run_cost(config, v, laps);
  }
  for (const auto& j : loaded) progress.total += run_cost(config, j.speed, laps);
  for (const auto& bj : budget_jobs) {
    progress.total += 5.0 + (bj.off ? 2.0 : 3.0) * run_cost(config, config.budget.speed_m_s, budget_laps);
  }

  // Phase 1: calibrations.
  {
    std::vector<std::function<void()>> jobs;
    for (int f = 0; f < 2; ++f) {
      if (!need_cell[f]) continue;
      jobs.emplace_back([&, f] {
        cells[f].emplace(build_setup_cell(config, f == 1));
        progress.add(5.0, f == 1 ? "calibration, sensor mounted" : "calibration, no sensor");
      });
    }
    run_parallel(jobs, options.threads);
  }
  // Phase 2: unloaded runs.
  {
    for (auto& fam : families) {
      for (double v : speeds) fam.unloaded[mm_s(v)];  // create slots before the threads start
    }
    std::vector<std::function<void()>> jobs;
    for (std::size_t f = 0; f < families.size(); ++f) {
      for (double v : speeds) {
        jobs.emplace_back([&, f, v] {
          Family& fam = families[f];
          RunSpec spec;
          spec.kind = RunKind::kUnloaded;
          spec.link = fam.link;
          spec.speed_m_s = v;
          spec.laps_cw = laps_cw;
          spec.laps_ccw = laps_ccw;
          spec.seed = run_seed(config.seed, fam.sensor, RunKind::kUnloaded, Strategy::kOffline, 0.0, v,
                               static_cast<std::uint64_t>(fam.link));
          fam.unloaded[mm_s(v)] = make_reference(simulate_run(config, *cells[fam.sensor ? 1 : 0], spec));
          progress.add(run_cost(config, v, laps), fmt::format("unloaded {} mm/s", mm_s(v)));
        });
      }
    }
    run_parallel(jobs, options.threads);
  }
  // Phase 3: loaded runs (slowest first so both cores finish together).
  {
    std::vector<std::size_t> order(loaded.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return loaded[a].speed < loaded[b].speed; });
    std::vector<std::function<void()>> jobs;
    for (std::size_t i : order) {
      jobs.emplace_back([&, i] {
        LoadedJob& j = loaded[i];
        Family& fam = families[static_cast<std::size_t>(j.family)];
        RunSpec spec;
        spec.kind = j.kind;
        spec.strategy = j.strategy;
        spec.link = fam.link;
        spec.load_n = j.load_n;
        spec.speed_m_s = j.speed;
        spec.laps_cw = laps_cw;
        spec.laps_ccw = laps_ccw;
        spec.seed = run_seed(config.seed, fam.sensor, j.kind, j.strategy, j.load_n, j.speed,
                             static_cast<std::uint64_t>(fam.link));
        RunOutput run = simulate_run(config, *cells[fam.sensor ? 1 : 0], spec);
        j.figures = evaluate_run(run, fam.unloaded.at(mm_s(j.speed)));
        j.link_cycles = run.link_cycles;
        j.rejected = run.link_counters.rejected();
        j.guard_trips = run.link_counters.guard_trips;
        j.max_deviation_rad = run.max_command_deviation_rad;
        j.max_tcp_m = run.max_tcp_correction_m;
        j.delay_s = run.measured_delay_s;
        if (j.plot) j.keep = std::move(run);
        progress.add(run_cost(config, j.speed, laps),
                     fmt::format("{} {} N {} mm/s", j.kind == RunKind::kUncompensated ? "UC" : to_string(j.strategy),
                                 j.load_n, mm_s(j.speed)));
      });
    }
    run_parallel(jobs, options.threads);
  }
  // Phase 4: error budget (its own cells: switching an effect off changes the calibration too).
  {
    std::vector<std::function<void()>> jobs;
    for (auto& bj : budget_jobs) {
      jobs.emplace_back([&] {
        const SetupConfig& sc = config.setups[static_cast<std::size_t>(bj.setup)];
        const CaseConfig cfg = bj.off ? without_effect(config, *bj.off) : config;
        const SetupCell cell = build_setup_cell(cfg, sc.sensor_mounted);
        const double load = sc.loads_n[static_cast<std::size_t>(config.budget.load_index)];
        const double v = config.budget.speed_m_s;
        RunSpec spec;
        spec.link = sc.link;
        spec.speed_m_s = v;
        spec.laps_cw = spec.laps_ccw = config.budget.laps_each_way;
        const std::uint64_t extra = 0xb0d6e7ULL;
        spec.kind = RunKind::kUnloaded;
        spec.seed = run_seed(config.seed, sc.sensor_mounted, spec.kind, sc.strategy, 0.0, v, extra);
        const Reference unloaded = make_reference(simulate_run(cfg, cell, spec));
        spec.kind = RunKind::kCompensated;
        spec.strategy = sc.strategy;
        spec.load_n = load;
        spec.seed = run_seed(config.seed, sc.sensor_mounted, spec.kind, sc.strategy, load, v, extra);
        bj.residual_mm = evaluate_run(simulate_run(cfg, cell, spec), unloaded).mean_mm;
        if (!bj.off) {
          spec.kind = RunKind::kUncompensated;
          spec.seed = run_seed(config.seed, sc.sensor_mounted, spec.kind, sc.strategy, load, v, extra);
          bj.uc_mm = evaluate_run(simulate_run(cfg, cell, spec), unloaded).mean_mm;
        }
        progress.add(5.0 + (bj.off ? 2.0 : 3.0) * run_cost(config, v, budget_laps),
                     bj.off ? fmt::format("budget: {}", to_string(*bj.off)) : std::string("budget"));
      });
    }
    run_parallel(jobs, options.threads);
  }

  // Assemble the study.
  StudyResult& study = out.study;
  study.case_name = config.name;
  study.seed = config.seed;
  for (double v : config.speeds_m_s) study.speeds_mm_s.push_back(mm_s(v));
  auto find = [&](int fam, RunKind kind, Strategy st, double load, double v) -> const LoadedJob* {
    for (const auto& j : loaded) {
      if (j.family == fam && j.kind == kind && (kind != RunKind::kCompensated || j.strategy == st) &&
          j.load_n == load && mm_s(j.speed) == mm_s(v)) {
        return &j;
      }
    }
    return nullptr;
  };
  for (const auto& s : config.setups) {
    const int fam = family_of(s);
    SetupResult sr;
    sr.setup = s.name;
    sr.description = describe(s.strategy, s.link);
    LinkSummary ls;
    ls.setup = s.name;
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
      ls.measured_delay_s += j.delay_s;
      ++delay_runs;
    }
    if (delay_runs > 0) {
      ls.measured_delay_s /= delay_runs;
      out.links.push_back(ls);
    }
    for (double load : s.loads_n) {
      LoadResult lr;
      lr.load_N = load;
      for (double v : config.speeds_m_s) {
        const LoadedJob* uc = find(fam, RunKind::kUncompensated, s.strategy, load, v);
        const LoadedJob* c = find(fam, RunKind::kCompensated, s.strategy, load, v);
        const int key = mm_s(v);
        lr.uc_mm[key] = uc->figures.mean_mm;
        lr.uc_std_mm[key] = uc->figures.std_mm;
        lr.uc_max_mm[key] = uc->figures.max_mm;
        lr.iso_accuracy_uc_mm[key] = uc->figures.iso_accuracy_mm;
        lr.c_mm[key] = c->figures.mean_mm;
        lr.c_std_mm[key] = c->figures.std_mm;
        lr.c_max_mm[key] = c->figures.max_mm;
        lr.iso_accuracy_c_mm[key] = c->figures.iso_accuracy_mm;
        lr.iso_repeatability_mm[key] = c->figures.iso_repeatability_mm;
        lr.uc_sync_mm[key] = uc->figures.sync_mm;
        lr.c_sync_mm[key] = c->figures.sync_mm;
      }
      lr.fill_compensation();
      sr.loads.push_back(lr);
    }
    study.setups.push_back(sr);
    if (options.speed_sweep) {
      const double load = sweep_load(s);
      for (double v : config.sweep_speeds_m_s) {
        const LoadedJob* uc = find(fam, RunKind::kUncompensated, s.strategy, load, v);
        const LoadedJob* c = find(fam, RunKind::kCompensated, s.strategy, load, v);
        SweepPoint p;
        p.setup = s.name;
        p.load_N = load;
        p.speed_mm_s = v * 1e3;
        p.uc_mm = uc->figures.mean_mm;
        p.c_mm = c->figures.mean_mm;
        p.compensation = compensation_ratio(p.uc_mm, p.c_mm);
        study.speed_sweep.push_back(p);
      }
    }
    // Path plot traces.
    const LoadedJob* uc = find(fam, RunKind::kUncompensated, s.strategy, s.loads_n.back(), config.speeds_m_s.front());
    const LoadedJob* c = find(fam, RunKind::kCompensated, s.strategy, s.loads_n.back(), config.speeds_m_s.front());
    if (uc && c && !uc->keep.trace.empty() && !c->keep.trace.empty()) {
      PlotTraces pt;
      pt.title =
          fmt::format("{}: {:.0f} N at {} mm/s (last lap)", s.name, s.loads_n.back(), mm_s(config.speeds_m_s.front()));
      pt.unloaded =
          thin_lap(families[static_cast<std::size_t>(fam)].unloaded.at(mm_s(config.speeds_m_s.front())).run, 1500);
      pt.uc = thin_lap(uc->keep, 1500);
      pt.c = thin_lap(c->keep, 1500);
      out.plots.push_back(std::move(pt));
    }
  }
  for (int si : budget_setups) {
    const SetupConfig& sc = config.setups[static_cast<std::size_t>(si)];
    BudgetResult b;
    b.setup = sc.name;
    b.load_n = sc.loads_n[static_cast<std::size_t>(config.budget.load_index)];
    b.speed_mm_s = config.budget.speed_m_s * 1e3;
    for (const auto& bj : budget_jobs) {
      if (bj.setup != si) continue;
      if (!bj.off) {
        b.residual_mm_all = bj.residual_mm;
        b.uc_mm = bj.uc_mm;
      } else {
        b.rows.push_back(BudgetRow{*bj.off, to_string(*bj.off), effect_size(config, *bj.off), bj.residual_mm});
      }
    }
    out.budgets.push_back(std::move(b));
  }

  // The cell in words.
  for (int f = 0; f < 2; ++f) {
    if (!need_cell[f]) continue;
    const SetupCell& cell = *cells[f];
    std::string k_true, k_id;
    const auto& kt = cell.robot->true_model().stiffness();
    const auto& ki = cell.calibration.identified.stiffness();
    for (int j = 0; j < kt.size(); ++j) {
      k_true += fmt::format("{}{:.3g}", j ? ", " : "", kt[j]);
      k_id += fmt::format("{}{:.3g}", j ? ", " : "", ki[j]);
    }
    out.setup_paragraphs.push_back(fmt::format(
        "Setup {} the force sensor: true joint stiffness (diagonal, Nm/rad) [{}]; identified from {} calibration "
        "measurements in the operating space [{}] (residual {:.1f} um RMS). The identified values absorb what the "
        "lumped model lacks ({}).",
        f == 1 ? "with" : "without", k_true, cell.calibration.measurements, k_id,
        cell.calibration.estimate.residual_rms_m * 1e6,
        f == 1 ? "sensor compliance, joint coupling, forearm bending, lost motion"
               : "joint coupling, forearm bending, lost motion"));
    for (const auto& note : cell.calibration.notes) {
      if (note.find("kept the assumed") != std::string::npos || note.find("poorly") != std::string::npos) {
        out.setup_paragraphs.back() += " Calibration: " + note + ".";
      }
    }
  }
  const auto& k = config.cell.controller;
  out.setup_paragraphs.push_back(fmt::format(
      "Circle of radius {:.1f} mm around ({:.0f}, {:.0f}, {:.0f}) mm in the base XY plane, tool pointing down, "
      "{} programmed configurations; LDBB bar {:.0f} mm inclined by {:.0f} deg (pivot below the centre); {} clockwise "
      "+ {} anticlockwise laps per run; tracker at {:.0f} Hz with {:.1f} um noise; servo {:.0f} ms. The online setups "
      "reach the controller through deflex's own links over the cell's network: EGM position guidance (deflex streams "
      "the program every {:.0f} ms; the controller follows after {:.0f} ms of dead time through a {:.0f} Hz filter, "
      "gain {:.0f}/s plus deflex's speed reference) or EGM path correction (the controller asks every {:.0f} ms and "
      "applies an offset {:.0f} ms later). Seed {}.",
      config.radius_m() * 1e3, config.circle.center_m.x() * 1e3, config.circle.center_m.y() * 1e3,
      config.circle.center_m.z() * 1e3, config.circle.points, config.cell.ldbb.bar_length_m * 1e3,
      rad_to_deg(config.cell.ldbb.inclination_rad), laps_cw, laps_ccw, config.cell.tracker.rate_hz,
      config.cell.tracker.noise_m * 1e6, k.servo_period_s * 1e3, k.egm_period_s * 1e3, k.egm_dead_time_s * 1e3,
      k.egm_lowpass_hz, k.egm_position_gain_per_s, k.path_corr_period_s * 1e3, k.path_corr_dead_time_s * 1e3,
      config.seed));
  out.runs = static_cast<int>(loaded.size()) + static_cast<int>(budget_jobs.size()) * 2 + static_cast<int>(budget_setups.size());
  out.runs += static_cast<int>(families.size() * speeds.size());
  out.simulated_s = progress.total;
  study.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace deflex::study
