// ISO 9283 path accuracy and repeatability from repeated runs.
#include "deflex/evaluate/iso9283_path.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

// Point at arc length s along a polyline with cumulative lengths `cum`.
Vector3 point_at(const TrackerTrace& path, const std::vector<double>& cum, double s) {
  s = std::clamp(s, 0.0, cum.back());
  const auto it = std::upper_bound(cum.begin(), cum.end(), s);
  std::size_t k = it == cum.begin() ? 0 : static_cast<std::size_t>(it - cum.begin()) - 1;
  if (k + 1 >= path.size()) {
    return path.back().p_m;
  }
  const double len = cum[k + 1] - cum[k];
  const double f = len > 0.0 ? (s - cum[k]) / len : 0.0;
  return path[k].p_m + f * (path[k + 1].p_m - path[k].p_m);
}

// A run cut into blocks of consecutive samples, each with a sphere that holds its samples and so
// every point of its segments (a block's last segment ends at the next block's first sample, which
// the block includes). A plane crossing within some distance of a point can only lie in a block whose
// sphere comes that close, so the search below skips the rest of the run: same answer as a scan of
// every segment, some fifty times faster for the paper's circles.
// Groups of kGroup blocks have a sphere each too (around their blocks' spheres), so a plane far from
// a whole lap is skipped group by group.
constexpr std::size_t kBlock = 64;
constexpr std::size_t kGroup = 16;

struct BlockedRun {
  const TrackerTrace* run = nullptr;
  std::vector<Vector3> centre, group_centre;
  std::vector<double> radius, group_radius;
};

// The spheres of the groups of blocks: centred on the box of their blocks' centres, each radius
// the largest distance to a block's sphere's far side.
void group_blocks(BlockedRun& b) {
  for (std::size_t first = 0; first < b.centre.size(); first += kGroup) {
    const std::size_t end = std::min(first + kGroup, b.centre.size());
    Vector3 lo = b.centre[first], hi = b.centre[first];
    for (std::size_t k = first + 1; k < end; ++k) {
      lo = lo.cwiseMin(b.centre[k]);
      hi = hi.cwiseMax(b.centre[k]);
    }
    const Vector3 centre = 0.5 * (lo + hi);
    double radius = 0.0;
    for (std::size_t k = first; k < end; ++k) radius = std::max(radius, (b.centre[k] - centre).norm() + b.radius[k]);
    b.group_centre.push_back(centre);
    b.group_radius.push_back(radius);
  }
}

BlockedRun block_run(const TrackerTrace& run) {
  BlockedRun b;
  b.run = &run;
  for (std::size_t first = 0; first + 1 < run.size(); first += kBlock) {
    const std::size_t last = std::min(first + kBlock, run.size() - 1);  // inclusive: the next block's first
    Vector3 lo = run[first].p_m, hi = run[first].p_m;
    for (std::size_t k = first + 1; k <= last; ++k) {
      lo = lo.cwiseMin(run[k].p_m);
      hi = hi.cwiseMax(run[k].p_m);
    }
    b.centre.push_back(0.5 * (lo + hi));
    b.radius.push_back(0.5 * (hi - lo).norm());
  }
  group_blocks(b);
  return b;
}

// Of the run's crossings of the plane through c with normal n that lie within max_offset of c, the
// one nearest to c; NaN if none.
Vector3 nearest_crossing(const BlockedRun& b, const Vector3& c, const Vector3& n, double max_offset) {
  const TrackerTrace& run = *b.run;
  Vector3 best = Vector3::Constant(std::numeric_limits<double>::quiet_NaN());
  double best_d2 = max_offset * max_offset;
  // A block is skipped only where every sample of it provably lies beyond max_offset of c, or on one
  // side of the plane (no sign change, so no crossing): the margin, far above the rounding of these
  // few operations and far below any tracker's resolution, keeps the scan's answer exactly the same.
  const double margin = 1e-9 * (1.0 + c.cwiseAbs().maxCoeff());
  for (std::size_t block = 0; block < b.centre.size(); ++block) {
    if (block % kGroup == 0) {
      const std::size_t group = block / kGroup;
      const Vector3 g = b.group_centre[group] - c;
      if (std::abs(g.dot(n)) > b.group_radius[group] + margin ||
          g.norm() > b.group_radius[group] + max_offset + margin) {
        block += kGroup - 1;  // none of its blocks comes near enough: each would be skipped below
        continue;
      }
    }
    const Vector3 r = b.centre[block] - c;
    if (std::abs(r.dot(n)) > b.radius[block] + margin) continue;
    if (r.norm() > b.radius[block] + max_offset) continue;
    const std::size_t first = block * kBlock;
    const std::size_t last = std::min(first + kBlock, run.size() - 1);
    double f_prev = (run[first].p_m - c).dot(n);
    for (std::size_t k = first; k < last; ++k) {
      const double f_next = (run[k + 1].p_m - c).dot(n);
      if ((f_prev <= 0.0 && f_next >= 0.0) || (f_prev >= 0.0 && f_next <= 0.0)) {
        const double denom = f_prev - f_next;
        const double a = denom != 0.0 ? f_prev / denom : 0.0;
        const Vector3 x = run[k].p_m + a * (run[k + 1].p_m - run[k].p_m);
        const double d2 = (x - c).squaredNorm();
        if (d2 <= best_d2) {
          best_d2 = d2;
          best = x;
        }
      }
      f_prev = f_next;
    }
  }
  return best;
}

}  // namespace

