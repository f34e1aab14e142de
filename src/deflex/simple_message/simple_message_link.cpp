// ROS-Industrial simple message streaming link (see simple_message_link.hpp).
#include "deflex/simple_message/simple_message_link.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <utility>

#include <fmt/format.h>

#include "deflex/online/online_strategy.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {

namespace sm = simple_message;

namespace {

constexpr std::size_t kPointFrameBytes = sm::kLengthBytes + sm::kHeaderBytes + sm::kJointTrajPtBytes;  // 68

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
    throw InputError(
        fmt::format("simple message link: the largest frame must be 64 bytes..1 MiB (got {})", max_frame_bytes));
  }
  if (!std::isnan(initial_delay_s) && !(std::isfinite(initial_delay_s) && initial_delay_s >= 0.0)) {
    throw InputError(fmt::format("simple message link: the initial delay must be >= 0 s (got {})", initial_delay_s));
  }
  if (!std::isfinite(max_behind_s) || !(max_behind_s > 0.0)) {
    throw InputError(
        fmt::format("simple message link: the largest delay behind the program must be > 0 s (got {})", max_behind_s));
  }
  stream.validate();
  stop.validate();
}

namespace {
CommandLimits point_limits(const OnlineCompensator& c, const JointTrajectory* program,
                           const SimpleMessageLinkConfig& config) {
  config.validate();
  if (program == nullptr) throw InputError("simple message link: no program to stream");
  if (program->dof() != c.model().dof()) {
    throw InputError(
        fmt::format("simple message link: the program has {} joints, the robot {}", program->dof(), c.model().dof()));
  }
  CommandLimits l = command_limits(CommandForm::kJointTarget, c.config(), c.model().dof(), program, &config.stream);
  l.rounding = WireRounding::kFloat32;  // JOINT_TRAJ_PT carries float32 radians
  return l;
}
}  // namespace

SimpleMessageLink::SimpleMessageLink(OnlineCompensator& compensator, OnlineStrategy& strategy,
                                     std::shared_ptr<const JointTrajectory> nominal, StreamTransport& motion,
                                     StreamTransport& state, const Clock& clock, const SimpleMessageLinkConfig& config)
    : ControllerLink(compensator, strategy, clock, point_limits(compensator, nominal.get(), config), config.stop,
                     config.history_cycles),
      motion_(motion),
      state_port_(state),
      config_(config),
      period_s_(compensator.config().period_s),
      stream_(std::move(nominal), config.stream),
      delay_(std::isnan(config.initial_delay_s) ? config.buffer_depth * compensator.config().period_s
                                                : config.initial_delay_s,
             (config.buffer_depth + 4) * compensator.config().period_s + 0.5),
      motion_reader_(config.byte_order, config.max_frame_bytes),
      state_reader_(config.byte_order, config.max_frame_bytes),
      outbox_(64 * kPointFrameBytes) {
  const RobotModel& model = compensator.model();
  const int n = model.dof();
  if (n > static_cast<int>(sm::kWireJoints)) {
    throw InputError(
        fmt::format("simple message link: the robot has {} joints, the protocol carries {}", n, sm::kWireJoints));
  }
  for (JointVector* q :
       {&program_, &program_velocity_, &blend_, &blend_velocity_, &nominal_, &last_sent_, &feedback_}) {
    *q = JointVector::Zero(n);
  }
  // A controller that reports joints beyond its own limits (plus 1 deg) is sending garbage.
  lower_ = model.lower_limits().array() - deg_to_rad(1.0);
  upper_ = model.upper_limits().array() + deg_to_rad(1.0);
}

double SimpleMessageLink::next_due_s() const noexcept {
  // `buffer_depth` points at once, then one a cycle: the (accepted + 1)-th is due depth cycles early.
  return schedule_origin_s_ + (static_cast<double>(accepted_) + 1.0 - config_.buffer_depth) * period_s_;
}

void SimpleMessageLink::fault(LinkStopCause cause, const char* format, ...) noexcept {
  if (state_ == LinkState::kStopped) return;
  std::array<char, 256> text{};
  va_list args;
  va_start(args, format);
  std::vsnprintf(text.data(), text.size(), format, args);
  va_end(args);
  stop_link(cause, "%s", text.data());
  if (sent_any_) send_stop();
}

void SimpleMessageLink::stop() noexcept {
  if (state_ == LinkState::kStopped || state_ == LinkState::kRefused) return;
  stop_link(LinkStopCause::kRequested, "stopped on request");
  (void)announce_terminal();  // the caller asked: nothing to announce
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
  const std::size_t n = sm::encode(config_.byte_order, {sm::kJointTrajPt, sm::kServiceRequest, sm::kReplyInvalid}, stop,
                                   at, kPointFrameBytes);
  outbox_.commit(n);
  ++sm_.stops_sent;
  stop_reply_due_ = true;
  flush();
}

