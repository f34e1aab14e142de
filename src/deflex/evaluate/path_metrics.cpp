// Distances of measured points from a reference path, by an exact nearest-segment search.
#include "deflex/evaluate/path_metrics.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <numeric>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

constexpr std::uint32_t kLeafSize = 4;

// The largest float at most x (x a lower bound: so is the float); NaN certifies nothing.
float float_below(double x) {
  if (std::isnan(x)) return -std::numeric_limits<float>::infinity();
  if (!(x < static_cast<double>(std::numeric_limits<float>::max()))) {
    return x == std::numeric_limits<double>::infinity() ? std::numeric_limits<float>::infinity()
                                                        : std::numeric_limits<float>::max();
  }
  if (x <= -static_cast<double>(std::numeric_limits<float>::max())) return -std::numeric_limits<float>::infinity();
  float f = static_cast<float>(x);
  if (static_cast<double>(f) > x) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}

}  // namespace

// A bounding-volume hierarchy over the segments: each node holds the box around its segments, and
// a query descends nearer child first, skipping every node whose box is farther than the best
// distance found so far. Boxes bound the segments exactly, so the answer is exact, whatever the mix
// of segment lengths (dense tracker laps, sparse commanded points, drop-outs). A query seeded with
// the previous query's segment (consecutive tracker points are close) first walks along the path to
// the nearest segment there, then tries a certificate kept per segment: a lower bound C_w on the
// distance from that segment to every segment more than w places away along the path (w from 1 to
// 16). A point at d from segment k is at least C_w - d from each of those (triangle inequality),
// so when d <= C_w - d the segments within w places hold the nearest one and the tree is not
// searched at all; otherwise the search starts at the walked-to segment's leaf and climbs, its bound
// tight from the start. Either way the answer is the exact nearest segment.
struct PolylineIndex::Impl {
  struct Segment {
    std::uint32_t a, b;  // vertex indices; a == b for a piece of a single sample
  };
  struct Node {
    Vector3 lo, hi;
    std::uint32_t start = 0, end = 0;   // leaf: segments [start, end)
    std::uint32_t left = 0, right = 0;  // inner node: children (0 = none: the root is never a child)
  };
  std::vector<Vector3> vertices;
  std::vector<Segment> segments;
  std::vector<Node> nodes;
  // Per segment, in the order of `segments` (leaf by leaf): its start, its direction and its squared
  // length, so a leaf's segments are read in a row and none is rebuilt from its vertices.
  std::vector<Vector3> seg_a, seg_ab;
  std::vector<double> seg_len2;
  std::vector<std::uint32_t> parent;   // per node (the root's is itself)
  std::vector<std::uint32_t> leaf_of;  // per vertex that starts a segment: the leaf holding that segment
  static constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  // The segments in path order (pieces concatenated), for the walk and the certificate: per place
  // its index in `segments`; per vertex that starts a segment, its place; per place, the clearances
  // C_w for the windows kWindows (m, rounded down to floats: a lower bound stays one, in half the
  // memory).
  static constexpr std::array<std::uint32_t, 8> kWindows{1, 2, 3, 4, 6, 8, 11, 16};
  std::vector<std::uint32_t> path_slot, path_place;
  std::vector<std::array<float, kWindows.size()>> clearance;
  // Per place, copies of its segment's start, direction, squared length and first vertex: the walk
  // and the follower read a few neighbouring places a sample, in a row here rather than scattered
  // over the tree's order (the same doubles, so the same answers).
  std::vector<Vector3> place_a, place_ab;
  std::vector<double> place_len2;
  std::vector<std::uint32_t> place_vertex;

  // The closest point of a segment (start a, direction ab, squared length len2) to q: its fraction
  // along it and its squared distance. One expression for every search, so all agree to the bit.
  static double closest(const Vector3& a, const Vector3& ab, double len2, const Vector3& q, double& f, Vector3& c) {
    f = len2 <= 0.0 ? 0.0 : std::clamp((q - a).dot(ab) / len2, 0.0, 1.0);
    c = a + f * ab;
    return (c - q).squaredNorm();
  }
  double place_distance2(std::uint32_t k, const Vector3& q) const {
    double f;
    Vector3 c;
    return closest(place_a[k], place_ab[k], place_len2[k], q, f, c);
  }

