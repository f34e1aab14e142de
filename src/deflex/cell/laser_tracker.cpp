// The simulated laser tracker (see laser_tracker.hpp).
#include "deflex/cell/laser_tracker.hpp"

namespace deflex::cell {

LaserTracker::LaserTracker(const TrackerConfig& config, std::uint64_t seed, double first_sample_s, double last_sample_s,
                           double time_origin_s)
    : config_(config),
      rng_(seed),
      next_s_(first_sample_s),
      last_s_(last_sample_s),
      origin_s_(time_origin_s),
      period_s_(1.0 / config.rate_hz) {
  trigger_s_ = config.trigger_jitter_s * normal_(rng_);
  rate_ = 1.0 + config.clock_rate_error * normal_(rng_);
  if (config.fast_noise) rng_.reseed(seed ^ kFastNoiseSalt, true);
  period_s_ /= rate_;  // it samples at its own clock's rate
}

void LaserTracker::observe(double t0_s, const Vector3& p0_m, double t1_s, const Vector3& p1_m, TrackerTrace& out) {
  for (; next_s_ <= t1_s + 1e-12 && next_s_ <= last_s_ + 1e-12; next_s_ += period_s_) {
    const double f = t1_s > t0_s ? (next_s_ - t0_s) / (t1_s - t0_s) : 1.0;
    const Vector3 p = p0_m + (p1_m - p0_m) * f;
    TrackerSample s;
    s.t_s = (next_s_ - origin_s_ - trigger_s_) * rate_;
    s.p_m = p + config_.noise_m * Vector3(normal_(rng_), normal_(rng_), normal_(rng_));
    out.push_back(s);
  }
}

}  // namespace deflex::cell