bool SimpleMessageLink::winding_down() const {
  return !motion_closed_ && (outbox_.pending_bytes() > 0 || stop_reply_due_);
}

void SimpleMessageLink::discard_input() noexcept {
  // After a stop nothing the controller sends matters, but it must be read: a connection closed with
  // unread bytes is reset, and the controller's program would see an error instead of a close.
  unsigned char sink[256];
  for (StreamTransport* s : {&motion_, &state_port_}) {
    bool& closed = s == &motion_ ? motion_closed_ : state_closed_;
    if (closed) continue;
    for (long n = s->read(sink, sizeof(sink)); n != 0; n = s->read(sink, sizeof(sink))) {
      if (n == StreamTransport::kClosed) {
        closed = true;
        break;
      }
      if (s == &motion_) stop_reply_due_ = false;  // the reply to STOP_TRAJECTORY (or whatever came): read
    }
  }
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
      if (state_ == LinkState::kFinished) {  // the program is over: a server may hang up
        stop_link(LinkStopCause::kEnded, "the controller closed the %s connection after the program's end", which);
        return false;
      }
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
  if (f.header.msg_type == sm::kJointPosition) return take_joint_position(f, now);
  if (f.header.msg_type == sm::kRobotStatus) return take_robot_status(f);
  ++sm_.unknown_type;
  ++counters_.malformed;
  fault(LinkStopCause::kProtocol,
        "state connection: message type %d is not one the link speaks (JOINT_POSITION 10, ROBOT_STATUS 13)",
        f.header.msg_type);
  return false;
}

void SimpleMessageLink::count_bad_decode(sm::DecodeStatus s) noexcept {
  if (s == sm::DecodeStatus::kTruncated) {
    ++counters_.truncated;
  } else if (s == sm::DecodeStatus::kNonFinite) {
    ++counters_.non_finite;
  } else {
    ++counters_.malformed;
  }
}

