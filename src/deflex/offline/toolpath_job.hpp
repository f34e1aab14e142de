// The offline job of a CAM toolpath, in one streamed pass (deflex offline --toolpath, and the Python
// module's compensate_toolpath): every point of the program read in order, the milling force at it
// from the stock as the program leaves it, the spindle's free angle chosen (or fixed), the arm's
// inverse kinematics in one configuration, the compensation, and the outputs a point at a time: the
// CSV, the compensated G-code over the source program, a RAPID or KRL program. Memory does not grow
// with the program (the spin's choice holds a bounded window of points).
//
// Frames (docs/machining.md, "From CAM to a compensated program"): the program's points are in the
// workpiece frame, placed in the robot's base frame by base_T_workpiece; the robot model's TCP is
// the tool tip, its z axis -tool_axis, its x the spin reference turned by the spin.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "deflex/machining/milling_force_model.hpp"
#include "deflex/offline/compensate_path.hpp"
#include "deflex/offline/offline_csv.hpp"
#include "deflex/offline/tool_spin.hpp"
#include "deflex/offline/toolpath_program.hpp"
#include "deflex/toolpath/gcode_write_back.hpp"
#include "deflex/toolpath/toolpath_reader.hpp"

namespace deflex {

struct ToolpathJobOptions {
  Pose base_T_workpiece = Pose::Identity();
  ToolSpinOptions spin;
  IkRequest first;  ///< the path's arm configuration and first seed (--config, --seed-deg)
  OfflineOptions compensation;
  PathIkOptions ik;
  /// The SVG chart's samples: at most this many points are kept (every k-th, k doubling as needed).
  std::size_t chart_samples = 0;
};

/// One point of a toolpath job, as the outputs see it.
struct ToolpathJobPoint {
  ToolpathPoint source;
  MillingPointForce force;
  double spin_rad = 0.0;
  OfflinePoint compensated;
  Vector3 command_tip_workpiece_m = Vector3::Zero();  ///< where the compensated program sends the tip
};

/// Where the points go; each optional, owned by the caller.
struct ToolpathSinks {
  OfflineCsvWriter* csv = nullptr;  ///< made with toolpath_csv_columns() as extra columns
  GcodeWriteBack* gcode = nullptr;
  ToolpathProgramWriter* program = nullptr;
  std::vector<ToolpathJobPoint>* keep = nullptr;  ///< every point (bounded by check_held_path_points)
};

/// A sample of the job along the path for the charts (path length in m, N, m).
struct ToolpathChartSample {
  double s_m = 0.0;
  double force_n = 0.0, peak_force_n = 0.0;
  double deflection_m = 0.0, residual_m = 0.0, gcode_residual_m = 0.0;
  double spin_rad = 0.0;
};

struct ToolpathJobResult {
  OfflineResult summary;  ///< over every point (max, mean, residual, corrections)
  ToolpathSummary toolpath;
  MillingRunCounts counts;
  double removed_volume_m3 = 0.0;
  std::size_t points = 0;
  /// The figure of merit: the mean (and max) predicted deflection over the cutting points, m.
  double mean_cutting_deflection_m = 0.0, max_cutting_deflection_m = 0.0;
  double max_force_n = 0.0, max_peak_force_n = 0.0, tooth_passing_hz = 0.0;
  double path_length_m = 0.0, cutting_length_m = 0.0;
  double spin_min_rad = 0.0, spin_max_rad = 0.0;
  double max_spin_rate_rad_per_m = 0.0;  ///< over feed moves
  ToolSpinStats spin;
  ArmConfiguration configuration;
  /// With a G-code output: the orientation part of the correction it cannot carry (the largest
  /// rotation between the desired and the commanded TCP, rad), and the tip's residual when the
  /// compensated positions are run at the programmed orientation and spin (m; every tenth cutting point).
  double max_orientation_correction_rad = 0.0;
  double max_gcode_residual_m = 0.0, mean_gcode_residual_m = 0.0;
  std::vector<ToolpathChartSample> chart;  ///< options.chart_samples of them at most
};

/// The extra CSV columns of a toolpath job, after offline_csv_columns(): line, cutting (1 when the
/// tool cuts), feed_mm_min, spindle_rpm, ae_mm, ap_mm, tool_spin_deg, peak_force_N, tooth_passing_Hz,
/// and the commanded tip in the workpiece frame x_cmd_wp_mm, y_cmd_wp_mm, z_cmd_wp_mm.
[[nodiscard]] std::vector<std::string> toolpath_csv_columns();

/// Runs the job. `stock` may be null when the force gives both ae_mm= and ap_mm=. Throws InputError
/// naming the toolpath file and line (the arm cannot reach a point at any spindle angle, a stock the
/// tool never touches, a tool axis the stock cannot follow, ...), DataError from the reader, before a
/// sink is finished: the caller's outputs are then discarded.
[[nodiscard]] ToolpathJobResult run_toolpath_job(const RobotModel& model, ToolpathReader& reader,
                                                 const MillingForceModel& force, Stock* stock,
                                                 const ToolpathJobOptions& options, const ToolpathSinks& sinks);

/// One text block for humans (the command's summary and the program's trailer): mm, deg, N.
[[nodiscard]] std::string toolpath_summary_text(const ToolpathJobResult& result, bool gcode);

}  // namespace deflex
