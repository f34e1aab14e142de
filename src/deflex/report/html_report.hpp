// The case study's report: one self-contained HTML file (inline SVG and CSS, no scripts, no
// network) plus the figures as separate SVG files.
#pragma once

#include <string>
#include <vector>

#include "deflex/report/svg_charts.hpp"
#include "deflex/study/case_study.hpp"
#include "deflex/study/error_budget.hpp"
#include "deflex/study/study_tables.hpp"

namespace deflex {

struct ReportContent {
  std::string title = "deflex case study";
  /// The setup in words: one paragraph an entry (robot, path, loads, speeds, cell effects, seed).
  std::vector<std::string> setup_paragraphs;
  StudyResult study;
  std::vector<PathPlot> path_plots;
  /// Honest notes: where our figures differ from the paper's and why; one paragraph an entry.
  std::vector<std::string> notes;
  /// Optional: the case file as given (shown verbatim in a <pre> block).
  std::string case_text;
  /// Optional: what the online setups' controller links did (one table row a setup).
  std::vector<study::LinkSummary> links;
};

std::string html_report(const ReportContent& content);

/// Writes out_dir/report.html, figure5.svg (the paper's setups; all when none is the paper's),
/// figure5_beyond.svg (the other setups, when there are both), compensation.svg, parity.svg (when a
/// setup is the paper's), speed_sweep.svg and sweep.csv (when there is a sweep), per path plot
/// path_<n>.svg, polar_<n>.svg, laps_<n>.svg and signed_<n>.svg, per error budget budget_<n>.svg,
/// tables.md, tables.csv, error_budget.csv (when there is a budget) and results.json (the study's
/// JSON, study_to_json); creates out_dir if needed. The
/// files are outputs of `outputs` (output_file.hpp), written when it commits. Throws Error when the
/// folder cannot be made, InputError when a file cannot be an output.
void write_report(const ReportContent& content, const std::string& out_dir, OutputTransaction& outputs);
/// The same, committed at once.
void write_report(const ReportContent& content, const std::string& out_dir);

}  // namespace deflex
