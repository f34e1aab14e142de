// The machining study's part, tool and cuts in the workpiece (stock) frame: z the tool axis (from the
// tip into the spindle, the stock's top at z = 0), x the feed of the straight passes. What a CAM
// system would hand the cell; the probing plan a metrologist would write for it.
#pragma once

#include <string>
#include <vector>

#include "deflex/cell/part_probe.hpp"
#include "deflex/machining/cutter.hpp"
#include "deflex/machining/cutting_coefficients.hpp"
#include "deflex/machining/dexel_stock.hpp"
#include "deflex/model/types.hpp"

namespace deflex::study {

/// A block of stock (stock frame, m) and the dexel model's resolution: lines every cell_m in x and
/// y, layers at most layer_m apart in z.
struct StockBox {
  Vector3 min_m = Vector3::Zero(), max_m = Vector3::Zero();
  double cell_m = 0.1e-3, layer_m = 0.5e-3;
  EngagementSampling sampling{64, 20, 10e-6, 1e-6};  ///< the dexel stock's own default
};
[[nodiscard]] DexelStock make_stock(const StockBox& box);

/// One pass of the tool: a polyline of tip points (stock frame, m) at the pass's feed.
struct MillPass {
  std::string name;
  std::vector<Vector3> corners;  ///< the polyline's corners, the first outside the stock
};

/// The part: its stock block, the passes in the order they run, and what is probed.
struct MillPart {
  StockBox stock;
  std::vector<MillPass> passes;
  cell::WallSpec climb_wall, conventional_wall, contour_wall, slot_wall_a, slot_wall_b;
  cell::FloorSpec pocket_floor, slot_floor;
};

/// The study's tool: a 10 mm three-flute carbide end mill at 12 000 rpm, M3.
[[nodiscard]] Cutter study_cutter();
inline constexpr double kStudySpindleRpm = 12000.0;
/// The published Al7075-T6 set (data/machining/al7075-t6.yaml).
[[nodiscard]] CuttingCoefficients al7075_published();

/// The part; `quick` makes it shorter along the feed.
[[nodiscard]] MillPart make_mill_part(bool quick);

/// The slot cuts a user runs to fit coefficients: one slot each, side by side in their own block.
struct SlotCutPlan {
  StockBox stock;
  std::vector<MillPass> passes;
  std::vector<double> fz_m;
  double ap_m = 0.0;
  double window_from_x_m = 0.0, window_to_x_m = 0.0;  ///< the steady full-slot stretch of the tip's x
};
[[nodiscard]] SlotCutPlan make_slot_cut_plan(bool quick);

/// The tip points of a pass sampled every `step_m` along it (the corners kept).
[[nodiscard]] std::vector<Vector3> sample_pass(const MillPass& pass, double step_m);

}  // namespace deflex::study
