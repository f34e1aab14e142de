// ISO 9283:1998 section 7.2 path accuracy (AT_p) and path repeatability (RT_p), positions only.
#pragma once

#include <vector>

#include "deflex/model/tracker_trace.hpp"

namespace deflex {

/// Path figures per ISO 9283 7.2, from n repeated runs of the same path. How they are computed:
///  - `evaluation_points` points c_i are placed along the reference at equal arc length, at the
///    middles of equal parts (s_i = (i + 1/2) L / N), so no point sits on an open path's end.
///  - At each c_i the plane normal to the reference path (tangent: the chord between the reference's
///    points 1% of its length before and after c_i, clamped to its ends) is intersected with every
///    run (linear interpolation on the segment crossing the plane; of several crossings, the one
///    closest to c_i). Runs that do not cross within `max_offset_m` of c_i make the point invalid.
///  - Barycentre of the n crossing points: x_bar_i. AT_p = max_i |x_bar_i - c_i|.
///  - l_ij = |x_ij - x_bar_i|, l_bar_i = mean_j l_ij, S_l_i = sqrt(sum_j (l_ij - l_bar_i)^2 / (n-1)),
///    RT_p = max_i (l_bar_i + 3 S_l_i). RT_p needs n >= 2 (it is 0 for n = 1).
struct Iso9283Path {
  double accuracy_m = 0.0;       ///< AT_p
  double repeatability_m = 0.0;  ///< RT_p
  double mean_accuracy_m = 0.0;  ///< mean_i |x_bar_i - c_i| (not in ISO 9283; comparable with the paper's mean)
  int evaluation_points = 0;     ///< planes where every run crossed
  int skipped_points = 0;        ///< planes some run did not cross (left out of the figures)
  int runs = 0;
};

/// Throws InputError when there is no run, a run or the reference has fewer than 2 samples, or no
/// plane is crossed by every run.
Iso9283Path iso9283_path(const std::vector<TrackerTrace>& repeated_runs, const TrackerTrace& commanded_or_reference,
                         int evaluation_points = 81, double max_offset_m = 0.01);

}  // namespace deflex
