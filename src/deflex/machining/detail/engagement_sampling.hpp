// Building an Engagement from the material's extent along the tool axis at points of the cutter's
// circle, for any stock that can say that extent (a height map's column, a dexel's intervals).
//
// The front half of the circle (immersion 0..pi) is sampled at `samples` + 1 angles; each sample's
// material along the axis is an interval above the tip. Runs of engaged samples are arcs; an arc's
// ends are refined by bisection to the angle where the material is half as deep as inside the arc
// (the middle of a height map's one-cell ramp at a wall). Samples of one run whose extents agree within the tolerance
// form one patch, so a flat-floored side cut is one patch and a step or a sloped floor several.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>

#include "deflex/machining/engagement.hpp"
#include "deflex/machining/milling_force.hpp"
#include "deflex/machining/stock.hpp"
#include "deflex/model/types.hpp"

namespace deflex::detail {

inline constexpr int kMaxSamples = 256;

/// The cos and sin of the sample angles pi i / samples, computed once per sample count.
struct AngleTable {
  int samples = 0;
  std::array<double, kMaxSamples + 1> c{}, s{};
};

inline const AngleTable& angle_table(int samples) {
  static thread_local AngleTable table;
  if (table.samples != samples) {
    table.samples = samples;
    for (int i = 0; i <= samples; ++i) {
      table.c[static_cast<std::size_t>(i)] = std::cos(kPi * i / samples);
      table.s[static_cast<std::size_t>(i)] = std::sin(kPi * i / samples);
    }
  }
  return table;
}

/// `extent(x, y, lo, hi)` sets the material's interval along the axis at (x, y) in the stock's frame,
/// heights above the tip clipped at 0, and returns false where there is none. The tool axis is the
/// stock's z (3-axis), the frame's feed and normal lie in its xy plane.
template <class Extent>
void sample_engagement(double radius_m, const CutFrame& frame, const Vector3& tip_m, SpindleTurn turn,
                       const EngagementSampling& opt, const Extent& extent, Engagement& out) noexcept {
  out.clear();
  const int k = std::clamp(opt.samples, 4, kMaxSamples);
  const AngleTable& table = angle_table(k);
  const double s = turn_sign(turn);
  const Eigen::Vector2d f = frame.feed.head<2>(), n = s * frame.normal.head<2>(), c = tip_m.head<2>();
  std::array<double, kMaxSamples + 1> lo{}, hi{};
  std::array<bool, kMaxSamples + 1> in{};
  auto probe = [&](double cphi, double sphi, double& l, double& h) {
    const Eigen::Vector2d p = c + radius_m * (n * cphi + f * sphi);
    return extent(p.x(), p.y(), l, h) && h - l > opt.min_depth_m;
  };
  for (int i = 0; i <= k; ++i) {
    const auto u = static_cast<std::size_t>(i);
    in[u] = probe(table.c[u], table.s[u], lo[u], hi[u]);
  }
  auto depth = [&](int i) { return hi[static_cast<std::size_t>(i)] - lo[static_cast<std::size_t>(i)]; };
  // The angle between samples a (shallow) and b (deep) where the material's depth is `threshold`.
  auto refine = [&](int a, int b, double threshold) {
    double pa = kPi * a / k, pb = kPi * b / k;
    for (int step = 0; step < opt.refine_steps; ++step) {
      const double m = 0.5 * (pa + pb);
      double l = 0.0, h = 0.0;
      const bool deep = probe(std::cos(m), std::sin(m), l, h) && h - l > threshold;
      (deep ? pb : pa) = m;
    }
    return 0.5 * (pa + pb);
  };
  int i = 0;
  while (i <= k) {
    if (!in[static_cast<std::size_t>(i)]) {
      ++i;
      continue;
    }
    int first = i;
    while (i + 1 <= k && in[static_cast<std::size_t>(i) + 1]) ++i;
    int last = i++;
    // An arc ends where the material is half as deep as next to it: a sample on a wall's ramp (a
    // height map's last cell) belongs to neither side, so it is left out of the arc and its patches.
    const double edge_in = 0.5 * std::max(depth(first), depth(std::min(first + 2, last)));
    const double edge_out = 0.5 * std::max(depth(last), depth(std::max(last - 2, first)));
    while (first < last && depth(first) <= edge_in) ++first;
    while (last > first && depth(last) <= edge_out) --last;
    const double entry = first == 0 ? 0.0 : refine(first - 1, first, edge_in);
    const double exit = last == k ? kPi : refine(last + 1, last, edge_out);
    // Patches of samples whose extents agree; a boundary between two samples at their middle angle.
    int start = first;
    double from = entry;
    while (start <= last) {
      double sum_lo = 0.0, sum_hi = 0.0;
      int end = start;
      const auto u0 = static_cast<std::size_t>(start);
      const double tol = std::max(opt.depth_tolerance_m, 0.01 * (hi[u0] - lo[u0]));
      while (end + 1 <= last && std::abs(hi[static_cast<std::size_t>(end) + 1] - hi[u0]) <= tol &&
             std::abs(lo[static_cast<std::size_t>(end) + 1] - lo[u0]) <= tol) {
        ++end;
      }
      for (int j = start; j <= end; ++j) {
        sum_lo += lo[static_cast<std::size_t>(j)];
        sum_hi += hi[static_cast<std::size_t>(j)];
      }
      const double to = end == last ? exit : kPi * (end + 0.5) / k;
      const double count = end - start + 1;
      EngagementPatch p{from, to, sum_lo / count, sum_hi / count};
      if (!out.add(p) && out.count > 0) {
        // Out of room: the last patch stretches over the rest (the force integrates it at its depth).
        out.patches[static_cast<std::size_t>(out.count - 1)].exit_rad = to;
      }
      from = to;
      start = end + 1;
    }
  }
  out.summarise(radius_m);
}

}  // namespace deflex::detail
