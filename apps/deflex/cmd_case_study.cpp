// `deflex case-study`: the paper's experiment on the simulated cell: Tables 1 and 2 beside
// the paper's, Figure 5, path plots, the error budget and the HTML report.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <mutex>
#include <optional>

#include "cli_util.hpp"
#include "command.hpp"
#include "deflex/evaluate/path_metrics.hpp"
#include "deflex/evaluate/tracker_csv.hpp"
#include "deflex/evaluate/tracker_files.hpp"
#include "deflex/model/tracker_trace.hpp"
#include "deflex/report/case_report.hpp"
#include "deflex/report/html_report.hpp"
#include "deflex/study/case_study.hpp"
#include "deflex/study/study_tables.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/input_file.hpp"
#include "deflex/text/output_file.hpp"

namespace deflex::cli {
namespace {

struct CaseStudyOpts {
  std::string case_file, out_dir = "case-study-out", traces_dir;
  long long seed = -1;
  int seeds = 0;
  int threads = 0;
  bool json = false, quick = false, exact = false, no_sweep = false, no_budget = false, no_progress = false;
};

// The first path containing `part` (sorted, so the pick does not depend on the threads' order).
std::string first_matching(std::vector<std::string> paths, const std::string& part) {
  std::sort(paths.begin(), paths.end());
  for (const auto& p : paths) {
    if (p.find(part) != std::string::npos) return p;
  }
  return paths.empty() ? std::string() : paths.front();
}

study::CaseStudyOptions case_study_options(const CaseStudyOpts& o) {
  study::CaseStudyOptions options;
  options.quick = o.quick;
  options.exact = o.exact;
  options.speed_sweep = !o.no_sweep;
  options.error_budget = !o.no_budget;
  options.threads = o.threads;
  options.seeds = o.seeds;
  if (!o.no_progress)
    options.progress = [](double f, const std::string& l) { draw_study_progress("case-study", f, l); };
  return options;
}

// --write-traces: each simulated tracker run as a CSV and as a Spatial Analyzer ASCII export, as a
// tracker session leaves it (the simulated tracker measures in the robot's base frame, so that is the
// working frame it names). Called from the study's threads.
class CaseTraceWriter {
 public:
  CaseTraceWriter(std::string dir, OutputTransaction& outputs) : dir_(std::move(dir)), outputs_(outputs) {}

  void write(const std::string& name, const TrackerTrace& trace) {
    const std::string path = (std::filesystem::path(dir_) / (name + ".csv")).string();
    const std::string sa_path = (std::filesystem::path(dir_) / (name + ".sa.txt")).string();
    SaExportOptions sa;
    sa.frame = "Robot Base";
    sa.group = name;
    const std::lock_guard lock(mutex_);
    write_tracker_csv(trace, outputs_.add(path, "option --write-traces"));
    write_sa_export(trace, outputs_.add(sa_path, "option --write-traces"), sa);
    written_.push_back(path);
    written_.push_back(sa_path);
  }
  [[nodiscard]] const std::vector<std::string>& written() const { return written_; }

