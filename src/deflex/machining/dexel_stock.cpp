// The dexel stock.
//
// A wall's position at a point of a layer comes from one family of lines: on each of the two lines of
// the family nearest to the point, the signed distance from the point's coordinate along the line to
// the nearest interval end (positive inside the material), interpolated between the two lines by the
// point's position across them. For a plane wall the two ends lie on the wall, so the interpolation is
// the wall itself. The family whose ends change least from one line to the next crosses the wall more
// squarely and is used; where neither has ends on both lines (an empty line, a corner) the height
// map's answer stays.
#include "deflex/machining/dexel_stock.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "deflex/machining/detail/cutter_sweep.hpp"
#include "deflex/machining/detail/engagement_sampling.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

/// The radius of a vertical cutter's cross-section at height h above its tip: the corner's arc below
/// the corner radius, the full radius above; negative (nothing) below the tip.
double section_radius(double h, double radius, double rc) noexcept {
  if (h <= 0.0) return -1.0;
  if (h >= rc) return radius;
  const double u = rc - h;
  return radius - rc + std::sqrt(std::max(0.0, rc * rc - u * u));
}

}  // namespace

DexelStock DexelStock::box(const Vector3& min_m, const Vector3& max_m, double cell_m, double layer_m) {
  ZMapStock top = ZMapStock::box(min_m, max_m, cell_m);  // checks the box and the cell
  if (!std::isfinite(layer_m) || layer_m < 1e-6 || layer_m > 0.1) {
    throw InputError(fmt::format("dexel stock: layer_mm: {:g} mm is outside 0.001..100 mm", layer_m * 1e3));
  }
  const int nz = std::max(1, static_cast<int>(std::ceil((max_m.z() - min_m.z()) / layer_m - 1e-9)));
  const double lines = static_cast<double>(nz) * (top.nx() + top.ny());
  if (lines > kMaxLines) {
    throw InputError(fmt::format("dexel stock: {:.0f} lines exceed {:g} M; use a coarser cell_mm or layer_mm", lines,
                                 kMaxLines * 1e-6));
  }
  DexelStock s(std::move(top), min_m.x(), min_m.y(), min_m.z(), cell_m, (max_m.z() - min_m.z()) / nz, nz);
  Line full_x, full_y;
  full_x.count = full_y.count = 1;
  full_x.ends[0] = static_cast<float>(min_m.x());
  full_x.ends[1] = static_cast<float>(max_m.x());
  full_y.ends[0] = static_cast<float>(min_m.y());
  full_y.ends[1] = static_cast<float>(max_m.y());
  for (int k = 0; k < nz; ++k) {
    for (int j = 0; j < s.ny_; ++j) {
      if (min_m.y() + j * cell_m <= max_m.y() + 1e-12) s.along_x_[index(k, s.ny_, j)] = full_x;
    }
    for (int i = 0; i < s.nx_; ++i) {
      if (min_m.x() + i * cell_m <= max_m.x() + 1e-12) s.along_y_[index(k, s.nx_, i)] = full_y;
    }
  }
  return s;
}

DexelStock::DexelStock(ZMapStock top, double min_x, double min_y, double min_z, double cell, double layer, int nz)
    : top_(std::move(top)),
      min_x_(min_x),
      min_y_(min_y),
      min_z_(min_z),
      cell_(cell),
      layer_(layer),
      nx_(top_.nx()),
      ny_(top_.ny()),
      nz_(nz),
      along_x_(static_cast<std::size_t>(nz) * static_cast<std::size_t>(ny_)),
      along_y_(static_cast<std::size_t>(nz) * static_cast<std::size_t>(nx_)) {}

void DexelStock::subtract(Line& line, double lo, double hi) noexcept {
  std::array<double, 2 * static_cast<std::size_t>(kMaxIntervals) + 2> out{};
  std::size_t n = 0;
  bool changed = false;
  for (int i = 0; i < line.count; ++i) {
    const double a = line.lo(i), b = line.hi(i);
    if (b <= lo || a >= hi) {
      out[n++] = a;
      out[n++] = b;
      continue;
    }
    changed = true;
    if (a < lo) {
      out[n++] = a;
      out[n++] = lo;
    }
    if (b > hi) {
      out[n++] = hi;
      out[n++] = b;
    }
  }
  if (!changed) return;
  if (n / 2 > static_cast<std::size_t>(kMaxIntervals)) {
    // Keep the material of the narrowest gap: the line then holds a sliver too much, never too little.
    ++overflows_;
    std::size_t best = 0;  // gap g lies between out[2 g + 1] and out[2 g + 2]
    for (std::size_t g = 1; g + 1 < n / 2; ++g) {
      if (out[2 * g + 2] - out[2 * g + 1] < out[2 * best + 2] - out[2 * best + 1]) best = g;
    }
    std::copy(out.begin() + static_cast<std::ptrdiff_t>(2 * best + 3), out.begin() + static_cast<std::ptrdiff_t>(n),
              out.begin() + static_cast<std::ptrdiff_t>(2 * best + 1));
    n -= 2;
  }
  line.count = static_cast<std::uint8_t>(n / 2);
  for (std::size_t i = 0; i < n; ++i) line.ends[i] = static_cast<float>(out[i]);
}

