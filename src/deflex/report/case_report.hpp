// The case study's report from its results: the report's content (the setup in words, the tables,
// the path plots) and the notes that compare our figures with the paper's, computed from the figures
// rather than asserted. Used by `deflex case-study` and by the Python module alike.
#pragma once

#include <string>
#include <vector>

#include "deflex/report/html_report.hpp"
#include "deflex/study/case_config.hpp"
#include "deflex/study/case_study.hpp"

namespace deflex::study {

/// Where our figures stand against the paper's, one paragraph an entry, every claim computed from the
/// printed figures (ours and the paper's): what the case file marks as tuned (read from `case_text`,
/// the case file's text; nothing said of it when empty), the loads outside the fidelity targets, each
/// setup's compensation range against the paper's, and the paper's headline order (online ahead of
/// offline at the highest load) checked on both.
[[nodiscard]] std::vector<std::string> honest_notes(const CaseConfig& config, const StudyResult& study,
                                                    const std::string& case_text = "");

/// The values a case file marks as tuned: each line whose comment starts with "tuned", as
/// "section.key = value (comment)", in the file's order.
[[nodiscard]] std::vector<std::string> tuned_values(const std::string& case_text);

/// The report of a case study's output: title, setup, tables, path plots, notes; `case_text` shown
/// verbatim when not empty.
[[nodiscard]] ReportContent case_report(const CaseConfig& config, const CaseStudyOutput& output,
                                        const std::string& case_text);

}  // namespace deflex::study
