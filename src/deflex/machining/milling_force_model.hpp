// The milling force along a CAM toolpath (`--force "milling:..."` with `--cutter`): the mechanistic
// model of machining/milling_force.hpp at every point, its engagement from a stock the path cuts
// away as it goes (or the ae_mm=/ap_mm= overrides), its cut frame from the move into the point.
//
// The force at a point needs what came before it (the move's direction, the material the earlier
// moves left), so a path index and a pose are not enough: MillingForceModel holds what does not
// change (cutter, coefficients, overrides) and is the ForceModel the spec grammar gives; a
// MillingProcess, one a run, walks the toolpath in program order with the stock. docs/machining.md
// ("From CAM to a compensated program") states the conventions.
#pragma once

#include <cstddef>
#include <optional>
#include <string>

#include "deflex/force/force_model.hpp"
#include "deflex/force/force_spec.hpp"
#include "deflex/machining/cutting_coefficients.hpp"
#include "deflex/machining/milling_force.hpp"
#include "deflex/machining/stock.hpp"

namespace deflex {

/// Thread safety: immutable once built: any number of threads may share one.
class MillingForceModel final : public ForceModel {
 public:
  /// Throws InputError when the cutter is out of range (validate_cutter) or an ae_mm override is
  /// wider than it (check_overrides).
  MillingForceModel(MillingSpec spec, const Cutter& cutter);

  /// Always throws InputError: the milling force needs a toolpath's feed, spindle and engagement
  /// (deflex offline --toolpath, or MillingProcess).
  [[nodiscard]] Wrench wrench_at(std::size_t index, const Pose& base_T_tcp) const override;
  [[nodiscard]] std::string describe() const override;
  [[nodiscard]] std::string label() const override { return "milling"; }

  [[nodiscard]] const MillingSpec& spec() const { return spec_; }
  [[nodiscard]] const Cutter& cutter() const { return cutter_; }
  /// Both ae_mm= and ap_mm= are given: a run needs no stock.
  [[nodiscard]] bool has_full_override() const { return spec_.ae_m.has_value() && spec_.ap_m.has_value(); }

 private:
  MillingSpec spec_;
  Cutter cutter_;
};

/// The parser of milling: force specs (force_spec.hpp) with `cutter`, for ForceSpecContext::milling: one
/// MillingForceModel a spec. It throws InputError quoting the spec (a bad key, a cutter out of range, an
/// ae_mm override wider than the cutter) and ModelError for a coefficient file it cannot read.
[[nodiscard]] ProcessForceSpecs milling_force_specs(const Cutter& cutter);

/// One toolpath point as the force needs it, in the workpiece (stock) frame.
struct MillingPointInput {
  Vector3 tip_m = Vector3::Zero();
  Vector3 tool_axis = Vector3::UnitZ();  ///< unit, from the tip into the spindle
  double feed_mm_min = 0.0;              ///< programmed feed of the move into the point
  double spindle_rpm = 0.0;
  std::optional<SpindleTurn> turn;  ///< none: the spindle is off
  bool rapid = false;               ///< a positioning move (G0, APT RAPID): never a cut
  int tool = 0;
  std::size_t line = 0;  ///< the source line, for messages
};

/// What the tool does at a point.
enum class MillingPointState {
  kStart,   ///< the path's first point: no move into it
  kRapid,   ///< a positioning move
  kPlunge,  ///< a move mostly along the tool axis (in-plane share below kMinInPlaneFraction): the end
            ///< face's cutting is not modelled, no force
  kInAir,   ///< a feed move that touches no material
  kCut,
};

/// The force at a point. Zero wrench unless kCut.
struct MillingPointForce {
  MillingPointState state = MillingPointState::kStart;
  /// On the tool (= on the robot), workpiece frame, N and Nm, moment about the tool tip (the TCP):
  /// averaged over a revolution.
  Wrench wrench = Wrench::Zero();
  CutFrame frame;     ///< feed, normal, axis (workpiece frame); valid when kCut
  double ae_m = 0.0;  ///< radial width (one-arc summary of the engagement)
  double ap_m = 0.0;  ///< axial depth
  double fz_m = 0.0;  ///< feed per tooth in the plane normal to the axis
  /// Largest force magnitude over a revolution, of the engagement's one-arc summary (first entry to
  /// last exit over all its heights), within 1 degree and 2 % of the point's.
  double peak_force_n = 0.0;
  double tooth_passing_hz = 0.0;
};

/// A move whose velocity lies less than this share in the plane normal to the tool axis (84 degrees
/// or more from it) is a plunge: no force.
inline constexpr double kMinInPlaneFraction = 0.1;

/// What a run's points were.
struct MillingRunCounts {
  std::size_t cut = 0, in_air = 0, plunges = 0, rapids = 0;
  std::size_t rapids_through_stock = 0;  ///< positioning moves that removed material (a collision)
  std::size_t first_rapid_through_stock_line = 0;
};

/// The per-run state: the stock as the path leaves it, the previous point, the last peak.
/// Thread safety: one thread at a time; it changes the stock it is given.
class MillingProcess {
 public:
  /// `stock` may be null when the model has both ae_mm= and ap_mm= (every feed move with an in-plane
  /// component then cuts with them); the process keeps a pointer to it and to the model. Throws
  /// InputError when there is neither a stock nor both overrides.
  MillingProcess(const MillingForceModel& model, Stock* stock);
  MillingProcess(MillingForceModel&& model, Stock* stock) = delete;

  /// The next point of the path, in program order: the engagement at the point with the cut frame of
  /// the move into it, the force, then that move removed from the stock. Throws InputError "line N:
  /// ..." for a tool axis the stock cannot follow, a cut with the spindle off or a feed or speed of
  /// zero, and a tool other than the first cutting tool (one --cutter describes one tool).
  const MillingPointForce& next(const MillingPointInput& in);

  [[nodiscard]] const MillingRunCounts& counts() const { return counts_; }
  /// The material removed so far, m^3 (0 without a stock).
  [[nodiscard]] double removed_volume_m3() const { return stock_ != nullptr ? stock_->removed_volume_m3() : 0.0; }

 private:
  bool engage(const MillingPointInput& in, Engagement& e);
  void update_peak(const MillingCut& cut, const Engagement& e);
  void remove(const MillingPointInput& in);

  const MillingForceModel& model_;
  Stock* stock_;
  MillingPointForce out_;
  MillingRunCounts counts_;
  std::optional<Vector3> previous_;
  std::optional<int> tool_;
  Engagement engagement_;
  // The last peak and the one-arc band it was computed for: recomputed when the band or the feed per
  // tooth moves.
  EngagementPatch peak_band_;
  double peak_fz_m_ = -1.0, peak_n_ = 0.0;
};

}  // namespace deflex
