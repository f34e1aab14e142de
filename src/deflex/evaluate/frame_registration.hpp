// The tracker-to-robot-base transform: from points measured in both frames (closed-form least squares,
// Horn's unit-quaternion method), optionally with circles (a joint turned alone, or the TCP on a
// commanded circle) whose centre and axis are known in both frames; and its small YAML file.
//
// B. K. P. Horn, "Closed-form solution of absolute orientation using unit quaternions", J. Opt. Soc.
// Am. A 4(4), 1987: the rotation is the eigenvector of the largest eigenvalue of a symmetric 4x4
// matrix built from the centred points' cross-covariance; the translation follows from the centroids.
#pragma once

#include <string>
#include <vector>

#include "deflex/model/types.hpp"
#include "deflex/text/output_file.hpp"

namespace deflex {

/// A circle fitted to points measured in order along it: its centre (m), its axis (unit, oriented by
/// the right-hand rule along the direction of travel), its radius (m), the RMS distance of the points
/// from it (m) and the angle the points span (rad).
struct CircleFit {
  Vector3 centre_m = Vector3::Zero();
  Vector3 axis = Vector3::UnitZ();
  double radius_m = 0.0;
  double rms_m = 0.0;
  double arc_rad = 0.0;
  std::size_t points = 0;
};

/// Fits a circle (plane of best fit, then the circle in that plane by algebraic least squares refined
/// by Gauss-Newton on the geometric distances). Throws InputError (`what` names the points) for fewer
/// than 5 points, points on a line, or an arc of less than 20 degrees (its centre is then too poorly
/// determined to register a frame with).
CircleFit fit_circle(const std::vector<Vector3>& points_m, const std::string& what);

/// The largest registration RMS accepted by default (m): a laser tracker measures nests to some 0.01 mm
/// and a robot reaches a taught point to some 0.1 mm, so 1 mm means pairs that do not belong together
/// (a name or an order mixed up, a unit slipped, a nest that moved), not noise. `deflex register
/// --max-rms-mm` raises it, e.g. for base points known only to a robot's absolute accuracy.
inline constexpr double kDefaultMaxRegistrationRmsM = 1e-3;

/// The measurements a registration is computed from: points paired by index (tracker frame, base
/// frame; `names` optional, for messages), and circles paired by index.
struct RegistrationInput {
  std::vector<Vector3> tracker_m, base_m;
  std::vector<std::string> names;
  std::vector<CircleFit> tracker_circles, base_circles;
  double max_rms_m = kDefaultMaxRegistrationRmsM;  ///< a larger RMS refuses the frame
};

struct RegistrationResidual {
  std::string name;
  double distance_m = 0.0;  ///< |base_T_tracker * tracker - base|
};

struct FrameRegistration {
  Pose base_T_tracker = Pose::Identity();       ///< p_base = base_T_tracker * p_tracker
  std::vector<RegistrationResidual> residuals;  ///< one per point, then one per circle centre
  std::vector<double> circle_axis_error_rad;    ///< angle between each rotated tracker axis and its base axis
  double rms_m = 0.0;
  double max_m = 0.0;
  std::size_t points = 0;
  std::size_t circles = 0;
};

struct TrackerFile;  // tracker_files.hpp

/// Pairs the points of a tracker file with those of a base file (`deflex register`, Python's
/// register_frames): by name when both name their points (the whole name, else the target's own name,
/// so "Job::Reference::REF1" pairs with "REF1"), else by order (as many points on both sides); the
/// tracker's order is kept. Throws DataError naming the file, the line and the point: a name repeated on
/// one side, a name missing from the other, counts that differ without names. A point's `line` 0 (one
/// not read from a file) is named by its file alone.
[[nodiscard]] RegistrationInput pair_tracker_points(const TrackerFile& tracker, const TrackerFile& base);

/// Least-squares rigid transform (rotation and translation, no scale) from the tracker frame to the
/// base frame. A circle counts as its centre (a point) and its axis (a direction, weighted by the
/// radius squared: as much as two points a radius apart along it). Throws InputError when the
/// measurements cannot fix the transform: fewer than 3 points and no circle, points all on one line
/// (their spread across the line under 1/1000 of their spread along it) with no circle axis off that
/// line, sizes that do not match, or values that are not finite; and when the transform found is not
/// one to use: the base points a mirror image of the tracker points (a reflection fits them at under a
/// third of the best rotation's RMS: one file's frame is left-handed or has an axis reversed), or an
/// RMS above `max_rms_m` (the message names the worst points).
FrameRegistration register_frames(const RegistrationInput& input);

/// The transform and what it came from, as written to and read from a frame YAML file.
struct TrackerFrame {
  Pose base_T_tracker = Pose::Identity();
  std::string tracker_frame;  ///< the tracker's working frame name, "" when not known
  double rms_m = kNaN;
  double max_m = kNaN;
  double rms_limit_m = kNaN;  ///< the largest RMS the registration accepted (NaN: the default)
  std::size_t points = 0, circles = 0;
};

/// Writes the frame file (position in m, quaternion w x y z, the registration's figures as comments and
/// fields). Throws OutputError when a write fails.
void write_tracker_frame(const TrackerFrame& frame, OutputFile& out);
/// Reads it. Throws ModelError naming the file, line and field, also for a frame whose recorded RMS
/// exceeds the limit it records (kDefaultMaxRegistrationRmsM when it records none): a registration
/// that failed is never used.
TrackerFrame read_tracker_frame(const std::string& path);

}  // namespace deflex
