// Distances of measured points from a reference path, by an exact nearest-segment search.
#include "deflex/evaluate/path_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>

#include <fmt/format.h>

#include "deflex/model/errors.hpp"

namespace deflex {
namespace {

constexpr std::size_t kLeafSize = 8;

// Closest point of segment [a, b] to p, as the fraction along it.
double segment_fraction(const Vector3& a, const Vector3& b, const Vector3& p) {
  const Vector3 ab = b - a;
  const double len2 = ab.squaredNorm();
  if (len2 <= 0.0) {
    return 0.0;
  }
  return std::clamp((p - a).dot(ab) / len2, 0.0, 1.0);
}

}  // namespace

// The search rests on one bound: if the nearest point c of the path lies on a segment s, the
// endpoint of s nearer to c is within |s|/2 of c, so within d* + |s|/2 of the query, where
// d* <= d_v, the distance to the nearest vertex. A radius search of d_v + max|s|/2 around the query
// therefore finds an endpoint of the right segment. Rare long segments (tracker drop-outs, sparse
// commanded paths mixed with dense ones) would inflate max|s| for every query, so they are kept
// apart and checked one by one.
struct PolylineIndex::Impl {
  std::vector<Vector3> vertices;
  std::vector<std::uint8_t> segment_valid;  // segment i joins vertex i and i+1 (same piece)
  std::vector<std::size_t> long_segments;
  double half_max_short_length = 0.0;
  // k-d tree: points in tree order, their vertex indices, the split dimension at each median.
  std::vector<Vector3> tree_points;
  std::vector<std::uint32_t> tree_index;
  std::vector<std::uint8_t> split_dim;

  void build(std::size_t lo, std::size_t hi) {
    if (hi - lo <= kLeafSize) {
      return;
    }
    Vector3 lo_c = tree_points[lo];
    Vector3 hi_c = tree_points[lo];
    for (std::size_t i = lo; i < hi; ++i) {
      lo_c = lo_c.cwiseMin(tree_points[i]);
      hi_c = hi_c.cwiseMax(tree_points[i]);
    }
    int dim = 0;
    (hi_c - lo_c).maxCoeff(&dim);
    const std::size_t mid = lo + (hi - lo) / 2;
    // Sort an index range, then apply it, so points and indices stay together.
    std::vector<std::uint32_t> order(hi - lo);
    std::iota(order.begin(), order.end(), 0u);
    std::nth_element(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(mid - lo), order.end(),
                     [&](std::uint32_t a, std::uint32_t b) {
                       return tree_points[lo + a][dim] < tree_points[lo + b][dim];
                     });
    std::vector<Vector3> pts(hi - lo);
    std::vector<std::uint32_t> idx(hi - lo);
    for (std::size_t i = 0; i < order.size(); ++i) {
      pts[i] = tree_points[lo + order[i]];
      idx[i] = tree_index[lo + order[i]];
    }
    std::copy(pts.begin(), pts.end(), tree_points.begin() + static_cast<std::ptrdiff_t>(lo));
    std::copy(idx.begin(), idx.end(), tree_index.begin() + static_cast<std::ptrdiff_t>(lo));
    split_dim[mid] = static_cast<std::uint8_t>(dim);
    build(lo, mid);
    build(mid + 1, hi);
  }

  void nearest_vertex(std::size_t lo, std::size_t hi, const Vector3& q, double& best2) const {
    if (hi - lo <= kLeafSize) {
      for (std::size_t i = lo; i < hi; ++i) {
        best2 = std::min(best2, (tree_points[i] - q).squaredNorm());
      }
      return;
    }
    const std::size_t mid = lo + (hi - lo) / 2;
    best2 = std::min(best2, (tree_points[mid] - q).squaredNorm());
    const double diff = q[split_dim[mid]] - tree_points[mid][split_dim[mid]];
    if (diff < 0.0) {
      nearest_vertex(lo, mid, q, best2);
      if (diff * diff < best2) {
        nearest_vertex(mid + 1, hi, q, best2);
      }
    } else {
      nearest_vertex(mid + 1, hi, q, best2);
      if (diff * diff < best2) {
        nearest_vertex(lo, mid, q, best2);
      }
    }
  }

