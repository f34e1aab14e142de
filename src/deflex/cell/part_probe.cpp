// The part measured after the cut (see part_probe.hpp).
#include "deflex/cell/part_probe.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex::cell {
namespace {

// Points a side of a probed grid at most: a CMM's program probes tens to hundreds.
constexpr int kMaxGrid = 10000;

void check_range(double lo, double hi, const char* what) {
  if (!std::isfinite(lo) || !std::isfinite(hi) || hi < lo) {
    throw InputError(fmt::format("part probe: {}: {} .. {} m is not an increasing range", what, lo, hi));
  }
}

double grid_at(double lo, double hi, int i, int n) { return n == 1 ? 0.5 * (lo + hi) : lo + (hi - lo) * i / (n - 1); }

// The wall's end on a line of material intervals: the upper end of an interval when the material is
// below the wall, the lower one when above, the one nearest the nominal within `search`.
bool wall_end(const DexelStock::Intervals& intervals, const WallSpec& spec, double& end) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& [lo, hi] : intervals) {
    const double e = spec.material_below ? hi : lo;
    const double d = std::abs(e - spec.nominal_m);
    if (d <= spec.search_m && d < best) {
      best = d;
      end = e;
    }
  }
  return std::isfinite(best);
}

void summarise(WallProfile& p) {
  p.points = static_cast<int>(p.deviation_m.size());
  if (p.points == 0) return;
  double sum = 0.0, sum2 = 0.0, max_abs = 0.0;
  p.min_m = p.max_m = p.deviation_m.front();
  for (double d : p.deviation_m) {
    sum += d;
    sum2 += d * d;
    p.min_m = std::min(p.min_m, d);
    p.max_m = std::max(p.max_m, d);
    max_abs = std::max(max_abs, std::abs(d));
  }
  p.mean_m = sum / p.points;
  p.rms_m = std::sqrt(sum2 / p.points);
  p.peak_to_valley_m = p.max_m - p.min_m;
  p.profile_m = 2.0 * max_abs;
}

}  // namespace

PartProbe::PartProbe(double noise_m, std::uint64_t seed) : noise_m_(noise_m), rng_(seed) {
  if (!std::isfinite(noise_m) || noise_m < 0.0) {
    throw InputError(fmt::format("part probe: noise: {} m is not a 1-sigma (>= 0)", noise_m));
  }
}

WallProfile PartProbe::wall(const DexelStock& stock, const WallSpec& spec) {
  check_range(spec.along_lo_m, spec.along_hi_m, "wall: along");
  check_range(spec.z_lo_m, spec.z_hi_m, "wall: z");
  if (spec.points_along < 1 || spec.points_up < 1 || spec.points_along > kMaxGrid || spec.points_up > kMaxGrid) {
    throw InputError(fmt::format("part probe: wall: {} x {} points: each side needs 1..{}", spec.points_along,
                                 spec.points_up, kMaxGrid));
  }
  if (!std::isfinite(spec.nominal_m) || !(spec.search_m > 0.0)) {
    throw InputError("part probe: wall: the nominal must be finite and the search distance positive");
  }
  WallProfile p;
  double position_sum = 0.0;
  for (int k = 0; k < spec.points_up; ++k) {
    const double z = grid_at(spec.z_lo_m, spec.z_hi_m, k, spec.points_up);
    for (int i = 0; i < spec.points_along; ++i) {
      const double a = grid_at(spec.along_lo_m, spec.along_hi_m, i, spec.points_along);
      const DexelStock::Intervals line =
          spec.normal == WallSpec::Normal::kY ? stock.along_y(a, z) : stock.along_x(a, z);
      double end = 0.0;
      if (!wall_end(line, spec, end)) {
        ++p.missing;
        continue;
      }
      end += noise();
      position_sum += end;
      p.along_m.push_back(a);
      p.z_m.push_back(z);
      p.deviation_m.push_back(spec.material_below ? end - spec.nominal_m : spec.nominal_m - end);
    }
  }
  summarise(p);
  if (p.points > 0) p.mean_position_m = position_sum / p.points;
  return p;
}

FloorFlatness PartProbe::floor(const DexelStock& stock, const FloorSpec& spec) {
  check_range(spec.x_lo_m, spec.x_hi_m, "floor: x");
  check_range(spec.y_lo_m, spec.y_hi_m, "floor: y");
  if (spec.nx < 1 || spec.ny < 1 || spec.nx > kMaxGrid || spec.ny > kMaxGrid || spec.nx * spec.ny < 3) {
    throw InputError(fmt::format("part probe: floor: {} x {} points: a plane needs at least 3, each side at most {}",
                                 spec.nx, spec.ny, kMaxGrid));
  }
  std::vector<Vector3> pts;
  pts.reserve(static_cast<std::size_t>(spec.nx) * static_cast<std::size_t>(spec.ny));
  for (int j = 0; j < spec.ny; ++j) {
    for (int i = 0; i < spec.nx; ++i) {
      const double x = grid_at(spec.x_lo_m, spec.x_hi_m, i, spec.nx), y = grid_at(spec.y_lo_m, spec.y_hi_m, j, spec.ny);
      pts.emplace_back(x, y, stock.heights().height_m(x, y) + noise());
    }
  }
  // The least-squares plane z = c0 + c1 (x - x_mean) + c2 (y - y_mean) (a line when one row or
  // column: the missing slope stays 0).
  Vector3 mean = Vector3::Zero();
  for (const Vector3& q : pts) mean += q;
  mean /= static_cast<double>(pts.size());
  Matrix3 a = Matrix3::Zero();
  Vector3 b = Vector3::Zero();
  for (const Vector3& q : pts) {
    const Vector3 row(1.0, q.x() - mean.x(), q.y() - mean.y());
    a += row * row.transpose();
    b += row * q.z();
  }
  for (int i = 1; i < 3; ++i) {
    if (a(i, i) <= 0.0) a(i, i) = 1.0;  // a single row or column has no slope across it
  }
  const Vector3 c = a.ldlt().solve(b);
  FloorFlatness f;
  f.points = static_cast<int>(pts.size());
  double lo = std::numeric_limits<double>::infinity(), hi = -lo, sum = 0.0, sum2 = 0.0;
  for (const Vector3& q : pts) {
    const double r = q.z() - (c[0] + c[1] * (q.x() - mean.x()) + c[2] * (q.y() - mean.y()));
    lo = std::min(lo, r);
    hi = std::max(hi, r);
    sum += q.z() - spec.nominal_m;
    sum2 += r * r;
  }
  f.flatness_m = hi - lo;
  f.mean_m = sum / f.points;
  f.rms_m = std::sqrt(sum2 / f.points);
  return f;
}

WidthMeasure PartProbe::width(const WallProfile& a, const WallSpec& a_spec, const WallProfile& b,
                              const WallSpec& b_spec) {
  WidthMeasure w;
  w.width_m = std::abs(b.mean_position_m - a.mean_position_m);
  w.nominal_m = std::abs(b_spec.nominal_m - a_spec.nominal_m);
  w.error_m = w.width_m - w.nominal_m;
  return w;
}

}  // namespace deflex::cell
