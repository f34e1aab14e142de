// The simulated robot controller: the programmed circle as a closed joint-space program, the lap
// schedule at the TCP speed (3 clockwise then 3 anticlockwise laps, after a settling pause), and the
// correction channel that carries the online strategy's joint targets with the link's delay and the
// controller's own low-pass filter.
#pragma once

#include <array>
#include <vector>

#include "deflex/model/types.hpp"

namespace deflex::cell {

/// N configurations at equal angles 2*pi*k/N around the circle, interpolated by a periodic
/// Catmull-Rom spline in joint space (stands in for the controller's circular interpolation through
/// the programmed points, whose chord error would otherwise swamp the figures).
class JointProgram {
 public:
  JointProgram() = default;
  explicit JointProgram(std::vector<JointVector> points);
  /// Configuration at circle angle `angle_rad` (any real; periodic). Does not allocate.
  void at(double angle_rad, JointVector& q) const;
  [[nodiscard]] int size() const { return static_cast<int>(points_.size()); }
  [[nodiscard]] const std::vector<JointVector>& points() const { return points_; }

 private:
  std::vector<JointVector> points_;
};

/// Angle of the path parameter over time: hold at angle 0 for `settle_s`, then `laps_cw` laps
/// clockwise seen from above (angle decreasing), then `laps_ccw` laps anticlockwise.
struct LapSchedule {
  double omega_rad_s = 0.0;
  double settle_s = 0.0;
  int laps_cw = 3;
  int laps_ccw = 3;
  [[nodiscard]] double motion_s() const;
  [[nodiscard]] double duration_s() const { return settle_s + motion_s(); }
  [[nodiscard]] double angle(double t_s) const;
  /// -1 clockwise, +1 anticlockwise, 0 settling.
  [[nodiscard]] int direction(double t_s) const;
};

/// One joint correction in flight: the offset from the planned joints that the compensator's
/// target amounts to (decoded from its EGM reply), the time of the cycle it came from, and when it
/// reaches the servo.
struct CorrectionMessage {
  double arrival_s = 0.0;
  double reference_s = 0.0;
  JointVector offset_rad;
};

/// Fixed-capacity FIFO of corrections in flight (no allocation once built).
class CorrectionChannel {
 public:
  explicit CorrectionChannel(std::size_t capacity = 64) : buffer_(capacity) {}
  /// False when full (the message is dropped, as a lost UDP packet would be).
  bool push(const CorrectionMessage& m);
  /// Pops the newest message that has arrived by `now_s` (older arrived ones are discarded, as the
  /// controller keeps only the newest packet). False when none arrived.
  bool pop_arrived(double now_s, CorrectionMessage& out);

 private:
  std::vector<CorrectionMessage> buffer_;
  std::size_t head_ = 0, count_ = 0;
};

}  // namespace deflex::cell
