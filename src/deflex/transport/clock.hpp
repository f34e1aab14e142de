// Time for the controller links: a link never reads the wall clock itself but asks a Clock, so the
// same link code runs in real time on a cell (SteadyClock) and in a deterministic, faster-than-real-
// time simulation (ManualClock, advanced by the simulation).
#pragma once

#include <chrono>

namespace deflex {

/// Seconds since some fixed start, monotonic. Reading it never allocates, locks or throws.
class Clock {
 public:
  virtual ~Clock() = default;
  [[nodiscard]] virtual double now_s() const noexcept = 0;

 protected:
  Clock() = default;
  Clock(const Clock&) = default;
  Clock& operator=(const Clock&) = default;
};

/// std::chrono::steady_clock, in seconds since construction.
class SteadyClock final : public Clock {
 public:
  SteadyClock() : start_(std::chrono::steady_clock::now()) {}
  [[nodiscard]] double now_s() const noexcept override {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  std::chrono::steady_clock::time_point start_;
};

/// A clock set by its owner (simulations, tests). Starts at 0 s.
class ManualClock final : public Clock {
 public:
  [[nodiscard]] double now_s() const noexcept override { return now_s_; }
  void set(double t_s) noexcept { now_s_ = t_s; }
  void advance(double dt_s) noexcept { now_s_ += dt_s; }

 private:
  double now_s_ = 0.0;
};

}  // namespace deflex
