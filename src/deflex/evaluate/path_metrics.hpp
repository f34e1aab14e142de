// Distances between measured paths: the paper's mean deformation (mean distance of a loaded path's
// points from the unloaded path) and its companions (max, RMS, standard deviation).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "deflex/model/tracker_trace.hpp"

namespace deflex {

/// Nearest point on a reference path made of one or more polylines (each trace is one polyline: the
/// last sample of one trace is not joined to the first of the next). Built once, then queried many
/// times: a bounding-box hierarchy over the segments skips every part of the path farther than the
/// best point found so far, so a query costs about O(log n) for the dense paths a tracker records.
/// The answer is exact (the same as a brute-force search over all segments).
/// Thread safety: immutable once built: nearest() from any number of threads.
class PolylineIndex {
 public:
  /// Throws InputError when there is no sample at all or a position is not finite.
  explicit PolylineIndex(const TrackerTrace& reference);
  explicit PolylineIndex(const std::vector<TrackerTrace>& pieces);
  ~PolylineIndex();
  PolylineIndex(PolylineIndex&&) noexcept;
  PolylineIndex& operator=(PolylineIndex&&) noexcept;
  PolylineIndex(const PolylineIndex&) = delete;
  PolylineIndex& operator=(const PolylineIndex&) = delete;

  struct Nearest {
    double distance_m = 0.0;
    Vector3 point_m = Vector3::Zero();  ///< nearest point on the path
    std::size_t segment = 0;            ///< index of the nearest segment's first vertex (all pieces concatenated)
    double fraction = 0.0;              ///< 0..1 along that segment
  };
  [[nodiscard]] Nearest nearest(const Vector3& p_m) const;
  /// The same, seeded with the answer for a nearby point (the previous tracker sample): same result,
  /// found faster. A NaN distance when p_m is not finite.
  [[nodiscard]] Nearest nearest(const Vector3& p_m, const Nearest* hint) const;
  /// Vertices of all pieces, concatenated in order.
  [[nodiscard]] const std::vector<Vector3>& vertices() const;

  /// The nearest points of a sequence of nearby points (a tracker trace, sample by sample): the
  /// same distances as nearest(), most found from three segments. Each full query leaves an anchor:
  /// the point, its segment with the two beside it, and a lower bound on the distance from the point
  /// to every other segment; a later point within that bound of the anchor (less its nearest distance
  /// among the three) cannot be nearer to any other segment. One per thread; the index must outlive it.
  class Follower {
   public:
    explicit Follower(const PolylineIndex& index) : index_(&index) {}
    [[nodiscard]] Nearest next(const Vector3& p_m);

   private:
    bool from_anchor(const Vector3& p_m);
    void anchor(const Vector3& p_m, std::uint32_t place, double distance_m);
    static constexpr std::uint32_t kSpan = 2;  ///< places checked either side of the anchor's
    const PolylineIndex* index_;
    Nearest last_;
    bool has_last_ = false;
    Vector3 anchor_m_ = Vector3::Zero();
    double clearance_m_ = 0.0;                  ///< lower bound on the anchor's distance to the other segments; 0: none
    std::uint32_t first_ = 0, last_place_ = 0;  ///< the anchor's segments, as places along the path
  };

 private:
  void init(const std::vector<const TrackerTrace*>& pieces);
  struct Impl;
  Impl* impl_;
};

/// The paper's figure of merit: the mean, over all points of `loaded`, of the distance to the
/// nearest point of the `reference` polyline (m). Throws InputError on an empty trace.
double mean_distance_to_path_m(const TrackerTrace& loaded, const TrackerTrace& reference);

struct PathDeviationStats {
  double mean_m = 0.0;  ///< the paper's mean deformation
  double max_m = 0.0;
  double rms_m = 0.0;
  double std_m = 0.0;  ///< sample standard deviation of the distances
  std::size_t samples = 0;
};
PathDeviationStats path_deviation(const TrackerTrace& loaded, const TrackerTrace& reference);
/// Several loaded laps against a reference made of several laps (each its own polyline).
PathDeviationStats path_deviation(const std::vector<TrackerTrace>& loaded, const std::vector<TrackerTrace>& reference);
/// Against a reference indexed once (a study compares many runs with one unloaded reference).
PathDeviationStats path_deviation(const TrackerTrace& loaded, const PolylineIndex& reference);

/// The time-synchronous (along-path) error: the mean distance between the loaded and the reference
/// positions at the same time (both traces stamped from the same start of motion; each loaded sample
/// against the reference interpolated linearly at its time). Unlike the nearest-point distance it
/// sees lag along the path. Samples outside the reference's time span are left out; throws
/// InputError when no sample overlaps.
PathDeviationStats time_synchronous_deviation(const TrackerTrace& loaded, const TrackerTrace& reference);

/// Compensation achieved: 1 - C/UC (0.67 means 67% of the uncompensated deviation removed). NaN when
/// UC is not a positive finite number (compensation is then undefined; tables print "n/a").
double compensation_ratio(double uc, double c);

}  // namespace deflex
