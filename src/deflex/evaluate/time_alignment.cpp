// Time alignment of a tracker trace with a commanded trajectory (see time_alignment.hpp).
#include "deflex/evaluate/time_alignment.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

// The commanded path as a function of time: linear between its samples, with a cursor that walks
// forward (the queries of one pass come in increasing time).
class Commanded {
 public:
  explicit Commanded(const TrackerTrace& c) : c_(c) {}
  [[nodiscard]] double start() const { return c_.front().t_s; }
  [[nodiscard]] double end() const { return c_.back().t_s; }
  void reset() { fresh_ = true; }
  // Position and velocity at t (inside the span).
  void at(double t, Vector3& p, Vector3& v) {
    if (fresh_ || k_ + 1 >= c_.size() || c_[k_].t_s > t) {  // a new pass starts with a binary search
      fresh_ = false;
      k_ = static_cast<std::size_t>(
          std::upper_bound(c_.begin(), c_.end(), t, [](double x, const TrackerSample& s) { return x < s.t_s; }) -
          c_.begin());
      k_ = k_ == 0 ? 0 : k_ - 1;
    }
    while (k_ + 2 < c_.size() && c_[k_ + 1].t_s <= t) ++k_;
    const auto& a = c_[std::min(k_, c_.size() - 2)];
    const auto& b = c_[std::min(k_, c_.size() - 2) + 1];
    const double dt = b.t_s - a.t_s;
    v = (b.p_m - a.p_m) / dt;
    p = a.p_m + v * (t - a.t_s);
  }

 private:
  const TrackerTrace& c_;
  std::size_t k_ = 0;
  bool fresh_ = true;
};

struct Model {
  double offset = 0.0, drift = 0.0, t_ref = 0.0;
  [[nodiscard]] double map(double t) const { return t + offset + drift * (t - t_ref); }
};

// Mean squared distance over the samples (indices) that fall inside the commanded span; +inf when fewer
// than `min_inside` do.
double cost(const TrackerTrace& m, const std::vector<std::size_t>& idx, Commanded& c, const Model& model,
            std::size_t min_inside) {
  c.reset();
  double ss = 0.0;
  std::size_t inside = 0;
  Vector3 p, v;
  for (std::size_t i : idx) {
    const double t = model.map(m[i].t_s);
    if (t < c.start() || t > c.end()) continue;
    c.at(t, p, v);
    ss += (m[i].p_m - p).squaredNorm();
    ++inside;
  }
  return inside >= min_inside && inside > 0 ? ss / static_cast<double>(inside)
                                            : std::numeric_limits<double>::infinity();
}

// Gauss-Newton on the offset (and the drift when asked) over samples [first, last).
Model refine(const TrackerTrace& m, std::size_t first, std::size_t last, Commanded& c, Model model, bool drift) {
  Vector3 p, v;
  for (int it = 0; it < 30; ++it) {
    c.reset();
    Eigen::Matrix2d JtJ = Eigen::Matrix2d::Zero();
    Eigen::Vector2d Jtr = Eigen::Vector2d::Zero();
    for (std::size_t i = first; i < last; ++i) {
      const double t = model.map(m[i].t_s);
      if (t < c.start() || t > c.end()) continue;
      c.at(t, p, v);
      const Vector3 r = m[i].p_m - p;
      const double dtd = m[i].t_s - model.t_ref;
      JtJ(0, 0) += v.squaredNorm();
      JtJ(0, 1) += v.squaredNorm() * dtd;
      JtJ(1, 1) += v.squaredNorm() * dtd * dtd;
      Jtr[0] += v.dot(r);
      Jtr[1] += v.dot(r) * dtd;
    }
    JtJ(1, 0) = JtJ(0, 1);
    if (!(JtJ(0, 0) > 0.0)) return model;
    Eigen::Vector2d step = Eigen::Vector2d::Zero();
    if (drift && JtJ.determinant() > 1e-12 * JtJ(0, 0) * JtJ(1, 1)) {
      step = JtJ.ldlt().solve(Jtr);
    } else {
      step[0] = Jtr[0] / JtJ(0, 0);
    }
    model.offset += step[0];
    if (drift) model.drift += step[1];
    if (std::abs(step[0]) < 1e-10 && std::abs(step[1]) < 1e-13) break;
  }
  return model;
}

}  // namespace

