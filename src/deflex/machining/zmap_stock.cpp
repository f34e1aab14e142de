// The height-map stock.
#include "deflex/machining/zmap_stock.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "deflex/machining/detail/cutter_sweep.hpp"
#include "deflex/machining/detail/engagement_sampling.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
using detail::kInf;
using detail::profile;
using detail::stadium_row;

namespace {
bool vertical(const Vector3& axis) noexcept { return detail::vertical(axis, ZMapStock::kMaxTiltRad); }
}  // namespace

double lowest_cutter_surface_m(const Cutter& cutter, const Vector3& a, const Vector3& b, double px,
                               double py) noexcept {
  const double radius = cutter.radius_m(), rc = cutter.corner_radius_m;
  const Eigen::Vector2d p(px, py), a2 = a.head<2>(), d2 = b.head<2>() - a.head<2>();
  const double dz = b.z() - a.z(), len2 = d2.squaredNorm();
  const Eigen::Vector2d pa = p - a2;
  if (std::abs(dz) <= 1e-12) {  // a level move: the closest point of the move is the lowest
    const double t = len2 > 0.0 ? std::clamp(pa.dot(d2) / len2, 0.0, 1.0) : 0.0;
    return a.z() + profile((pa - t * d2).norm(), radius, rc);
  }
  if (len2 <= 1e-24) {  // a plunge
    return std::min(a.z(), b.z()) + profile(pa.norm(), radius, rc);
  }
  // The part of the move whose cutter covers p: |pa - t d2| <= R.
  const double bq = pa.dot(d2), cq = pa.squaredNorm() - radius * radius;
  const double disc = bq * bq - len2 * cq;
  if (disc < 0.0) return kInf;
  const double root = std::sqrt(disc);
  const double t1 = std::max(0.0, (bq - root) / len2), t2 = std::min(1.0, (bq + root) / len2);
  if (t1 > t2) return kInf;
  auto height = [&](double t) { return a.z() + t * dz + profile((pa - t * d2).norm(), radius, rc); };
  if (rc <= 0.0) {
    return a.z() + std::min(t1 * dz, t2 * dz);  // the lower end of the covered part
  }
  // Convex in t (a convex, non-decreasing profile of a convex distance, plus a linear rise): golden section.
  double lo = t1, hi = t2;
  constexpr double kGolden = 0.6180339887498949;
  double m1 = hi - kGolden * (hi - lo), m2 = lo + kGolden * (hi - lo);
  double h1 = height(m1), h2 = height(m2);
  for (int i = 0; i < 48 && hi - lo > 1e-12; ++i) {
    if (h1 <= h2) {
      hi = m2;
      m2 = m1;
      h2 = h1;
      m1 = hi - kGolden * (hi - lo);
      h1 = height(m1);
    } else {
      lo = m1;
      m1 = m2;
      h1 = h2;
      m2 = lo + kGolden * (hi - lo);
      h2 = height(m2);
    }
  }
  return std::min({h1, h2, height(t1), height(t2)});
}

ZMapStock ZMapStock::box(const Vector3& min_m, const Vector3& max_m, double cell_m) {
  if (!min_m.allFinite() || !max_m.allFinite() || !((max_m - min_m).minCoeff() > 0.0)) {
    throw InputError(fmt::format(
        "box stock: min_mm {:g};{:g};{:g} to max_mm {:g};{:g};{:g} is not a box (every max "
        "above its min)",
        min_m.x() * 1e3, min_m.y() * 1e3, min_m.z() * 1e3, max_m.x() * 1e3, max_m.y() * 1e3, max_m.z() * 1e3));
  }
  if (!std::isfinite(cell_m) || cell_m < 1e-6 || cell_m > 0.1) {
    throw InputError(fmt::format("box stock: cell_mm: {:g} mm is outside 0.001..100 mm", cell_m * 1e3));
  }
  const double nx = std::ceil((max_m.x() - min_m.x()) / cell_m - 1e-9) + 1.0;
  const double ny = std::ceil((max_m.y() - min_m.y()) / cell_m - 1e-9) + 1.0;
  if (nx * ny > kMaxNodes) {
    throw InputError(fmt::format(
        "box stock: {:.0f} x {:.0f} nodes at cell_mm={:g} exceed {:g} M nodes; use cell_mm={:.3g} or coarser", nx, ny,
        cell_m * 1e3, kMaxNodes * 1e-6, cell_m * 1e3 * std::sqrt(nx * ny / kMaxNodes) * 1.01));
  }
  std::vector<float> heights(static_cast<std::size_t>(nx * ny), static_cast<float>(max_m.z()));
  ZMapStock stock(min_m.x(), min_m.y(), cell_m, static_cast<int>(nx), static_cast<int>(ny), min_m.z(),
                  std::move(heights));
  stock.x1_m_ = max_m.x();
  stock.y1_m_ = max_m.y();
  return stock;
}

