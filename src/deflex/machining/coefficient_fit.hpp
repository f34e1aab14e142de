// Cutting coefficients from slot cuts (Altintas, Manufacturing Automation, ch. 2): in a full slot the
// force averaged over a revolution is linear in the feed per tooth,
//   along the feed   -N ap (fz Krc / 4 + Kre / pi)
//   normal to it      s N ap (fz Ktc / 4 + Kte / pi)      (s = +1 for M3, -1 for M4)
//   along the axis   -N ap (fz Kac / pi + Kae / 2)
// (milling_force.hpp's signs: the force on the tool), so a least-squares line through a few cuts at
// different feeds per tooth gives the cutting coefficients from its slope and the edge coefficients
// from its intercept, with standard errors from the residuals. And the force logs those cuts leave:
// the force sensor's CSV (t_s, fx_N, fy_N, fz_N[, mx_Nm, my_Nm, mz_Nm]), averaged over a window.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "deflex/machining/cutting_coefficients.hpp"
#include "deflex/machining/engagement.hpp"
#include "deflex/model/types.hpp"

namespace deflex {

/// One full-slot cut: its conditions and its force averaged over whole revolutions.
struct SlotCut {
  double fz_m = 0.0;  ///< feed per tooth, m
  double ap_m = 0.0;  ///< axial depth, m
  int flutes = 0;
  SpindleTurn turn = SpindleTurn::kClockwise;
  Vector3 mean_force_n = Vector3::Zero();  ///< on the tool, cut frame (feed, normal, axis), N
  std::string label;                       ///< names the cut in messages (its log file)
};

/// Below this ratio of the largest to the smallest feed per tooth the fit warns: the intercepts (edge
/// coefficients) are then extrapolated from a short line, and their standard errors grow as the
/// span shrinks (for two feeds a and b, the intercept's error is about (a + b) / (b - a) times the
/// force's).
inline constexpr double kMinFeedSpanRatio = 2.0;
/// Fewer distinct feeds than this leave the fit nothing to check the model's straight line with.
inline constexpr int kMinDistinctFeeds = 3;

struct CoefficientFit {
  CuttingCoefficients k;
  /// One standard error per coefficient, from the residuals (NaN with two cuts: nothing left over).
  CuttingCoefficients standard_error;
  /// Residual RMS of the mean forces per direction (feed, normal, axis), N.
  Vector3 residual_rms_n = Vector3::Zero();
  int cuts = 0;
  int distinct_feeds = 0;
  double fz_min_m = 0.0, fz_max_m = 0.0;
  /// What the user should know: too few or too close feeds, a coefficient set to 0.
  std::vector<std::string> warnings;
};

/// The least-squares fit, each direction on its own: F = b1 (N ap fz) + b2 (N ap). Throws InputError
/// for fewer than two cuts, fewer than two distinct feeds per tooth, a cut's non-positive or
/// non-finite fz, ap or flutes, a fitted coefficient below zero by more than three standard errors
/// (the logs do not follow the model: check the axes and the sign of the force), or a fitted set
/// outside the ranges of validate_coefficients(). A negative coefficient within three standard errors
/// of zero is set to zero with a warning.
[[nodiscard]] CoefficientFit fit_cutting_coefficients(const std::vector<SlotCut>& cuts);

/// How a force log's axes relate to the cut: which of the log's x, y, z (0, 1, 2) points along the
/// feed and which along the tool axis (from the tip into the spindle), each with its sign; the normal
/// follows as axis x feed. A wrist sensor on the robot measures the force on the tool; a table
/// dynamometer under the workpiece the force on the workpiece, its opposite.
struct SlotLogOptions {
  int feed_axis = 0;
  double feed_sign = 1.0;
  int tool_axis = 2;
  double tool_sign = 1.0;
  bool force_on_workpiece = false;
  std::optional<double> window_from_s, window_to_s;  ///< the steady cut; default the whole log
  std::optional<double> air_from_s, air_to_s;        ///< spindle on, not cutting: its mean is subtracted
  /// When given (rpm), the cut window is shortened to whole revolutions from its first sample, so its
  /// mean holds no part revolution of the force's ripple.
  std::optional<double> spindle_rpm;
};

struct SlotLogMean {
  Vector3 mean_force_n = Vector3::Zero();  ///< on the tool, cut frame
  int samples = 0;
  double duration_s = 0.0;   ///< of the window, first to last sample
  double revolutions = 0.0;  ///< whole revolutions the window was shortened to (0 without spindle_rpm)
  int air_samples = 0;
};

/// The mean force of a log over its window, in the cut frame. Throws DataError naming the file (bad
/// CSV, a window or air window with fewer than 2 samples, time not increasing) and InputError for axes
/// that are not two different axes.
[[nodiscard]] SlotLogMean read_slot_log(const std::string& path, const SlotLogOptions& options);

}  // namespace deflex
