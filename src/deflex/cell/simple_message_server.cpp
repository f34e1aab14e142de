// The controller side of ROS-Industrial simple message streaming (see simple_message_server.hpp).
#include "deflex/cell/simple_message_server.hpp"

#include <cmath>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex::cell {

namespace sm = simple_message;

void SimpleMessageServerConfig::validate() const {
  if (buffer_points == 0 || buffer_points > 10000) {
    throw InputError(fmt::format("simple message server: the buffer holds 1..10000 points (got {})", buffer_points));
  }
  if (!std::isfinite(state_period_s) || !(state_period_s > 0.0)) {
    throw InputError(fmt::format("simple message server: the state period must be > 0 s (got {})", state_period_s));
  }
  motion.validate();
}

SimpleMessageServer::SimpleMessageServer(const SimpleMessageServerConfig& config, const RobotModel& model,
                                         const JointVector& q_start, StreamTransport& motion, StreamTransport& state)
    : config_([&] {
        config.validate();
        return config;
      }()),
      lower_(model.lower_limits()),
      upper_(model.upper_limits()),
      motion_(motion),
      state_(state),
      moves_(config.motion, model, q_start, config.buffer_points),
      reader_(config.byte_order, config.max_frame_bytes),
      motion_out_(std::size_t{64} * 1024),
      state_out_(std::size_t{64} * 1024),
      next_publish_s_(0.0),
      q_(q_start),
      last_target_(q_start) {}

void SimpleMessageServer::flush(StreamTransport& s, sm::FrameOutbox& box, bool& closed) {
  while (!closed && box.pending_bytes() > 0) {
    const long n = s.write(box.pending(), box.pending_bytes());
    if (n == StreamTransport::kClosed) {
      closed = true;
      box.clear();
      return;
    }
    if (n == 0) return;
    box.consume(static_cast<std::size_t>(n));
  }
}

void SimpleMessageServer::reply(const sm::Header& request, std::int32_t reply_code, const sm::JointTrajPt& point) {
  if (request.comm_type != sm::kServiceRequest) return;  // a topic asks for no reply
  const sm::Header h{sm::kJointTrajPt, sm::kServiceReply, reply_code};
  constexpr std::size_t kMax = sm::kLengthBytes + sm::kHeaderBytes + sm::kJointTrajPtBytes;
  unsigned char* at = motion_out_.reserve(kMax);
  if (at == nullptr) return;  // the client stopped reading: a RAPID SocketSend would block here
  const std::size_t n = config_.reply_with_data ? sm::encode(config_.byte_order, h, point, at, kMax)
                                                : sm::encode_frame(config_.byte_order, h, nullptr, 0, at, kMax);
  motion_out_.commit(n);
  ++counters_.replies;
}

