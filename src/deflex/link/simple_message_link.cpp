// ROS-Industrial simple message streaming link (see simple_message_link.hpp).
#include "deflex/link/simple_message_link.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>

#include <fmt/format.h>

#include "deflex/model/errors.hpp"

namespace deflex {

namespace sm = simple_message;

namespace {

constexpr std::size_t kPointFrameBytes = sm::kLengthBytes + sm::kHeaderBytes + sm::kJointTrajPtBytes;  // 68

// The float32 the wire carries is the command rounded to 24 bits: the final check allows that rounding
// (half an ulp of the value, below 1e-7 rad for any joint angle) and nothing else.
double float_rounding(double value) {
  return std::max(std::abs(value), 1.0) * static_cast<double>(std::numeric_limits<float>::epsilon());
}

}  // namespace

void SimpleMessageLinkConfig::validate() const {
  if (buffer_depth < 1 || buffer_depth > 64) {
    throw InputError(fmt::format("simple message link: buffer depth must be 1..64 points (got {})", buffer_depth));
  }
  if (!std::isfinite(reply_timeout_s) || !(reply_timeout_s > 0.0)) {
    throw InputError(fmt::format("simple message link: reply timeout must be > 0 s (got {})", reply_timeout_s));
  }
  if (!std::isfinite(state_timeout_s) || !(state_timeout_s > 0.0)) {
    throw InputError(fmt::format("simple message link: state timeout must be > 0 s (got {})", state_timeout_s));
  }
  if (max_failures < 1) {
    throw InputError(
        fmt::format("simple message link: max FAILURE replies in a row must be >= 1 (got {})", max_failures));
  }
  if (max_frame_bytes < sm::kHeaderBytes + sm::kJointTrajPtBytes || max_frame_bytes > (std::size_t{1} << 20)) {
    throw InputError(fmt::format("simple message link: the largest frame must be 64 bytes..1 MiB (got {})",
                                 max_frame_bytes));
  }
  if (!std::isnan(initial_delay_s) && !(std::isfinite(initial_delay_s) && initial_delay_s >= 0.0)) {
    throw InputError(fmt::format("simple message link: the initial delay must be >= 0 s (got {})", initial_delay_s));
  }
  stream.validate();
}

SimpleMessageLink::SimpleMessageLink(OnlineCompensator& compensator, OnlineStrategy& strategy,
                                     std::shared_ptr<const JointTrajectory> nominal, StreamTransport& motion,
                                     StreamTransport& state, const Clock& clock, ForceSource* force,
                                     const SimpleMessageLinkConfig& config)
    : comp_(compensator),
      strategy_(strategy),
      motion_(motion),
      state_port_(state),
      clock_(clock),
      force_(force),
      config_([&] {
        config.validate();
        return config;
      }()),
      period_s_(compensator.config().period_s),
      stream_(nominal, [&] {
        // The program clock here is the points' own (one cycle a point), so no step of it is a silence.
        JointStreamConfig c = config.stream;
        c.pause_after_s = std::max(c.pause_after_s, 2.0 * compensator.config().period_s);
        return c;
      }()),
      delay_(std::isnan(config.initial_delay_s) ? config.buffer_depth * compensator.config().period_s
                                                : config.initial_delay_s,
             (config.buffer_depth + 4) * compensator.config().period_s + 0.5),
      history_(config.history_cycles, compensator.model().dof()),
      motion_reader_(config.byte_order, config.max_frame_bytes),
      state_reader_(config.byte_order, config.max_frame_bytes),
      outbox_(64 * kPointFrameBytes),
      ws_(compensator.model()),
      jac_(6, compensator.model().dof()) {
  const RobotModel& model = compensator.model();
  const int n = model.dof();
  if (nominal->dof() != n) {
    throw InputError(
        fmt::format("simple message link: the program has {} joints, the robot {}", nominal->dof(), n));
  }
  if (n > static_cast<int>(sm::kWireJoints)) {
    throw InputError(fmt::format("simple message link: the robot has {} joints, the protocol carries {}", n,
                                 sm::kWireJoints));
  }
  for (JointVector* q : {&input_.q_planned, &input_.q_feedback, &nominal_, &nominal_velocity_, &command_, &last_sent_,
                         &feedback_}) {
    *q = JointVector::Zero(n);
  }
  // A controller that reports joints beyond its own limits (plus 1 deg) is sending garbage.
  lower_ = model.lower_limits().array() - deg_to_rad(1.0);
  upper_ = model.upper_limits().array() + deg_to_rad(1.0);
  last_ = history_.blank();
}

double SimpleMessageLink::next_due_s() const noexcept {
  // `buffer_depth` points at once, then one a cycle: the (accepted + 1)-th is due depth cycles early.
  return schedule_origin_s_ + (static_cast<double>(accepted_) + 1.0 - config_.buffer_depth) * period_s_;
}

void SimpleMessageLink::fault(LinkStopCause cause, const char* format, ...) noexcept {
  if (state_ == LinkState::kStopped) return;
  va_list args;
  va_start(args, format);
  std::vsnprintf(stop_reason_.data(), stop_reason_.size(), format, args);
  va_end(args);
  stop_cause_ = cause;
  fault_pending_ = true;
  state_ = LinkState::kStopped;
  announced_ = false;
  if (sent_any_) send_stop();
}

void SimpleMessageLink::stop() noexcept {
  if (state_ == LinkState::kStopped || state_ == LinkState::kRefused) return;
  std::snprintf(stop_reason_.data(), stop_reason_.size(), "stopped on request");
  stop_cause_ = LinkStopCause::kRequested;
  state_ = LinkState::kStopped;
  announced_ = true;
  if (sent_any_) send_stop();
}

void SimpleMessageLink::send_stop() noexcept {
  if (motion_closed_ || !motion_.is_open()) return;
  // STOP_TRAJECTORY carries the last target sent, never a new one: a server that took it for a point
  // would hold the arm where it was going anyway.
  sm::JointTrajPt stop{};
  stop.sequence = sm::kStopTrajectory;
  for (int j = 0; j < last_sent_.size(); ++j) {
    stop.joints_rad[static_cast<std::size_t>(j)] = static_cast<float>(last_sent_[j]);
  }
  unsigned char* at = outbox_.reserve(kPointFrameBytes);
  if (at == nullptr) return;  // cannot happen: a point is queued only with room for a STOP behind it
  const std::size_t n = sm::encode(config_.byte_order, {sm::kJointTrajPt, sm::kServiceRequest, sm::kReplyInvalid},
                                   stop, at, kPointFrameBytes);
  outbox_.commit(n);
  ++sm_.stops_sent;
  flush();
}

bool SimpleMessageLink::flush() noexcept {
  while (outbox_.pending_bytes() > 0) {
    const long n = motion_.write(outbox_.pending(), outbox_.pending_bytes());
    if (n == StreamTransport::kClosed) {
      motion_closed_ = true;
      outbox_.clear();
      ++counters_.send_errors;
      return false;
    }
    if (n == 0) return true;  // the window is full: the rest goes at the next poll
    if (static_cast<std::size_t>(n) < outbox_.pending_bytes()) ++sm_.partial_writes;
    outbox_.consume(static_cast<std::size_t>(n));
  }
  return true;
}

bool SimpleMessageLink::read_port(Port port, double now) noexcept {
  const bool motion = port == Port::kMotion;
  StreamTransport& s = motion ? motion_ : state_port_;
  sm::FrameReader& reader = motion ? motion_reader_ : state_reader_;
  bool& closed = motion ? motion_closed_ : state_closed_;
  const char* which = motion ? "motion" : "state";
  if (closed) return true;
  for (;;) {
    const long n = s.read(reader.space(), reader.space_bytes());
    if (n == StreamTransport::kClosed) {
      closed = true;
      if (state_ == LinkState::kFinished) return true;  // the program is over: a server may hang up
      fault(LinkStopCause::kConnection, "the controller closed the %s connection (or it broke)", which);
      return false;
    }
    if (n == 0) return true;
    reader.commit(static_cast<std::size_t>(n));
    for (;;) {
      sm::FrameView f;
      const sm::FrameStatus st = reader.next(f);
      if (st == sm::FrameStatus::kIncomplete) break;
      if (st != sm::FrameStatus::kComplete) {
        ++counters_.datagrams;
        if (st == sm::FrameStatus::kOversized) {
          ++counters_.oversized;
        } else {
          ++counters_.malformed;
        }
        fault(LinkStopCause::kProtocol,
              "%s connection: frame LENGTH %lld (%s, which is 12..%zu bytes): the stream is out of step", which,
              static_cast<long long>(reader.length()), sm::to_string(st), config_.max_frame_bytes);
        return false;
      }
      if (!(motion ? handle_motion_frame(f, now) : handle_state_frame(f, now))) return false;
    }
  }
}

bool SimpleMessageLink::handle_state_frame(const sm::FrameView& f, double now) noexcept {
  ++counters_.datagrams;
  ++sm_.state_frames;
  if (f.header.comm_type != sm::kTopic) {
    ++sm_.unexpected;
    ++counters_.malformed;
    fault(LinkStopCause::kProtocol, "state connection: a %s frame (type %d) with COMM_TYPE %d, TOPIC (1) expected",
          sm::message_type_name(f.header.msg_type), f.header.msg_type, f.header.comm_type);
    return false;
  }
  const auto count_bad = [this](sm::DecodeStatus s) {
    if (s == sm::DecodeStatus::kTruncated) {
      ++counters_.truncated;
    } else if (s == sm::DecodeStatus::kNonFinite) {
      ++counters_.non_finite;
    } else {
      ++counters_.malformed;
    }
  };
  if (f.header.msg_type == sm::kJointPosition) {
    const sm::DecodeStatus s = sm::decode(config_.byte_order, f.data, f.data_bytes, position_);
    if (s != sm::DecodeStatus::kOk) {
      count_bad(s);
      fault(LinkStopCause::kProtocol, "state connection: JOINT_POSITION %s (%zu data bytes, %zu expected)",
            sm::to_string(s), f.data_bytes, sm::kJointPositionBytes);
      return false;
    }
    for (int j = 0; j < feedback_.size(); ++j) {
      const double q = position_.joints_rad[static_cast<std::size_t>(j)];
      if (q < lower_[j] || q > upper_[j]) {
        ++counters_.out_of_limits;
        fault(LinkStopCause::kProtocol,
              "state connection: JOINT_POSITION joint %d at %.3f deg is beyond the robot's limits (check the byte "
              "order, now %s)",
              j + 1, rad_to_deg(q), sm::to_string(config_.byte_order));
        return false;
      }
      feedback_[j] = q;
    }
    have_feedback_ = true;
    last_state_s_ = now;
    ++sm_.joint_positions;
    delay_.observe_feedback(now, feedback_);
    return true;
  }
  if (f.header.msg_type == sm::kRobotStatus) {
    const sm::DecodeStatus s = sm::decode(config_.byte_order, f.data, f.data_bytes, status_);
    if (s != sm::DecodeStatus::kOk) {
      count_bad(s);
      fault(LinkStopCause::kProtocol, "state connection: ROBOT_STATUS %s (%zu data bytes, %zu expected)",
            sm::to_string(s), f.data_bytes, sm::kRobotStatusBytes);
      return false;
    }
    ++sm_.robot_statuses;
    if (status_.e_stopped == 1) {
      fault(LinkStopCause::kController, "the controller reports an emergency stop (ROBOT_STATUS e_stopped)");
      return false;
    }
    if (status_.in_error == 1) {
      fault(LinkStopCause::kController, "the controller reports an error (ROBOT_STATUS in_error, error code %d)",
            status_.error_code);
      return false;
    }
    return true;
  }
  ++sm_.unknown_type;
  ++counters_.malformed;
  fault(LinkStopCause::kProtocol,
        "state connection: message type %d is not one the link speaks (JOINT_POSITION 10, ROBOT_STATUS 13)",
        f.header.msg_type);
  return false;
}

bool SimpleMessageLink::handle_motion_frame(const sm::FrameView& f, double now) noexcept {
  ++counters_.datagrams;
  ++sm_.motion_frames;
  if (f.header.msg_type != sm::kJointTrajPt && f.header.msg_type != sm::kJointPosition) {
    ++sm_.unknown_type;
    ++counters_.malformed;
    fault(LinkStopCause::kProtocol,
          "motion connection: message type %d is not a reply the link expects (JOINT_TRAJ_PT 11; JOINT_POSITION 10 "
          "from Fanuc's relay)",
          f.header.msg_type);
    return false;
  }
  if (f.header.comm_type != sm::kServiceReply) {
    ++sm_.unexpected;
    ++counters_.malformed;
    fault(LinkStopCause::kProtocol, "motion connection: a %s frame with COMM_TYPE %d, SERVICE_REPLY (3) expected",
          sm::message_type_name(f.header.msg_type), f.header.comm_type);
    return false;
  }
  // A reply carries no data (ABB's RAPID server) or the whole message it answers (industrial_core's
  // servers echo the point; Fanuc's relay answers with a JOINT_POSITION): anything else is out of step.
  const std::size_t full = f.header.msg_type == sm::kJointTrajPt ? sm::kJointTrajPtBytes : sm::kJointPositionBytes;
  if (f.data_bytes != 0 && f.data_bytes != full) {
    if (f.data_bytes < full) {
      ++counters_.truncated;
    } else {
      ++counters_.malformed;
    }
    fault(LinkStopCause::kProtocol, "motion connection: a %s reply with %zu data bytes (0 or %zu expected)",
          sm::message_type_name(f.header.msg_type), f.data_bytes, full);
    return false;
  }
  const bool has_sequence = f.data_bytes >= 4;
  const std::int32_t sequence = has_sequence ? sm::read_int32(config_.byte_order, f.data) : 0;
  if (!waiting_reply_) {
    ++sm_.unexpected;
    ++counters_.out_of_order;
    fault(LinkStopCause::kProtocol, "motion connection: a reply (sequence %d) when no point was waiting for one",
          sequence);
    return false;
  }
  if (has_sequence && sequence != waiting_sequence_) {
    ++sm_.wrong_sequence;
    ++counters_.out_of_order;
    fault(LinkStopCause::kProtocol, "motion connection: the reply names point %d, but point %d was waiting", sequence,
          waiting_sequence_);
    return false;
  }
  if (f.header.reply_code == sm::kReplySuccess) {
    waiting_reply_ = false;
    ++accepted_;
    ++sm_.points_accepted;
    ++counters_.replies;
    failures_in_row_ = 0;
    ++next_sequence_;
    if (waiting_is_last_) state_ = LinkState::kFinished;
    return true;
  }
  if (f.header.reply_code == sm::kReplyFailure) {
    // Not taken: the controller's buffer was full, so it runs behind deflex's clock. Wait a cycle from
    // now and send the same point again (the schedule moves with it); a controller that keeps refusing
    // stops the link.
    waiting_reply_ = false;
    ++sm_.failures;
    ++failures_in_row_;
    schedule_origin_s_ = now + period_s_ - (static_cast<double>(accepted_) + 1.0 - config_.buffer_depth) * period_s_;
    if (failures_in_row_ >= config_.max_failures) {
      fault(LinkStopCause::kController,
            "the controller refused point %d %d times in a row (FAILURE replies): its buffer stays full or it refuses "
            "the point",
            waiting_sequence_, failures_in_row_);
      return false;
    }
    return true;
  }
  ++counters_.malformed;
  fault(LinkStopCause::kProtocol, "motion connection: reply code %d, SUCCESS (1) or FAILURE (2) expected",
        f.header.reply_code);
  return false;
}

LinkPollResult SimpleMessageLink::poll(double timeout_s) noexcept {
  if (state_ == LinkState::kRefused || state_ == LinkState::kStopped) {
    if (!motion_closed_) flush();  // the STOP_TRAJECTORY, if the window held it back
    if (!announced_) {
      announced_ = true;
      return state_ == LinkState::kRefused ? LinkPollResult::kRefused : LinkPollResult::kStopped;
    }
    return LinkPollResult::kIdle;
  }
  double now = clock_.now_s();
  double wait = std::isfinite(timeout_s) ? std::max(timeout_s, 0.0) : 0.0;
  if (state_ == LinkState::kRunning && !waiting_reply_) wait = std::min(wait, std::max(0.0, next_due_s() - now));
  wait_readable_any(motion_, state_port_, wait);
  now = clock_.now_s();
  const auto stopped = [this] {
    announced_ = true;
    return LinkPollResult::kStopped;
  };
  if (!read_port(Port::kState, now) || !read_port(Port::kMotion, now)) return stopped();

  if (state_ == LinkState::kRunning) {
    if (now - last_state_s_ > config_.state_timeout_s) {
      fault(LinkStopCause::kConnection, "no JOINT_POSITION on the state connection for %.2f s (timeout %.2f s)",
            now - last_state_s_, config_.state_timeout_s);
      return stopped();
    }
    if (waiting_reply_ && now - waiting_since_s_ > config_.reply_timeout_s) {
      fault(LinkStopCause::kConnection, "no reply to point %d for %.2f s (timeout %.2f s)", waiting_sequence_,
            now - waiting_since_s_, config_.reply_timeout_s);
      return stopped();
    }
  }
  if (state_ == LinkState::kWaiting) {
    if (!have_feedback_) {
      flush();
      return LinkPollResult::kIdle;
    }
    // The session starts with the arm where the controller says it is: it must be at the program's
    // start, or nothing is ever sent.
    if (!stream_.begin(0.0, feedback_)) {
      state_ = LinkState::kRefused;
      ++counters_.refused;
      fault_pending_ = true;
      announced_ = true;
      return LinkPollResult::kRefused;
    }
    state_ = LinkState::kRunning;
    schedule_origin_s_ = now;
  }
  if (state_ == LinkState::kRunning && !waiting_reply_ && now + 1e-9 >= next_due_s()) return send_point(now);
  if (!flush() && state_ == LinkState::kRunning) {
    fault(LinkStopCause::kConnection, "the motion connection is closed (a write failed)");
    return stopped();
  }
  return LinkPollResult::kIdle;
}

LinkPollResult SimpleMessageLink::send_point(double now) noexcept {
  const auto t_start = std::chrono::steady_clock::now();
  // The program clock of the points: one cycle a point, however late the controller takes them.
  stream_.advance(static_cast<double>(next_sequence_) * period_s_, nominal_, nominal_velocity_);
  const bool last = stream_.finished();

  input_.t_s = now;
  input_.q_planned = nominal_;
  input_.q_feedback = feedback_;
  // The point is executed buffer_depth cycles from now: the strategy is told the measured delay and
  // the configuration the point is for.
  const StrategyStatus ss = strategy_.prepare(input_, feedback_, nominal_, delay_.delay_s(), comp_.filter_delay_s());
  input_.hold_to_zero = input_.hold_to_zero || ss != StrategyStatus::kOk;
  const CycleOutput out = force_ != nullptr ? comp_.step(input_, *force_) : comp_.step(input_);

  LinkCycleRecord& r = last_;
  r.t_s = now;
  r.program_time_s = stream_.program_time_s();
  r.sequence = static_cast<std::uint32_t>(next_sequence_);
  r.q_nominal = nominal_;
  r.q_feedback = feedback_;
  r.dtheta = out.dtheta;
  r.wrench_base = out.wrench_base;
  r.wrench_measured_base = out.wrench_measured_base;
  r.status = out.status;
  r.replied = false;
  r.delay_s = delay_.delay_s();
  r.rotation_uncorrected_rad = 0.0;
  if (out.status == CycleStatus::kForceFault || out.status == CycleStatus::kInvalidInput) fault_pending_ = true;
  const auto finish = [&](LinkPollResult result) {
    r.compute_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
    history_.record(r);
    return result;
  };
  if (static_cast<int>(out.status) < 0) {
    ++counters_.invalid_cycles;
    r.q_command = nominal_;
    fault(LinkStopCause::kSafety, "the compensator refused point %d (%s): nothing sent", next_sequence_,
          to_string(out.status));
    announced_ = true;
    return finish(LinkPollResult::kStopped);
  }
  command_ = nominal_ - out.dtheta;

  // The last check before anything leaves deflex, on the float32 values the wire carries: every joint
  // within the bound of the nominal.
  const double bound = comp_.config().max_joint_correction_rad * (1.0 + 1e-9) + 1e-12;
  int bad_joint = -1;
  point_ = sm::JointTrajPt{};
  for (int j = 0; j < command_.size(); ++j) {
    const auto f = static_cast<float>(command_[j]);
    point_.joints_rad[static_cast<std::size_t>(j)] = f;
    const double sent = static_cast<double>(f);
    if (!std::isfinite(sent) || std::abs(sent - nominal_[j]) > bound + float_rounding(nominal_[j])) {
      bad_joint = j;
      break;
    }
    command_[j] = sent;
  }
  r.q_command = command_;
  if (bad_joint >= 0) {
    ++counters_.guard_trips;
    fault(LinkStopCause::kSafety,
          "the final check found joint %d of point %d %.6f deg from the nominal (bound %.6f deg): nothing sent",
          bad_joint + 1, next_sequence_, rad_to_deg(std::abs(command_[bad_joint] - nominal_[bad_joint])),
          rad_to_deg(comp_.config().max_joint_correction_rad));
    announced_ = true;
    return finish(LinkPollResult::kStopped);
  }
  // The velocity field: the fastest joint's share of its top speed (ABB's and Fanuc's servers ignore it).
  double velocity = 0.0;
  const RobotModel& model = comp_.model();
  if (model.has_max_speed()) {
    const JointVector& from = sent_any_ ? last_sent_ : feedback_;
    for (int j = 0; j < command_.size(); ++j) {
      velocity = std::max(velocity, std::abs(command_[j] - from[j]) / period_s_ / model.max_speed()[j]);
    }
  }
  point_.sequence = next_sequence_;
  point_.velocity = static_cast<float>(std::min(velocity, 1.0));
  point_.duration_s = static_cast<float>(period_s_);
  // Room for this point and a STOP_TRAJECTORY behind it, always.
  unsigned char* at = outbox_.reserve(2 * kPointFrameBytes);
  if (at == nullptr) {
    ++counters_.send_errors;
    fault(LinkStopCause::kConnection, "the controller has not read %zu bytes of earlier points: it stopped reading",
          outbox_.pending_bytes());
    announced_ = true;
    return finish(LinkPollResult::kStopped);
  }
  const std::size_t n = sm::encode(config_.byte_order, {sm::kJointTrajPt, sm::kServiceRequest, sm::kReplyInvalid},
                                   point_, at, kPointFrameBytes);
  outbox_.commit(n);
  if (!flush()) {
    fault(LinkStopCause::kConnection, "the motion connection is closed: point %d could not be sent", next_sequence_);
    announced_ = true;
    return finish(LinkPollResult::kStopped);
  }
  waiting_reply_ = true;
  waiting_sequence_ = next_sequence_;
  waiting_since_s_ = now;
  waiting_is_last_ = last;
  sent_any_ = true;
  last_sent_ = command_;
  ++sm_.points_sent;
  delay_.record_reference(now, command_);
  jacobian(model, ws_, nominal_, EndPoint::kTcp, jac_);
  r.tcp_correction_m = -(jac_.topRows<3>() * out.dtheta);  // what the correction moves the TCP by
  r.replied = true;
  return finish(LinkPollResult::kAnswered);
}

}  // namespace deflex
