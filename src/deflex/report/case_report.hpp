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

/// Where our figures differ from the paper's and why, one paragraph an entry.
[[nodiscard]] std::vector<std::string> honest_notes(const CaseConfig& config, const StudyResult& study);

/// The report of a case study's output: title, setup, tables, path plots, notes; `case_text` shown
/// verbatim when not empty.
[[nodiscard]] ReportContent case_report(const CaseConfig& config, const CaseStudyOutput& output,
                                        const std::string& case_text);

}  // namespace deflex::study