void SimpleMessageServer::serve_motion(double t_s) {
  if (counters_.motion_closed) return;
  const int n_joints = static_cast<int>(q_.size());
  for (;;) {
    const long got = motion_.read(reader_.space(), reader_.space_bytes());
    if (got == StreamTransport::kClosed) {
      counters_.motion_closed = true;  // the client left: the motion task runs out its queue
      return;
    }
    if (got == 0) return;
    reader_.commit(static_cast<std::size_t>(got));
    for (;;) {
      sm::FrameView f;
      const sm::FrameStatus st = reader_.next(f);
      if (st == sm::FrameStatus::kIncomplete) break;
      if (st != sm::FrameStatus::kComplete) {
        counters_.out_of_step = counters_.motion_closed = true;
        motion_.close();
        return;
      }
      // RAPID checks the type and that at least the 52 data bytes are there; it reads those 52.
      if (f.header.msg_type != sm::kJointTrajPt || f.data_bytes < sm::kJointTrajPtBytes) {
        ++counters_.skipped;
        continue;
      }
      ++counters_.requests;
      sm::JointTrajPt p;
      const sm::DecodeStatus ds = sm::decode(config_.byte_order, f.data, sm::kJointTrajPtBytes, p);
      if (ds == sm::DecodeStatus::kOk && p.sequence == sm::kStopTrajectory) {
        moves_.stop(t_s);
        ++counters_.stops;
        reply(f.header, sm::kReplySuccess, p);
        continue;
      }
      if (ds != sm::DecodeStatus::kOk || p.sequence < 0 || estopped_ || !(p.duration_s > 0.0f)) {
        ++counters_.refused_invalid;
        reply(f.header, sm::kReplyFailure, p);
        continue;
      }
      JointVector target(n_joints);
      bool inside = true;
      for (int j = 0; j < n_joints; ++j) {
        target[j] = p.joints_rad[static_cast<std::size_t>(j)];
        inside = inside && target[j] >= lower_[j] && target[j] <= upper_[j];
      }
      if (!inside) {
        // A joint target out of range is a motion error in RAPID: the motion task stops.
        ++counters_.refused_invalid;
        moves_.stop(t_s);
        reply(f.header, sm::kReplyFailure, p);
        continue;
      }
      if (!moves_.push(t_s, target, p.duration_s)) {
        ++counters_.refused_full;
        reply(f.header, sm::kReplyFailure, p);
        continue;
      }
      ++counters_.accepted;
      last_target_ = target;
      last_sequence_ = p.sequence;
      if (config_.record_points) accepted_points_.push_back({t_s, target});
      reply(f.header, sm::kReplySuccess, p);
    }
  }
}

void SimpleMessageServer::publish_state(double /*t_s*/) {
  if (counters_.state_closed) return;
  constexpr std::size_t kJoint = sm::kLengthBytes + sm::kHeaderBytes + sm::kJointPositionBytes;
  constexpr std::size_t kStatus = sm::kLengthBytes + sm::kHeaderBytes + sm::kRobotStatusBytes;
  unsigned char* at = state_out_.reserve(kJoint + kStatus);
  if (at == nullptr) return;  // the client stopped reading: nothing more goes out
  sm::JointPosition jp;
  jp.sequence = 0;  // ROS_stateServer sends 0
  const JointVector& q = moves_.position();
  for (int j = 0; j < q.size(); ++j) jp.joints_rad[static_cast<std::size_t>(j)] = static_cast<float>(q[j]);
  std::size_t n = sm::encode(config_.byte_order, {sm::kJointPosition, sm::kTopic, sm::kReplyInvalid}, jp, at, kJoint);
  if (config_.publish_status) {
    sm::RobotStatus rs;
    rs.drives_powered = estopped_ ? 0 : 1;
    rs.e_stopped = estopped_ ? 1 : 0;
    rs.error_code = 0;
    rs.in_error = 0;
    rs.in_motion = moves_.at_rest() ? 0 : 1;
    rs.mode = 2;  // auto
    rs.motion_possible = estopped_ ? 0 : 1;
    n += sm::encode(config_.byte_order, {sm::kRobotStatus, sm::kTopic, sm::kReplyInvalid}, rs, at + n, kStatus);
  }
  state_out_.commit(n);
  ++counters_.joint_positions;
}

const JointVector& SimpleMessageServer::tick(double t_s) {
  moves_.advance(t_s);
  if (t_s + 1e-12 >= next_read_s_) {
    next_read_s_ = t_s + config_.read_period_s;
    serve_motion(t_s);
  }
  // The state connection carries nothing in; reading it finds the client gone.
  if (!counters_.state_closed) {
    unsigned char sink[64];
    for (long got = state_.read(sink, sizeof(sink)); got != 0; got = state_.read(sink, sizeof(sink))) {
      if (got == StreamTransport::kClosed) {
        counters_.state_closed = true;
        break;
      }
    }
  }
  if (t_s + 1e-12 >= next_publish_s_) {
    next_publish_s_ += config_.state_period_s;
    publish_state(t_s);
  }
  flush(motion_, motion_out_, counters_.motion_closed);
  flush(state_, state_out_, counters_.state_closed);
  q_ = moves_.position();
  return q_;
}

void SimpleMessageServer::emergency_stop(double t_s) {
  estopped_ = true;
  moves_.stop(t_s);
}

}  // namespace deflex::cell
