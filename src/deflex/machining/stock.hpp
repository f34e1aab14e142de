// The material a toolpath cuts: what the cutter is engaged in at a point (for the force) and what it
// removes along a move. One interface, several representations: a height map (zmap_stock.hpp) now,
// dexels along x, y and z (tri-dexel) for walls resolved finer than the grid next.
//
// Order along a path: query the engagement at a point's end position first, then remove the move
// that led there. The teeth cut on the front half of the cutter (immersion 0..pi), which the move
// has not swept yet, so the answer is the engagement at the end of the move; split a long move where
// its engagement changes (a pass entering the stock) to follow it.
#pragma once

#include <string>

#include "deflex/machining/cutter.hpp"
#include "deflex/machining/engagement.hpp"
#include "deflex/machining/milling_force.hpp"
#include "deflex/model/types.hpp"

namespace deflex {

/// What a stock says about a query or a move.
enum class StockStatus {
  kCut,              ///< engaged (a query) or material removed (a move)
  kInAir,            ///< the cutter touches no material
  kUnsupportedAxis,  ///< this representation cannot follow the tool axis (a height map: 3-axis only)
};

/// How a stock's engagement query samples the cutter's circle (detail/engagement_sampling.hpp): the
/// front half at `samples` + 1 angles (4..256), each arc's ends bisected `refine_steps` times; samples
/// whose material extents agree within `depth_tolerance_m` (or 1 % of the depth) share a patch;
/// material thinner than `min_depth_m` is air (a floor the tip rides on).
struct EngagementSampling {
  int samples = 64;
  int refine_steps = 12;
  double depth_tolerance_m = 10e-6;
  double min_depth_m = 1e-6;
};

/// Thread safety: queries are const and may run on several threads at once; a move (remove_swept)
/// needs the stock to itself.
class Stock {
 public:
  virtual ~Stock() = default;

  /// The engagement of `cutter` with its tip at `tip_m` and the cut frame `frame` (feed, normal and
  /// axis), all in the stock's frame, turning `turn`. Fills `out` (cleared first) and returns kCut,
  /// or kInAir with `out` empty, or kUnsupportedAxis. Never allocates or throws.
  [[nodiscard]] virtual StockStatus engagement(const Cutter& cutter, const CutFrame& frame, const Vector3& tip_m,
                                               SpindleTurn turn, Engagement& out) const noexcept = 0;

  /// Removes what the cutter sweeps when its tip moves in a straight line from `from_m` to `to_m`
  /// with its axis along `axis` (from the tip into the spindle). kCut when material went, kInAir
  /// when none did, kUnsupportedAxis (nothing changed) when this stock cannot follow the axis.
  /// Never allocates or throws.
  virtual StockStatus remove_swept(const Cutter& cutter, const Vector3& from_m, const Vector3& to_m,
                                   const Vector3& axis) noexcept = 0;

  /// The material removed so far, m^3 (0: the tool never touched the stock).
  [[nodiscard]] virtual double removed_volume_m3() const noexcept = 0;

  /// One line for humans: kind, size, resolution.
  [[nodiscard]] virtual std::string describe() const = 0;

 protected:
  Stock() = default;
  Stock(const Stock&) = default;
  Stock& operator=(const Stock&) = default;
};

}  // namespace deflex
