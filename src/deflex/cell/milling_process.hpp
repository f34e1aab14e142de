// The cell's spindle and workpiece: a milling cut as a process force on the true arm. The true tool
// (the cutter, its runout) stands where the true, deflected arm puts it; its engagement in the stock
// gives the true cutting force from the true coefficients (drawn around a published set, unknown to
// the compensators), and that force goes back into the same tick's coupled solve
// (coupled_tick.hpp): a tool pushed away from a wall engages less of it and is pushed less, and the
// solve finds where the two agree. At the tick's end the stock loses what the true tool swept, so the
// part keeps what the deflected tool left (part_probe.hpp measures it).
//
// Tooth-passing content is averaged, not sampled: the force is the revolution average of the linear
// edge-force model (machining/milling_force.hpp). The teeth pass at N S / 60 (600 Hz for three flutes
// at 12 000 rpm, 2 kHz for four at 30 000), at or above the Nyquist frequency of the cell's 1 kHz,
// so a sample a tick would alias the tooth force into a slow force the cut does not have; and the
// true arm is solved quasi-statically each tick (no structural mode that could answer at the tooth
// frequency), so what moves it is the average. The surface is what the teeth's envelope swept: the
// tool's radius plus its runout (the outermost tooth cuts the wall), with the feed's scallop
// fz^2 / (8 R) (0.06 um at 0.05 mm a tooth on a 10 mm tool) far below the stock's resolution.
// The feed per tooth and the feed direction are the tool's true ones: its mean velocity over the last
// revolution, the arm's yield included (a tool held back cuts thinner chips).
// Runout leaves the averaged force unchanged to first order (the teeth's chip changes sum to zero
// over a revolution while every tooth stays in the cut), so it enters through the envelope alone.
#pragma once

#include <array>
#include <cstdint>

#include "deflex/cell/process_force.hpp"
#include "deflex/machining/cutter.hpp"
#include "deflex/machining/cutting_coefficients.hpp"
#include "deflex/machining/engagement.hpp"
#include "deflex/machining/stock.hpp"

namespace deflex::cell {

/// The spindle, the true tool and where the workpiece sits. SI units.
struct MillingProcessConfig {
  Cutter cutter;          ///< the nominal tool (the compensators' tool list has the same)
  CuttingCoefficients k;  ///< the true coefficients (draw_true_coefficients())
  double spindle_rpm = 12000.0;
  SpindleTurn turn = SpindleTurn::kClockwise;
  /// The true tool's axis offset from the spindle's axis (m): its teeth sweep a circle this much
  /// larger in radius than the nominal tool's.
  double runout_m = 0.0;
  /// The stock's frame in the base frame: the stock (a 3-axis model) takes its z as the tool axis.
  Pose base_T_stock = Pose::Identity();
  /// The tool axis in the TCP frame, from the tip into the spindle (the TCP sits at the tool's tip,
  /// the centre of its end face; a tool frame's z points out of the tool).
  Vector3 tool_axis_tcp = -Vector3::UnitZ();
};

/// The true coefficients of a run: each of the published set's six times exp(relative_sigma z), z a
/// standard normal draw from `seed` (a log-normal spread keeps them positive; independent draws,
/// since tool, coating and speed move the cutting and edge terms differently). 0: the published set.
[[nodiscard]] CuttingCoefficients draw_true_coefficients(const CuttingCoefficients& published, double relative_sigma,
                                                         std::uint64_t seed);

/// What the cut did at the last committed tick (for logs and reports; the compensators never see it).
struct MillingTickRecord {
  bool engaged = false;
  Wrench wrench_base = Wrench::Zero();  ///< on the tool, N and Nm at the TCP, base frame
  double ae_m = 0.0;                    ///< the true radial width
  double ap_m = 0.0;                    ///< the true axial depth
  double fz_m = 0.0;                    ///< the true feed per tooth
};

/// Thread safety: one thread at a time (the stock changes at each commit).
class MillingProcess final : public ProcessForce {
 public:
  /// `stock` (in the stock frame of `config`) is the workpiece; it outlives the process and is the
  /// caller's to measure after the cut. Throws InputError for a bad cutter, coefficients out of
  /// range, a spindle speed not positive or a runout outside 0..1 mm.
  MillingProcess(const MillingProcessConfig& config, Stock& stock);

  void advance(double dt_s) override;
  [[nodiscard]] Wrench wrench_at(const TcpMotion& motion) const override;
  void commit(const TcpMotion& motion) override;

  [[nodiscard]] const MillingTickRecord& last() const { return last_; }
  /// Ticks whose true tool axis was tilted from the stock's z by more than a 3-axis stock follows
  /// (ZMapStock::kMaxTiltRad): the cut took the stock's z there, and a report must say so.
  [[nodiscard]] std::uint64_t tilted_ticks() const { return tilted_ticks_; }
  /// The teeth's envelope: the nominal cutter with the runout added to its radius.
  [[nodiscard]] const Cutter& envelope() const { return envelope_; }

 private:
  // The tool's tip in the stock frame, and whether its axis is off the stock's z.
  [[nodiscard]] Vector3 tip_in_stock(const TcpMotion& motion, bool& tilted) const;
  // The tool's feed velocity (stock frame) for a tip at `tip` this tick: its mean over a revolution.
  [[nodiscard]] Vector3 feed_velocity(const Vector3& tip, const TcpMotion& motion) const;
  // The averaged wrench (base frame) at `motion`; `record` gets the engagement's summary.
  [[nodiscard]] Wrench cut_at(const TcpMotion& motion, MillingTickRecord& record) const;

  MillingProcessConfig config_;
  Cutter envelope_;
  Stock& stock_;
  Pose stock_T_base_;
  Matrix3 stock_R_base_;
  double dt_s_ = 0.0;
  // The committed tips (stock frame) of the last ticks, a ring: the newest at history_next_ - 1.
  static constexpr int kHistory = 64;
  std::array<Vector3, kHistory> history_{};
  int history_next_ = 0;
  int history_count_ = 0;
  MillingTickRecord last_;
  std::uint64_t tilted_ticks_ = 0;
};

}  // namespace deflex::cell
