// The offline job (paper, Figure 2) in one pass along a path: each pose, its inverse kinematics, then
// every load's compensation, with each load's CSV rows streamed as they are made. `deflex offline`
// and the Python module's compensate_path / compensate_loads both run it, so the two give the same
// points, the same figures and the same errors. What an output needs whole (a RAPID module's points,
// a timed trajectory's poses and joints) is kept only when asked for, so a path written to CSV
// alone streams in memory independent of its length.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "deflex/force/force_model.hpp"
#include "deflex/offline/compensate_path.hpp"
#include "deflex/offline/offline_csv.hpp"
#include "deflex/offline/rapid_module.hpp"
#include "deflex/paths/path_ik.hpp"
#include "deflex/paths/pose_source.hpp"

namespace deflex {

/// One load of a job. The job keeps the pointers for the length of run_offline_job() only.
struct OfflineLoad {
  const ForceModel* force = nullptr;  ///< required
  OfflineCsvWriter* csv = nullptr;    ///< when given, a row a point (finish() is called at the end)
  bool keep_points = false;           ///< keep every OfflinePoint in the result (RAPID, trajectories, Python)
};

struct OfflineJobOptions {
  OfflineOptions compensation;  ///< predict the deflection and residual, or compensate only
  IkRequest first;              ///< the first point's arm configuration and seed
  bool keep_nominal = false;    ///< keep the poses and their nominal joints (a nominal trajectory)
};

/// The range of an LDBB bar's length (m) and inclination to the base XY plane (rad) along the path.
struct BarRange {
  double length_min_m = 0.0, length_max_m = 0.0;
  double inclination_min_rad = 0.0, inclination_max_rad = 0.0;
};

struct OfflineJobResult {
  std::vector<OfflineResult> loads;           ///< one a load, in order; `points` filled when keep_points
  std::vector<std::optional<BarRange>> bars;  ///< one a load: set for an LdbbForceModel
  ArmConfiguration configuration;             ///< the arm configuration the path was solved in
  std::size_t points = 0;
  std::vector<Pose> poses;             ///< keep_nominal: the path's poses
  std::vector<JointVector> q_nominal;  ///< keep_nominal: their inverse kinematics (rad)
};

/// Runs the job. Throws InputError when there is no load or no point, a load has no force model,
/// more points are to be kept than check_held_path_points() allows, and every error of PathIkSolver
/// and PathCompensator (each naming the path point), before a CSV writer is finished.
[[nodiscard]] OfflineJobResult run_offline_job(const RobotModel& model, PoseSource& source,
                                               const std::vector<OfflineLoad>& loads, const OfflineJobOptions& options);

/// Labels for the loads' files ("ldbb_125N_push"), identifier-safe and unique: a repeated label gets
/// "_2", "_3" ... by its position.
[[nodiscard]] std::vector<std::string> offline_load_labels(const std::vector<const ForceModel*>& forces);

/// "out.csv" + "ldbb_125N_push" -> "out_ldbb_125N_push.csv" (one file a load when there are several).
[[nodiscard]] std::string path_with_label(const std::string& path, const std::string& label);

/// "absj" or "movel"; throws InputError naming `what` (an option or argument) for anything else.
[[nodiscard]] RapidMotion parse_rapid_motion(const std::string& text, const std::string& what);

/// A TCP speed a timed trajectory is made at: finite, > 0 and at most 10000 mm/s. Throws InputError
/// naming `what`.
void check_trajectory_speed(double speed_mm_s, const std::string& what);

}  // namespace deflex
