// `deflex machining-study`: the simulated cell mills a small aluminium part uncompensated and with each
// strategy, the part is probed, and the part errors are tabled with their spread over seeds.
#include <fmt/format.h>

#include <filesystem>
#include <iostream>
#include <memory>

#include "cli_util.hpp"
#include "command.hpp"
#include "deflex/report/machining_report.hpp"
#include "deflex/study/machining_study.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/output_file.hpp"

namespace deflex::cli {
namespace {

struct MachiningStudyOpts {
  std::string out_dir = "machining-study-out", report;
  int seeds = 0;
  int threads = 0;
  bool quick = false, no_progress = false;
};

void run_machining_study_command(const MachiningStudyOpts& o, int& exit_code) {
  if (o.seeds < 0 || o.seeds > 20) throw InputError(fmt::format("option --seeds: {} is outside 1..20", o.seeds));
  if (o.threads < 0 || o.threads > 256) {
    throw InputError(fmt::format("option --threads: {} is outside 0..256", o.threads));
  }
  // The outputs' folder before the study runs, so a path that cannot be one fails at once.
  OutputFolder out_folder(o.out_dir, "option --out");
  OutputTransaction outputs;
  const std::string csv_path = (std::filesystem::path(o.out_dir) / "machining-table.csv").string();
  const std::string json_path = (std::filesystem::path(o.out_dir) / "machining-study.json").string();
  OutputFile& csv = outputs.add(csv_path, "option --out");
  OutputFile& json = outputs.add(json_path, "option --out");
  OutputFile* html = o.report.empty() ? nullptr : &outputs.add(o.report, "option --report");
  study::MachiningStudyOptions options;
  options.quick = o.quick;
  options.seeds = o.seeds;
  options.threads = o.threads;
  if (!o.no_progress)
    options.progress = [](double f, const std::string& l) { draw_study_progress("machining-study", f, l); };
  std::cerr << fmt::format("deflex machining-study: {} seeds{}\n", o.seeds > 0 ? o.seeds : (o.quick ? 2 : 3),
                           o.quick ? ", quick" : "");
  const study::MachiningStudyOutput result = study::run_machining_study(options);
  if (!o.no_progress) end_study_progress();
  csv.write(study::machining_table_csv(result));
  json.write(study::machining_json(result));
  if (html != nullptr) html->write(machining_report_html(result));
  outputs.commit();
  out_folder.keep();
  for (const std::string& p : result.setup_paragraphs) std::cout << p << "\n";
  std::cout << "\n" << study::machining_table_text(result) << "\n" << study::machining_fit_text(result);
  const cell::CoupledTickCounters& c = result.coupled;
  std::cout << fmt::format(
      "\nThe cell: {} cutting ticks of the parts, each the arm and the cut solved together ({:.2f} solves of the arm "
      "a tick, at most {}); {} reached the cap of 8 without converging (the worst left {:.1f} N between the arm and "
      "the cut)\n",
      c.ticks, c.ticks > 0 ? static_cast<double>(c.arm_solves) / static_cast<double>(c.ticks) : 0.0, c.most_arm_solves,
      c.unconverged, c.worst_mismatch_n);
  std::cout << fmt::format("\nTable as CSV in {}, the whole result as JSON in {}{}\n", csv_path, json_path,
                           o.report.empty() ? "" : ", report in " + o.report);
  exit_code = 0;
}

void setup_machining_study(CLI::App& sub, int& exit_code) {
  auto o = std::make_shared<MachiningStudyOpts>();
  sub.add_flag("--quick", o->quick, "A shorter part, 3 slot cuts for the fit, 2 seeds (default 3)");
  sub.add_option("--seeds", o->seeds, "Seeds to run, each its own cell, tool and calibration (1..20)");
  sub.add_option("--out", o->out_dir,
                 "Directory for machining-table.csv and machining-study.json (default ./machining-study-out)");
  sub.add_option("--report", o->report, "Write the HTML report (wall profiles, force, deflection) to this file");
  sub.add_option("--threads", o->threads, "Worker threads, 0..256 (default 0: one per hardware thread)");
  sub.add_flag("--no-progress", o->no_progress, "No progress on stderr");
  sub.callback([o, &exit_code] { run_machining_study_command(*o, exit_code); });
}

}  // namespace

DEFLEX_COMMAND("machining-study",
               "The simulated cell mills an aluminium part under each strategy; the part's probed errors, tabled",
               setup_machining_study, 61);

}  // namespace deflex::cli