  std::uint32_t build(std::uint32_t start, std::uint32_t end) {
    Node node;
    node.lo = node.hi = vertices[segments[start].a];
    for (std::uint32_t i = start; i < end; ++i) {
      for (const std::uint32_t v : {segments[i].a, segments[i].b}) {
        node.lo = node.lo.cwiseMin(vertices[v]);
        node.hi = node.hi.cwiseMax(vertices[v]);
      }
    }
    const auto index = static_cast<std::uint32_t>(nodes.size());
    nodes.push_back(node);
    if (end - start <= kLeafSize) {
      nodes[index].start = start;
      nodes[index].end = end;
      for (std::uint32_t i = start; i < end; ++i) leaf_of[segments[i].a] = index;
      return index;
    }
    int dim = 0;
    (node.hi - node.lo).maxCoeff(&dim);
    const std::uint32_t mid = start + (end - start) / 2;
    std::nth_element(segments.begin() + start, segments.begin() + mid, segments.begin() + end,
                     [&](const Segment& x, const Segment& y) {
                       return vertices[x.a][dim] + vertices[x.b][dim] < vertices[y.a][dim] + vertices[y.b][dim];
                     });
    const std::uint32_t left = build(start, mid);
    const std::uint32_t right = build(mid, end);
    nodes[index].left = left;
    nodes[index].right = right;
    return index;
  }

  static double box_distance2(const Node& n, const Vector3& q) {
    const Vector3 d = (n.lo - q).cwiseMax(q - n.hi).cwiseMax(0.0);
    return d.squaredNorm();
  }

  // Segment i (of `segments`) against the best so far: its closest point to q, as the fraction
  // along it (0 for a segment of one sample), from the kept start, direction and squared length.
  void consider(std::uint32_t i, const Vector3& q, Nearest& best, double& best2) const {
    double f;
    Vector3 c;
    const double d2 = closest(seg_a[i], seg_ab[i], seg_len2[i], q, f, c);
    if (d2 < best2) {
      best2 = d2;
      best.point_m = c;
      best.segment = segments[i].a;
      best.fraction = f;  // 0 for a piece of one sample: its length is 0
    }
  }

  // Starting at the leaf that holds the hint's segment: its segments first (a tight bound at once),
  // then, up to the root, each sibling's subtree wherever its box is nearer than the best so far.
  // Every segment lies in the leaf or in one of those subtrees, so the answer stays exact, and the
  // descent from the root to the leaf (twice the box tests) is saved.
  void search_from_leaf(std::uint32_t leaf, const Vector3& q, Nearest& best, double& best2) const {
    for (std::uint32_t i = nodes[leaf].start; i < nodes[leaf].end; ++i) consider(i, q, best, best2);
    for (std::uint32_t node = leaf; node != 0;) {
      const std::uint32_t up = parent[node];
      search(nodes[up].left == node ? nodes[up].right : nodes[up].left, q, best, best2);
      node = up;
    }
  }

  void search(std::uint32_t root, const Vector3& q, Nearest& best, double& best2) const {
    descend(root, q, best2, [&](std::uint32_t i) { consider(i, q, best, best2); });
  }

  // Place k of the path against the best so far.
  void consider_place(std::uint32_t k, const Vector3& q, Nearest& best, double& best2) const {
    double f;
    Vector3 c;
    const double d2 = closest(place_a[k], place_ab[k], place_len2[k], q, f, c);
    if (d2 < best2) {
      best2 = d2;
      best.point_m = c;
      best.segment = place_vertex[k];
      best.fraction = f;
    }
  }

  // From the place of the hint's segment downhill along the path while the distance falls (a few
  // steps: consecutive tracker points are close); returns the place reached and its squared distance.
  std::uint32_t walk(std::uint32_t k, const Vector3& q, double& d2) const {
    d2 = place_distance2(k, q);
    const auto n = static_cast<std::int64_t>(path_slot.size());
    int steps = 0;
    const auto go = [&](std::int64_t dir) {
      for (; steps < 64; ++steps) {
        const std::int64_t j = static_cast<std::int64_t>(k) + dir;
        if (j < 0 || j >= n) return;
        const double d2j = place_distance2(static_cast<std::uint32_t>(j), q);
        if (!(d2j < d2)) return;
        k = static_cast<std::uint32_t>(j);
        d2 = d2j;
      }
    };
    const std::uint32_t start = k;
    go(1);
    if (k == start) go(-1);
    return k;
  }