// NOLINTNEXTLINE(readability-function-size): listed in docs/architecture.md, "Functions over 80 lines"
Iso9283Path iso9283_path(const std::vector<TrackerTrace>& repeated_runs, const TrackerTrace& reference,
                         int evaluation_points, double max_offset_m) {
  if (repeated_runs.empty()) {
    throw InputError("ISO 9283 path figures: no run given");
  }
  // 1..100000, the range `deflex evaluate --evaluation-points` takes (the Python module calls this directly).
  if (evaluation_points < 1 || evaluation_points > 100000) {
    throw InputError(fmt::format("ISO 9283 path figures: {} evaluation points (need 1..100000)", evaluation_points));
  }
  if (!(max_offset_m > 0.0) || !(max_offset_m <= 100.0)) {
    throw InputError(
        "ISO 9283 path figures: the largest offset of a run from the path must be positive, at most 100 m");
  }
  if (reference.size() < 2) {
    throw InputError("ISO 9283 path figures: the reference path needs at least 2 samples");
  }
  // A non-finite sample would silently drop the planes it should cross (or, in the reference, make
  // the path length NaN and the error "zero length"): name it instead.
  for (std::size_t j = 0; j < repeated_runs.size(); ++j) {
    if (repeated_runs[j].size() < 2) {
      throw InputError(fmt::format("ISO 9283 path figures: run {} has fewer than 2 samples", j + 1));
    }
    for (std::size_t k = 0; k < repeated_runs[j].size(); ++k) {
      if (!repeated_runs[j][k].p_m.allFinite()) {
        throw InputError(fmt::format("ISO 9283 path figures: run {} sample {} (t = {} s) is not finite", j + 1, k,
                                     repeated_runs[j][k].t_s));
      }
    }
  }
  std::vector<double> cum(reference.size(), 0.0);
  for (std::size_t k = 0; k < reference.size(); ++k) {
    if (!reference[k].p_m.allFinite()) {
      throw InputError(fmt::format("ISO 9283 path figures: reference sample {} is not finite", k));
    }
    if (k > 0) {
      cum[k] = cum[k - 1] + (reference[k].p_m - reference[k - 1].p_m).norm();
    }
  }
  const double length = cum.back();
  if (!(length > 0.0)) {
    throw InputError("ISO 9283 path figures: the reference path has zero length");
  }

  Iso9283Path out;
  out.runs = static_cast<int>(repeated_runs.size());
  const auto n_runs = static_cast<double>(repeated_runs.size());
  const double h = 0.01 * length;
  double accuracy_sum = 0.0;
  std::vector<Vector3> x(repeated_runs.size());
  std::vector<BlockedRun> blocked;
  blocked.reserve(repeated_runs.size());
  for (const auto& run : repeated_runs) blocked.push_back(block_run(run));
  for (int i = 0; i < evaluation_points; ++i) {
    const double s = (i + 0.5) * length / evaluation_points;
    const Vector3 c = point_at(reference, cum, s);
    const Vector3 chord = point_at(reference, cum, s + h) - point_at(reference, cum, s - h);
    if (!(chord.norm() > 0.0)) {
      ++out.skipped_points;
      continue;
    }
    const Vector3 n = chord.normalized();
    bool all = true;
    for (std::size_t j = 0; j < repeated_runs.size() && all; ++j) {
      x[j] = nearest_crossing(blocked[j], c, n, max_offset_m);
      all = x[j].allFinite();
    }
    if (!all) {
      ++out.skipped_points;
      continue;
    }
    Vector3 bary = Vector3::Zero();
    for (const auto& xj : x) {
      bary += xj;
    }
    bary /= n_runs;
    const double at = (bary - c).norm();
    double l_mean = 0.0;
    for (const auto& xj : x) {
      l_mean += (xj - bary).norm();
    }
    l_mean /= n_runs;
    double s_l = 0.0;
    if (repeated_runs.size() > 1) {
      for (const auto& xj : x) {
        const double dl = (xj - bary).norm() - l_mean;
        s_l += dl * dl;
      }
      s_l = std::sqrt(s_l / (n_runs - 1.0));
    }
    out.accuracy_m = std::max(out.accuracy_m, at);
    out.repeatability_m = std::max(out.repeatability_m, l_mean + 3.0 * s_l);
    accuracy_sum += at;
    ++out.evaluation_points;
  }
  if (out.evaluation_points == 0) {
    throw InputError(fmt::format(
        "ISO 9283 path figures: no plane normal to the reference path is crossed by every run within {} mm of "
        "the path (do the runs follow the reference?)",
        max_offset_m * 1e3));
  }
  out.mean_accuracy_m = accuracy_sum / out.evaluation_points;
  return out;
}

}  // namespace deflex