ZMapStock::ZMapStock(double x0_m, double y0_m, double cell_m, int nx, int ny, double bottom_m,
                     std::vector<float> heights_m)
    : x0_m_(x0_m),
      y0_m_(y0_m),
      cell_m_(cell_m),
      nx_(nx),
      ny_(ny),
      bottom_m_(bottom_m),
      heights_m_(std::move(heights_m)) {
  if (!std::isfinite(x0_m) || !std::isfinite(y0_m) || !std::isfinite(bottom_m) || !std::isfinite(cell_m) ||
      cell_m < 1e-6 || cell_m > 0.1) {
    throw InputError("height-map stock: origin, bottom and cell must be finite, the cell 0.001..100 mm");
  }
  if (nx < 2 || ny < 2 || static_cast<double>(nx) * ny > kMaxNodes ||
      heights_m_.size() != static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny)) {
    throw InputError(fmt::format("height-map stock: {} heights for {} x {} nodes (at least 2 x 2, at most {:g} M)",
                                 heights_m_.size(), nx, ny, kMaxNodes * 1e-6));
  }
  for (float& h : heights_m_) {
    if (!std::isfinite(h)) throw InputError("height-map stock: a height is not finite");
    h = std::max(h, static_cast<float>(bottom_m));
  }
  x1_m_ = x0_m + (nx - 1) * cell_m;
  y1_m_ = y0_m + (ny - 1) * cell_m;
}

double ZMapStock::height_m(double x, double y) const noexcept {
  if (!(x >= x0_m_ && x <= x1_m_ && y >= y0_m_ && y <= y1_m_)) return bottom_m_;
  const double u = (x - x0_m_) / cell_m_, v = (y - y0_m_) / cell_m_;
  const int i = std::clamp(static_cast<int>(u), 0, nx_ - 2), j = std::clamp(static_cast<int>(v), 0, ny_ - 2);
  const double fu = u - i, fv = v - j;
  const float* row = heights_m_.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(nx_) + i;
  const double h00 = row[0], h10 = row[1], h01 = row[nx_], h11 = row[nx_ + 1];
  return (1.0 - fv) * ((1.0 - fu) * h00 + fu * h10) + fv * ((1.0 - fu) * h01 + fu * h11);
}

double ZMapStock::max_node_height_m(double x, double y) const noexcept {
  if (!(x >= x0_m_ && x <= x1_m_ && y >= y0_m_ && y <= y1_m_)) return bottom_m_;
  const int i = std::clamp(static_cast<int>((x - x0_m_) / cell_m_), 0, nx_ - 2);
  const int j = std::clamp(static_cast<int>((y - y0_m_) / cell_m_), 0, ny_ - 2);
  const float* row = heights_m_.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(nx_) + i;
  return std::max({row[0], row[1], row[nx_], row[nx_ + 1]});
}

StockStatus ZMapStock::engagement(const Cutter& cutter, const CutFrame& frame, const Vector3& tip_m, SpindleTurn turn,
                                  Engagement& out) const noexcept {
  out.clear();
  if (!vertical(frame.axis)) return StockStatus::kUnsupportedAxis;
  const double r = cutter.radius_m();
  if (tip_m.x() + r < x0_m_ || tip_m.x() - r > x1_m_ || tip_m.y() + r < y0_m_ || tip_m.y() - r > y1_m_) {
    return StockStatus::kInAir;
  }
  const double z_tip = tip_m.z(), lo = std::max(0.0, bottom_m_ - z_tip);
  auto extent = [&](double x, double y, double& l, double& h) {
    h = height_m(x, y) - z_tip;
    l = lo;
    return h > l;
  };
  detail::sample_engagement(r, frame, tip_m, turn, sampling_, extent, out);
  return out.engaged() ? StockStatus::kCut : StockStatus::kInAir;
}