  // The nearest segment with the certificate of place k (see above); false when no window's
  // certificate holds (`best` then holds place k).
  bool certified(std::uint32_t k, double d2, const Vector3& q, Nearest& best, double& best2) const {
    const double dk = std::sqrt(d2);
    const auto n = static_cast<std::uint32_t>(path_slot.size());
    consider_place(k, q, best, best2);
    for (std::size_t w = 0; w < kWindows.size(); ++w) {
      if (2.0 * dk <= clearance[k][w]) {
        const std::uint32_t lo = k >= kWindows[w] ? k - kWindows[w] : 0;
        const std::uint32_t hi = std::min(n - 1, k + kWindows[w]);
        for (std::uint32_t j = lo; j <= hi; ++j) {
          if (j != k) consider_place(j, q, best, best2);
        }
        return true;
      }
    }
    return false;
  }

  // Paths of more segments than this search from the hint's leaf without the certificate: their
  // clearances cost a tree search each to build, and a long reference is mostly a raw trace of
  // several laps over each other, whose clearances are too small to certify anything.
  static constexpr std::size_t kMaxCertifiedSegments = 1u << 16;

  void build_path_order() {
    if (segments.size() > kMaxCertifiedSegments) return;
    // The tree's build reordered `segments`; their first vertices give back the path's order.
    path_place.assign(vertices.size(), kNone);
    std::vector<std::uint32_t> slot_of(vertices.size(), kNone);
    for (std::uint32_t i = 0; i < segments.size(); ++i) slot_of[segments[i].a] = i;
    for (std::uint32_t v = 0; v < vertices.size(); ++v) {
      const std::uint32_t i = slot_of[v];
      if (i == kNone) continue;
      path_place[v] = static_cast<std::uint32_t>(path_slot.size());
      path_slot.push_back(i);
      place_a.push_back(seg_a[i]);
      place_ab.push_back(seg_ab[i]);
      place_len2.push_back(seg_len2[i]);
      place_vertex.push_back(segments[i].a);
    }
    build_clearances();
  }

  // C_w of every place: the distance from the segment's midpoint to every segment more than w places
  // away (the nearer ones one by one, those beyond the largest window by the tree, bounded by the
  // first of them), less half the segment's length (a point of the segment is at most that from its
  // midpoint) and a picometre for rounding.
  void build_clearances() {
    const auto n = static_cast<std::int64_t>(path_slot.size());
    constexpr std::int64_t kFar = kWindows.back();
    clearance.resize(path_slot.size());
    for (std::int64_t k = 0; k < n; ++k) {
      const auto uk = static_cast<std::size_t>(k);
      const std::uint32_t slot = path_slot[uk];
      const Vector3 mid = seg_a[slot] + 0.5 * seg_ab[slot];
      const double half = 0.5 * std::sqrt(seg_len2[slot]);
      const auto d2_at = [&](std::int64_t j) {
        return j < 0 || j >= n ? std::numeric_limits<double>::infinity()
                               : place_distance2(static_cast<std::uint32_t>(j), mid);
      };
      double far2 = std::min(d2_at(k - kFar - 1), d2_at(k + kFar + 1));
      descend(0, mid, far2, [&](std::uint32_t i) {
        const std::int64_t place = path_place[segments[i].a];
        if (std::abs(place - k) <= kFar) return;
        far2 = std::min(far2, closest_d2(i, mid));
      });
      double s2 = far2;
      std::size_t w = kWindows.size();
      for (std::int64_t m = kFar; m >= 1; --m) {
        if (w > 0 && kWindows[w - 1] == m) {
          clearance[uk][--w] = float_below(std::sqrt(s2) - half - 1e-12);
        }
        s2 = std::min({s2, d2_at(k - m), d2_at(k + m)});
      }
    }
  }

