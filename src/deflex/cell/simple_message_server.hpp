// The controller side of ROS-Industrial simple message streaming: an ABB robot running a RAPID
// streaming server (the motion and state servers of abb_driver, with the motion server queuing
// points for the motion task instead of collecting a whole trajectory), as it behaves and never more
// kindly:
//   - motion connection: each JOINT_TRAJ_PT service request with a sequence >= 0 is an absolute joint
//     target (rad) and a duration; it is queued in a small buffer (buffer_points) and answered SUCCESS,
//     or FAILURE when the buffer is full or the point is refused (non-finite, a duration <= 0, a joint
//     beyond its limits: that one also stops the motion, as RAPID's motion error does); the motion task
//     runs the queue as joint moves with a zone (joint_move_queue.hpp: MoveAbsJ \T, z10);
//     STOP_TRAJECTORY (-4) stops the arm as soon as possible and empties the buffer; the other special
//     sequences (download) are answered FAILURE; ABB's server answers with the header only (a
//     setting: industrial_core's servers echo the point);
//   - a frame of another type, or with too few data bytes, is skipped without a reply (RAPID raises
//     and skips the instruction); a LENGTH that cannot be a frame closes the motion connection (the
//     stream is out of step); the queue keeps running either way, and when the client goes;
//   - state connection: every state_period_s (abb_driver: 0.1 s) a JOINT_POSITION topic with the
//     motor-side joints (sequence 0), then a ROBOT_STATUS topic (publish_status);
//   - emergency_stop() (for tests): the arm stops, ROBOT_STATUS says e_stopped, every point is refused.
// It knows nothing of deflex: only the wire format, over two stream transports, on the caller's clock.
#pragma once

#include <cstdint>
#include <vector>

#include "deflex/cell/joint_move_queue.hpp"
#include "deflex/cell/robot_controller.hpp"
#include "deflex/transport/stream_transport.hpp"
#include "deflex/wire/simple_message_stream.hpp"

namespace deflex::cell {

struct SimpleMessageServerConfig {
  simple_message::ByteOrder byte_order = simple_message::ByteOrder::kLittle;  ///< RAPID PackRawBytes: little
  std::size_t buffer_points = 4;  ///< points accepted and not yet taken by the motion task
  double state_period_s = 0.1;    ///< ROS_stateServer's update_rate
  bool publish_status = true;     ///< a ROBOT_STATUS after each JOINT_POSITION, as ROS_stateServer does
  bool reply_with_data = false;   ///< ABB: header-only replies; industrial_core servers echo the point
  bool record_points = false;     ///< keep every accepted point with its time (stand-ins check the wire with it)
  std::size_t max_frame_bytes = simple_message::kDefaultMaxFrameBytes;
  JointMoveConfig motion;  ///< the motion task's MoveAbsJ with its zone
  /// The server task reads the motion connection at most once this often (0: every tick): a slow
  /// robot program (a busy task, a slow loop) that takes points less often than deflex sends them.
  double read_period_s = 0.0;
  /// Throws InputError naming the setting.
  void validate() const;
};

struct SimpleMessageServerCounters {
  std::uint64_t requests = 0;         ///< JOINT_TRAJ_PT frames taken from the motion connection
  std::uint64_t accepted = 0;         ///< points queued (SUCCESS)
  std::uint64_t refused_full = 0;     ///< FAILURE: the buffer was full
  std::uint64_t refused_invalid = 0;  ///< FAILURE: the point was refused
  std::uint64_t stops = 0;            ///< STOP_TRAJECTORY requests
  std::uint64_t skipped = 0;          ///< frames of another type or too short: no reply
  std::uint64_t replies = 0;
  std::uint64_t joint_positions = 0;  ///< JOINT_POSITION topics published
  bool motion_closed = false;         ///< the motion connection is over (the client left, or out of step)
  bool state_closed = false;
  bool out_of_step = false;  ///< a frame LENGTH that cannot be closed the motion connection
};

/// Thread safety: one thread at a time (the simulation's), with its connections.
class SimpleMessageServer final : public RobotController {
 public:
  /// The arm starts at rest at `q_start` (rad). `motion` and `state` are the accepted connections of
  /// the motion (11000) and state (11002) servers; they must outlive the server. `model` gives the
  /// joint limits, speed limits and the TCP (for the zone). Throws InputError on a bad configuration.
  SimpleMessageServer(const SimpleMessageServerConfig& config, const RobotModel& model, const JointVector& q_start,
                      StreamTransport& motion, StreamTransport& state);

  /// Advances the motion to t_s, takes what arrived on the motion connection, publishes the state when
  /// it is time; returns the motor-side joints (rad).
  const JointVector& tick(double t_s) override;
  [[nodiscard]] const char* name() const override { return "ROS-Industrial simple message server (RAPID streaming)"; }

  /// The controller's emergency stop at t_s (tests: a fault the link must see on the state port).
  void emergency_stop(double t_s);

  [[nodiscard]] const SimpleMessageServerCounters& counters() const { return counters_; }
  [[nodiscard]] const JointMoveQueue& motion() const { return moves_; }
  /// The last point accepted (rad), and its sequence number (-1 before the first).
  [[nodiscard]] const JointVector& last_target() const { return last_target_; }
  [[nodiscard]] std::int32_t last_sequence() const { return last_sequence_; }
  /// With record_points: every point accepted, in order, with the time it was taken (s) and its joints
  /// as the wire carried them (rad).
  struct AcceptedPoint {
    double t_s;
    JointVector q;
  };
  [[nodiscard]] const std::vector<AcceptedPoint>& accepted_points() const { return accepted_points_; }

 private:
  void serve_motion(double t_s);
  void publish_state(double t_s);
  void reply(const simple_message::Header& request, std::int32_t reply_code, const simple_message::JointTrajPt& point);
  void flush(StreamTransport& s, simple_message::FrameOutbox& box, bool& closed);

  SimpleMessageServerConfig config_;
  JointVector lower_, upper_;
  StreamTransport& motion_;
  StreamTransport& state_;
  JointMoveQueue moves_;
  simple_message::FrameReader reader_;
  simple_message::FrameOutbox motion_out_, state_out_;
  SimpleMessageServerCounters counters_;
  double next_publish_s_;
  double next_read_s_ = 0.0;
  bool estopped_ = false;
  JointVector q_, last_target_;
  std::vector<AcceptedPoint> accepted_points_;
  std::int32_t last_sequence_ = -1;
};

}  // namespace deflex::cell
