// The machining study's report: one self-contained HTML file (inline SVG and CSS, no scripts, no
// network): the table of part errors, the fitted coefficients, the walls' profiles per strategy, the
// predicted against the true force along the passes, and the tool's deflection from the path.
#pragma once

#include <string>

#include "deflex/study/machining_study.hpp"

namespace deflex {

[[nodiscard]] std::string machining_report_html(const study::MachiningStudyOutput& out);

}  // namespace deflex