StockStatus ZMapStock::remove_swept(const Cutter& cutter, const Vector3& from_m, const Vector3& to_m,
                                    const Vector3& axis) noexcept {
  if (!vertical(axis)) return StockStatus::kUnsupportedAxis;
  if (!from_m.allFinite() || !to_m.allFinite()) return StockStatus::kInAir;
  const double r = cutter.radius_m(), rc = cutter.corner_radius_m;
  const bool level = std::abs(to_m.z() - from_m.z()) <= 1e-12;
  const Eigen::Vector2d a = from_m.head<2>(), b = to_m.head<2>();
  const int j0 = std::max(0, static_cast<int>(std::floor((std::min(a.y(), b.y()) - r - y0_m_) / cell_m_)));
  const int j1 = std::min(ny_ - 1, static_cast<int>(std::ceil((std::max(a.y(), b.y()) + r - y0_m_) / cell_m_)));
  const double lowest_tip = std::min(from_m.z(), to_m.z());
  const bool continues =
      level && last_level_end_ && *last_level_end_ == from_m && last_corner_m_ == rc && last_radius_m_ == r;
  double removed = 0.0;
  auto lower = [&](float& node, double cut) {
    if (cut < node) {
      const float lowered = static_cast<float>(std::max(cut, bottom_m_));
      removed += node - lowered;
      node = lowered;
    }
  };
  auto node_range = [&](double xl, double xr, int& i0, int& i1) {
    i0 = std::max(0, static_cast<int>(std::ceil((xl - x0_m_) / cell_m_)));
    i1 = std::min(nx_ - 1, static_cast<int>(std::floor((xr - x0_m_) / cell_m_)));
  };
  for (int j = j0; j <= j1; ++j) {
    float* row = heights_m_.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(nx_);
    const double y = y0_m_ + j * cell_m_;
    double xl = 0.0, xr = 0.0;
    if (!stadium_row(a, b, r, y, xl, xr)) continue;
    int i0 = 0, i1 = -1;
    node_range(xl, xr, i0, i1);
    if (level) {
      // The flat part of the end at the tip's height over the inner stadium, the corner node by node.
      // When the last move ended here at this height, its end disc is already down to the tip's height.
      double il = 0.0, ir = -1.0;
      const bool inner = stadium_row(a, b, r - rc, y, il, ir);
      int k0 = i1 + 1, k1 = i1;
      if (inner) node_range(il, ir, k0, k1);
      int s0 = k1 + 1, s1 = k1;
      double dl = 0.0, dr = -1.0;
      // (1 nm inside it: a node on its rim may have fallen outside the last move's band by rounding)
      if (continues && stadium_row(a, a, r - rc - 1e-9, y, dl, dr)) node_range(dl, dr, s0, s1);
      for (int i = k0; i <= k1; ++i) {
        if (i == s0 && s0 <= s1) i = s1 + 1;
        if (i > k1) break;
        lower(row[i], from_m.z());
      }
      for (int i = i0; i <= i1; ++i) {
        if (i == k0 && k0 <= k1) i = k1 + 1;
        if (i > i1) break;
        if (row[i] > lowest_tip) lower(row[i], lowest_cutter_surface_m(cutter, from_m, to_m, x0_m_ + i * cell_m_, y));
      }
      continue;
    }
    for (int i = i0; i <= i1; ++i) {
      if (row[i] <= lowest_tip) continue;  // already below anything the cutter reaches
      lower(row[i], lowest_cutter_surface_m(cutter, from_m, to_m, x0_m_ + i * cell_m_, y));
    }
  }
  removed *= cell_m_ * cell_m_;
  removed_m3_ += removed;
  if (level) {
    last_level_end_ = to_m;
    last_radius_m_ = r;
    last_corner_m_ = rc;
  } else {
    last_level_end_.reset();
  }
  return removed > 0.0 ? StockStatus::kCut : StockStatus::kInAir;
}

std::string ZMapStock::describe() const {
  return fmt::format("height map {:g} x {:g} mm, bottom at {:g} mm, cell {:g} mm ({} x {} nodes)",
                     (x1_m_ - x0_m_) * 1e3, (y1_m_ - y0_m_) * 1e3, bottom_m_ * 1e3, cell_m_ * 1e3, nx_, ny_);
}

}  // namespace deflex
