// The machining study: seeds, the cell's slot cuts and the fit, the part under each strategy and
// feed, the probe's figures and the table (see machining_study.hpp).
#include "deflex/study/machining_study.hpp"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>
#include <random>

#include "deflex/cell/milling_process.hpp"
#include "deflex/cell/part_probe.hpp"
#include "deflex/study/case_study.hpp"
#include "deflex/study/detail/machining_run.hpp"
#include "deflex/text/errors.hpp"

namespace deflex::study {
namespace {

// The cell's truth about the tool and the material (data/cases/effect-ranges.yaml, milling:): the
// coefficients' 1-sigma about the published set, the runout drawn uniformly in a collet's range.
constexpr double kCoefficientSpread = 0.15;
constexpr double kRunoutLoM = 3e-6, kRunoutHiM = 10e-6;
// The probe: a bridge CMM's 1-sigma per point.
constexpr double kProbeNoiseM = 1e-6;
// The study's feeds (mm/min): fz 0.042 and 0.083 mm at 12 000 rpm, three flutes.
constexpr double kFeedsMmMin[] = {1500.0, 3000.0};

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct SeedCell {
  double calibration_s = 0.0, slot_cuts_s = 0.0;
  std::unique_ptr<MillCell> cell;
  CuttingCoefficients truth;
  double runout_m = 0.0;
  MachiningFit fit;
};

PartErrors probe_part(const MillPart& part, const DexelStock& stock, std::uint64_t seed,
                      std::vector<WallTrace>* walls) {
  cell::PartProbe probe(kProbeNoiseM, seed);
  PartErrors e;
  const cell::WallProfile climb = probe.wall(stock, part.climb_wall);
  const cell::WallProfile conv = probe.wall(stock, part.conventional_wall);
  const cell::WallProfile contour = probe.wall(stock, part.contour_wall);
  const cell::WallProfile slot_a = probe.wall(stock, part.slot_wall_a);
  const cell::WallProfile slot_b = probe.wall(stock, part.slot_wall_b);
  const std::pair<const char*, const cell::WallProfile*> all[] = {{"the pocket's climb wall", &climb},
                                                                  {"the pocket's conventional wall", &conv},
                                                                  {"the contour's wall", &contour},
                                                                  {"the slot's first wall", &slot_a},
                                                                  {"the slot's second wall", &slot_b}};
  for (const auto& [name, w] : all) {
    if (w->missing > 0) {
      throw Error(fmt::format("machining study: {} of {}'s probed points found no wall within the probe's search",
                              w->missing, name));
    }
  }
  e.climb_wall_mean_m = climb.mean_m;
  e.climb_wall_pv_m = climb.peak_to_valley_m;
  e.climb_wall_rms_m = climb.rms_m;
  e.conventional_wall_mean_m = conv.mean_m;
  e.conventional_wall_pv_m = conv.peak_to_valley_m;
  e.conventional_wall_rms_m = conv.rms_m;
  e.contour_wall_mean_m = contour.mean_m;
  e.contour_wall_pv_m = contour.peak_to_valley_m;
  e.contour_wall_rms_m = contour.rms_m;
  const cell::FloorFlatness pf = probe.floor(stock, part.pocket_floor);
  e.pocket_floor_flatness_m = pf.flatness_m;
  e.pocket_floor_mean_m = pf.mean_m;
  e.pocket_width_error_m = cell::PartProbe::width(climb, part.climb_wall, conv, part.conventional_wall).error_m;
  e.slot_width_error_m = cell::PartProbe::width(slot_a, part.slot_wall_a, slot_b, part.slot_wall_b).error_m;
  e.slot_floor_flatness_m = probe.floor(stock, part.slot_floor).flatness_m;
  if (walls != nullptr) {
    const std::pair<const char*, const cell::WallProfile*> named[] = {
        {"pocket wall, climb", &climb}, {"pocket wall, conventional", &conv}, {"contour wall", &contour}};
    for (const auto& [name, w] : named) {
      WallTrace t;
      t.name = name;
      // The row at mid-depth (the probe reads height by height): one profile along the wall.
      const double mid_z = 0.5 * (part.climb_wall.z_lo_m + part.climb_wall.z_hi_m);
      for (std::size_t i = 0; i < w->along_m.size(); ++i) {
        if (std::abs(w->z_m[i] - mid_z) > 1e-6) continue;
        t.along_m.push_back(w->along_m[i]);
        t.deviation_m.push_back(w->deviation_m[i]);
      }
      walls->push_back(std::move(t));
    }
  }
  return e;
}

Spread seed_spread(const std::vector<double>& v) {
  Spread s;
  s.n = static_cast<int>(v.size());
  if (v.empty()) return s;
  double sum = 0.0;
  for (double x : v) sum += x;
  s.mean = sum / s.n;
  double ss = 0.0;
  for (double x : v) ss += (x - s.mean) * (x - s.mean);
  s.sd = s.n > 1 ? std::sqrt(ss / (s.n - 1)) : 0.0;
  return s;
}

void assemble_rows(MachiningStudyOutput& out) {
  for (MachiningStrategy st : kMachiningStrategies) {
    for (double feed : out.feeds_mm_min) {
      MachiningRow row;
      row.strategy = st;
      row.feed_mm_min = feed;
      std::vector<double> v[9];
      for (const MachiningRun& r : out.runs) {
        if (r.strategy != st || r.feed_mm_min != feed) continue;
        const PartErrors& e = r.errors;
        const double x[9] = {e.climb_wall_mean_m,       e.climb_wall_pv_m,      e.conventional_wall_mean_m,
                             e.conventional_wall_pv_m,  e.contour_wall_mean_m,  e.contour_wall_pv_m,
                             e.pocket_floor_flatness_m, e.pocket_width_error_m, e.slot_width_error_m};
        for (int i = 0; i < 9; ++i) v[i].push_back(x[i]);
      }
      Spread* cells[9] = {&row.climb_mean,      &row.climb_pv,     &row.conventional_mean,
                          &row.conventional_pv, &row.contour_mean, &row.contour_pv,
                          &row.pocket_flatness, &row.pocket_width, &row.slot_width};
      for (int i = 0; i < 9; ++i) *cells[i] = seed_spread(v[i]);
      out.rows.push_back(row);
    }
  }
}

// The slot cuts' logs go to a directory of deflex's own, removed afterwards.
std::string make_log_dir(std::uint64_t seed) {
  std::random_device rd;
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    fmt::format("deflex-slot-logs-{}-{:x}", seed, static_cast<std::uint64_t>(rd()));
  std::filesystem::create_directories(dir);
  return dir.string();
}

void prepare_seed(SeedCell& sc, int index, const SlotCutPlan& plan) {
  const std::uint64_t seed = static_cast<std::uint64_t>(index) + 1;
  const auto t0 = std::chrono::steady_clock::now();
  sc.cell = std::make_unique<MillCell>(build_mill_cell(seed));
  sc.calibration_s = seconds_since(t0);
  const auto t1 = std::chrono::steady_clock::now();
  const std::uint64_t tool_seed = splitmix(seed ^ 0x70015eedULL);
  sc.truth = cell::draw_true_coefficients(al7075_published(), kCoefficientSpread, tool_seed);
  std::mt19937_64 rng(splitmix(tool_seed));
  sc.runout_m = std::uniform_real_distribution<double>(kRunoutLoM, kRunoutHiM)(rng);
  MillRunSpec spec;
  spec.true_k = sc.truth;
  spec.runout_m = sc.runout_m;
  spec.seed = splitmix(seed ^ 0x5107ULL);
  const std::string dir = make_log_dir(seed);
  std::vector<SlotCut> cuts;
  try {
    cuts = run_slot_cuts(*sc.cell, plan, spec, dir);
  } catch (...) {
    std::filesystem::remove_all(dir);
    throw;
  }
  std::filesystem::remove_all(dir);
  sc.fit.seed_index = index;
  sc.fit.fit = fit_cutting_coefficients(cuts);
  sc.fit.truth = sc.truth;
  sc.fit.truth_runout_m = sc.runout_m;
  sc.fit.slot_fz_m = plan.fz_m;
  sc.slot_cuts_s = seconds_since(t1);
}

MachiningRun run_part(const SeedCell& sc, const MillPart& part, MachiningStrategy strategy, double feed, int index) {
  const auto t0 = std::chrono::steady_clock::now();
  const CuttingCoefficients* k = &sc.fit.fit.k;  // never the truth
  const std::vector<PassProgram> programs = plan_passes(*sc.cell, part.passes, part.stock, strategy, feed, k);
  DexelStock stock = make_stock(part.stock);
  MillRunSpec spec;
  spec.strategy = strategy;
  spec.feed_mm_min = feed;
  spec.true_k = sc.truth;
  spec.runout_m = sc.runout_m;
  spec.seed = splitmix((static_cast<std::uint64_t>(index) + 1) ^ (static_cast<std::uint64_t>(feed) << 8) ^
                       (static_cast<std::uint64_t>(strategy) << 24));
  spec.trace = index == 0;
  MillRunResult r = run_mill_passes(*sc.cell, part.passes, programs, stock, spec, false);
  MachiningRun run;
  run.strategy = strategy;
  run.feed_mm_min = feed;
  run.seed_index = index;
  run.coupled = r.coupled;
  run.link_cycles = r.link_cycles;
  run.passes = std::move(r.passes);
  run.errors = probe_part(part, stock, splitmix(spec.seed ^ 0x9b0beULL), index == 0 ? &run.walls : nullptr);
  run.seconds = seconds_since(t0);
  return run;
}

MachiningSizes study_sizes(const MillPart& part, const SlotCutPlan& plan, const std::vector<double>& feeds) {
  MachiningSizes z;
  z.coefficient_spread = kCoefficientSpread;
  z.runout_lo_m = kRunoutLoM;
  z.runout_hi_m = kRunoutHiM;
  z.stock_cell_m = part.stock.cell_m;
  z.probe_noise_m = kProbeNoiseM;
  const Cutter cutter = study_cutter();
  for (double f : feeds) z.fz_m.push_back(f / 60.0 * 1e-3 * 60.0 / (kStudySpindleRpm * cutter.flutes));
  z.fz_m.insert(z.fz_m.end(), plan.fz_m.begin(), plan.fz_m.end());
  for (const MillPass& p : part.passes) z.ap_m.push_back(-p.corners.front().z());
  z.ap_m.push_back(plan.ap_m);
  return z;
}

}  // namespace

const char* to_string(MachiningStrategy s) {
  switch (s) {
    case MachiningStrategy::kUncompensated:
      return "uncompensated";
    case MachiningStrategy::kOffline:
      return "offline";
    case MachiningStrategy::kOnline:
      return "online";
    case MachiningStrategy::kHybrid:
      return "hybrid";
  }
  return "?";
}

MachiningStudyOutput run_machining_study(const MachiningStudyOptions& options) {
  const int seeds = options.seeds > 0 ? options.seeds : (options.quick ? 2 : 3);
  if (options.seeds < 0 || seeds > 20) throw InputError(fmt::format("seeds: {} is outside 1..20", options.seeds));
  const MillPart part = make_mill_part(options.quick);
  const SlotCutPlan plan = make_slot_cut_plan(options.quick);
  MachiningStudyOutput out;
  out.published = al7075_published();
  out.feeds_mm_min.assign(std::begin(kFeedsMmMin), std::end(kFeedsMmMin));
  out.seeds = seeds;
  out.probe_noise_m = kProbeNoiseM;
  std::mutex mutex;
  const int total = seeds * (1 + static_cast<int>(out.feeds_mm_min.size() * std::size(kMachiningStrategies)));
  int done = 0;
  auto report = [&](const std::string& label) {
    std::lock_guard<std::mutex> lock(mutex);
    ++done;
    if (options.progress) options.progress(static_cast<double>(done) / total, label);
  };
  std::vector<SeedCell> cells(static_cast<std::size_t>(seeds));
  std::vector<std::function<void()>> jobs;
  for (int s = 0; s < seeds; ++s) {
    jobs.emplace_back([&, s] {
      prepare_seed(cells[static_cast<std::size_t>(s)], s, plan);
      report(fmt::format("seed {}: calibrated, slot cuts fitted", s + 1));
    });
  }
  run_parallel(jobs, options.threads);
  jobs.clear();
  std::vector<MachiningRun> runs;
  for (int s = 0; s < seeds; ++s) {
    for (double feed : out.feeds_mm_min) {
      for (MachiningStrategy st : kMachiningStrategies) {
        jobs.emplace_back([&, s, feed, st] {
          MachiningRun r = run_part(cells[static_cast<std::size_t>(s)], part, st, feed, s);
          report(fmt::format("seed {}: {} at {:g} mm/min", s + 1, to_string(st), feed));
          std::lock_guard<std::mutex> lock(mutex);
          runs.push_back(std::move(r));
        });
      }
    }
  }
  run_parallel(jobs, options.threads);
  std::sort(runs.begin(), runs.end(), [](const MachiningRun& a, const MachiningRun& b) {
    return std::tie(a.seed_index, a.feed_mm_min, a.strategy) < std::tie(b.seed_index, b.feed_mm_min, b.strategy);
  });
  out.runs = std::move(runs);
  for (const MachiningRun& r : out.runs) {
    out.coupled.add(r.coupled);
    out.times.parts_s[static_cast<int>(r.strategy)] += r.seconds;
  }
  for (const SeedCell& sc : cells) {
    out.times.calibration_s += sc.calibration_s;
    out.times.slot_cuts_s += sc.slot_cuts_s;
  }
  out.sizes = study_sizes(part, plan, out.feeds_mm_min);
  for (const SeedCell& sc : cells) out.fits.push_back(sc.fit);
  assemble_rows(out);
  out.setup_paragraphs.push_back(fmt::format(
      "Part: Al7075-T6 block {:g} x 40 x 8 mm; a 10 mm slot 3 mm deep; an open pocket 14 mm wide and 4 mm deep, "
      "roughed by a slot and finished 2 mm a side (one wall in climb, one in conventional milling); an outside "
      "contour 2 mm into the block's side, round a corner. Tool: 10 mm three-flute carbide end mill, 30 deg "
      "helix, 12 000 rpm, M3; feeds {:g} and {:g} mm/min. Probe: 1 um per point (a CMM).",
      (part.stock.max_m.x() - part.stock.min_m.x()) * 1e3, out.feeds_mm_min[0], out.feeds_mm_min[1]));
  out.setup_paragraphs.push_back(fmt::format(
      "Cell per seed: the LDBB case's IRB 6700 with its own draws and calibration; true coefficients drawn "
      "log-normally about the published Al7075-T6 set ({:g} % 1-sigma), runout {:g}-{:g} um. The offline model "
      "and the hybrid strategy use coefficients fitted from {} slot cuts the cell ran and its sensor logged.",
      kCoefficientSpread * 100.0, kRunoutLoM * 1e6, kRunoutHiM * 1e6, plan.fz_m.size()));
  return out;
}

}  // namespace deflex::study