// NOLINTNEXTLINE(readability-function-size): listed in docs/architecture.md, "Functions over 80 lines"
TimeAlignment align_time(const TrackerTrace& measured, const TrackerTrace& commanded, const TimeAlignmentOptions& o) {
  if (measured.size() < 10 || commanded.size() < 10) {
    throw InputError(fmt::format("time alignment: {} measured and {} commanded samples; at least 10 of each are needed",
                                 measured.size(), commanded.size()));
  }
  // Compared with > and <= below, where a NaN quietly widened the search to every offset.
  if (std::isnan(o.search_s)) {
    throw InputError("time alignment: search_s is not a number (0 or less searches every offset)");
  }
  if (!std::isfinite(o.centre_s)) {
    throw InputError(fmt::format("time alignment: centre_s must be finite (got {})", o.centre_s));
  }
  for (const auto* trace : {&measured, &commanded}) {
    for (std::size_t i = 0; i < trace->size(); ++i) {
      if (!std::isfinite((*trace)[i].t_s) || !(*trace)[i].p_m.allFinite() ||
          (i > 0 && !((*trace)[i].t_s > (*trace)[i - 1].t_s))) {
        throw InputError(
            fmt::format("time alignment: the {} trace's sample {} is not finite or not later than the one "
                        "before",
                        trace == &measured ? "measured" : "commanded", i + 1));
      }
    }
  }
  Commanded c(commanded);
  double moving = 0.0;
  for (std::size_t i = 1; i < commanded.size(); ++i)
    moving = std::max(moving, (commanded[i].p_m - commanded[i - 1].p_m).norm());
  if (!(moving > 1e-9))
    throw InputError("time alignment: the commanded path never moves, so it has no timing to match");

  const double tm0 = measured.front().t_s, tm1 = measured.back().t_s;
  const double need = 0.5 * std::min(tm1 - tm0, c.end() - c.start());
  double lo = c.start() - tm1 + need, hi = c.end() - tm0 - need;
  if (o.search_s > 0.0) {
    lo = std::max(lo, o.centre_s - o.search_s);
    hi = std::min(hi, o.centre_s + o.search_s);
  }
  if (!(hi >= lo)) {
    throw InputError(
        fmt::format("time alignment: no offset in the searched range puts half of the measured run "
                    "({:.3f} s) inside the commanded one ({:.3f} s)",
                    tm1 - tm0, c.end() - c.start()));
  }
  // Coarse: a subsample of the run against every offset on a grid fine against the run's sampling.
  std::vector<std::size_t> coarse_idx;
  const std::size_t coarse_n = std::min<std::size_t>(400, measured.size());
  for (std::size_t k = 0; k < coarse_n; ++k)
    coarse_idx.push_back(k * (measured.size() - 1) / std::max<std::size_t>(1, coarse_n - 1));
  const double dt_m = (tm1 - tm0) / static_cast<double>(measured.size() - 1);
  const double step = std::max((hi - lo) / 20000.0, std::min(dt_m, (hi - lo) / 10.0));
  Model best;
  best.t_ref = 0.5 * (tm0 + tm1);
  double best_cost = std::numeric_limits<double>::infinity();
  const std::size_t min_inside = coarse_n / 2;
  for (double tau = lo; tau <= hi + 0.5 * step; tau += step) {
    Model m{tau, 0.0, best.t_ref};
    const double f = cost(measured, coarse_idx, c, m, min_inside);
    if (f < best_cost) {
      best_cost = f;
      best.offset = tau;
    }
  }
  if (!std::isfinite(best_cost)) throw InputError("time alignment: no offset put enough samples inside the command");
  // Golden section within one grid step either side, with every sample.
  std::vector<std::size_t> all(measured.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
  const std::size_t min_all = measured.size() / 4;
  double a = best.offset - step, b = best.offset + step;
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  for (int it = 0; it < 40 && b - a > 1e-7; ++it) {
    const double x1 = b - g * (b - a), x2 = a + g * (b - a);
    if (cost(measured, all, c, {x1, 0.0, best.t_ref}, min_all) <
        cost(measured, all, c, {x2, 0.0, best.t_ref}, min_all)) {
      b = x2;
    } else {
      a = x1;
    }
  }
  best.offset = 0.5 * (a + b);
  best = refine(measured, 0, measured.size(), c, best, o.fit_drift);

  TimeAlignment out;
  out.offset_s = best.offset;
  out.drift = best.drift;
  out.reference_t_s = best.t_ref;
  // The uncertainty from the spread of the offsets the run's blocks give on their own: the residuals
  // (deflection, servo error) are correlated along the path, so a formula for white noise would claim
  // far too much.
  const int blocks = std::max(2, o.blocks);
  std::vector<double> taus;
  for (int k = 0; k < blocks; ++k) {
    const std::size_t first = measured.size() * static_cast<std::size_t>(k) / static_cast<std::size_t>(blocks);
    const std::size_t last = measured.size() * static_cast<std::size_t>(k + 1) / static_cast<std::size_t>(blocks);
    // Only blocks that move enough to carry timing.
    c.reset();
    double moving_time = 0.0;
    Vector3 p, v;
    for (std::size_t i = first; i < last; ++i) {
      const double t = best.map(measured[i].t_s);
      if (t < c.start() || t > c.end()) continue;
      c.at(t, p, v);
      if (v.norm() > 1e-4) moving_time += 1.0;
    }
    if (moving_time < 0.5 * static_cast<double>(last - first)) continue;
    const Model mk = refine(measured, first, last, c, best, false);
    taus.push_back(mk.offset);
  }
  if (taus.size() >= 2) {
    double mean = 0.0;
    for (double t : taus) mean += t;
    mean /= static_cast<double>(taus.size());
    double var = 0.0;
    for (double t : taus) var += (t - mean) * (t - mean);
    var /= static_cast<double>(taus.size() - 1);
    out.offset_std_s = std::sqrt(var / static_cast<double>(taus.size()));
  } else {
    out.offset_std_s = kNaN;
  }
  c.reset();
  double ss = 0.0;
  std::size_t inside = 0, moving_n = 0;
  Vector3 p, v;
  for (const auto& s : measured) {
    const double t = best.map(s.t_s);
    if (t < c.start() || t > c.end()) continue;
    c.at(t, p, v);
    ss += (s.p_m - p).squaredNorm();
    ++inside;
    if (v.norm() > 1e-4) ++moving_n;
  }
  out.samples = inside;
  out.rms_m = inside > 0 ? std::sqrt(ss / static_cast<double>(inside)) : kNaN;
  out.moving_fraction = inside > 0 ? static_cast<double>(moving_n) / static_cast<double>(inside) : 0.0;
  return out;
}

TrackerTrace to_program_time(const TrackerTrace& measured, const TimeAlignment& alignment) {
  for (const auto& [name, value] : {std::pair{"offset_s", alignment.offset_s}, std::pair{"drift", alignment.drift},
                                    std::pair{"reference_t_s", alignment.reference_t_s}}) {
    if (!std::isfinite(value)) {
      throw InputError(fmt::format("time alignment: {} is not a finite number", name));
    }
  }
  TrackerTrace out = measured;
  for (auto& s : out) s.t_s = alignment.program_time(s.t_s);
  return out;
}

}  // namespace deflex