  // A lower bound on the distance from q to every segment more than `span` places from place k
  // (d_k: q's distance to place k): the rings of places span + 1, span + 2, ... away one by one, the
  // rest by the clearance of a window (C_w - d_k, as in certified()), the ring widened while the
  // clearance bounds less than the nearest ring. 0 when nothing is bounded (a long path keeps no
  // clearances).
  double ring_clearance(std::uint32_t k, std::uint32_t span, const Vector3& q, double dk) const {
    if (clearance.empty()) return 0.0;
    const auto n = static_cast<std::int64_t>(path_slot.size());
    double ring = std::numeric_limits<double>::infinity();
    double bound = 0.0;
    for (std::size_t w = 0; w < kWindows.size(); ++w) {
      if (kWindows[w] < span) continue;
      const std::int64_t from = w == 0 || kWindows[w - 1] < span ? span + 1 : kWindows[w - 1] + 1;
      for (std::int64_t m = from; m <= kWindows[w]; ++m) {
        for (const std::int64_t j : {static_cast<std::int64_t>(k) - m, static_cast<std::int64_t>(k) + m}) {
          if (j >= 0 && j < n) ring = std::min(ring, std::sqrt(place_distance2(static_cast<std::uint32_t>(j), q)));
        }
      }
      const double beyond = static_cast<double>(clearance[k][w]) - dk;
      bound = std::max(bound, std::min(ring, beyond));
      if (beyond >= ring) break;  // the ring, which only shrinks, bounds it from here on
    }
    return bound;
  }

  double closest_d2(std::uint32_t i, const Vector3& q) const {
    double f;
    Vector3 c;
    return closest(seg_a[i], seg_ab[i], seg_len2[i], q, f, c);
  }

  // The tree from `root`, nearer child first, every node nearer than best2 opened: `visit(i)` for each
  // segment of its leaves (it may lower best2).
  template <class Visit>
  void descend(std::uint32_t root, const Vector3& q, const double& best2, Visit visit) const {
    std::uint32_t stack[128];
    int top = 0;
    stack[top++] = root;
    while (top > 0) {
      const Node& n = nodes[stack[--top]];
      if (box_distance2(n, q) >= best2) {
        continue;
      }
      if (n.left == 0) {
        for (std::uint32_t i = n.start; i < n.end; ++i) {
          visit(i);
        }
        continue;
      }
      const double dl = box_distance2(nodes[n.left], q);
      const double dr = box_distance2(nodes[n.right], q);
      // Push the farther child first so the nearer one is searched first.
      if (dl < dr) {
        if (dr < best2) stack[top++] = n.right;
        if (dl < best2) stack[top++] = n.left;
      } else {
        if (dl < best2) stack[top++] = n.left;
        if (dr < best2) stack[top++] = n.right;
      }
    }
  }
};

PolylineIndex::PolylineIndex(const TrackerTrace& reference) : impl_(nullptr) { init({&reference}); }

PolylineIndex::PolylineIndex(const std::vector<TrackerTrace>& pieces) : impl_(nullptr) {
  std::vector<const TrackerTrace*> p;
  for (const auto& piece : pieces) {
    p.push_back(&piece);
  }
  init(p);
}

void PolylineIndex::init(const std::vector<const TrackerTrace*>& piece_ptrs) {
  auto owner = std::make_unique<Impl>();  // freed if a check below throws
  Impl& m = *owner;
  std::size_t total = 0;
  for (const auto* piece : piece_ptrs) {
    total += piece->size();
  }
  if (total == 0) {
    throw InputError("reference path: no samples");
  }
  if (total >= std::numeric_limits<std::uint32_t>::max() / 2) {
    throw InputError("reference path: too many samples");
  }
  m.vertices.reserve(total);
  for (const auto* piece_ptr : piece_ptrs) {
    const TrackerTrace& piece = *piece_ptr;
    const auto first = static_cast<std::uint32_t>(m.vertices.size());
    for (std::size_t i = 0; i < piece.size(); ++i) {
      if (!piece[i].p_m.allFinite()) {
        throw InputError(
            fmt::format("reference path: sample {} (t = {} s) has a position that is not finite", i, piece[i].t_s));
      }
      m.vertices.push_back(piece[i].p_m);
    }
    if (piece.size() == 1) {
      m.segments.push_back({first, first});
    }
    for (std::uint32_t i = 0; i + 1 < piece.size(); ++i) {
      m.segments.push_back({first + i, first + i + 1});
    }
  }
  m.nodes.reserve(m.segments.size() + 1);  // a balanced tree with leaves of 2-4 segments has fewer nodes
  m.leaf_of.assign(m.vertices.size(), Impl::kNone);
  m.build(0, static_cast<std::uint32_t>(m.segments.size()));
  m.parent.assign(m.nodes.size(), 0);
  for (std::uint32_t i = 0; i < m.nodes.size(); ++i) {
    if (m.nodes[i].left != 0) {
      m.parent[m.nodes[i].left] = i;
      m.parent[m.nodes[i].right] = i;
    }
  }
  m.seg_a.reserve(m.segments.size());
  m.seg_ab.reserve(m.segments.size());
  m.seg_len2.reserve(m.segments.size());
  for (const auto& sg : m.segments) {
    m.seg_a.push_back(m.vertices[sg.a]);
    m.seg_ab.push_back(m.vertices[sg.b] - m.vertices[sg.a]);
    m.seg_len2.push_back(m.seg_ab.back().squaredNorm());
  }
  m.build_path_order();
  impl_ = owner.release();
}