/// Removes from layers k0..k1 - 1 the stadium of radius `radius` around the segment a..b (the
/// cutter's cross-section swept at those heights): each line's interval computed once for them all.
void DexelStock::cut_layers(int k0, int k1, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                            double radius) noexcept {
  k0 = std::max(k0, 0);
  k1 = std::min(k1, nz_);
  if (radius <= 0.0 || k0 >= k1) return;
  const int j0 = std::max(0, static_cast<int>(std::floor((std::min(a.y(), b.y()) - radius - min_y_) / cell_)));
  const int j1 = std::min(ny_ - 1, static_cast<int>(std::ceil((std::max(a.y(), b.y()) + radius - min_y_) / cell_)));
  for (int j = j0; j <= j1; ++j) {
    double lo = 0.0, hi = 0.0;
    if (detail::stadium_row(a, b, radius, min_y_ + j * cell_, lo, hi)) {
      for (int k = k0; k < k1; ++k) subtract(along_x_[index(k, ny_, j)], lo, hi);
    }
  }
  const Eigen::Vector2d at(a.y(), a.x()), bt(b.y(), b.x());  // the same with x and y swapped
  const int i0 = std::max(0, static_cast<int>(std::floor((std::min(a.x(), b.x()) - radius - min_x_) / cell_)));
  const int i1 = std::min(nx_ - 1, static_cast<int>(std::ceil((std::max(a.x(), b.x()) + radius - min_x_) / cell_)));
  for (int i = i0; i <= i1; ++i) {
    double lo = 0.0, hi = 0.0;
    if (detail::stadium_row(at, bt, radius, min_x_ + i * cell_, lo, hi)) {
      for (int k = k0; k < k1; ++k) subtract(along_y_[index(k, nx_, i)], lo, hi);
    }
  }
}

void DexelStock::cut_level(const Cutter& cutter, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                           double tip_z) noexcept {
  const double r = cutter.radius_m(), rc = cutter.corner_radius_m;
  // The corner's layers one by one, the layers above it at the full radius together.
  int k = std::max(0, layer_of(tip_z) - 1);
  for (; k < nz_ && min_z_ + (k + 0.5) * layer_ - tip_z < rc; ++k) {
    cut_layers(k, k + 1, a, b, section_radius(min_z_ + (k + 0.5) * layer_ - tip_z, r, rc));
  }
  cut_layers(k, nz_, a, b, r);
}

StockStatus DexelStock::remove_swept(const Cutter& cutter, const Vector3& from_m, const Vector3& to_m,
                                     const Vector3& axis) noexcept {
  const StockStatus status = top_.remove_swept(cutter, from_m, to_m, axis);
  if (status == StockStatus::kUnsupportedAxis || !from_m.allFinite() || !to_m.allFinite()) return status;
  const double dz = to_m.z() - from_m.z();
  const Eigen::Vector2d a = from_m.head<2>(), b = to_m.head<2>();
  if (std::abs(dz) <= 1e-12) {
    cut_level(cutter, a, b, from_m.z());
  } else if (cutter.corner_radius_m <= 0.0) {
    // A flat end on a ramp: at each layer, the part of the move whose tip is below it, at full radius.
    for (int k = 0; k < nz_; ++k) {
      const double z = min_z_ + (k + 0.5) * layer_;
      double t0 = 0.0, t1 = 1.0;
      const double t = (z - from_m.z()) / dz;
      (dz > 0.0 ? t1 : t0) = std::clamp(t, 0.0, 1.0);
      if (t1 > t0 || (t1 == t0 && std::min(from_m.z(), to_m.z()) < z)) {
        cut_layers(k, k + 1, a + t0 * (b - a), a + t1 * (b - a), cutter.radius_m());
      }
    }
  } else {
    // A rounded cutter on a ramp: level steps of at most half a layer, each at its middle height.
    const int steps = std::clamp(static_cast<int>(std::ceil(std::abs(dz) / (0.5 * layer_))), 1, 10000);
    for (int s = 0; s < steps; ++s) {
      const double u0 = static_cast<double>(s) / steps, u1 = static_cast<double>(s + 1) / steps;
      cut_level(cutter, a + u0 * (b - a), a + u1 * (b - a), from_m.z() + 0.5 * (u0 + u1) * dz);
    }
  }
  return status;
}

