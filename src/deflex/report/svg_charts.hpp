// SVG charts of a case study: the paper's Figure 5 (grouped bars), compensation per load, a parity
// plot against the paper's tables, the speed sweep, and per run: path plots with magnified
// deviations, per-lap deviation against the angle on the circle, and a polar deviation plot. Each
// function returns one standalone <svg> element (no scripts, no external resources), at most 1020 px
// wide with no text under 11 px, that can be saved as a file or inlined in HTML. Where a study has
// several seeds, whiskers show the range (min to max) over the seeds.
#pragma once

#include <string>

#include "deflex/evaluate/lap_split.hpp"
#include "deflex/model/tracker_trace.hpp"
#include "deflex/offline/toolpath_job.hpp"
#include "deflex/study/study_tables.hpp"

namespace deflex {

/// Which setups a study figure draws: those compared with a table of the paper (offline, online, and
/// a setup on the paper's own kind of link: SetupResult::paper_table), the others (beyond the
/// paper), or all.
enum class SetupSelection { kPaper, kBeyondPaper, kAll };
/// True when the paper has a table of the setup's name.
[[nodiscard]] bool paper_has_setup(const std::string& setup);
/// True when the setup is compared with a table of the paper (its own name's or its paper_table).
[[nodiscard]] bool paper_has_setup(const SetupResult& setup);

/// Figure 5 of the paper: mean deformation after compensation per setup, load and speed (upper
/// panel, one bar per speed), and before it (lower panel, pale bars: UC, mean over the speeds); the
/// paper's values as outlined bars beside ours; whiskers: min to max over the seeds.
std::string svg_figure5(const StudyResult& study, SetupSelection which = SetupSelection::kAll);

/// Compensation 1 - C/UC per setup and load (the figure the paper quotes: offline 67%, online
/// 69-80%): ours, mean over the speeds, whiskers min to max over the seeds; the paper's outlined.
std::string svg_compensation(const StudyResult& study);

/// The trends against load, one panel per paper table: C/UC (left axis; compensation 1 - C/UC on the
/// right) of every setup compared with that table, ours solid with whiskers over the seeds, the
/// paper's dashed, so a slope the paper has and ours lacks shows at a glance.
std::string svg_trends(const StudyResult& study);

/// Parity plot: ours (y) against the paper's (x) for every figure of Tables 1 and 2 (C per load and
/// speed, UC per load), every setup compared with a table (a setup on the paper's own kind of link
/// against Table 2, marked with its paper_label), log axes, the line y = x, the band of C's fidelity
/// target (kCTarget) and the lines of UC's (kUcTarget); whiskers: min to max over the seeds.
std::string svg_parity(const StudyResult& study);

/// The error budget as what it is, a one-effect-at-a-time sensitivity: one horizontal bar per effect,
/// C with that effect alone off (mm), with reference lines at C with every effect on and C with
/// every effect off at once (when run); each bar labelled with its value and its sensitivity
/// computed from the printed figures.
std::string svg_error_budget(const ErrorBudget& budget);

/// A path in the plane of best fit of the reference (the unloaded laps' mean, else the last
/// unloaded lap): the reference, the last lap of the loaded uncompensated (UC) and compensated (C)
/// runs, each drawn at reference + magnification * (its deviation from the reference).
/// magnification <= 0 picks a nice factor (1, 2 or 5 x 10^k) that draws the largest deviation at up
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

/// Distance from the reference (the unloaded laps' mean) against the angle about the circle's centre
/// (0 deg: the base's +x direction from the centre, growing anticlockwise seen from above), one line
/// per lap of the UC runs (left) and the C runs (right), clockwise and anticlockwise laps in their
/// own colours, each with an arrow in its direction of travel. Laps: plot.uc_laps and plot.c_laps.
std::string svg_lap_overlay(const PathPlot& plot);

/// Signed error of the compensated run along the path: for each sample of a C lap, its deviation from
/// the reference projected on the direction of the UC run's deviation at the same angle (the UC
/// laps of the same direction of travel averaged in 5 deg sectors), so + is under-compensated
/// (still deflected the way the load pushes) and - over-compensated; per direction of travel the
/// sector means against the angle (as in svg_lap_overlay), in mm.
std::string svg_signed_error(const PathPlot& plot);

/// A toolpath job along its path length (samples from ToolpathJobOptions::chart_samples): the cutting
/// force averaged over a revolution and its per-revolution peak (N); the predicted deflection of the
/// tip without compensation, with the compensated robot program and, when `gcode`, with the compensated
/// G-code run at the programmed orientation (mm); the spindle angle (deg).
std::string svg_toolpath_chart(const std::vector<ToolpathChartSample>& samples, const std::string& title, bool gcode);

/// Polar deviation plot: around the circle (angle as in svg_lap_overlay), the distance from the
/// reference drawn outward from a ring that stands for 0 mm, magnified, with rings labelled in mm;
/// UC and C, clockwise and anticlockwise laps each averaged in 5 deg sectors.
std::string svg_polar_deviation(const PathPlot& plot);

/// The speed sweep against TCP speed, one line per setup and load: compensation, C (the paper's
/// nearest-point metric), C time-synchronous (sees lag along the path) and UC; whiskers min to max
/// over the seeds; the paper's speeds shaded.
std::string svg_speed_sweep(const StudyResult& study);

/// Escapes &, <, >, " and ' for XML text and attributes.
std::string xml_escape(const std::string& text);

}  // namespace deflex