PolylineIndex::~PolylineIndex() { delete impl_; }
PolylineIndex::PolylineIndex(PolylineIndex&& other) noexcept : impl_(other.impl_) { other.impl_ = nullptr; }
PolylineIndex& PolylineIndex::operator=(PolylineIndex&& other) noexcept {
  std::swap(impl_, other.impl_);
  return *this;
}

const std::vector<Vector3>& PolylineIndex::vertices() const { return impl_->vertices; }

PolylineIndex::Nearest PolylineIndex::nearest(const Vector3& p_m) const { return nearest(p_m, nullptr); }

PolylineIndex::Nearest PolylineIndex::nearest(const Vector3& p_m, const Nearest* hint) const {
  const Impl& m = *impl_;
  Nearest best;
  double best2 = std::numeric_limits<double>::infinity();
  if (!p_m.allFinite()) {
    best.distance_m = std::numeric_limits<double>::quiet_NaN();
    return best;
  }
  if (hint != nullptr && hint->segment < m.path_place.size() && m.path_place[hint->segment] != Impl::kNone) {
    double d2 = 0.0;
    const std::uint32_t k = m.walk(m.path_place[hint->segment], p_m, d2);
    if (!m.certified(k, d2, p_m, best, best2)) {
      m.search_from_leaf(m.leaf_of[m.segments[m.path_slot[k]].a], p_m, best, best2);
    }
  } else if (hint != nullptr && hint->segment < m.leaf_of.size() && m.leaf_of[hint->segment] != Impl::kNone) {
    m.search_from_leaf(m.leaf_of[hint->segment], p_m, best, best2);
  } else {
    m.search(0, p_m, best, best2);
  }
  best.distance_m = std::sqrt(best2);
  return best;
}

PolylineIndex::Nearest PolylineIndex::Follower::next(const Vector3& p_m) {
  if (!p_m.allFinite()) return index_->nearest(p_m);  // NaN; the anchor and the last answer still hold
  if (clearance_m_ > 0.0 && from_anchor(p_m)) return last_;
  const Impl& m = *index_->impl_;
  if (has_last_ && !m.path_place.empty()) {
    // Anchored again at p, around the place the walk from the last answer reaches: at a sample a
    // segment or more from the last, this usually proves the answer without a search.
    double d2 = 0.0;
    const std::uint32_t k = m.walk(m.path_place[last_.segment], p_m, d2);
    anchor(p_m, k, std::sqrt(d2));
    if (clearance_m_ > 0.0 && from_anchor(p_m)) return last_;
  }
  last_ = index_->nearest(p_m, has_last_ ? &last_ : nullptr);
  has_last_ = true;
  clearance_m_ = 0.0;
  if (!m.path_place.empty()) anchor(p_m, m.path_place[last_.segment], last_.distance_m);
  return last_;
}

bool PolylineIndex::Follower::from_anchor(const Vector3& p_m) {
  // Every other segment is at least clearance_m_ - |p - anchor| from p (triangle inequality); the
  // margin covers the rounding of the distances, as the picometre of the clearances does.
  const double margin = 1e-12 + 1e-14 * p_m.cwiseAbs().maxCoeff();
  const double reach = clearance_m_ - (p_m - anchor_m_).norm() - margin;
  if (!(reach > 0.0)) return false;
  const Impl& m = *index_->impl_;
  Nearest best;
  double best2 = std::numeric_limits<double>::infinity();
  for (std::uint32_t k = first_; k <= last_place_; ++k) m.consider_place(k, p_m, best, best2);
  if (!(best2 <= reach * reach)) return false;
  best.distance_m = std::sqrt(best2);
  last_ = best;
  has_last_ = true;
  return true;
}