int DexelStock::layer_of(double z) const noexcept {
  return std::clamp(static_cast<int>(std::floor((z - min_z_) / layer_)), 0, nz_ - 1);
}

DexelStock::WallProbe DexelStock::probe(const std::vector<Line>& lines, int lines_per_layer, int k, double along,
                                        double across) const noexcept {
  WallProbe p;
  const double v = across / cell_;
  if (!(v >= 0.0 && v <= lines_per_layer - 1)) return p;
  const int j0 = std::clamp(static_cast<int>(std::floor(v)), 0, lines_per_layer - 2);
  const double w = std::clamp(v - j0, 0.0, 1.0);
  double signed_distance[2] = {0.0, 0.0}, end[2] = {0.0, 0.0};
  for (int s = 0; s < 2; ++s) {
    const Line& line = lines[index(k, lines_per_layer, j0 + s)];
    if (line.count == 0) return p;
    double nearest = 1e300;
    bool in = false;
    for (int i = 0; i < line.count; ++i) {
      const double lo = line.lo(i), hi = line.hi(i);
      in = in || (along >= lo && along <= hi);
      for (double e : {lo, hi}) {
        if (std::abs(along - e) < nearest) {
          nearest = std::abs(along - e);
          end[s] = e;
        }
      }
    }
    signed_distance[s] = in ? nearest : -nearest;
  }
  p.valid = true;
  p.inside_m = (1.0 - w) * signed_distance[0] + w * signed_distance[1];
  p.slope = std::abs(end[1] - end[0]) / cell_;
  return p;
}

double DexelStock::inside_m(int k, double x, double y, bool& ok) const noexcept {
  const WallProbe px = probe(along_x_, ny_, k, x, y - min_y_);
  const WallProbe py = probe(along_y_, nx_, k, y, x - min_x_);
  // The family crossing the wall more squarely: its ends move less from one line to the next.
  const bool use_x = px.valid && px.slope <= 1.0 && (!py.valid || py.slope > 1.0 || px.slope <= py.slope);
  const bool use_y = !use_x && py.valid && py.slope <= 1.0;
  ok = use_x || use_y;
  return use_x ? px.inside_m : py.inside_m;
}

StockStatus DexelStock::engagement(const Cutter& cutter, const CutFrame& frame, const Vector3& tip_m, SpindleTurn turn,
                                   Engagement& out) const noexcept {
  out.clear();
  if (!detail::vertical(frame.axis, ZMapStock::kMaxTiltRad)) return StockStatus::kUnsupportedAxis;
  const double r = cutter.radius_m(), z_tip = tip_m.z(), lo = std::max(0.0, top_.bottom_m() - z_tip);
  // At a point of the circle: inside or not from the dexels of the layer halfway up the material
  // there, the depth from the highest of the four height-map nodes around it (the uncut top beside a
  // wall, which the bilinear height smears over a cell); the height map alone where the dexels
  // cannot say (no line with material on either side, outside the grid).
  auto extent = [&](double x, double y, double& l, double& h) {
    const double top = top_.max_node_height_m(x, y);
    if (!(top - z_tip > lo)) return false;
    bool ok = false;
    const double inside = inside_m(layer_of(z_tip + 0.5 * (lo + top - z_tip)), x, y, ok);
    l = lo;
    if (!ok) {
      h = top_.height_m(x, y) - z_tip;
      return h > l;
    }
    h = top - z_tip;
    return inside > 0.0;
  };
  detail::sample_engagement(r, frame, tip_m, turn, sampling_, extent, out);
  return out.engaged() ? StockStatus::kCut : StockStatus::kInAir;
}

DexelStock::Intervals DexelStock::intervals(const Line& line) const {
  Intervals out;
  for (int i = 0; i < line.count; ++i) {
    out.emplace_back(line.lo(i), line.hi(i));
  }
  return out;
}

DexelStock::Intervals DexelStock::along_x(double y_m, double z_m) const {
  const int j = std::clamp(static_cast<int>(std::lround((y_m - min_y_) / cell_)), 0, ny_ - 1);
  return intervals(along_x_[index(layer_of(z_m), ny_, j)]);
}

DexelStock::Intervals DexelStock::along_y(double x_m, double z_m) const {
  const int i = std::clamp(static_cast<int>(std::lround((x_m - min_x_) / cell_)), 0, nx_ - 1);
  return intervals(along_y_[index(layer_of(z_m), nx_, i)]);
}

std::string DexelStock::describe() const {
  return fmt::format("tri-dexel: {}; {} layers {:g} mm apart ({} lines along x, {} along y)", top_.describe(), nz_,
                     layer_ * 1e3, along_x_.size(), along_y_.size());
}

}  // namespace deflex
