// Identification of the lumped joint stiffness from measured TCP deflections under known loads
// (DESIGN.md, "Stiffness identification"). The model is linear in the compliances c_j = 1/k_j:
//
//   dp_i = sum_j c_j * J_tcp,j(q_i) * (J_wap,j(q_i)^T W_i)
//
// with J_wap the Jacobian at the wrench application point (the torque each joint feels) and
// J_tcp the Jacobian at the TCP, the point the tracker measures (its linear rows for dp, its
// angular rows for an orientation change). It is the first-order model: the Jacobian at the
// encoder configuration q_i, not at the deflected one; for a deflection of 1 mrad the difference is
// about 1e-3 of the deflection, below a tracker's noise.
//
// Solution: nonnegative least squares (c >= 0) on the column-scaled, weighted regressor, inside
// an iteratively re-weighted loop (Huber, then Tukey's bisquare) on each measurement's residual.
// See docs/identify.md for the estimator, its thresholds and the identifiability checks.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "deflex/identify/stiffness_measurements.hpp"
#include "deflex/model/kinematics.hpp"

namespace deflex {

struct IdentificationOptions {
  /// Per joint: a known stiffness (Nm/rad) to hold fixed and leave out of the estimate, or nullopt
  /// to estimate it. Empty: estimate every joint. Otherwise its size is the robot's dof.
  std::vector<std::optional<double>> fixed_stiffness_nm_per_rad;
  /// Re-weight against outliers: Huber IRLS, then Tukey's bisquare from the Huber solution.
  bool robust = true;
  /// Rows of orientation measurements are multiplied by this length (m) so they mix with positions:
  /// 1 m means 1 urad of rotation weighs like 1 um of displacement.
  double rotation_scale_m = 1.0;
  /// A joint whose regressor column is below this fraction of the largest column is "not excited".
  double min_relative_excitation = 1e-8;
  /// A group of joints whose column-scaled regressor has a singular value below this fraction of the
  /// largest is "collinear": only a combination of their compliances is observable.
  double min_relative_singular_value = 1e-8;
  /// A joint whose relative standard error (se_k / k) exceeds this is reported as unidentifiable.
  double max_relative_std_error = 0.5;
  int max_robust_iterations = 50;
  /// Bytes of stacked measurement rows (8 (dof + 1) a row, 3 or 6 rows a measurement) held in
  /// memory; the rest go to an unlinked scratch file in TMPDIR and are seen in place (a read-only
  /// map, a chunk at a time) on each pass, with results bit for bit the same. 8 MiB holds about
  /// 50,000 six-joint position measurements (a million: 41 MB in all, under the 50 MB goal).
  std::size_t rows_in_memory_bytes = std::size_t{8} << 20;
};

struct StiffnessEstimate {
  /// Identified stiffness, Nm/rad. A fixed joint shows its given value. NaN for a joint the data
  /// cannot identify (not excited, collinear, or compliance at the c >= 0 bound): see warnings.
  std::vector<double> stiffness_nm_per_rad;
  /// Standard error of each stiffness, Nm/rad (delta method from the compliance's); 0 for a fixed
  /// joint, NaN where the stiffness is NaN.
  std::vector<double> std_error_nm_per_rad;
  std::vector<double> compliance_rad_per_nm;            ///< c = 1/k (0 at the bound, NaN if not estimated)
  std::vector<double> compliance_std_error_rad_per_nm;  ///< its standard error
  double residual_rms_m = 0.0;                          ///< RMS of the position residuals of the measurements kept
  double residual_max_m = 0.0;                          ///< largest position residual norm of the measurements kept
  double residual_rms_rad = 0.0;  ///< RMS of the orientation residuals (0 without orientation data)
  double sigma_m = 0.0;           ///< estimated noise per component (the standard errors' sigma), m
  /// Condition number of the weighted regressor of the estimated joints, columns scaled to unit
  /// norm (1 is ideal; each factor of 10 costs about a digit of the stiffness).
  double condition_number = 0.0;
  std::vector<int> unidentifiable_joints;  ///< 1-based joint numbers
  std::vector<int> fixed_joints;           ///< 1-based joint numbers held at given values
  std::vector<std::string> warnings;       ///< one sentence each, naming the joint
  /// Final robust weight of each measurement (1 = full, 0 = rejected as an outlier).
  std::vector<double> robust_weights;
  std::vector<int> rejected_measurements;  ///< 0-based indices of measurements with robust weight 0
  std::vector<int> rejected_lines;         ///< their file lines (0 where a measurement came from no file)
  int measurements = 0;
  int iterations = 0;  ///< robust re-weighting iterations
};

/// Identifies the joint stiffness from compliance-calibration measurements, using the model's
/// kinematics, tool (TCP: the measured point) and WAP. Throws InputError when a measurement's joint
/// count differs from the robot's, a value is not finite, the options do not fit the robot, or no
/// joint is left to estimate; names the measurement (file line when known).
[[nodiscard]] StiffnessEstimate identify_stiffness(const RobotModel& model,
                                                   const std::vector<StiffnessMeasurement>& data,
                                                   const IdentificationOptions& options = {});

/// The same a measurement at a time, for data too large to hold as StiffnessMeasurement objects (a
/// million rows streamed from a file): add() checks and keeps a measurement's regressor rows in
/// compact form (8 (dof + 1) bytes a row: 168 bytes for a 6-joint position measurement), solve()
/// gives exactly what identify_stiffness gives for the same measurements.
/// Thread safety: one thread at a time (its own Workspace and row store); identifiers on different
/// threads may share the model.
class StiffnessIdentifier {
 public:
  /// Throws InputError when the options do not fit the robot or are out of their domain (a threshold
  /// that is not in [0, 1), NaN included; a scale or error bound that is not finite and > 0; a negative
  /// iteration count), in Release too.
  StiffnessIdentifier(const RobotModel& model, const IdentificationOptions& options = {});
  /// The identifier keeps a reference to the model (docs/architecture.md, "Ownership"): a temporary
  /// would dangle, so it does not compile.
  StiffnessIdentifier(RobotModel&& model, const IdentificationOptions& options = {}) = delete;
  ~StiffnessIdentifier();
  StiffnessIdentifier(const StiffnessIdentifier&) = delete;
  StiffnessIdentifier& operator=(const StiffnessIdentifier&) = delete;
  /// Throws InputError naming the measurement (and its file line) for a wrong joint count, a value
  /// that is not finite or a weight that is not > 0.
  void add(const StiffnessMeasurement& m);
  [[nodiscard]] std::size_t measurements() const;
  /// Bytes of rows kept in the scratch file (beyond IdentificationOptions::rows_in_memory_bytes).
  [[nodiscard]] std::uint64_t scratch_bytes() const;
  /// Once: the estimate from every measurement added. Throws as identify_stiffness does.
  [[nodiscard]] StiffnessEstimate solve();

 private:
  struct RowStoreHolder;
  const RobotModel& model_;
  IdentificationOptions options_;
  Workspace ws_;
  Jacobian block_;
  std::unique_ptr<RowStoreHolder> store_;
  bool solved_ = false;
};

/// The regressor block of one measurement: rows 0-2 position (m per rad/Nm), rows 3-5 orientation
/// (rad per rad/Nm), column j the TCP motion per unit compliance of joint j under the wrench.
/// The planner uses it to judge poses; the identification stacks it.
/// Runs FK at q; does not allocate.
void stiffness_regressor(const RobotModel& model, Workspace& ws, const JointVector& q, const Wrench& wrench_base,
                         Jacobian& block);

/// The robot with its identified stiffness, as `deflex identify --write-robot` writes it: each joint
/// the estimate identified takes its value; a joint it did not (NaN, or listed unidentifiable) keeps
/// the robot file's, and the note says which ("joints 4, 6 kept from the previous file"). Throws
/// InputError naming the joint when one is not identified and the robot file gives no value to keep.
/// `data_name` names the measurements in the note.
[[nodiscard]] RobotModel identified_robot(const RobotModel& model, const StiffnessEstimate& estimate,
                                          const std::string& data_name);

}  // namespace deflex
