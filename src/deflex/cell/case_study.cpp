// The protocol runner of the simulated case study (see case_study.hpp).
#include "deflex/cell/case_study.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <map>
#include <mutex>
#include <optional>
#include <thread>

#include "deflex/cell/simulated_run.hpp"
#include "deflex/evaluate/iso9283_path.hpp"
#include "deflex/evaluate/path_metrics.hpp"
#include "deflex/model/errors.hpp"

namespace deflex::cell {
namespace {

int mm_s(double speed_m_s) { return static_cast<int>(std::lround(speed_m_s * 1e3)); }

struct Figures {
  double mean_mm = 0, std_mm = 0, max_mm = 0, iso_accuracy_mm = NAN, iso_repeatability_mm = NAN;
};

Figures evaluate_run(const RunOutput& loaded, const RunOutput& unloaded) {
  Figures f;
  const PathDeviationStats s = path_deviation(loaded.trace, unloaded.trace);
  f.mean_mm = s.mean_m * 1e3;
  f.std_mm = s.std_m * 1e3;
  f.max_mm = s.max_m * 1e3;
  const auto laps = split_laps(loaded);
  const auto ref_laps = split_laps(unloaded);
  if (!laps.empty() && !ref_laps.empty()) {
    try {
      const Iso9283Path iso = iso9283_path(laps, ref_laps.front());
      f.iso_accuracy_mm = iso.accuracy_m * 1e3;
      f.iso_repeatability_mm = iso.repeatability_m * 1e3;
    } catch (const InputError&) {
      // A path ISO 9283 cannot evaluate leaves its figures empty; the paper's figure stands alone.
    }
  }
  return f;
}

TrackerTrace thin_lap(const RunOutput& run, std::size_t max_points) {
  const auto laps = split_laps(run);
  if (laps.empty()) return {};
  const TrackerTrace& lap = laps.back();
  const std::size_t step = std::max<std::size_t>(1, lap.size() / max_points);
  TrackerTrace out;
  for (std::size_t i = 0; i < lap.size(); i += step) out.push_back(lap[i]);
  return out;
}

// One family of setups shares a physical configuration: with or without the sensor.
struct Family {
  bool sensor = false;
  std::optional<SetupCell> cell;
  std::map<int, RunOutput> unloaded;  // by speed mm/s
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
  return c.ldbb.settle_s + 2.0 * kPi * c.radius_m() * laps / speed_m_s;
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

  // Families and the speeds each needs unloaded.
  Family families[2];
  families[0].sensor = false;
  families[1].sensor = true;
  bool need[2] = {false, false};
  for (const auto& s : config.setups) need[s.sensor_mounted ? 1 : 0] = true;
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
    const int fam = s.sensor_mounted ? 1 : 0;
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
      if ((s.sensor_mounted ? 1 : 0) == j.family && j.load_n == s.loads_n.back() &&
          mm_s(j.speed) == mm_s(config.speeds_m_s.front()) &&
          (j.kind == RunKind::kUncompensated || j.strategy == s.strategy)) {
        j.plot = true;
      }
    }
  }

  // Error budget cells: per budgeted setup, all effects on plus each effect off.
  struct BudgetJob {
    int setup;
    std::optional<Effect> off;
    double residual_mm = NAN, uc_mm = NAN;
  };
  std::vector<BudgetJob> budget_jobs;
  std::vector<int> budget_setups;
  if (options.error_budget) {
    for (std::size_t i = 0; i < config.setups.size(); ++i) {
      const auto st = config.setups[i].strategy;
      if (st == Strategy::kOffline || st == Strategy::kOnline) {
        budget_setups.push_back(static_cast<int>(i));
        budget_jobs.push_back(BudgetJob{static_cast<int>(i), std::nullopt});
        for (Effect e : kAllEffects) {
          if (e == Effect::kSensorCompliance && !config.setups[i].sensor_mounted) continue;
          if ((e == Effect::kSensorErrors || e == Effect::kSensorCalibration || e == Effect::kLatency) &&
              st == Strategy::kOffline)
            continue;
          budget_jobs.push_back(BudgetJob{static_cast<int>(i), e});
        }
      }
    }
  }
  const int budget_laps = 2 * config.budget.laps_each_way;

  // Progress weights: simulated seconds.
  for (int f = 0; f < 2; ++f) {
    if (!need[f]) continue;
    progress.total += 5.0;  // calibration
    for (double v : speeds) progress.total += run_cost(config, v, laps);
  }
  for (const auto& j : loaded) progress.total += run_cost(config, j.speed, laps);
  for (std::size_t i = 0; i < budget_jobs.size(); ++i) {
    progress.total +=
        5.0 + (i == 0 || !budget_jobs[i].off ? 3.0 : 2.0) * run_cost(config, config.budget.speed_m_s, budget_laps);
  }

