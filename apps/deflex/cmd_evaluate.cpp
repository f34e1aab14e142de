// `deflex evaluate`: the paper's mean deformation and ISO 9283 path figures from tracker files.
#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>

#include <fmt/format.h>

#include "cli_util.hpp"
#include "command.hpp"
#include "deflex/evaluate/commanded_path.hpp"
#include "deflex/evaluate/frame_registration.hpp"
#include "deflex/evaluate/iso9283_path.hpp"
#include "deflex/evaluate/lap_split.hpp"
#include "deflex/evaluate/path_metrics.hpp"
#include "deflex/evaluate/time_alignment.hpp"
#include "deflex/evaluate/tracker_csv.hpp"
#include "deflex/evaluate/tracker_files.hpp"
#include "deflex/evaluate/tracker_runs.hpp"
#include "deflex/model/tracker_trace.hpp"
#include "deflex/text/errors.hpp"
#include "tracker_options.hpp"

namespace deflex::cli {

void add_tracker_format_options(CLI::App& sub, TrackerReadOptions& o) {
  sub.add_option("--tracker-units", o.length_unit,
                 "Length unit of Spatial Analyzer exports whose header names none: mm, m, cm, in or ft (never "
                 "guessed; an error when the header names another)");
  sub.add_option("--tracker-angle-units", o.angle_unit,
                 "Angle unit (deg or rad) of cylindrical or spherical SA exports whose header names none");
  sub.add_option("--sa-columns", o.columns,
                 "The SA export's columns when its header does not say, e.g. \"target x y z time\" or "
                 "\"collection group target r theta phi\" (docs/evaluation.md)");
  sub.add_option("--expect-frame", o.expect_frame,
                 "The working frame the SA exports must name in their header (another name is an error)");
}

namespace {

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

std::string alignment_text(const std::string& path, const TimeAlignment& a) {
  // Decimals enough for two significant digits of the uncertainty (12 us: 6), at least 4, at most 9.
  int decimals = 4;
  if (std::isfinite(a.offset_std_s) && a.offset_std_s > 0.0) {
    decimals = std::clamp(static_cast<int>(std::ceil(-std::log10(a.offset_std_s))) + 1, 4, 9);
  }
  std::string out = fmt::format("  {}: offset {:+.{}f} s", path, a.offset_s, decimals);
  out += std::isfinite(a.offset_std_s) ? fmt::format(" +- {:.{}f} s", a.offset_std_s, decimals)
                                       : " (uncertainty n/a: too few moving blocks)";
  if (a.drift != 0.0) {
    out += fmt::format(", drift {:+.2f} ppm about tracker time {:.6f} s", a.drift * 1e6, a.reference_t_s);
  }
  out += fmt::format(", RMS from the command {:.4f} mm, {} samples ({:.0f} % moving)\n", a.rms_m * 1e3, a.samples,
                     a.moving_fraction * 100);
  return out;
}

struct EvaluateOpts {
  std::vector<std::string> unloaded, loaded;
  std::string commanded, tracker_frame, align_to, robot;
  int points = 81;
  double max_offset_mm = 10.0, search_s = 0.0, clock_offset_s = kNaN;
  bool json = false, split = false, mean_reference = false, fit_drift = false;
  TrackerReadOptions read;
};

TrackerRunReading make_reading(const EvaluateOpts& o) {
  TrackerRunReading r;
  r.split_laps = o.split;
  r.options = o.read;
  if (!o.tracker_frame.empty()) {
    r.have_frame = true;
    r.frame = read_tracker_frame(o.tracker_frame);
    // The frame file says which tracker frame it maps from: a tracker file in another frame is refused.
    if (r.options.expect_frame.empty()) r.options.expect_frame = r.frame.tracker_frame;
  }
  if (!o.align_to.empty()) {
    r.align = true;
    std::unique_ptr<RobotModel> model;
    if (!o.robot.empty()) model = std::make_unique<RobotModel>(load_cli_robot("evaluate", o.robot));
    r.commanded = read_commanded_path(o.align_to, model.get());
    r.alignment.search_s = o.search_s;
    r.alignment.fit_drift = o.fit_drift;
  } else if (o.fit_drift || o.search_s > 0.0 || std::isfinite(o.clock_offset_s)) {
    throw InputError("options --fit-drift, --search-s and --clock-offset-s need --align-to");
  }
  return r;
}

/// The options of `deflex evaluate`, in the order --help lists them.
void add_evaluate_options(CLI::App& sub, EvaluateOpts& o) {
  sub.add_option("--unloaded", o.unloaded,
                 "Tracker file of the unloaded path: CSV (t_s,x_mm,y_mm,z_mm or x_m...) or a Spatial Analyzer ASCII "
                 "export; repeat the option for several laps/runs")
      ->required();
  sub.add_option("--loaded", o.loaded,
                 "Tracker file of the loaded path (uncompensated or compensated); repeat for several laps/runs "
                 "(each file is one run for ISO 9283 repeatability)")
      ->required();
  sub.add_option("--commanded", o.commanded,
                 "CSV of the commanded path (t_s,x_mm,y_mm,z_mm, base frame; t_s may be 0): ISO 9283 accuracy is then "
                 "taken against it instead of the first unloaded run");
  sub.add_option("--tracker-frame", o.tracker_frame,
                 "Frame file from deflex register: the tracker files are in the tracker's frame and are moved into "
                 "the robot's base frame with it");
  sub.add_option("--align-to", o.align_to,
                 "The commanded trajectory with its times (a Cartesian CSV t_s,x_mm,..., a joint trajectory "
                 "t_s,q1_deg,... or deflex online's --log, the joint forms with --robot): each tracker file is put "
                 "on its clock, and the time-synchronous error is printed");
  sub.add_option("--robot", o.robot, "Robot file for a joint trajectory or cycle log given to --align-to");
  sub.add_option("--search-s", o.search_s,
                 "--align-to: search offsets within this many s of 0 (default: every offset that overlaps half a run)");
  sub.add_flag("--fit-drift", o.fit_drift, "--align-to: also fit the clocks' rate difference (ppm)");
  sub.add_option("--clock-offset-s", o.clock_offset_s,
                 "--align-to: program time minus tracker time when known from a shared trigger; the lag of each run "
                 "behind its command is then printed (without it a constant lag is part of the clock offset)");
  add_tracker_format_options(sub, o.read);
  sub.add_option("--evaluation-points", o.points,
                 "ISO 9283: planes normal to the path, 1..100000 (default 81, the paper's)");
  sub.add_option("--max-offset-mm", o.max_offset_mm,
                 "ISO 9283: a run crossing a plane farther than this from the path does not count there (default 10)");
  sub.add_flag("--split-laps", o.split,
               "Split each file of a closed path (a circle) into its laps, each lap one run (a lap ends after a "
               "full turn or where the direction reverses)");
  sub.add_flag("--mean-reference", o.mean_reference,
               "Take the distances to the mean of the unloaded laps (a closed path, binned by angle about its "
               "centre), as deflex case-study does, instead of to the nearest of every unloaded sample: a dense, "
               "noisy reference biases the nearest-point distance low by its own noise");
  sub.add_flag("--json", o.json, "Print one JSON document on stdout");
}

/// The tracker files of both groups as read, with the clock alignments of their runs (unloaded first).
struct EvaluateRuns {
  TrackerRunReading reading;
  TrackerRuns unloaded, loaded;
  std::vector<std::pair<std::string, TimeAlignment>> alignments;
};

/// Checks the options no file is needed for, then reads every tracker file; the readers' notes go to stderr.
EvaluateRuns read_evaluate_runs(const EvaluateOpts& o) {
  if (!(o.max_offset_mm > 0.0)) {
    throw InputError("option --max-offset-mm: must be a positive number of mm");
  }
  if (!o.robot.empty() && o.align_to.empty()) throw InputError("option --robot: only used with --align-to");
  EvaluateRuns r;
  r.reading = make_reading(o);
  r.unloaded = read_tracker_runs(o.unloaded, r.reading, "unloaded");
  r.loaded = read_tracker_runs(o.loaded, r.reading, "loaded");
  for (const auto* g : {&r.unloaded, &r.loaded}) {
    for (const std::string& note : g->notes) std::cerr << "deflex evaluate: " << note << "\n";
  }
  r.alignments = r.unloaded.alignments;
  r.alignments.insert(r.alignments.end(), r.loaded.alignments.begin(), r.loaded.alignments.end());
  return r;
}

/// What evaluate prints, from the runs read.
struct EvaluateFigures {
  PathDeviationStats dev;       // the loaded runs' distance from the unloaded path (or its mean)
  bool have_commanded = false;  // ISO 9283 against --commanded, else against the first unloaded run
  std::string ref_name;
  Iso9283Path iso_loaded, iso_unloaded;        // iso_unloaded only with --commanded
  PathDeviationStats sync;                     // when aligned: loaded against unloaded at the same program time
  std::vector<PathDeviationStats> to_command;  // when aligned: each file against its command, unloaded first
};

/// With --mean-reference, the mean of the unloaded laps as the one reference path; else none.
std::vector<TrackerTrace> mean_unloaded_reference(const EvaluateOpts& o, const std::vector<TrackerTrace>& unloaded) {
  std::vector<TrackerTrace> distance_reference;
  if (o.mean_reference) {
    TrackerTrace all;
    for (const auto& t : unloaded) all.insert(all.end(), t.begin(), t.end());
    // Bins of about two samples a lap each, at most 3600 (0.1 deg): fewer than that would leave bins
    // empty on a sparse file (50 Hz), more would average too few laps' samples per bin.
    const auto per_lap = static_cast<int>(all.size() / std::max<std::size_t>(1, unloaded.size()));
    try {
      distance_reference.push_back(mean_closed_path(all, std::clamp(per_lap / 2, 36, 3600)));
    } catch (const InputError& e) {
      std::string files;
      for (const auto& u : o.unloaded) files += (files.empty() ? "" : ", ") + u;
      throw InputError(fmt::format("option --mean-reference: the mean of the unloaded laps ({}; {} sample(s)): {}",
                                   files, all.size(), e.what()));
    }
  }
  return distance_reference;
}

/// The distance, ISO 9283 and time-synchronous figures of the runs; a note on a noisy reference goes to stderr.
EvaluateFigures evaluate_figures(const EvaluateOpts& o, const EvaluateRuns& r) {
  const std::vector<TrackerTrace>& unloaded = r.unloaded.runs;
  const std::vector<TrackerTrace>& loaded = r.loaded.runs;
  EvaluateFigures f;
  const std::vector<TrackerTrace> distance_reference = mean_unloaded_reference(o, unloaded);
  if (!o.mean_reference && o.split && unloaded.size() > 1) {
    std::cerr << "deflex evaluate: note: the nearest-point distance to noisy unloaded laps is biased low by their "
                 "noise; --mean-reference takes the distance to their mean instead (docs/evaluation.md)\n";
  }
  f.dev = path_deviation(loaded, o.mean_reference ? distance_reference : unloaded);
  // ISO 9283 wants one reference path: the commanded one when given, else the first unloaded run.
  f.have_commanded = !o.commanded.empty();
  const TrackerTrace reference = f.have_commanded ? read_tracker_csv(o.commanded) : unloaded.front();
  f.ref_name = f.have_commanded ? "commanded" : "unloaded (first run)";
  const std::string ref_file = f.have_commanded ? o.commanded : r.unloaded.names.front();
  f.iso_loaded = iso_of(loaded, r.loaded.names, reference, ref_file, o.points, o.max_offset_mm * 1e-3);
  if (f.have_commanded) {
    f.iso_unloaded = iso_of(unloaded, r.unloaded.names, reference, ref_file, o.points, o.max_offset_mm * 1e-3);
  }
  // On the program's clock: the study's time-synchronous error (loaded against unloaded at the same
  // program time) and each run against its command.
  if (r.reading.align) {
    f.sync = time_synchronous_deviation(r.loaded.whole.front(), r.unloaded.whole.front());
    for (const auto* group : {&r.unloaded.whole, &r.loaded.whole}) {
      for (const auto& t : *group) f.to_command.push_back(time_synchronous_deviation(t, r.reading.commanded.trace));
    }
  }
  return f;
}

/// The JSON document of the figures.
nlohmann::json evaluate_json(const EvaluateOpts& o, const EvaluateRuns& r, const EvaluateFigures& f) {
  const PathDeviationStats& dev = f.dev;
  nlohmann::json doc{{"mean_deformation_mm", dev.mean_m * 1e3},
                     {"distance_to", o.mean_reference ? "mean of the unloaded laps" : "unloaded samples"},
                     {"max_mm", dev.max_m * 1e3},
                     {"rms_mm", dev.rms_m * 1e3},
                     {"std_mm", dev.std_m * 1e3},
                     {"loaded_samples", dev.samples},
                     {"unloaded_samples", samples_of(r.unloaded.runs)},
                     {"iso9283_loaded", iso_json(f.iso_loaded, f.ref_name)}};
  if (f.have_commanded) {
    doc["iso9283_unloaded"] = iso_json(f.iso_unloaded, f.ref_name);
  }
  if (r.reading.have_frame) {
    const TrackerFrame& fr = r.reading.frame;
    const auto mm = [](double m) { return std::isfinite(m) ? nlohmann::json(m * 1e3) : nlohmann::json(nullptr); };
    doc["tracker_frame"] = o.tracker_frame;
    doc["registration"] = {{"tracker_frame", fr.tracker_frame},  {"rms_mm", mm(fr.rms_m)}, {"max_mm", mm(fr.max_m)},
                           {"rms_limit_mm", mm(fr.rms_limit_m)}, {"points", fr.points},    {"circles", fr.circles}};
  }
  if (r.reading.align) {
    nlohmann::json runs = nlohmann::json::array();
    for (std::size_t k = 0; k < r.alignments.size(); ++k) {
      const auto& [path, a] = r.alignments[k];
      nlohmann::json run{
          {"file", path},
          {"offset_s", a.offset_s},
          {"offset_std_s", std::isfinite(a.offset_std_s) ? nlohmann::json(a.offset_std_s) : nlohmann::json(nullptr)},
          {"drift_ppm", a.drift * 1e6},
          // program time = tracker time + offset_s + drift_ppm 1e-6 (tracker time - reference_t_s)
          {"reference_t_s", a.reference_t_s},
          {"rms_from_command_mm", a.rms_m * 1e3},
          {"samples", a.samples},
          {"synchronous_error_to_command_mm", f.to_command[k].mean_m * 1e3}};
      if (std::isfinite(o.clock_offset_s)) run["lag_s"] = o.clock_offset_s - a.offset_s;
      runs.push_back(run);
    }
    doc["alignment"] = {{"commanded", o.align_to}, {"commanded_kind", r.reading.commanded.kind}, {"runs", runs}};
    doc["time_synchronous_mm"] = {{"mean", f.sync.mean_m * 1e3},
                                  {"max", f.sync.max_m * 1e3},
                                  {"rms", f.sync.rms_m * 1e3},
                                  {"samples", f.sync.samples}};
  }
  return doc;
}

/// The clock alignment of each run and the time-synchronous error, as text on stdout.
void print_evaluate_alignment(const EvaluateOpts& o, const EvaluateRuns& r, const EvaluateFigures& f) {
  std::cout << fmt::format("Clock alignment with {} ({}): program time = tracker time + offset\n", o.align_to,
                           r.reading.commanded.kind);
  for (std::size_t k = 0; k < r.alignments.size(); ++k) {
    std::cout << alignment_text(r.alignments[k].first, r.alignments[k].second);
    if (std::isfinite(o.clock_offset_s)) {
      std::cout << fmt::format("    lag behind the command {:+.4f} s (with --clock-offset-s {})\n",
                               o.clock_offset_s - r.alignments[k].second.offset_s, o.clock_offset_s);
    }
  }
  std::cout << fmt::format(
      "Time-synchronous error (loaded against unloaded at the same program time, first files): mean {:.4f} mm, "
      "max {:.4f} mm, RMS {:.4f} mm, {} samples\n",
      f.sync.mean_m * 1e3, f.sync.max_m * 1e3, f.sync.rms_m * 1e3, f.sync.samples);
}

/// The figures as text on stdout.
void print_evaluate_text(const EvaluateOpts& o, const EvaluateRuns& r, const EvaluateFigures& f) {
  const std::vector<TrackerTrace>& unloaded = r.unloaded.runs;
  const std::vector<TrackerTrace>& loaded = r.loaded.runs;
  const PathDeviationStats& dev = f.dev;
  const std::string distance_to = o.mean_reference ? "the mean of the unloaded laps" : "the unloaded path";
  if (r.reading.have_frame) {
    std::cout << fmt::format("Tracker files moved into the base frame with {} (registration RMS {:.4f} mm)\n",
                             o.tracker_frame, r.reading.frame.rms_m * 1e3);
  }
  std::cout << fmt::format(
      "Distance of the loaded path from {} ({} loaded points, {} run{}; {} unloaded points, {} "
      "run{}):\n  mean (the paper's mean deformation) {:.4f} mm\n  max {:.4f} mm   RMS {:.4f} mm   std {:.4f} mm\n",
      distance_to, dev.samples, loaded.size(), loaded.size() > 1 ? "s" : "", samples_of(unloaded), unloaded.size(),
      unloaded.size() > 1 ? "s" : "", dev.mean_m * 1e3, dev.max_m * 1e3, dev.rms_m * 1e3, dev.std_m * 1e3);
  std::cout << iso_text(fmt::format("ISO 9283 (loaded runs against the {} path)", f.ref_name), f.iso_loaded);
  if (f.have_commanded) {
    std::cout << iso_text("ISO 9283 (unloaded runs against the commanded path)", f.iso_unloaded);
  }
  if (r.reading.align) {
    print_evaluate_alignment(o, r, f);
  }
}

/// Reads the tracker files, computes the figures and prints them, as JSON with --json.
void run_evaluate(const EvaluateOpts& o, int& exit_code) {
  const EvaluateRuns runs = read_evaluate_runs(o);
  const EvaluateFigures figures = evaluate_figures(o, runs);
  if (o.json) {
    print_json(evaluate_json(o, runs, figures));
  } else {
    print_evaluate_text(o, runs, figures);
  }
  exit_code = 0;
}

/// Registers the options; the command runs once they parse.
void setup_evaluate(CLI::App& sub, int& exit_code) {
  auto o = std::make_shared<EvaluateOpts>();
  add_evaluate_options(sub, *o);
  sub.callback([o, &exit_code] { run_evaluate(*o, exit_code); });
}

}  // namespace

DEFLEX_COMMAND("evaluate",
               "Judge a path from tracker CSV files: the paper's mean deformation (loaded vs unloaded) and ISO 9283 "
               "path accuracy and repeatability, in mm",
               setup_evaluate, 60);

}  // namespace deflex::cli