bool SimpleMessageLink::take_joint_position(const sm::FrameView& f, double now) noexcept {
  const sm::DecodeStatus s = sm::decode(config_.byte_order, f.data, f.data_bytes, position_);
  if (s != sm::DecodeStatus::kOk) {
    count_bad_decode(s);
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
  heard(now);
  ++sm_.joint_positions;
  delay_.observe_feedback(now, feedback_);
  return true;
}

bool SimpleMessageLink::take_robot_status(const sm::FrameView& f) noexcept {
  const sm::DecodeStatus s = sm::decode(config_.byte_order, f.data, f.data_bytes, status_);
  if (s != sm::DecodeStatus::kOk) {
    count_bad_decode(s);
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
  return reply_in_step(f) && take_reply(f.header.reply_code, now);
}

bool SimpleMessageLink::reply_in_step(const sm::FrameView& f) noexcept {
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
  return true;
}

bool SimpleMessageLink::take_reply(int reply_code, double now) noexcept {
  if (reply_code == sm::kReplySuccess) {
    waiting_reply_ = false;
    ++accepted_;
    ++sm_.points_accepted;
    ++counters_.replies;
    failures_in_row_ = 0;
    ++next_sequence_;
    stream_.consumed(period_s_);  // the program moves on by the point the controller took
    if (waiting_is_last_ && state_ == LinkState::kRunning) {
      state_ = LinkState::kFinished;
      finished_at_s_ = now;
    }
    return true;
  }
  if (reply_code == sm::kReplyFailure) {
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
  fault(LinkStopCause::kProtocol, "motion connection: reply code %d, SUCCESS (1) or FAILURE (2) expected", reply_code);
  return false;
}

std::string SimpleMessageLink::protocol_summary() const {
  return fmt::format(
      "simple message: {} points sent, {} taken, {} FAILURE replies; buffer {} points = {:.0f} ms of lag, measured "
      "command-to-feedback delay {:.0f} ms ({} measurements); the program ran at most {:.2f} s behind its schedule "
      "(limit {:g} s); JOINT_POSITION {}, ROBOT_STATUS {}; unknown types {}, unexpected {}, wrong sequence {}; "
      "STOP_TRAJECTORY sent {}",
      sm_.points_sent, sm_.points_accepted, sm_.failures, config_.buffer_depth, buffer_lag_s() * 1e3,
      delay_.delay_s() * 1e3, delay_.measurements(), sm_.max_behind_s, config_.max_behind_s, sm_.joint_positions,
      sm_.robot_statuses, sm_.unknown_type, sm_.unexpected, sm_.wrong_sequence, sm_.stops_sent);
}

LinkPollResult SimpleMessageLink::poll(double timeout_s) noexcept {
  if (state_ == LinkState::kRefused || state_ == LinkState::kStopped) {
    if (!motion_closed_) flush();  // the STOP_TRAJECTORY, if the window held it back
    if (winding_down())
      wait_readable_any(motion_, state_port_, std::isfinite(timeout_s) ? std::max(timeout_s, 0.0) : 0.0);
    discard_input();
    return announce_terminal();
  }
  double now = clock_.now_s();
  double wait = std::isfinite(timeout_s) ? std::max(timeout_s, 0.0) : 0.0;
  if (state_ == LinkState::kRunning && !waiting_reply_) wait = std::min(wait, std::max(0.0, next_due_s() - now));
  wait_readable_any(motion_, state_port_, wait);
  now = clock_.now_s();
  if (!read_port(Port::kState, now) || !read_port(Port::kMotion, now)) return announce_terminal();

  if (!within_deadlines(now)) return announce_terminal();
  if (state_ == LinkState::kWaiting) {
    if (!have_feedback_) {
      flush();
      return LinkPollResult::kIdle;
    }
    if (!begin_session(now)) return announce_terminal();
  }
  if (state_ == LinkState::kRunning && !waiting_reply_ && now + 1e-9 >= next_due_s()) return send_point(now);
  if (!flush() && state_ == LinkState::kRunning) {
    fault(LinkStopCause::kConnection, "the motion connection is closed (a write failed)");
    return announce_terminal();
  }
  return LinkPollResult::kIdle;
}

// The session's clocks: the controller's silence, a reply that does not come, a stop ramp or the
// program's end run out. False when one of them ended the link.
bool SimpleMessageLink::within_deadlines(double now) noexcept {
  if (state_ == LinkState::kRunning) {
    // A stop ramp needs the controller to take points: one that fell silent meanwhile has nothing to ramp.
    if (ramping_down_ && now - last_state_s_ > std::max(0.25, 2.5 * period_s_)) {
      fault(LinkStopCause::kRequested,
            "stopped on request: the controller fell silent for %.2f s during the stop ramp, so deflex stopped there",
            now - last_state_s_);
      return false;
    }
    if (now - last_state_s_ > config_.state_timeout_s) {
      fault(LinkStopCause::kSilent, "no JOINT_POSITION on the state connection for %.2f s (timeout %.2f s)",
            now - last_state_s_, config_.state_timeout_s);
      return false;
    }
    if (waiting_reply_ && now - waiting_since_s_ > config_.reply_timeout_s) {
      fault(LinkStopCause::kSilent, "no reply to point %d for %.2f s (timeout %.2f s)", waiting_sequence_,
            now - waiting_since_s_, config_.reply_timeout_s);
      return false;
    }
  }
  if (state_ == LinkState::kFinished && ramping_down_ && now - finished_at_s_ > config_.buffer_depth * period_s_) {
    fault(LinkStopCause::kRequested,
          "stopped on request: the program was brought to a standstill on its path over %.2f s and the controller "
          "ran out its queue; STOP_TRAJECTORY sent",
          ramp_down_s_);
    return false;
  }
  if (state_ == LinkState::kFinished && now - finished_at_s_ > rules_.end_silence_s) {
    // The program's last point was taken: the session is over (the controller runs out its queue).
    stop_link(LinkStopCause::kEnded, "the program's last point was taken %.2f s ago: the session is over",
              now - finished_at_s_);
    return false;
  }
  return true;
}

// The session starts with the arm where the controller says it is: it must be at the program's
// start, or nothing is ever sent.
bool SimpleMessageLink::begin_session(double now) noexcept {
  if (!stream_.begin(feedback_, cycle_.correction())) {
    refuse_start(stream_.distance());
    return false;
  }
  cycle_.anchor_joints(feedback_, true);  // the first session: nothing was sent before
  state_ = LinkState::kRunning;
  schedule_origin_s_ = first_origin_s_ = now;
  return true;
}

LinkPollResult SimpleMessageLink::send_point(double now) noexcept {
  const auto t_start = std::chrono::steady_clock::now();
  const auto compute = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  };
  if (too_far_behind(now)) return announce_terminal();
  const double due_at_send = next_due_s();
  bool last = false;
  const LinkCycle::Verdict verdict = plan_point(now, last);
  if (verdict == LinkCycle::Verdict::kInvalid) {
    cycle_.not_sent(compute());
    fault(LinkStopCause::kSafety, "the compensator refused point %d (%s): nothing sent", next_sequence_,
          to_string(cycle_.output().status));
    return announce_terminal();
  }
  if (verdict == LinkCycle::Verdict::kGuard) {
    cycle_.not_sent(compute());
    fault(LinkStopCause::kSafety, "point %d: %s", next_sequence_, cycle_.guard_message());
    return announce_terminal();
  }
  const JointVector& command = cycle_.joint_command();  // float32-rounded: what the wire carries
  fill_point(command);
  // Room for this point and a STOP_TRAJECTORY behind it, always.
  unsigned char* at = outbox_.reserve(2 * kPointFrameBytes);
  if (at == nullptr) {
    ++counters_.send_errors;
    cycle_.not_sent(compute());
    fault(LinkStopCause::kTooSlow, "the controller has not read %zu bytes of earlier points: it stopped reading",
          outbox_.pending_bytes());
    return announce_terminal();
  }
  const std::size_t n = sm::encode(config_.byte_order, {sm::kJointTrajPt, sm::kServiceRequest, sm::kReplyInvalid},
                                   point_, at, kPointFrameBytes);
  outbox_.commit(n);
  if (!flush()) {
    cycle_.not_sent(compute());
    fault(LinkStopCause::kConnection, "the motion connection is closed: point %d could not be sent", next_sequence_);
    return announce_terminal();
  }
  waiting_reply_ = true;
  waiting_sequence_ = next_sequence_;
  waiting_since_s_ = now;
  waiting_is_last_ = last;
  sent_any_ = true;
  last_sent_ = command;
  ++sm_.points_sent;
  delay_.record_reference(now, command);
  // The controller does not wait for a point the way EGM and RSI wait for an answer: what counts is
  // how late the point left against its schedule (its "answer time").
  cycle_.sent(compute(), std::max(0.0, now - due_at_send));
  return LinkPollResult::kAnswered;
}

// How far behind its schedule the program runs: a controller that takes a point less often than once
// a cycle (FAILURE replies, slow replies) makes it late; past the limit the motion stops.
bool SimpleMessageLink::too_far_behind(double now) noexcept {
  const double due = first_origin_s_ + (static_cast<double>(accepted_) + 1.0 - config_.buffer_depth) * period_s_;
  sm_.behind_s = std::max(0.0, now - due);
  sm_.max_behind_s = std::max(sm_.max_behind_s, sm_.behind_s);
  if (sm_.behind_s <= config_.max_behind_s) return false;
  fault(LinkStopCause::kTooSlow,
        "the controller has taken %llu points in %.2f s, %.2f s behind the program's %.0f ms a point (limit %.2f s): "
        "it runs the program slower than planned",
        static_cast<unsigned long long>(accepted_), now - first_origin_s_, sm_.behind_s, period_s_ * 1e3,
        config_.max_behind_s);
  return true;
}

// Where the program is at this point (the stop ramp's, when one runs) and the cycle's command for it;
// `last` says the program ends with it.
LinkCycle::Verdict SimpleMessageLink::plan_point(double now, bool& last) noexcept {
  if (ramping_down_) stream_.begin_stop(ramp_down_s_);
  stream_.sample(program_, program_velocity_, blend_, blend_velocity_);
  nominal_ = program_ + blend_;
  // A planned stop: the point at rest after the ramp is the last, and what is queued is run out as at
  // the program's end.
  last = stream_.finished() || (ramping_down_ && stream_.at_standstill());
  // The point is executed buffer_depth cycles from now: the strategy is told the measured delay and
  // the configuration the point is for.
  CycleRequest rq;
  rq.t_s = now;
  rq.sequence = static_cast<std::uint32_t>(next_sequence_);
  rq.program_time_s = stream_.program_time_s();
  rq.nominal = &program_;
  rq.blend = &blend_;
  rq.feedback = &feedback_;
  rq.target = &nominal_;
  rq.delay_s = rq.lead_s = delay_.delay_s();
  rq.session_start = !sent_any_;
  return cycle_.run(rq);
}

// The JOINT_TRAJ_PT that carries the command.
void SimpleMessageLink::fill_point(const JointVector& command) noexcept {
  point_ = sm::JointTrajPt{};
  for (int j = 0; j < command.size(); ++j)
    point_.joints_rad[static_cast<std::size_t>(j)] = static_cast<float>(command[j]);
  // The velocity field: the fastest joint's share of its top speed (ABB's and Fanuc's servers ignore it).
  double velocity = 0.0;
  const RobotModel& model = cycle_.compensator().model();
  if (model.has_max_speed()) {
    const JointVector& from = sent_any_ ? last_sent_ : feedback_;
    for (int j = 0; j < command.size(); ++j) {
      velocity = std::max(velocity, std::abs(command[j] - from[j]) / period_s_ / model.max_speed()[j]);
    }
  }
  point_.sequence = next_sequence_;
  point_.velocity = static_cast<float>(std::min(velocity, 1.0));
  point_.duration_s = static_cast<float>(period_s_);
}

}  // namespace deflex