  // Phase 1: calibrations.
  {
    std::vector<std::function<void()>> jobs;
    for (int f = 0; f < 2; ++f) {
      if (!need[f]) continue;
      jobs.emplace_back([&, f] {
        families[f].cell.emplace(build_setup_cell(config, families[f].sensor));
        progress.add(5.0, families[f].sensor ? "calibration, sensor mounted" : "calibration, no sensor");
      });
    }
    run_parallel(jobs, options.threads);
  }
  // Phase 2: unloaded runs.
  {
    for (int f = 0; f < 2; ++f) {
      for (double v : speeds) families[f].unloaded[mm_s(v)];  // create slots before the threads start
    }
    std::vector<std::function<void()>> jobs;
    for (int f = 0; f < 2; ++f) {
      if (!need[f]) continue;
      for (double v : speeds) {
        jobs.emplace_back([&, f, v] {
          RunSpec spec;
          spec.kind = RunKind::kUnloaded;
          spec.speed_m_s = v;
          spec.laps_cw = laps_cw;
          spec.laps_ccw = laps_ccw;
          spec.seed = run_seed(config.seed, families[f].sensor, RunKind::kUnloaded, Strategy::kOffline, 0.0, v);
          families[f].unloaded[mm_s(v)] = simulate_run(*families[f].cell, spec);
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
        Family& fam = families[j.family];
        RunSpec spec;
        spec.kind = j.kind;
        spec.strategy = j.strategy;
        spec.load_n = j.load_n;
        spec.speed_m_s = j.speed;
        spec.laps_cw = laps_cw;
        spec.laps_ccw = laps_ccw;
        spec.seed = run_seed(config.seed, fam.sensor, j.kind, j.strategy, j.load_n, j.speed);
        RunOutput run = simulate_run(*fam.cell, spec);
        j.figures = evaluate_run(run, fam.unloaded.at(mm_s(j.speed)));
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
        spec.speed_m_s = v;
        spec.laps_cw = spec.laps_ccw = config.budget.laps_each_way;
        const std::uint64_t extra = 0xb0d6e7ULL;
        spec.kind = RunKind::kUnloaded;
        spec.seed = run_seed(config.seed, sc.sensor_mounted, spec.kind, sc.strategy, 0.0, v, extra);
        const RunOutput unloaded = simulate_run(cell, spec);
        spec.kind = RunKind::kCompensated;
        spec.strategy = sc.strategy;
        spec.load_n = load;
        spec.seed = run_seed(config.seed, sc.sensor_mounted, spec.kind, sc.strategy, load, v, extra);
        bj.residual_mm = evaluate_run(simulate_run(cell, spec), unloaded).mean_mm;
        if (!bj.off) {
          spec.kind = RunKind::kUncompensated;
          spec.seed = run_seed(config.seed, sc.sensor_mounted, spec.kind, sc.strategy, load, v, extra);
          bj.uc_mm = evaluate_run(simulate_run(cell, spec), unloaded).mean_mm;
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
    const int fam = s.sensor_mounted ? 1 : 0;
    SetupResult sr;
    sr.setup = s.name;
    switch (s.strategy) {
      case Strategy::kOffline:
        sr.description = "offline compensation from the LDBB force model (paper, Figure 2)";
        break;
      case Strategy::kOnline:
        sr.description = "online compensation from the force sensor (paper, Figure 3)";
        break;
      case Strategy::kHybrid:
        sr.description = "hybrid: offline feed-forward + online correction of measured minus modelled force";
        break;
      case Strategy::kOnlineLatency:
        sr.description = "online with the wrench and pose predicted one delay ahead";
        break;
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
      pt.unloaded = thin_lap(families[fam].unloaded.at(mm_s(config.speeds_m_s.front())), 1500);
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
    if (!need[f]) continue;
    const SetupCell& cell = *families[f].cell;
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
        families[f].sensor ? "with" : "without", k_true, cell.calibration.measurements, k_id,
        cell.calibration.estimate.residual_rms_m * 1e6,
        families[f].sensor ? "sensor compliance, joint coupling, forearm bending, lost motion"
                           : "joint coupling, forearm bending, lost motion"));
    for (const auto& note : cell.calibration.notes) {
      if (note.find("kept the assumed") != std::string::npos || note.find("poorly") != std::string::npos) {
        out.setup_paragraphs.back() += " Calibration: " + note + ".";
      }
    }
  }
  out.setup_paragraphs.push_back(fmt::format(
      "Circle of radius {:.1f} mm around ({:.0f}, {:.0f}, {:.0f}) mm in the base XY plane, tool pointing down; LDBB "
      "bar "
      "{:.0f} mm inclined by {:.0f} deg (pivot below the centre); {} clockwise + {} anticlockwise laps per run; "
      "tracker "
      "at {:.0f} Hz with {:.1f} um noise; servo {:.0f} ms; online cycle {:.0f} ms. Seed {}.",
      config.radius_m() * 1e3, config.circle.center_m.x() * 1e3, config.circle.center_m.y() * 1e3,
      config.circle.center_m.z() * 1e3, config.ldbb.bar_length_m * 1e3, rad_to_deg(config.ldbb.inclination_rad),
      laps_cw, laps_ccw, config.tracker.rate_hz, config.tracker.noise_m * 1e6, config.controller.servo_period_s * 1e3,
      config.online.cycle_s * 1e3, config.seed));
  out.runs = static_cast<int>(loaded.size()) + static_cast<int>(budget_jobs.size()) * 2;
  for (int f = 0; f < 2; ++f) out.runs += need[f] ? static_cast<int>(speeds.size()) : 0;
  out.simulated_s = progress.total;
  study.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace deflex::cell