  void consider_segment(std::size_t s, const Vector3& q, Nearest& best, double& best2) const {
    const Vector3& a = vertices[s];
    const Vector3& b = vertices[s + 1];
    const double f = segment_fraction(a, b, q);
    const Vector3 c = a + f * (b - a);
    const double d2 = (c - q).squaredNorm();
    if (d2 < best2) {
      best2 = d2;
      best.point_m = c;
      best.segment = s;
      best.fraction = f;
    }
  }

  void consider_vertex(std::size_t v, const Vector3& q, Nearest& best, double& best2) const {
    if (v > 0 && segment_valid[v - 1] != 0) {
      consider_segment(v - 1, q, best, best2);
    }
    if (v + 1 < vertices.size() && segment_valid[v] != 0) {
      consider_segment(v, q, best, best2);
    }
    const double d2 = (vertices[v] - q).squaredNorm();
    if (d2 < best2) {  // an isolated vertex (a piece of one sample)
      best2 = d2;
      best.point_m = vertices[v];
      best.segment = v;
      best.fraction = 0.0;
    }
  }

  void radius_search(std::size_t lo, std::size_t hi, const Vector3& q, double r2, Nearest& best,
                     double& best2) const {
    if (hi - lo <= kLeafSize) {
      for (std::size_t i = lo; i < hi; ++i) {
        if ((tree_points[i] - q).squaredNorm() <= r2) {
          consider_vertex(tree_index[i], q, best, best2);
        }
      }
      return;
    }
    const std::size_t mid = lo + (hi - lo) / 2;
    if ((tree_points[mid] - q).squaredNorm() <= r2) {
      consider_vertex(tree_index[mid], q, best, best2);
    }
    const double diff = q[split_dim[mid]] - tree_points[mid][split_dim[mid]];
    if (diff <= 0.0 || diff * diff <= r2) {
      radius_search(lo, mid, q, r2, best, best2);
    }
    if (diff >= 0.0 || diff * diff <= r2) {
      radius_search(mid + 1, hi, q, r2, best, best2);
    }
  }
};

PolylineIndex::PolylineIndex(const TrackerTrace& reference) : PolylineIndex(std::vector<TrackerTrace>{reference}) {}

PolylineIndex::PolylineIndex(const std::vector<TrackerTrace>& pieces) : impl_(new Impl) {
  Impl& m = *impl_;
  for (const auto& piece : pieces) {
    for (std::size_t i = 0; i < piece.size(); ++i) {
      if (!piece[i].p_m.allFinite()) {
        delete impl_;
        throw InputError(fmt::format("reference path: sample {} (t = {} s) has a position that is not finite", i,
                                     piece[i].t_s));
      }
      m.vertices.push_back(piece[i].p_m);
      m.segment_valid.push_back(i + 1 < piece.size() ? 1 : 0);
    }
  }
  if (m.vertices.empty()) {
    delete impl_;
    throw InputError("reference path: no samples");
  }
  if (m.vertices.size() > std::numeric_limits<std::uint32_t>::max()) {
    delete impl_;
    throw InputError("reference path: too many samples");
  }
  // Segments longer than 4x the 90th percentile of lengths are "long" (see the bound above).
  std::vector<double> lengths;
  for (std::size_t s = 0; s + 1 < m.vertices.size(); ++s) {
    if (m.segment_valid[s] != 0) {
      lengths.push_back((m.vertices[s + 1] - m.vertices[s]).norm());
    }
  }
  double threshold = 0.0;
  if (!lengths.empty()) {
    std::vector<double> sorted = lengths;
    const auto k = static_cast<std::ptrdiff_t>(static_cast<double>(sorted.size() - 1) * 0.9);
    std::nth_element(sorted.begin(), sorted.begin() + k, sorted.end());
    threshold = 4.0 * sorted[static_cast<std::size_t>(k)];
  }
  for (std::size_t s = 0; s + 1 < m.vertices.size(); ++s) {
    if (m.segment_valid[s] == 0) {
      continue;
    }
    const double len = (m.vertices[s + 1] - m.vertices[s]).norm();
    if (len > threshold) {
      m.long_segments.push_back(s);
    } else {
      m.half_max_short_length = std::max(m.half_max_short_length, 0.5 * len);
    }
  }
  m.tree_points = m.vertices;
  m.tree_index.resize(m.vertices.size());
  std::iota(m.tree_index.begin(), m.tree_index.end(), 0u);
  m.split_dim.assign(m.vertices.size(), 0);
  m.build(0, m.vertices.size());
}

PolylineIndex::~PolylineIndex() { delete impl_; }
PolylineIndex::PolylineIndex(PolylineIndex&& other) noexcept : impl_(other.impl_) { other.impl_ = nullptr; }
PolylineIndex& PolylineIndex::operator=(PolylineIndex&& other) noexcept {
  std::swap(impl_, other.impl_);
  return *this;
}

const std::vector<Vector3>& PolylineIndex::vertices() const { return impl_->vertices; }

PolylineIndex::Nearest PolylineIndex::nearest(const Vector3& p_m) const {
  const Impl& m = *impl_;
  Nearest best;
  double best2 = std::numeric_limits<double>::infinity();
  if (!p_m.allFinite()) {
    best.distance_m = std::numeric_limits<double>::quiet_NaN();
    return best;
  }
  double dv2 = std::numeric_limits<double>::infinity();
  m.nearest_vertex(0, m.tree_points.size(), p_m, dv2);
  // A hair more than the bound, so rounding never drops the segment that holds the answer.
  const double r = (std::sqrt(dv2) + m.half_max_short_length) * (1.0 + 1e-12) + 1e-15;
  m.radius_search(0, m.tree_points.size(), p_m, r * r, best, best2);
  for (const std::size_t s : m.long_segments) {
    m.consider_segment(s, p_m, best, best2);
  }
  best.distance_m = std::sqrt(best2);
  return best;
}

namespace {

PathDeviationStats stats_of(const std::vector<TrackerTrace>& loaded, const PolylineIndex& index) {
  PathDeviationStats st;
  double sum = 0.0;
  double sum2 = 0.0;
  std::vector<double> d;
  for (const auto& trace : loaded) {
    for (std::size_t i = 0; i < trace.size(); ++i) {
      if (!trace[i].p_m.allFinite()) {
        throw InputError(fmt::format("loaded path: sample {} (t = {} s) has a position that is not finite", i,
                                     trace[i].t_s));
      }
      const double di = index.nearest(trace[i].p_m).distance_m;
      d.push_back(di);
      sum += di;
      sum2 += di * di;
      st.max_m = std::max(st.max_m, di);
    }
  }
  if (d.empty()) {
    throw InputError("loaded path: no samples");
  }
  const auto n = static_cast<double>(d.size());
  st.samples = d.size();
  st.mean_m = sum / n;
  st.rms_m = std::sqrt(sum2 / n);
  double var = 0.0;
  for (const double di : d) {
    var += (di - st.mean_m) * (di - st.mean_m);
  }
  st.std_m = d.size() > 1 ? std::sqrt(var / (n - 1.0)) : 0.0;
  return st;
}

}  // namespace

PathDeviationStats path_deviation(const std::vector<TrackerTrace>& loaded, const std::vector<TrackerTrace>& reference) {
  const PolylineIndex index(reference);
  return stats_of(loaded, index);
}

PathDeviationStats path_deviation(const TrackerTrace& loaded, const TrackerTrace& reference) {
  return path_deviation(std::vector<TrackerTrace>{loaded}, std::vector<TrackerTrace>{reference});
}

double mean_distance_to_path_m(const TrackerTrace& loaded, const TrackerTrace& reference) {
  return path_deviation(loaded, reference).mean_m;
}

double compensation_ratio(double uc, double c) {
  if (!std::isfinite(uc) || !std::isfinite(c) || uc <= 0.0) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  return 1.0 - c / uc;
}

}  // namespace deflex
