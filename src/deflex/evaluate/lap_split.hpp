// Splitting a tracker trace of a closed path (the paper's circle) into laps, so repeated laps in
// one file become the repeated runs ISO 9283 asks for; and the plane of best fit such paths lie in.
#pragma once

#include <vector>

#include "deflex/model/tracker_trace.hpp"

namespace deflex {

/// Plane of best fit of a path: through the centroid, normal along the points' weakest direction
/// (smallest eigenvalue of their covariance), oriented with n.z >= 0. In-plane axes u, v follow the
/// base x (or y, when x is nearly normal to the plane) so a horizontal path keeps x to the right.
struct PathPlane {
  Vector3 centroid_m = Vector3::Zero();
  Vector3 normal = Vector3::UnitZ();
  Vector3 u = Vector3::UnitX();
  Vector3 v = Vector3::UnitY();
};
/// Throws InputError for fewer than 2 samples or a sample that is not finite (naming it, 0-based).
PathPlane best_fit_plane(const TrackerTrace& path);

struct LapSplit {
  std::vector<TrackerTrace> laps;
  int dropped_partial = 0;  ///< pieces that turned less than `min_turn_rad` (approach, partial laps)
};

/// Splits a trace that goes round a closed path (any number of laps, either direction, reversals
/// allowed) by the angle it turns about the centroid in its plane of best fit: a lap ends after a
/// full turn (2 pi) or where the direction of travel reverses (the angle falls back by more than
/// `reversal_rad` from its extreme; the lap ends at the extreme). Pieces that turn less than
/// `min_turn_rad` are dropped and counted. Throws InputError for fewer than 2 samples, a sample that is
/// not finite (as best_fit_plane does), a min_turn_rad outside (0, 2 pi] or a reversal_rad that is not
/// finite and > 0.
LapSplit split_laps(const TrackerTrace& trace, double min_turn_rad = 0.9 * 2.0 * kPi,
                    double reversal_rad = deg_to_rad(5.0));

/// A lap and its direction of travel: clockwise when, seen from the side the plane's normal points
/// to (n.z >= 0: from above), it turns clockwise about the trace's centroid.
struct DirectedLap {
  TrackerTrace trace;
  bool clockwise = false;
};
/// split_laps(trace).laps, each with its direction (the sign of the area it sweeps about the
/// centroid of the whole trace in its plane of best fit).
std::vector<DirectedLap> directed_laps(const TrackerTrace& trace);

/// The mean of a closed path's laps, as one closed polyline: the samples binned by their angle about
/// the centroid in the plane of best fit (`bins` equal sectors), each bin's positions averaged, the
/// bins in angle order and the first repeated at the end. A nearest-point distance to a dense, noisy
/// reference is biased low (the reference's noise fills a band the loaded point finds its nearest
/// neighbour in); to the laps' mean it is not. Needs a path around its centroid: throws InputError
/// for fewer than 2 samples, a sample that is not finite, or when fewer than 90 % of the bins hold a
/// sample.
TrackerTrace mean_closed_path(const TrackerTrace& trace, int bins = 3600);

}  // namespace deflex
