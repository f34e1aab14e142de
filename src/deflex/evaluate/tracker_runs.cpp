// Tracker files as runs (see tracker_runs.hpp).
#include "deflex/evaluate/tracker_runs.hpp"

#include <fmt/format.h>

#include "deflex/evaluate/lap_split.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

/// One file as a trace in the base frame: on the program's clock when aligning (its alignment
/// appended to `runs.alignments`), else with its own stamps.
TrackerTrace read_one_run(const std::string& path, const TrackerRunReading& r, TrackerRuns& runs) {
  const TrackerFile file = read_tracker_file(path, r.options);
  TrackerTrace t = r.align ? timed_trace(file, "--align-to") : untimed_trace(file);
  if (r.have_frame) {
    for (auto& s : t) s.p_m = r.frame.base_T_tracker * s.p_m;
  }
  if (r.align) {
    TimeAlignment a;
    try {
      a = align_time(t, r.commanded.trace, r.alignment);
    } catch (const InputError& e) {
      throw InputError(fmt::format("{}: {}", path, e.what()));
    }
    runs.alignments.emplace_back(path, a);
    t = to_program_time(t, a);
  }
  return t;
}

}  // namespace

TrackerRuns read_tracker_runs(const std::vector<std::string>& paths, const TrackerRunReading& reading,
                              const std::string& group) {
  TrackerRuns out;
  for (const auto& p : paths) {
    TrackerTrace t = read_one_run(p, reading, out);
    if (reading.align) out.whole.push_back(t);
    if (!reading.split_laps) {
      out.runs.push_back(std::move(t));
      out.names.push_back(p);
      continue;
    }
    LapSplit s = split_laps(t);
    if (s.laps.empty()) {
      throw InputError(fmt::format("{}: --split-laps found no full lap of a closed path in the {} run", p, group));
    }
    out.notes.push_back(fmt::format(
        "{}: {} lap{}{}", p, s.laps.size(), s.laps.size() == 1 ? "" : "s",
        s.dropped_partial > 0
            ? fmt::format(" ({} partial piece{} left out)", s.dropped_partial, s.dropped_partial == 1 ? "" : "s")
            : ""));
    for (std::size_t k = 0; k < s.laps.size(); ++k) {
      out.runs.push_back(std::move(s.laps[k]));
      out.names.push_back(fmt::format("{} lap {}", p, k + 1));
    }
  }
  return out;
}

}  // namespace deflex
