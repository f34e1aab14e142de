// `deflex evaluate`: the paper's mean deformation and ISO 9283 path figures from tracker files.
#include <algorithm>
#include <iostream>
#include <memory>

#include <fmt/format.h>

#include "cli_util.hpp"
#include "command.hpp"
#include "deflex/evaluate/iso9283_path.hpp"
#include "deflex/evaluate/lap_split.hpp"
#include "deflex/evaluate/path_metrics.hpp"
#include "deflex/evaluate/tracker_trace.hpp"
#include "deflex/model/errors.hpp"

namespace deflex::cli {
namespace {

// Each file is one run, or with --split-laps each lap of a closed path in a file is one run.
// `names` gets each run's file (and lap), for messages about a run.
std::vector<TrackerTrace> read_all(const std::vector<std::string>& paths, bool split, const char* what,
                                   std::vector<std::string>& names) {
  std::vector<TrackerTrace> out;
  for (const auto& p : paths) {
    TrackerTrace t = read_tracker_csv(p);
    if (!split) {
      out.push_back(std::move(t));
      names.push_back(p);
      continue;
    }
    LapSplit s = split_laps(t);
    if (s.laps.empty()) {
      throw InputError(fmt::format("{}: --split-laps found no full lap of a closed path in the {} run", p, what));
    }
    std::cerr << fmt::format("deflex evaluate: {}: {} lap{}{}\n", p, s.laps.size(), s.laps.size() == 1 ? "" : "s",
                             s.dropped_partial > 0 ? fmt::format(" ({} partial piece{} left out)", s.dropped_partial,
                                                                 s.dropped_partial == 1 ? "" : "s")
                                                   : "");
    for (std::size_t k = 0; k < s.laps.size(); ++k) {
      out.push_back(std::move(s.laps[k]));
      names.push_back(fmt::format("{} lap {}", p, k + 1));
    }
  }
  return out;
}

/// ISO 9283 figures of `runs` against `reference`; an error names the files ("run 2" alone would not).
Iso9283Path iso_of(const std::vector<TrackerTrace>& runs, const std::vector<std::string>& names,
                   const TrackerTrace& reference, const std::string& reference_name, int points, double max_offset_m) {
  try {
    return iso9283_path(runs, reference, points, max_offset_m);
  } catch (const InputError& e) {
    std::string legend;
    for (std::size_t k = 0; k < names.size(); ++k) {
      legend += fmt::format("{}run {} = {}", legend.empty() ? "" : ", ", k + 1, names[k]);
    }
    throw InputError(fmt::format("{} ({}; reference = {})", e.what(), legend, reference_name));
  }
}

std::size_t samples_of(const std::vector<TrackerTrace>& traces) {
  std::size_t n = 0;
  for (const auto& t : traces) {
    n += t.size();
  }
  return n;
}

nlohmann::json iso_json(const Iso9283Path& iso, const std::string& reference) {
  return {{"reference", reference},
          {"accuracy_mm", iso.accuracy_m * 1e3},
          {"mean_accuracy_mm", iso.mean_accuracy_m * 1e3},
          {"repeatability_mm", iso.runs > 1 ? nlohmann::json(iso.repeatability_m * 1e3) : nlohmann::json(nullptr)},
          {"runs", iso.runs},
          {"evaluation_points", iso.evaluation_points},
          {"skipped_points", iso.skipped_points}};
}

std::string iso_text(const std::string& what, const Iso9283Path& iso) {
  std::string rt = iso.runs > 1 ? fmt::format("{:.4f} mm", iso.repeatability_m * 1e3)
                                : "n/a (one run: give each lap as its own file)";
  std::string out = fmt::format(
      "{}:\n  path accuracy AT_p      {:.4f} mm  (mean over the planes {:.4f} mm)\n"
      "  path repeatability RT_p {}\n  {} run{}, {} planes normal to the path",
      what, iso.accuracy_m * 1e3, iso.mean_accuracy_m * 1e3, rt, iso.runs, iso.runs == 1 ? "" : "s",
      iso.evaluation_points);
  if (iso.skipped_points > 0) {
    out += fmt::format(" ({} planes left out: not crossed by every run)", iso.skipped_points);
  }
  return out + "\n";
}

void setup_evaluate(CLI::App& sub, int& exit_code) {
  struct Opts {
    std::vector<std::string> unloaded, loaded;
    std::string commanded;
    int points = 81;
    double max_offset_mm = 10.0;
    bool json = false, split = false, mean_reference = false;
  };
  auto o = std::make_shared<Opts>();
  sub.add_option("--unloaded", o->unloaded,
                 "Tracker CSV (t_s,x_mm,y_mm,z_mm) of the unloaded path; repeat the option for several laps/runs")
      ->required();
  sub.add_option("--loaded", o->loaded,
                 "Tracker CSV of the loaded path (uncompensated or compensated); repeat for several laps/runs "
                 "(each file is one run for ISO 9283 repeatability)")
      ->required();
  sub.add_option("--commanded", o->commanded,
                 "CSV of the commanded path (same columns; t_s may be 0): ISO 9283 accuracy is then taken against "
                 "it instead of the first unloaded run");
  sub.add_option("--evaluation-points", o->points,
                 "ISO 9283: planes normal to the path, 1..100000 (default 81, the paper's)");
  sub.add_option("--max-offset-mm", o->max_offset_mm,
                 "ISO 9283: a run crossing a plane farther than this from the path does not count there (default 10)");
  sub.add_flag("--split-laps", o->split,
               "Split each file of a closed path (a circle) into its laps, each lap one run (a lap ends after a "
               "full turn or where the direction reverses)");
  sub.add_flag("--mean-reference", o->mean_reference,
               "Take the distances to the mean of the unloaded laps (a closed path, binned by angle about its "
               "centre), as deflex case-study does, instead of to the nearest of every unloaded sample: a dense, "
               "noisy reference biases the nearest-point distance low by its own noise");
  sub.add_flag("--json", o->json, "Print one JSON document on stdout");
  sub.callback([o, &exit_code] {
    if (!(o->max_offset_mm > 0.0)) {
      throw InputError("option --max-offset-mm: must be a positive number of mm");
    }
    std::vector<std::string> unloaded_names;
    std::vector<std::string> loaded_names;
    const std::vector<TrackerTrace> unloaded = read_all(o->unloaded, o->split, "unloaded", unloaded_names);
    const std::vector<TrackerTrace> loaded = read_all(o->loaded, o->split, "loaded", loaded_names);
    std::vector<TrackerTrace> distance_reference;
    if (o->mean_reference) {
      TrackerTrace all;
      for (const auto& t : unloaded) all.insert(all.end(), t.begin(), t.end());
      // Bins of about two samples a lap each, at most 3600 (0.1 deg): fewer than that would leave bins
      // empty on a sparse file (50 Hz), more would average too few laps' samples per bin.
      const auto per_lap = static_cast<int>(all.size() / std::max<std::size_t>(1, unloaded.size()));
      distance_reference.push_back(mean_closed_path(all, std::clamp(per_lap / 2, 36, 3600)));
    }
    if (!o->mean_reference && o->split && unloaded.size() > 1) {
      std::cerr << "deflex evaluate: note: the nearest-point distance to noisy unloaded laps is biased low by their "
                   "noise; --mean-reference takes the distance to their mean instead (docs/evaluation.md)\n";
    }
    const PathDeviationStats dev = path_deviation(loaded, o->mean_reference ? distance_reference : unloaded);
    const std::string distance_to = o->mean_reference ? "the mean of the unloaded laps" : "the unloaded path";
    // ISO 9283 wants one reference path: the commanded one when given, else the first unloaded run.
    const bool have_commanded = !o->commanded.empty();
    const TrackerTrace reference = have_commanded ? read_tracker_csv(o->commanded) : unloaded.front();
    const std::string ref_name = have_commanded ? "commanded" : "unloaded (first run)";
    const std::string ref_file = have_commanded ? o->commanded : unloaded_names.front();
    const Iso9283Path iso_loaded =
        iso_of(loaded, loaded_names, reference, ref_file, o->points, o->max_offset_mm * 1e-3);
    Iso9283Path iso_unloaded;
    if (have_commanded) {
      iso_unloaded = iso_of(unloaded, unloaded_names, reference, ref_file, o->points, o->max_offset_mm * 1e-3);
    }
    if (o->json) {
      nlohmann::json doc{{"mean_deformation_mm", dev.mean_m * 1e3},
                         {"distance_to", o->mean_reference ? "mean of the unloaded laps" : "unloaded samples"},
                         {"max_mm", dev.max_m * 1e3},
                         {"rms_mm", dev.rms_m * 1e3},
                         {"std_mm", dev.std_m * 1e3},
                         {"loaded_samples", dev.samples},
                         {"unloaded_samples", samples_of(unloaded)},
                         {"iso9283_loaded", iso_json(iso_loaded, ref_name)}};
      if (have_commanded) {
        doc["iso9283_unloaded"] = iso_json(iso_unloaded, ref_name);
      }
      print_json(doc);
    } else {
      std::cout << fmt::format(
          "Distance of the loaded path from {} ({} loaded points, {} run{}; {} unloaded points, {} "
          "run{}):\n  mean (the paper's mean deformation) {:.4f} mm\n  max {:.4f} mm   RMS {:.4f} mm   std {:.4f} mm\n",
          distance_to, dev.samples, loaded.size(), loaded.size() > 1 ? "s" : "", samples_of(unloaded), unloaded.size(),
          unloaded.size() > 1 ? "s" : "", dev.mean_m * 1e3, dev.max_m * 1e3, dev.rms_m * 1e3, dev.std_m * 1e3);
      std::cout << iso_text(fmt::format("ISO 9283 (loaded runs against the {} path)", ref_name), iso_loaded);
      if (have_commanded) {
        std::cout << iso_text("ISO 9283 (unloaded runs against the commanded path)", iso_unloaded);
      }
    }
    exit_code = 0;
  });
}

}  // namespace

DEFLEX_COMMAND("evaluate",
               "Judge a path from tracker CSV files: the paper's mean deformation (loaded vs unloaded) and ISO 9283 "
               "path accuracy and repeatability, in mm",
               setup_evaluate, 60);

}  // namespace deflex::cli
