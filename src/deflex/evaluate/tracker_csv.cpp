// Laser-tracker traces as CSV files (tracker_csv.hpp).
#include "deflex/evaluate/tracker_csv.hpp"

#include <array>

#include <fmt/format.h>

#include "deflex/text/csv_table.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

TrackerTrace from_table(const CsvTable& table) {
  table.require({"t_s", "x_mm", "y_mm", "z_mm"});
  const std::size_t ct = table.column("t_s");
  const std::size_t cx = table.column("x_mm");
  const std::size_t cy = table.column("y_mm");
  const std::size_t cz = table.column("z_mm");
  if (table.rows() == 0) {
    throw DataError(fmt::format("{}: no samples (only a header row)", table.source()));
  }
  TrackerTrace trace;
  trace.reserve(table.rows());
  for (std::size_t r = 0; r < table.rows(); ++r) {
    TrackerSample s;
    s.t_s = table.at(r, ct);
    s.p_m = Vector3(table.at(r, cx), table.at(r, cy), table.at(r, cz)) * 1e-3;
    // Equal times are allowed (a tracker may repeat a stamp); going back means the rows are
    // shuffled or two files were concatenated, and distances along the path would be wrong.
    if (!trace.empty() && s.t_s < trace.back().t_s) {
      table.fail(r, "t_s", fmt::format("time goes backwards ({} s after {} s)", s.t_s, trace.back().t_s));
    }
    trace.push_back(s);
  }
  return trace;
}

// The columns read; any other (a name, a note) is ignored, text or number.
const std::vector<std::string> kTrackerColumns = {"t_s", "x_mm", "y_mm", "z_mm"};

}  // namespace

TrackerTrace read_tracker_csv(const std::string& path) {
  return from_table(CsvTable::read_file(path, kTrackerColumns));
}

TrackerTrace parse_tracker_csv(const std::string& text, const std::string& source) {
  return from_table(CsvTable::parse(text, source, kTrackerColumns));
}

void write_tracker_csv(const TrackerTrace& trace, const std::string& path) {
  OutputFile out(path, "tracker file");
  write_tracker_csv(trace, out);
  out.commit();
}

void write_tracker_csv(const TrackerTrace& trace, OutputFile& out) {
  CsvWriter w(out, {"t_s", "x_mm", "y_mm", "z_mm"});
  for (const auto& s : trace) {
    const std::array<double, 4> row{s.t_s, s.p_m.x() * 1e3, s.p_m.y() * 1e3, s.p_m.z() * 1e3};
    w.row(row);
  }
  w.finish();
}

}  // namespace deflex
