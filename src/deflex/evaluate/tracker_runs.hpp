// Tracker files as the runs an evaluation compares: each file read in its format, put in the robot
// base frame (a registered tracker frame), optionally put on the program's clock (time alignment
// against the commanded path), and one run a file or, with lap splitting, one run a lap of a closed
// path. `deflex evaluate` reads its unloaded and loaded groups through it.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "deflex/evaluate/commanded_path.hpp"
#include "deflex/evaluate/frame_registration.hpp"
#include "deflex/evaluate/time_alignment.hpp"
#include "deflex/evaluate/tracker_files.hpp"
#include "deflex/model/tracker_trace.hpp"

namespace deflex {

/// How the files are read.
struct TrackerRunReading {
  TrackerReadOptions options;  ///< format options of the files
  bool have_frame = false;     ///< apply `frame` (tracker frame -> robot base)
  TrackerFrame frame;
  bool align = false;  ///< put each file on the program's clock against `commanded`
  CommandedPath commanded;
  TimeAlignmentOptions alignment;
  bool split_laps = false;  ///< one run a full lap of a closed path, partial pieces left out
};

/// One group of runs (unloaded or loaded).
struct TrackerRuns {
  std::vector<TrackerTrace> runs;
  std::vector<std::string> names;   ///< a run's file, and its lap ("a.csv lap 2"), for messages
  std::vector<TrackerTrace> whole;  ///< when aligning: each file whole (the time-synchronous figures)
  std::vector<std::pair<std::string, TimeAlignment>> alignments;  ///< when aligning: a file's alignment
  std::vector<std::string> notes;  ///< with lap splitting: "a.csv: 3 laps (1 partial piece left out)"
};

/// Reads `paths` as one group; `group` names it in messages ("unloaded"). Throws InputError or
/// DataError naming the file: a file that does not read, an alignment that fails, or, with lap
/// splitting, a file without a full lap.
[[nodiscard]] TrackerRuns read_tracker_runs(const std::vector<std::string>& paths, const TrackerRunReading& reading,
                                            const std::string& group);

}  // namespace deflex
