// The machining study's runs on the simulated cell: one seed's cell (the LDBB case's robot, its own
// calibration, the force sensor), a pass of the tool driven tick by tick through the coupled solve
// with the cell's milling process, by the controller's own program or by deflex over EGM, and the
// slot cuts whose sensor logs the coefficient fit reads.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "deflex/cell/coupled_tick.hpp"
#include "deflex/force/force_model.hpp"
#include "deflex/machining/coefficient_fit.hpp"
#include "deflex/machining/dexel_stock.hpp"
#include "deflex/study/detail/machining_part.hpp"
#include "deflex/study/detail/simulated_run.hpp"
#include "deflex/study/machining_study.hpp"

namespace deflex::study {

/// One seed's cell: the case's hardware (the seed's draws), the robot's calibration as the case
/// study runs it, and where the user placed the workpiece (nominal: the program's frame).
struct MillCell {
  CaseConfig config;
  SetupCell setup;
  Pose base_T_workpiece = Pose::Identity();
  Matrix3 tcp_orientation = Matrix3::Identity();
};
[[nodiscard]] MillCell build_mill_cell(std::uint64_t seed);

/// The predicted wrench along a pass's program points (base frame, at the TCP): a table by index for
/// the offline compensation, and by the nearest point for the hybrid strategy's cycle.
class PathWrenchModel final : public ForceModel {
 public:
  PathWrenchModel(std::vector<Vector3> positions_base_m, std::vector<Wrench> wrenches);
  [[nodiscard]] Wrench wrench_at(std::size_t index, const Pose& base_T_tcp) const override;
  [[nodiscard]] bool wrench_at_pose(const Pose& base_T_tcp, Wrench& out) const noexcept override;
  [[nodiscard]] std::string describe() const override { return "milling force predicted along the toolpath"; }
  [[nodiscard]] std::optional<std::size_t> points() const override { return wrenches_.size(); }

 private:
  std::vector<Vector3> positions_;
  std::vector<Wrench> wrenches_;
};

/// What the cell does to one part or one set of slot cuts: the true coefficients and runout, the
/// seeds of the run's noise.
struct MillRunSpec {
  MachiningStrategy strategy = MachiningStrategy::kUncompensated;
  double feed_mm_min = 1500.0;
  CuttingCoefficients true_k;
  double runout_m = 0.0;
  std::uint64_t seed = 1;
  bool trace = false;
};

/// The passes' programs: the tip points and the joints of each (nominal IK, or compensated).
struct PassProgram {
  std::vector<Vector3> tips_workpiece_m;
  std::vector<Pose> poses;
  std::vector<JointVector> q;
  /// The offline model's wrench at each point (base frame), when the strategy has one.
  std::shared_ptr<const PathWrenchModel> predicted;
};

struct MillRunResult {
  cell::CoupledTickCounters coupled;
  std::uint64_t link_cycles = 0;
  double simulated_s = 0.0;
  std::vector<PassTrace> passes;
  /// Per pass, the sensor's decoupled readings (sensor frame, N) and their times, for slot cuts.
  std::vector<std::vector<std::pair<double, Vector3>>> sensor_logs;
};

/// The programs of `passes` for a strategy: nominal IK of the tips with the identified model, and
/// for offline and hybrid the compensated joints from the force the user's model predicts with `k`
/// along the passes on the nominal stock.
[[nodiscard]] std::vector<PassProgram> plan_passes(const MillCell& cell, const std::vector<MillPass>& passes,
                                                   const StockBox& stock, MachiningStrategy strategy,
                                                   double feed_mm_min, const CuttingCoefficients* k);

/// Cuts the passes in order into `stock` (the true workpiece, stock frame) on the cell. Throws Error
/// when the cell cannot run them (a refused session, a controller that timed out).
[[nodiscard]] MillRunResult run_mill_passes(const MillCell& cell, const std::vector<MillPass>& passes,
                                            const std::vector<PassProgram>& programs, DexelStock& stock,
                                            const MillRunSpec& spec, bool log_sensor);

/// The slot cuts of `plan` at their feeds on the cell, their sensor logs written as a user's DAQ
/// writes them (CSV in `log_dir`, t_s, fx_N, fy_N, fz_N, decoupled, sensor frame) and read back by
/// read_slot_log with the mounting's nominal axes; returns the cuts for fit_cutting_coefficients.
[[nodiscard]] std::vector<SlotCut> run_slot_cuts(const MillCell& cell, const SlotCutPlan& plan, const MillRunSpec& spec,
                                                 const std::string& log_dir);

}  // namespace deflex::study
