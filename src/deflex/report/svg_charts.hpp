// SVG charts of a case study: the paper's Figure 5 (grouped bars), path plots with magnified
// deviations, and the speed sweep. Each function returns one standalone <svg> element (no scripts,
// no external resources) that can be saved as a file or inlined in HTML.
#pragma once

#include <string>

#include "deflex/evaluate/study_tables.hpp"
#include "deflex/evaluate/lap_split.hpp"
#include "deflex/evaluate/tracker_trace.hpp"

namespace deflex {

/// Figure 5 of the paper: mean deformation after compensation (and before, lighter) per load, one
/// group of bars per setup and load, one bar per speed; the paper's values marked beside ours.
std::string svg_figure5(const StudyResult& study);

/// A path in the plane of best fit of the unloaded path: the unloaded path, the loaded uncompensated
/// (UC) and compensated (C) paths, each drawn at unloaded + magnification * (its deviation from the
/// unloaded path). magnification <= 0 picks a nice factor (1, 2 or 5 x 10^k) that draws the largest deviation at up
/// to 12% of the path's size.
struct PathPlot {
  std::string title;
  TrackerTrace unloaded, uc, c;  ///< one lap each (the last)
  double magnification = 0.0;
  // Optional, for the per-lap and polar figures: the reference the distances are taken to (the
  // unloaded laps' mean) and every lap of the loaded runs with its direction.
  TrackerTrace unloaded_mean;
  std::vector<DirectedLap> uc_laps, c_laps;
};
std::string svg_path_plot(const PathPlot& plot);

/// Compensation (or residual) versus TCP speed, one line per setup and load in the sweep.
std::string svg_speed_sweep(const StudyResult& study);

/// Escapes &, <, >, " and ' for XML text and attributes.
std::string xml_escape(const std::string& text);

}  // namespace deflex
