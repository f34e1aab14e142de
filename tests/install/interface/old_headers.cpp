// The headers that moved in deflex 0.2.0, included by their 0.1 paths (src/compat/: forwarding headers
// with a deprecation warning, for one minor version), and a name from each.
#include "deflex/evaluate/error_budget.hpp"
#include "deflex/evaluate/paper_figures.hpp"
#include "deflex/evaluate/study_tables.hpp"
#include "deflex/evaluate/tracker_trace.hpp"
#include "deflex/model/csv_table.hpp"
#include "deflex/model/errors.hpp"
#include "deflex/model/format_number.hpp"
#include "deflex/model/input_file.hpp"
#include "deflex/model/input_ranges.hpp"
#include "deflex/model/nearest_name.hpp"
#include "deflex/model/output_file.hpp"
#include "deflex/model/parse_number.hpp"
#include "deflex/model/robot_io.hpp"
#include "deflex/model/run_files.hpp"
#include "deflex/model/yaml_fields.hpp"
#include "deflex/online/payload_identification.hpp"
#include "deflex/paths/key_value_spec.hpp"
#include "deflex/study/case_report.hpp"

int main() {
  const deflex::InputError error("old paths");  // deflex/model/errors.hpp
  const deflex::TrackerTrace trace;             // deflex/evaluate/tracker_trace.hpp
  const deflex::StudyResult study;              // deflex/evaluate/study_tables.hpp
  return trace.empty() && study.setups.empty() && error.what()[0] == 'o' ? 0 : 1;
}
