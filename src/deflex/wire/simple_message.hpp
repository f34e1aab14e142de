// The ROS-Industrial "simple message" wire format (industrial_core's simple_message; the server
// programs of abb_driver and fanuc_driver speak it), used by deflex's simple-message link and by the
// simulated controller alike. Over TCP each frame is
//     int32 LENGTH (the bytes that follow: header + data), int32 MSG_TYPE, int32 COMM_TYPE,
//     int32 REPLY_CODE, data
// all in the controller's byte order, which is a setting (ABB's RAPID packs little-endian; Fanuc's
// KAREL and Motoman's FS100 big-endian). Floats are IEEE float32; joints are radians (SI already).
// Written from the protocol facts (../shared/reference/simple_message.md and the public server
// programs), not from industrial_core's code. Nothing here allocates or throws once running: a frame
// that is not what it claims to be is a status, and the caller decides what that means.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

namespace deflex::simple_message {

enum class ByteOrder { kLittle, kBig };
[[nodiscard]] const char* to_string(ByteOrder order);
/// "little" or "big"; throws InputError naming the text otherwise.
[[nodiscard]] ByteOrder parse_byte_order(const std::string& text);

// Message types (industrial_core StandardMsgTypes).
inline constexpr std::int32_t kPing = 1;
inline constexpr std::int32_t kJointPosition = 10;
inline constexpr std::int32_t kJointTrajPt = 11;
inline constexpr std::int32_t kJointTraj = 12;
inline constexpr std::int32_t kRobotStatus = 13;
// Communication types.
inline constexpr std::int32_t kTopic = 1;
inline constexpr std::int32_t kServiceRequest = 2;
inline constexpr std::int32_t kServiceReply = 3;
// Reply codes.
inline constexpr std::int32_t kReplyInvalid = 0;
inline constexpr std::int32_t kReplySuccess = 1;
inline constexpr std::int32_t kReplyFailure = 2;
// Special sequence numbers of JOINT_TRAJ_PT.
inline constexpr std::int32_t kStartTrajectoryDownload = -1;
inline constexpr std::int32_t kStartTrajectoryStreaming = -2;
inline constexpr std::int32_t kEndTrajectory = -3;
inline constexpr std::int32_t kStopTrajectory = -4;

inline constexpr std::size_t kLengthBytes = 4;   ///< the LENGTH prefix
inline constexpr std::size_t kHeaderBytes = 12;  ///< MSG_TYPE, COMM_TYPE, REPLY_CODE
inline constexpr std::size_t kWireJoints = 10;   ///< joint slots in every joint message (unused ones 0)
/// 52: sequence, joints, velocity, duration.
inline constexpr std::size_t kJointTrajPtBytes = 4 + 4 * kWireJoints + 4 + 4;
inline constexpr std::size_t kJointPositionBytes = 4 + 4 * kWireJoints;  ///< 44: sequence, joints
inline constexpr std::size_t kRobotStatusBytes = std::size_t{7} * 4;     ///< 28: seven int32
/// industrial_core reads frames into 1024-byte buffers: a longer LENGTH is no simple message deflex
/// speaks, and on a stream it means the reader is out of step.
inline constexpr std::size_t kDefaultMaxFrameBytes = 1024;

struct Header {
  std::int32_t msg_type = 0;
  std::int32_t comm_type = 0;
  std::int32_t reply_code = kReplyInvalid;
};

/// JOINT_TRAJ_PT data: an absolute joint target and how long the move to it should take.
struct JointTrajPt {
  std::int32_t sequence = 0;
  std::array<float, kWireJoints> joints_rad{};
  float velocity = 0.0f;  ///< one scalar for the move, normalised (fraction of the joints' top speed)
  float duration_s = 0.0f;
};

/// JOINT_POSITION data: where the arm is (the state port publishes it as a TOPIC).
struct JointPosition {
  std::int32_t sequence = 0;
  std::array<float, kWireJoints> joints_rad{};
};

/// ROBOT_STATUS data (the state servers publish it beside JOINT_POSITION). Tri-states: -1 unknown,
/// 0 false/off, 1 true/on; mode -1 unknown, 1 manual, 2 auto.
struct RobotStatus {
  std::int32_t drives_powered = -1;
  std::int32_t e_stopped = -1;
  std::int32_t error_code = 0;
  std::int32_t in_error = -1;
  std::int32_t in_motion = -1;
  std::int32_t mode = -1;
  std::int32_t motion_possible = -1;
};

/// A whole frame (prefix, header, `data_bytes` of data) into `out`. Returns its size, 0 when
/// `capacity` is too small or the data would not fit an int32 length.
std::size_t encode_frame(ByteOrder order, const Header& header, const unsigned char* data, std::size_t data_bytes,
                         unsigned char* out, std::size_t capacity) noexcept;
std::size_t encode(ByteOrder order, const Header& header, const JointTrajPt& point, unsigned char* out,
                   std::size_t capacity) noexcept;
std::size_t encode(ByteOrder order, const Header& header, const JointPosition& position, unsigned char* out,
                   std::size_t capacity) noexcept;
std::size_t encode(ByteOrder order, const Header& header, const RobotStatus& status, unsigned char* out,
                   std::size_t capacity) noexcept;

/// What the start of a byte stream holds.
enum class FrameStatus {
  kComplete,    ///< a whole frame of `frame_bytes` (prefix included)
  kIncomplete,  ///< not yet a whole frame: wait for more bytes
  kTooShort,    ///< LENGTH below the 12-byte header: the stream is out of step
  kOversized,   ///< LENGTH above the maximum: the stream is out of step
};
[[nodiscard]] const char* to_string(FrameStatus status);

/// Looks at the first bytes of a stream. `length` is set to the frame's LENGTH whenever the prefix
/// is there (also for kTooShort and kOversized, so the caller can name it).
FrameStatus peek_frame(ByteOrder order, const unsigned char* data, std::size_t size, std::size_t max_frame_bytes,
                       std::size_t& frame_bytes, std::int64_t& length) noexcept;

/// A complete frame's header and where its data lies (inside the caller's buffer).
struct FrameView {
  Header header;
  const unsigned char* data = nullptr;
  std::size_t data_bytes = 0;
};
/// `frame` holds a complete frame of `frame_bytes` (peek_frame said kComplete).
FrameView view_frame(ByteOrder order, const unsigned char* frame, std::size_t frame_bytes) noexcept;

enum class DecodeStatus {
  kOk,
  kTruncated,  ///< fewer data bytes than the message has
  kTooLong,    ///< more data bytes than the message has (another message's layout, e.g. float64 joints)
  kNonFinite,  ///< a NaN or infinite float
};
[[nodiscard]] const char* to_string(DecodeStatus status);

DecodeStatus decode(ByteOrder order, const unsigned char* data, std::size_t bytes, JointTrajPt& out) noexcept;
DecodeStatus decode(ByteOrder order, const unsigned char* data, std::size_t bytes, JointPosition& out) noexcept;
DecodeStatus decode(ByteOrder order, const unsigned char* data, std::size_t bytes, RobotStatus& out) noexcept;

/// The int32 at `data` in `order` (the first field of every joint message is its sequence number).
[[nodiscard]] std::int32_t read_int32(ByteOrder order, const unsigned char* data) noexcept;
[[nodiscard]] float read_float32(ByteOrder order, const unsigned char* data) noexcept;
void write_int32(ByteOrder order, std::int32_t value, unsigned char* out) noexcept;
void write_float32(ByteOrder order, float value, unsigned char* out) noexcept;

/// "JOINT_POSITION", "JOINT_TRAJ_PT", ... or "unknown" (for messages; never allocates).
[[nodiscard]] const char* message_type_name(std::int32_t msg_type) noexcept;

}  // namespace deflex::simple_message