 private:
  std::string dir_;
  OutputTransaction& outputs_;
  std::mutex mutex_;
  std::vector<std::string> written_;
};

void print_speed_sweep(const StudyResult& study) {
  std::cout << "\nSpeed sweep (beyond the paper): mean distance from the unloaded path, mm\n"
            << "  setup            load    speed mm/s  UC mm   C mm    compensation\n";
  for (const auto& p : study.speed_sweep) {
    // The compensation from the two figures as printed beside it.
    std::cout << fmt::format("  {:<15} {:>5.0f} N  {:>10.0f}  {:.3f}   {:.3f}   {}\n", p.setup, p.load_N, p.speed_mm_s,
                             p.uc_mm, p.c_mm,
                             percent_text(compensation_ratio(as_printed(p.uc_mm), as_printed(p.c_mm))));
  }
}

void print_error_budget(const ErrorBudget& b) {
  std::cout << fmt::format(
      "\nError budget, one effect at a time, {} {:.0f} N at {:.0f} mm/s (seed {}, the table's runs, {} laps each): "
      "C = {:.3f} mm with every effect (UC {:.3f} mm){}\n",
      b.setup, b.load_N, b.speed_mm_s, b.seed, b.laps, b.residual_mm_all, b.uc_mm,
      std::isfinite(b.residual_mm_all_off)
          ? fmt::format(", {:.3f} mm with every effect off at once", b.residual_mm_all_off)
          : std::string());
  // Columns as wide as their longest entry, so a long size never runs into the figures.
  std::size_t effect_w = 6, size_w = 4;
  for (const auto& e : b.entries) {
    effect_w = std::max(effect_w, e.effect.size());
    size_w = std::max(size_w, e.size.size());
  }
  std::cout << fmt::format("  {:<{}}  {:<{}}  {:>18}  {:>11}\n", "effect", effect_w, "size", size_w,
                           "C without it (mm)", "sensitivity");
  for (const auto& e : b.entries) {
    std::cout << fmt::format("  {:<{}}  {:<{}}  {:>18.3f}  {:>11}\n", e.effect, effect_w, e.size, size_w,
                             e.residual_mm_without_it, percent_text(printed_sensitivity(b, e)));
  }
  std::cout << "  sensitivity: (C with every effect - C without it alone) / C with every effect, from the printed "
               "figures; one effect at a time, so they need not add up to 100%\n";
}

void print_case_links(const study::CaseStudyOutput& result) {
  std::cout << "\nThe online setups' controller links (deflex's deployable link code, over the cell's network):\n";
  for (const auto& l : result.links) {
    const std::string correction =
        l.joint_commands
            ? fmt::format("largest correction {:.3f} mrad of the {:.1f} mrad bound ({:.3f} mm at the TCP)",
                          l.max_command_deviation_rad * 1e3, l.bound_rad * 1e3, l.max_tcp_correction_m * 1e3)
            : fmt::format("largest offset {:.3f} mm at the TCP", l.max_tcp_correction_m * 1e3);
    // The compensation from the two figures as printed beside it.
    std::cout << fmt::format(
        "  {:<16} {:<14} {:>8} cycles answered, {} datagrams rejected, {} commands stopped by the guard; {}; "
        "measured delay {}; at {:.0f} N UC {:.3f} mm, C {:.3f} mm ({} compensated){}\n",
        l.setup, l.link, l.cycles, l.rejected, l.guard_trips, correction,
        std::isfinite(l.measured_delay_s) ? fmt::format("{:.0f} ms", l.measured_delay_s * 1e3) : "n/a", l.load_n,
        l.uc_mm, l.c_mm, percent_text(l.compensation),
        l.controller_note.empty() ? std::string() : "; " + l.controller_note);
  }
}

void print_case_study_text(const CaseStudyOpts& o, const study::CaseStudyOutput& result,
                           const std::vector<std::string>& traces_written) {
  std::cout << study_tables_text(result.study);
  if (!result.study.speed_sweep.empty()) print_speed_sweep(result.study);
  for (const auto& b : result.study.error_budgets) print_error_budget(b);
  if (!result.links.empty()) print_case_links(result);
  std::cout << "\nThe cell: " << study::describe_coupled_solves(result.coupled, result.coupled_options) << "\n";
  std::cout << fmt::format(
      "\n{} runs and {} calibrations, {:.0f} s of robot time simulated in {:.1f} s wall time; report in "
      "{}/report.html\n",
      result.runs, result.calibrations, result.simulated_s, result.study.wall_time_s, o.out_dir);
  if (!traces_written.empty()) {
    std::cout << fmt::format(
        "{} tracker traces (t_s,x_mm,y_mm,z_mm) in {}; try: deflex evaluate --split-laps --unloaded {} --loaded {}\n",
        traces_written.size(), o.traces_dir, first_matching(traces_written, "_unloaded_"),
        first_matching(traces_written, "_uc_"));
  }
}

void run(const CaseStudyOpts& o, int& exit_code) {
  study::CaseConfig config = o.case_file.empty() ? study::paper_case() : study::load_case(o.case_file);
  // The report's folder before the study runs, so a path that cannot be one fails at once; made as
  // every output's folder is, and removed again if the study ends without its report.
  OutputFolder out_folder(o.out_dir, "option --out");
  std::optional<OutputFolder> traces_folder;
  if (!o.traces_dir.empty()) traces_folder.emplace(o.traces_dir, "option --write-traces");
  OutputTransaction outputs;  // the report and the traces: all or none
  if (o.seed >= 0) config.seed = static_cast<std::uint64_t>(o.seed);
  study::CaseStudyOptions options = case_study_options(o);
  CaseTraceWriter traces(o.traces_dir, outputs);
  if (!o.traces_dir.empty()) {
    options.trace_sink = [&traces](const std::string& name, const TrackerTrace& trace) { traces.write(name, trace); };
  }
  const int seeds = o.seeds > 0 ? o.seeds : config.seeds;
  std::cerr << fmt::format("deflex case-study: {} ({} seed{} from {}{})\n", config.name, seeds, seeds == 1 ? "" : "s",
                           config.seed, o.quick ? ", quick" : "");
  const study::CaseStudyOutput result = study::run_case_study(config, options);
  if (!o.no_progress) end_study_progress();

  // The case file's text goes into the report as it is, and its notes read what it marks as tuned.
  const ReportContent report = study::case_report(
      config, result,
      o.case_file.empty() ? study::paper_case_yaml() : read_input_file(o.case_file, InputKind::kConfig));
  write_report(report, o.out_dir, outputs);
  outputs.commit();
  out_folder.keep();
  if (traces_folder) traces_folder->keep();

  if (o.json) {
    print_json(study_to_json(result.study));
  } else {
    print_case_study_text(o, result, traces.written());
  }
  exit_code = 0;
}

void setup(CLI::App& sub, int& exit_code) {
  auto o = std::make_shared<CaseStudyOpts>();
  sub.add_option("--case", o->case_file, "Case file (YAML, see data/cases/paper.yaml); default: the paper's case");
  sub.add_option("--seed", o->seed, "Seed of every random effect (default: the case file's)");
  sub.add_option("--out", o->out_dir,
                 "Directory for report.html, the SVG figures and the tables (default ./case-study-out)");
  sub.add_option("--seeds", o->seeds,
                 "Seeds to run, from --seed up: each its own cell and runs; the tables give mean and spread "
                 "(default: the case file's protocol.seeds; 1..1000)");
  sub.add_option(
      "--write-traces", o->traces_dir,
      "Directory for the simulated tracker runs (CSV and Spatial Analyzer export, .sa.txt) of the first seed at "
      "the error budget's speed and each "
      "setup's highest load (unloaded, UC and C), to try `deflex evaluate` on");
  sub.add_option("--threads", o->threads, "Worker threads, 0..256 (default 0: one per hardware thread)");
  sub.add_flag("--json", o->json, "Print only the JSON document of the results on stdout");
  sub.add_flag("--quick", o->quick, "One clockwise and one anticlockwise lap per run instead of the protocol's 3 + 3");
  sub.add_flag("--exact", o->exact,
               "The slow reference computation (reference noise generator, tightest solver tolerances); without "
               "it the printed means stay within a tenth of their spread over the seeds of these");
  sub.add_flag("--no-sweep", o->no_sweep, "Skip the speed sweep");
  sub.add_flag("--no-budget", o->no_budget, "Skip the error budget");
  sub.add_flag("--no-progress", o->no_progress, "No progress bar on stderr");
  sub.callback([o, &exit_code] { run(*o, exit_code); });
}

}  // namespace

DEFLEX_COMMAND("case-study", "The paper's case study on the simulated cell: Tables 1 and 2 beside the paper's, report",
               setup, 60);

}  // namespace deflex::cli
