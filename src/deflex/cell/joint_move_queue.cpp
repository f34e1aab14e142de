// A controller's queue of joint moves with zones (see joint_move_queue.hpp). Every phase has a closed
// form in time, so the arm's position at a servo tick does not depend on when the ticks fall.
#include "deflex/cell/joint_move_queue.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex::cell {

void JointMoveConfig::validate() const {
  const auto check = [](double v, bool zero_ok, const char* what) {
    if (!std::isfinite(v) || v < 0.0 || (!zero_ok && v == 0.0)) {
      throw InputError(fmt::format("joint moves: {} must be {} (got {})", what, zero_ok ? ">= 0" : "> 0", v));
    }
  };
  check(zone_m, true, "the zone (m)");
  check(latency_s, true, "the planning latency (s)");
  check(ramp_s, false, "the ramp time (s)");
  check(stop_time_s, false, "the stop time (s)");
}

JointMoveQueue::JointMoveQueue(const JointMoveConfig& config, const RobotModel& model, const JointVector& q_start,
                               std::size_t capacity)
    : config_(config), model_(model), ws_(model_) {
  config_.validate();
  if (capacity == 0 || capacity > 100000) throw InputError("joint moves: the queue holds 1..100000 moves");
  if (q_start.size() != model_.dof() || !q_start.allFinite()) {
    throw InputError("joint moves: the start must be finite and have one value a joint");
  }
  const JointVector zero = JointVector::Zero(model_.dof());
  queue_.assign(capacity, Move{0.0, zero, 0.0});
  x_ = rest_x_ = a_ = b_ = bx0_ = sx0_ = q_start;
  v_ = sv_ = bvin_ = bvout_ = sv0_ = na_ = nv_ = zero;
}

double JointMoveQueue::tcp_distance(const JointVector& a, const JointVector& b) {
  forward_kinematics(model_, ws_, a);
  const Vector3 pa = ws_.base_T_tcp.translation();
  forward_kinematics(model_, ws_, b);
  return (ws_.base_T_tcp.translation() - pa).norm();
}

double JointMoveQueue::zone_half_time(double duration_s, double length_m) const {
  if (config_.zone_m <= 0.0) return 0.5 * std::min(duration_s, config_.ramp_s);  // fine point
  // The zone is at most half the move (RAPID shrinks a zone larger than half the distance).
  const double share = length_m > 0.0 ? std::min(0.5, config_.zone_m / length_m) : 0.5;
  return duration_s * share;
}

bool JointMoveQueue::push(double t_s, const JointVector& target, double duration_s) noexcept {
  if (count_ == queue_.size()) return false;
  Move& m = queue_[(head_ + count_) % queue_.size()];
  m.known_s = t_s;
  m.target = target;
  m.duration_s = duration_s;
  ++count_;
  ++counters_.pushed;
  return true;
}

void JointMoveQueue::take(const JointVector& from, double /*start_s*/) {
  const Move& m = queue_[head_];
  a_ = from;
  b_ = m.target;
  T_ = m.duration_s;
  if (model_.has_max_speed()) {
    // The planner never asks a joint for more than its top speed: the move takes longer instead.
    const double needed = ((b_ - a_).cwiseAbs().array() / model_.max_speed().array()).maxCoeff();
    if (needed > T_) {
      T_ = needed;
      ++counters_.stretched;
    }
  }
  sv_ = (b_ - a_) / T_;
  L_ = tcp_distance(a_, b_);
  head_ = (head_ + 1) % queue_.size();
  --count_;
  ++counters_.taken;
}

// NOLINTNEXTLINE(readability-function-size): listed in docs/architecture.md, "Functions over 80 lines"
const JointVector& JointMoveQueue::advance(double t_s) noexcept {
  const double t = std::max(t_s, last_t_s_);
  last_t_s_ = t;
  for (;;) {
    switch (phase_) {
      case Phase::kRest: {
        if (count_ > 0) {
          const double start = std::max(rest_since_s_, queue_[head_].known_s + config_.latency_s);
          if (start <= t) {
            take(rest_x_, start);
            const double tb = 0.5 * std::min(T_, config_.ramp_s);
            bt0_ = start;
            btb_ = tb;
            bx0_ = rest_x_;
            bvin_.setZero();
            bvout_ = sv_;
            s_ = start + tb;  // the segment's nominal timeline, centred on the ramp
            blend_to_line_ = true;
            phase_ = Phase::kBlend;
            continue;
          }
        }
        x_ = rest_x_;
        v_.setZero();
        return x_;
      }
      case Phase::kBlend: {
        const double end = bt0_ + 2.0 * btb_;
        if (t >= end) {
          if (blend_to_line_) {
            phase_ = Phase::kLine;
          } else {
            phase_ = Phase::kRest;
            rest_x_ = b_;
            rest_since_s_ = end;
          }
          continue;
        }
        const double tau = t - bt0_;
        if (tau < 0.0) {  // the blend is planned but the arm is still on the incoming line
          x_ = bx0_ + tau * bvin_;
          v_ = bvin_;
        } else {
          x_ = bx0_ + tau * bvin_ + (tau * tau / (4.0 * btb_)) * (bvout_ - bvin_);
          v_ = bvin_ + (tau / (2.0 * btb_)) * (bvout_ - bvin_);
        }
        return x_;
      }
      case Phase::kLine: {
        const double tb_in = zone_half_time(T_, L_);
        const double decision = s_ + T_ - tb_in;
        if (t >= decision) {
          const bool next_known =
              config_.zone_m > 0.0 && count_ > 0 && queue_[head_].known_s + config_.latency_s <= decision;
          bvin_ = sv_;
          if (next_known) {
            // Blend into the next move: the smaller of the two moves' zones.
            const JointVector from = b_;
            const double s_next = s_ + T_;
            take(from, s_next);
            const double tb = std::min(tb_in, zone_half_time(T_, L_));
            bt0_ = s_next - tb;
            btb_ = tb;
            bx0_ = from - tb * bvin_;
            bvout_ = sv_;
            s_ = s_next;
            blend_to_line_ = true;
            ++counters_.blended;
          } else {
            // Corner path failure (or a fine point): decelerate to a stop at the point.
            const double tb = tb_in;
            bt0_ = s_ + T_ - tb;
            btb_ = tb;
            bx0_ = b_ - tb * bvin_;
            bvout_.setZero();
            blend_to_line_ = false;
            if (config_.zone_m > 0.0) ++counters_.corner_failures;
          }
          phase_ = Phase::kBlend;
          continue;
        }
        x_ = a_ + (t - s_) * sv_;
        v_ = sv_;
        return x_;
      }
      case Phase::kStopping: {
        const double ts = config_.stop_time_s;
        const double tau = t - st0_;
        if (tau >= ts) {
          phase_ = Phase::kRest;
          rest_x_ = sx0_ + (0.5 * ts) * sv0_;
          rest_since_s_ = st0_ + ts;
          continue;
        }
        x_ = sx0_ + (tau - tau * tau / (2.0 * ts)) * sv0_;
        v_ = (1.0 - tau / ts) * sv0_;
        return x_;
      }
    }
  }
}

void JointMoveQueue::stop(double t_s) noexcept {
  advance(t_s);
  count_ = 0;
  head_ = 0;
  if (phase_ == Phase::kRest || phase_ == Phase::kStopping) return;
  ++counters_.stops;
  phase_ = Phase::kStopping;
  st0_ = last_t_s_;
  sx0_ = x_;
  sv0_ = v_;
}

}  // namespace deflex::cell
