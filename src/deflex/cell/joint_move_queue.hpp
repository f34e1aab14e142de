// How a robot controller's path planner runs a queue of joint moves, each "to this absolute target in
// this time, with a zone" (ABB RAPID: MoveAbsJ target \T:=duration, zone; the streaming server programs
// of ROS-Industrial queue one such move per point they take). Simulated hardware: exact and
// deterministic, as the real planner behaves and never more kindly:
//   - each move runs at constant joint velocity over its duration (stretched when a joint would exceed
//     its speed limit);
//   - at a zone the planner blends into the next move (the velocity changes linearly from one move's to
//     the next's over 2 tb, tb = duration x min(1/2, zone / TCP length of the move), the smaller of the
//     two moves'), so the arm passes inside the corner and misses the point itself by |dv| tb / 4;
//   - a move must be known `latency_s` before the blend into it begins; otherwise the planner cannot
//     blend (RAPID's "corner path failure") and the arm decelerates to a stop at the point, then
//     starts again from rest when the next move is known;
//   - from rest the arm ramps up to the move's speed (over 2 tb, tb = min(duration, ramp_s) / 2), so a
//     move started from rest arrives tb late;
//   - stop() is StopMove + ClearPath: the queue is emptied and the speed ramps to zero over stop_time_s.
// The positions are the motor-side joints (the true robot adds its elasticity). Nothing allocates after
// construction.
#pragma once

#include <cstdint>
#include <vector>

#include "deflex/model/kinematics.hpp"

namespace deflex::cell {

struct JointMoveConfig {
  double zone_m = 0.010;     ///< zone radius at the TCP (RAPID z10, abb_driver's corner zone); 0: fine points
  double latency_s = 0.05;   ///< a move must be known this long before the planner starts or blends into it
  double ramp_s = 0.1;       ///< from rest to a move's speed, and back to rest at a fine point
  double stop_time_s = 0.1;  ///< StopMove: the speed ramps to zero over this time
  /// Throws InputError naming the setting.
  void validate() const;
};

struct JointMoveCounters {
  std::uint64_t pushed = 0;           ///< moves queued
  std::uint64_t taken = 0;            ///< moves the planner took from the queue
  std::uint64_t blended = 0;          ///< junctions passed in a zone
  std::uint64_t corner_failures = 0;  ///< junctions where the next move came too late: the arm stopped
  std::uint64_t stretched = 0;        ///< moves slowed to the joints' speed limits
  std::uint64_t stops = 0;            ///< stop() calls that found the arm moving
};

/// Thread safety: one thread at a time (the simulation's).
class JointMoveQueue {
 public:
  /// The arm at rest at `q_start` (rad); at most `capacity` (>= 1) moves wait in the queue. `model`
  /// gives the TCP (for the zone) and the joints' speed limits. Throws InputError.
  JointMoveQueue(const JointMoveConfig& config, const RobotModel& model, const JointVector& q_start,
                 std::size_t capacity);

  /// Queues a move to `target` (rad) taking `duration_s` (> 0), known to the planner from t_s on.
  /// False when `capacity` moves are already waiting (the move is not queued).
  bool push(double t_s, const JointVector& target, double duration_s) noexcept;
  /// The joints at t_s (not before the previous call's time).
  const JointVector& advance(double t_s) noexcept;
  /// StopMove + ClearPath at t_s.
  void stop(double t_s) noexcept;

  [[nodiscard]] std::size_t queued() const { return count_; }
  [[nodiscard]] std::size_t capacity() const { return queue_.size(); }
  [[nodiscard]] bool at_rest() const { return phase_ == Phase::kRest; }
  [[nodiscard]] const JointVector& position() const { return x_; }
  [[nodiscard]] const JointVector& velocity() const { return v_; }
  [[nodiscard]] const JointMoveCounters& counters() const { return counters_; }

 private:
  enum class Phase { kRest, kBlend, kLine, kStopping };
  struct Move {
    double known_s = 0.0;
    JointVector target;
    double duration_s = 0.0;
  };
  // Takes the queue's first move as the segment from `from`; returns its (possibly stretched) duration.
  void take(const JointVector& from, double start_s);
  [[nodiscard]] double zone_half_time(double duration_s, double length_m) const;
  [[nodiscard]] double tcp_distance(const JointVector& a, const JointVector& b);

  JointMoveConfig config_;
  RobotModel model_;
  Workspace ws_;
  std::vector<Move> queue_;
  std::size_t head_ = 0, count_ = 0;
  JointMoveCounters counters_;
  Phase phase_ = Phase::kRest;
  double last_t_s_ = 0.0;
  JointVector x_, v_;
  // Rest.
  JointVector rest_x_;
  double rest_since_s_ = 0.0;
  // The current segment: from a_ to b_ over T_ at velocity sv_, nominally starting at s_.
  JointVector a_, b_, sv_;
  double s_ = 0.0, T_ = 0.0, L_ = 0.0;
  // The current blend: from t0 over 2 tb, from velocity vin_ to vout_, starting at x0_; then either the
  // segment above (blend_to_line_) or rest at b_.
  double bt0_ = 0.0, btb_ = 0.0;
  JointVector bx0_, bvin_, bvout_;
  bool blend_to_line_ = false;
  // StopMove.
  double st0_ = 0.0;
  JointVector sx0_, sv0_;
  // Scratch for the next move.
  JointVector na_, nv_;
};

}  // namespace deflex::cell
