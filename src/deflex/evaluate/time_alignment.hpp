// Putting a tracker file on the program's clock: the offset (and, if asked, the drift) between the
// tracker's time stamps and the commanded trajectory's, found by matching the measured path with the
// commanded one in time. The tracker, the controller and deflex's `--log` keep separate clocks; the
// time-synchronous error needs them on one.
#pragma once

#include <cstddef>

#include "deflex/model/tracker_trace.hpp"

namespace deflex {

struct TimeAlignmentOptions {
  /// Offsets searched: |offset - centre_s| <= search_s. A search_s of 0 or less searches every offset
  /// for which at least half the measured samples fall inside the commanded trajectory's time span.
  double search_s = 0.0;
  double centre_s = 0.0;
  bool fit_drift = false;  ///< also fit a clock rate difference
  int blocks = 10;         ///< pieces of the run the offset's uncertainty is estimated from
};

/// program time = tracker time + offset_s + drift * (tracker time - reference_t_s).
struct TimeAlignment {
  double offset_s = 0.0;
  double drift = 0.0;            ///< dimensionless (1e-6 = 1 ppm); 0 unless fitted
  double reference_t_s = 0.0;    ///< the tracker time the drift is taken about (the run's middle)
  double offset_std_s = 0.0;     ///< standard uncertainty of offset_s, from the spread over blocks
  double rms_m = 0.0;            ///< RMS distance of the measured points from the command at their time
  std::size_t samples = 0;       ///< measured samples inside the commanded span at the offset found
  double moving_fraction = 0.0;  ///< share of those samples where the command moves (hold still: no timing)
  [[nodiscard]] double program_time(double tracker_t_s) const {
    return tracker_t_s + offset_s + drift * (tracker_t_s - reference_t_s);
  }
};

/// Finds the offset (and drift) that brings `measured` onto `commanded`'s clock: a coarse search over
/// every offset in the range, then Gauss-Newton on the position residuals p_measured(t) -
/// p_commanded(program_time(t)) with all samples. Both traces in the same spatial frame (register the
/// tracker first); both with strictly increasing time stamps. The measured path may deviate from the
/// commanded one (deflection, a lag); what is found is the offset that best explains it in time, so a
/// constant lag of the robot behind its command is part of the offset. Throws InputError for fewer than
/// 10 samples in either trace, a commanded path that never moves, a search_s that is NaN or a centre_s
/// that is not finite, or a search range with no overlap.
TimeAlignment align_time(const TrackerTrace& measured, const TrackerTrace& commanded,
                         const TimeAlignmentOptions& options = {});

/// The trace with each time stamp mapped to program time. Throws InputError when the alignment's
/// offset_s, drift or reference_t_s is not finite.
TrackerTrace to_program_time(const TrackerTrace& measured, const TimeAlignment& alignment);

}  // namespace deflex
