// The stock as a height map (z-map): material from a flat bottom up to a height stored at the nodes
// of a square grid in the stock's xy plane, inside a rectangular footprint. Enough for 3-axis milling
// (a vertical tool leaves no overhang); a tilted tool axis is refused (StockStatus::kUnsupportedAxis):
// a height map cannot hold an undercut, and the sweep of a tilted cutter over it is not done here.
//
// Accuracy and cost, cell size c, cutter diameter D:
// - heights between nodes are bilinear, so floors and the stock's top are exact and a wall lies
//   within c / 2 of where it was cut (the engagement's arc ends: a radial width ae within about c / 2);
// - an engagement query costs `samples` + 1 bilinear look-ups plus two bisections, independent of c;
// - removing a move of length L visits about (L + D) D / c^2 nodes: halving c quadruples it, and a
//   wall resolved to 0.01 mm would need c = 0.02 mm, 250 000 nodes per 10 mm cutter position. That
//   is what dexels along x and y (a tri-dexel stock) avoid: their ends are continuous along their
//   direction, so a wall's position is exact whatever the spacing.
#pragma once

#include <optional>
#include <vector>

#include "deflex/machining/stock.hpp"

namespace deflex {

class ZMapStock final : public Stock {
 public:
  /// Nodes at most (50 M: 200 MB of heights); a finer grid is refused naming the cell size to use.
  static constexpr double kMaxNodes = 50e6;
  /// Tool axes within this angle of +z are taken as +z; others are refused.
  static constexpr double kMaxTiltRad = 0.1 * kPi / 180.0;

  /// A box from `min_m` to `max_m` (stock frame) sampled every `cell_m` in x and y. Throws
  /// InputError for an empty or non-finite box, a cell outside 1 um..100 mm or too many nodes.
  static ZMapStock box(const Vector3& min_m, const Vector3& max_m, double cell_m);

  /// A measured or modelled height map: `heights_m` row by row (x fastest), nx * ny nodes, node (i, j)
  /// at (x0 + i cell, y0 + j cell); material from `bottom_m` up. Throws InputError on a size mismatch,
  /// a non-finite height or too many nodes.
  ZMapStock(double x0_m, double y0_m, double cell_m, int nx, int ny, double bottom_m, std::vector<float> heights_m);

  [[nodiscard]] StockStatus engagement(const Cutter& cutter, const CutFrame& frame, const Vector3& tip_m,
                                       SpindleTurn turn, Engagement& out) const noexcept override;
  StockStatus remove_swept(const Cutter& cutter, const Vector3& from_m, const Vector3& to_m,
                           const Vector3& axis) noexcept override;
  [[nodiscard]] double removed_volume_m3() const noexcept override { return removed_m3_; }
  [[nodiscard]] std::string describe() const override;

  /// The top of the material at (x, y), bilinear between nodes; the bottom outside the footprint.
  [[nodiscard]] double height_m(double x, double y) const noexcept;
  /// The highest of the four nodes around (x, y); the bottom outside the footprint.
  [[nodiscard]] double max_node_height_m(double x, double y) const noexcept;
  [[nodiscard]] double bottom_m() const noexcept { return bottom_m_; }
  [[nodiscard]] double cell_m() const noexcept { return cell_m_; }
  [[nodiscard]] int nx() const noexcept { return nx_; }
  [[nodiscard]] int ny() const noexcept { return ny_; }
  /// The engagement query's sampling (stock.hpp); the defaults resolve an arc's
  /// ends to 0.001 deg and take 65 samples.
  void set_sampling(const EngagementSampling& options) noexcept { sampling_ = options; }

 private:
  double x0_m_, y0_m_, cell_m_;
  double x1_m_ = 0.0, y1_m_ = 0.0;  // the footprint's far corner (a box's own, not the last node's)
  int nx_, ny_;
  double bottom_m_;
  std::vector<float> heights_m_;
  double removed_m3_ = 0.0;
  EngagementSampling sampling_;
  // The end of the last level move and its cutter: a move that starts there at that height skips the
  // flat of its start disc, which that move left at the tip's height.
  std::optional<Vector3> last_level_end_;
  double last_radius_m_ = 0.0, last_corner_m_ = 0.0;
};

/// The lowest point of the cutter's surface over (px, py) while its tip moves from a to b with a
/// vertical axis (flat end, bull nose or ball from the corner radius); +inf where the cutter never
/// passes over the point. Exact for level moves and for flat end mills; a ramp with a rounded corner
/// is minimised numerically (the height along the move is convex).
[[nodiscard]] double lowest_cutter_surface_m(const Cutter& cutter, const Vector3& a, const Vector3& b, double px,
                                             double py) noexcept;

}  // namespace deflex
