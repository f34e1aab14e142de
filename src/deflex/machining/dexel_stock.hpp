// The stock as dexels along x and y over a height map: walls resolved to the floating-point
// precision of their ends whatever the grid's spacing, for 3-axis milling (a vertical tool).
//
// A dexel is a line of the grid with the intervals where it is inside the material; its ends are
// continuous, so a wall crossing it is where it was cut, not where the nearest node is. Dexels along
// x lie on rows (y, z), along y on columns (x, z), on layers of height through the stock; together
// with the height map (ZMapStock: one interval along z per node, exact floors) they are a tri-dexel
// model. The engagement query samples the cutter's circle as the height map's does, but whether a
// point is in the material comes from the dexels of the layer halfway up the material there, from the
// family crossing the wall more squarely, interpolated between its two nearest lines (exact for a
// plane wall): the arcs' ends, and so ae, are exact to well under a micrometre where the height map's
// are within half a cell. The depth is the height map's (exact floors and tops).
//
// Cost, cell c (x and y), layer spacing dz, cutter diameter D, move length L: a move updates about
// (2 D + L) / c lines on each of the layers between the tip and the stock's top (a line's update is
// one interval subtraction; lines above the corner radius share one computation a row), plus the
// height map's (L D / c^2) nodes; a query costs the height map's plus a bisection per arc end.
// Memory: (nx + ny) nz lines of 52 bytes, plus the height map's 4 bytes a node.
#pragma once

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "deflex/machining/zmap_stock.hpp"

namespace deflex {

class DexelStock final : public Stock {
 public:
  /// Intervals a line holds; a line cut into more keeps the material of its narrowest gap (counted
  /// in overflows(): the material is then over-estimated there, never under).
  static constexpr int kMaxIntervals = 6;
  /// Lines at most (20 M: 1 GB).
  static constexpr double kMaxLines = 20e6;

  /// A box from `min_m` to `max_m`, nodes and lines every `cell_m` in x and y, layers at most
  /// `layer_m` apart in z (at their middles, evenly through the box's height). Throws InputError for an
  /// empty box, a cell or layer outside 1 um..100 mm, or too many nodes or lines.
  static DexelStock box(const Vector3& min_m, const Vector3& max_m, double cell_m, double layer_m);

  [[nodiscard]] StockStatus engagement(const Cutter& cutter, const CutFrame& frame, const Vector3& tip_m,
                                       SpindleTurn turn, Engagement& out) const noexcept override;
  StockStatus remove_swept(const Cutter& cutter, const Vector3& from_m, const Vector3& to_m,
                           const Vector3& axis) noexcept override;
  [[nodiscard]] double removed_volume_m3() const noexcept override { return top_.removed_volume_m3(); }
  [[nodiscard]] std::string describe() const override;
  /// The engagement query's sampling (stock.hpp); the defaults resolve an arc's ends to pi / 64 / 2^20
  /// (0.2 nm along a 10 mm tool's edge) with 65 samples. A coarser one costs less per query.
  void set_sampling(const EngagementSampling& options) noexcept { sampling_ = options; }

  using Intervals = std::vector<std::pair<double, double>>;
  /// The material along x on the line nearest to (y, z): its intervals, m (for measuring a wall).
  [[nodiscard]] Intervals along_x(double y_m, double z_m) const;
  /// The material along y on the line nearest to (x, z).
  [[nodiscard]] Intervals along_y(double x_m, double z_m) const;
  /// The height map underneath (the top of the material, exact floors).
  [[nodiscard]] const ZMapStock& heights() const noexcept { return top_; }
  /// Lines that were cut into more than kMaxIntervals intervals.
  [[nodiscard]] std::size_t overflows() const noexcept { return overflows_; }

 private:
  struct Line {
    std::uint8_t count = 0;
    [[nodiscard]] double lo(int i) const { return ends[2 * static_cast<std::size_t>(i)]; }
    [[nodiscard]] double hi(int i) const { return ends[2 * static_cast<std::size_t>(i) + 1]; }
    std::array<float, 2 * static_cast<std::size_t>(kMaxIntervals)> ends{};  // lo0, hi0, lo1, hi1, ... sorted, disjoint
  };
  /// The signed distance to the wall at a point of a layer, from one family of lines (see .cpp).
  struct WallProbe {
    bool valid = false;
    double inside_m = 0.0;  // > 0 inside the material
    double slope = 0.0;     // |change of the nearest end| per line spacing
  };

  DexelStock(ZMapStock top, double min_x, double min_y, double min_z, double cell, double layer, int nz);
  void subtract(Line& line, double lo, double hi) noexcept;
  void cut_layers(int k0, int k1, const Eigen::Vector2d& a, const Eigen::Vector2d& b, double radius) noexcept;
  void cut_level(const Cutter& cutter, const Eigen::Vector2d& a, const Eigen::Vector2d& b, double tip_z) noexcept;
  [[nodiscard]] WallProbe probe(const std::vector<Line>& lines, int lines_per_layer, int k, double along,
                                double across) const noexcept;
  [[nodiscard]] double inside_m(int k, double x, double y, bool& ok) const noexcept;
  [[nodiscard]] int layer_of(double z) const noexcept;
  /// The line along x on row j of layer k, along y on column i of layer k.
  [[nodiscard]] static std::size_t index(int k, int per_layer, int j) noexcept {
    return static_cast<std::size_t>(k) * static_cast<std::size_t>(per_layer) + static_cast<std::size_t>(j);
  }
  [[nodiscard]] Intervals intervals(const Line& line) const;

  ZMapStock top_;
  double min_x_, min_y_, min_z_, cell_, layer_;
  int nx_, ny_, nz_;
  std::vector<Line> along_x_;  // row j of layer k at k * ny_ + j
  std::vector<Line> along_y_;  // column i of layer k at k * nx_ + i
  std::size_t overflows_ = 0;
  EngagementSampling sampling_{64, 20, 10e-6, 1e-6};  // arc ends to pi / 64 / 2^20
};

}  // namespace deflex
