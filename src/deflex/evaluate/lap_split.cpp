// Laps of a closed path from the angle turned about its centre.
#include "deflex/evaluate/lap_split.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include <fmt/format.h>

#include <Eigen/Eigenvalues>

#include "deflex/text/errors.hpp"

namespace deflex {

PathPlane best_fit_plane(const TrackerTrace& path) {
  if (path.size() < 2) {
    throw InputError("plane of a path: fewer than 2 samples");
  }
  // One NaN makes the whole plane NaN, and the laps and the mean path built on it nonsense: refused
  // here, where split_laps, directed_laps and mean_closed_path all begin (in the centroid's pass).
  PathPlane pl;
  for (std::size_t i = 0; i < path.size(); ++i) {
    const Vector3& p = path[i].p_m;
    if (!p.allFinite()) {
      throw InputError(fmt::format("plane of a path: sample {} (t = {} s) is not finite", i, path[i].t_s));
    }
    pl.centroid_m += p;
  }
  pl.centroid_m /= static_cast<double>(path.size());
  // The scatter matrix, its six distinct sums kept in plain doubles: the evaluation fits a plane to
  // every run, and summing the whole 3x3 outer product took three times as long (evaluate_bench,
  // BM_PlaneFit377k: 5.7 against 1.8 ms) for the same numbers.
  const Vector3 c = pl.centroid_m;
  double sxx = 0.0, sxy = 0.0, sxz = 0.0, syy = 0.0, syz = 0.0, szz = 0.0;
  for (const auto& s : path) {
    const double dx = s.p_m.x() - c.x(), dy = s.p_m.y() - c.y(), dz = s.p_m.z() - c.z();
    sxx += dx * dx;
    sxy += dx * dy;
    sxz += dx * dz;
    syy += dy * dy;
    syz += dy * dz;
    szz += dz * dz;
  }
  Matrix3 cov;
  cov << sxx, sxy, sxz, sxy, syy, syz, sxz, syz, szz;
  const Eigen::SelfAdjointEigenSolver<Matrix3> eig(cov);
  pl.normal = eig.eigenvectors().col(0);
  if (pl.normal.z() < 0.0) {
    pl.normal = -pl.normal;
  }
  Vector3 u = Vector3::UnitX() - Vector3::UnitX().dot(pl.normal) * pl.normal;
  if (u.norm() < 0.3) {
    u = Vector3::UnitY() - Vector3::UnitY().dot(pl.normal) * pl.normal;
  }
  pl.u = u.normalized();
  pl.v = pl.normal.cross(pl.u);
  return pl;
}

LapSplit split_laps(const TrackerTrace& trace, double min_turn_rad, double reversal_rad) {
  // A lap closes after a full turn, so a piece can never turn more than 2 pi; compared with >= and >
  // below, a NaN threshold dropped every lap or never saw a reversal.
  if (!(min_turn_rad > 0.0 && min_turn_rad <= 2.0 * kPi)) {
    throw InputError(fmt::format("laps: min_turn_rad must be in (0, 2 pi] (got {})", min_turn_rad));
  }
  if (!std::isfinite(reversal_rad) || !(reversal_rad > 0.0)) {
    throw InputError(fmt::format("laps: reversal_rad must be finite and > 0 (got {})", reversal_rad));
  }
  const PathPlane pl = best_fit_plane(trace);
  auto angle_of = [&](const Vector3& p) {
    const Vector3 r = p - pl.centroid_m;
    return std::atan2(r.dot(pl.v), r.dot(pl.u));
  };
  // Unwrapped angle of every sample, each sample's angle taken once. The step between two angles
  // of [-pi, pi] lies in [-2 pi, 2 pi]; one exact subtraction of 2 pi brings it into [-pi, pi], as
  // std::remainder would, without its cost.
  std::vector<double> theta(trace.size());
  double previous = angle_of(trace[0].p_m);
  theta[0] = previous;
  for (std::size_t i = 1; i < trace.size(); ++i) {
    const double angle = angle_of(trace[i].p_m);
    double d = angle - previous;
    if (d > kPi) {
      d -= 2.0 * kPi;
    } else if (d < -kPi) {
      d += 2.0 * kPi;
    }
    theta[i] = theta[i - 1] + d;
    previous = angle;
  }
  LapSplit out;
  auto close_lap = [&](std::size_t first, std::size_t last) {  // samples [first, last]
    if (last > first && std::abs(theta[last] - theta[first]) >= min_turn_rad) {
      out.laps.emplace_back(trace.begin() + static_cast<std::ptrdiff_t>(first),
                            trace.begin() + static_cast<std::ptrdiff_t>(last) + 1);
    } else {
      ++out.dropped_partial;
    }
  };
  std::size_t start = 0;
  std::size_t extreme = 0;  // sample of the largest turn from `start` so far
  for (std::size_t i = 1; i < trace.size(); ++i) {
    const double turned = theta[i] - theta[start];
    const double best = theta[extreme] - theta[start];
    if (std::abs(turned) > std::abs(best)) {
      extreme = i;
    }
    if (std::abs(theta[i] - theta[start]) >= 2.0 * kPi) {
      close_lap(start, i);
      start = extreme = i;
    } else if (std::abs(theta[extreme] - theta[i]) > reversal_rad &&
               std::abs(theta[i] - theta[start]) < std::abs(theta[extreme] - theta[start])) {
      // Fell back from the extreme: the path reversed there.
      close_lap(start, extreme);
      start = extreme;
      // The new lap's extreme is the furthest point since the reversal.
      std::size_t e = start;
      for (std::size_t k = start; k <= i; ++k) {
        if (std::abs(theta[k] - theta[start]) > std::abs(theta[e] - theta[start])) {
          e = k;
        }
      }
      extreme = e;
    }
  }
  if (start + 1 < trace.size()) {
    close_lap(start, trace.size() - 1);
  }
  return out;
}

std::vector<DirectedLap> directed_laps(const TrackerTrace& trace) {
  const PathPlane plane = best_fit_plane(trace);
  std::vector<DirectedLap> out;
  for (auto& lap : split_laps(trace).laps) {
    double area = 0.0;
    for (std::size_t k = 0; k + 1 < lap.size(); ++k) {
      area += (lap[k].p_m - plane.centroid_m).cross(lap[k + 1].p_m - plane.centroid_m).dot(plane.normal);
    }
    out.push_back(DirectedLap{std::move(lap), area < 0.0});
  }
  return out;
}

TrackerTrace mean_closed_path(const TrackerTrace& trace, int bins) {
  if (bins < 8 || bins > 1'000'000) {
    throw InputError(fmt::format("mean path: {} bins (use 8..1000000)", bins));
  }
  const PathPlane pl = best_fit_plane(trace);
  std::vector<Vector3> sum(static_cast<std::size_t>(bins), Vector3::Zero());
  std::vector<int> count(static_cast<std::size_t>(bins), 0);
  for (const auto& s : trace) {
    const Vector3 r = s.p_m - pl.centroid_m;
    const double a = std::atan2(r.dot(pl.v), r.dot(pl.u));  // [-pi, pi]
    auto b = static_cast<int>(std::floor((a + kPi) / (2.0 * kPi) * bins));
    b = std::clamp(b, 0, bins - 1);
    sum[static_cast<std::size_t>(b)] += s.p_m;
    ++count[static_cast<std::size_t>(b)];
  }
  TrackerTrace out;
  for (int b = 0; b < bins; ++b) {
    const auto k = static_cast<std::size_t>(b);
    if (count[k] == 0) continue;
    TrackerSample m;
    m.t_s = (b + 0.5) / bins * 2.0 * kPi - kPi;  // the bin's angle, rad (no time: a mean of laps)
    m.p_m = sum[k] / count[k];
    out.push_back(m);
  }
  if (out.size() < static_cast<std::size_t>(0.9 * bins)) {
    throw InputError(
        fmt::format("mean path: only {} of {} angle bins hold a sample: not a closed path around its "
                    "centre",
                    out.size(), bins));
  }
  out.push_back(out.front());
  return out;
}

}  // namespace deflex
