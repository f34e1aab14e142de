// Time for the controller links: a link never reads the wall clock itself but asks a Clock, so the
// same link code runs in real time on a cell (SteadyClock) and in a deterministic, faster-than-real-
// time simulation (ManualClock, advanced by the simulation).
#pragma once

#include <chrono>

namespace deflex {

/// Seconds since some fixed start, monotonic. Reading it never allocates, locks or throws.
/// Thread safety: now_s() is const, and a SteadyClock may be read from any number of threads at
/// once (a session's loop and its reporter both read it); a ManualClock belongs to one thread.
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
/// Thread safety: immutable once made: now_s() from any number of threads.
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
/// Thread safety: one thread at a time (set() and advance() are plain writes that now_s() reads).
class ManualClock final : public Clock {
 public:
  [[nodiscard]] double now_s() const noexcept override { return now_s_; }
  void set(double t_s) noexcept { now_s_ = t_s; }
  void advance(double dt_s) noexcept { now_s_ += dt_s; }

 private:
  double now_s_ = 0.0;
};

}  // namespace deflex