void PolylineIndex::Follower::anchor(const Vector3& p_m, std::uint32_t k, double dk) {
  const Impl& m = *index_->impl_;
  const auto n = static_cast<std::uint32_t>(m.path_slot.size());
  first_ = k > kSpan ? k - kSpan : 0;
  last_place_ = std::min(n - 1, k + kSpan);
  anchor_m_ = p_m;
  clearance_m_ = m.ring_clearance(k, kSpan, p_m, dk);
}

namespace {

// Mean, max, RMS and sample standard deviation of a set of distances (m).
PathDeviationStats stats_of_distances(const std::vector<double>& d) {
  PathDeviationStats st;
  const auto n = static_cast<double>(d.size());
  double sum = 0.0, sum2 = 0.0;
  for (const double di : d) {
    sum += di;
    sum2 += di * di;
    st.max_m = std::max(st.max_m, di);
  }
  st.samples = d.size();
  st.mean_m = sum / n;
  st.rms_m = std::sqrt(sum2 / n);
  double var = 0.0;
  for (const double di : d) var += (di - st.mean_m) * (di - st.mean_m);
  st.std_m = d.size() > 1 ? std::sqrt(var / (n - 1.0)) : 0.0;
  return st;
}

PathDeviationStats stats_of(const std::vector<const TrackerTrace*>& loaded, const PolylineIndex& index) {
  std::vector<double> d;
  std::size_t total = 0;
  for (const auto* trace_ptr : loaded) total += trace_ptr->size();
  d.reserve(total);
  PolylineIndex::Follower follower(index);
  for (const auto* trace_ptr : loaded) {
    const TrackerTrace& trace = *trace_ptr;
    for (std::size_t i = 0; i < trace.size(); ++i) {
      if (!trace[i].p_m.allFinite()) {
        throw InputError(
            fmt::format("loaded path: sample {} (t = {} s) has a position that is not finite", i, trace[i].t_s));
      }
      d.push_back(follower.next(trace[i].p_m).distance_m);
    }
  }
  if (d.empty()) {
    throw InputError("loaded path: no samples");
  }
  return stats_of_distances(d);
}

}  // namespace

PathDeviationStats path_deviation(const std::vector<TrackerTrace>& loaded, const std::vector<TrackerTrace>& reference) {
  const PolylineIndex index(reference);
  std::vector<const TrackerTrace*> runs;
  for (const auto& t : loaded) {
    runs.push_back(&t);
  }
  return stats_of(runs, index);
}

PathDeviationStats path_deviation(const TrackerTrace& loaded, const TrackerTrace& reference) {
  const PolylineIndex index(reference);
  return stats_of({&loaded}, index);
}

PathDeviationStats path_deviation(const TrackerTrace& loaded, const PolylineIndex& reference) {
  return stats_of({&loaded}, reference);
}

PathDeviationStats time_synchronous_deviation(const TrackerTrace& loaded, const TrackerTrace& reference) {
  if (reference.size() < 2) {
    throw InputError("time-synchronous deviation: the reference has fewer than 2 samples");
  }
  std::size_t j = 0;
  std::vector<double> d;
  d.reserve(loaded.size());
  for (const auto& s : loaded) {
    if (s.t_s < reference.front().t_s || s.t_s > reference.back().t_s) continue;
    while (j + 2 < reference.size() && reference[j + 1].t_s < s.t_s) ++j;
    while (j > 0 && reference[j].t_s > s.t_s) --j;
    const TrackerSample& a = reference[j];
    const TrackerSample& b = reference[j + 1];
    const double u = b.t_s > a.t_s ? std::clamp((s.t_s - a.t_s) / (b.t_s - a.t_s), 0.0, 1.0) : 0.0;
    const double di = (s.p_m - (a.p_m + u * (b.p_m - a.p_m))).norm();
    if (!std::isfinite(di)) {
      throw InputError(fmt::format("time-synchronous deviation: the sample at t = {} s is not finite", s.t_s));
    }
    d.push_back(di);
  }
  if (d.empty()) {
    throw InputError("time-synchronous deviation: no loaded sample lies in the reference's time span");
  }
  return stats_of_distances(d);
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
