// Yaskawa MotoROS2's real-time motion interface on the wire: packed little-endian UDP datagrams. The
// PC, after the ROS 2 service start_rt_mode has put the controller in the mode, sends one command
// (port 22000) and waits for its reply before sending the next (strict lock-step, paced by the
// controller's interpolation period, 4 ms for one arm). A command carries INCREMENTS for this cycle
// (joints in radians, order S L U R B T E 8; or a Cartesian X Y Z m, Rx Ry Rz Re rad), for up to
// eight groups of eight axes; the reply carries the feedback, the command position (the sum of every
// increment the controller accepted) and whether the Functional Safety Unit truncated the previous
// increment. A status datagram goes separately to the PC's port 22001 every 10 ms.
//
// The interface is the open pull request Yaskawa-Global/motoros2#449 (not yet in a release), so the
// layout may change: the sizes below follow from its packed structs with 8 groups of 8 axes (620-
// and 2053-byte datagrams). Written from the protocol facts in the project's reference notes, not
// from the pull request's code. Nothing here allocates or throws.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace deflex::motoros2_rt {

inline constexpr std::uint16_t kDefaultPort = 22000;        ///< commands to the controller
inline constexpr std::uint16_t kDefaultStatusPort = 22001;  ///< the controller's RobotState to the PC
inline constexpr std::int32_t kVersion = 1;
inline constexpr std::size_t kGroups = 8;
inline constexpr std::size_t kAxesPerGroup = 8;
inline constexpr std::size_t kCommandBytes = 620;
inline constexpr std::size_t kReplyBytes = 2053;
inline constexpr std::size_t kRobotStateBytes = 28;
/// The controller drops the session when the sequence jumps ahead by more than this (its default).
inline constexpr std::int32_t kDefaultMaxSequenceGap = 3;

/// Axis values of every group: [group][axis].
using GroupAxes = std::array<std::array<double, kAxesPerGroup>, kGroups>;

/// What a command's increments are (the packet's type field; the service's mode numbers differ).
enum class IncrementKind : std::int32_t { kJoint = 0, kCartesian = 1 };

struct Command {
  IncrementKind kind = IncrementKind::kJoint;
  std::uint32_t sequence = 0;
  GroupAxes delta{};                         ///< this cycle's increments: rad (joints), or m and rad (Cartesian)
  std::array<std::int32_t, kGroups> tool{};  ///< tool number per group, 0..63
};

struct Reply {
  std::uint32_t sequence_echo = 0;
  GroupAxes feedback_joints{};  ///< rad, absolute, trailing the command
  GroupAxes feedback_cartesian{};
  GroupAxes command_joints{};  ///< rad: the sum of every increment the controller accepted
  GroupAxes command_cartesian{};
  bool fsu_truncated = false;  ///< the safety unit truncated the PREVIOUS cycle's increment
};

/// The status side channel (six 4-byte booleans and the first active error code).
struct RobotState {
  bool drives_powered = false;
  bool e_stopped = false;
  bool in_motion = false;
  bool play_mode = false;
  bool motion_possible = false;
  bool error = false;
  std::int32_t error_code = 0;
};

enum class DecodeStatus {
  kOk,
  kWrongSize,       ///< not the struct's size (the controller drops the session on this too)
  kUnknownVersion,  ///< a command whose version is not 1
  kBadField,        ///< an unknown increment kind, a tool outside 0..63, a boolean neither 0 nor 1
  kNonFinite,       ///< a NaN or infinite value
};
[[nodiscard]] const char* to_string(DecodeStatus status) noexcept;

// Encoders return the datagram's size, or 0 when `capacity` is too small or a value is out of range
// (a non-finite increment, a tool outside 0..63): never a half-written datagram to send.
std::size_t encode(const Command& command, unsigned char* out, std::size_t capacity) noexcept;
std::size_t encode(const Reply& reply, unsigned char* out, std::size_t capacity) noexcept;
std::size_t encode(const RobotState& state, unsigned char* out, std::size_t capacity) noexcept;

DecodeStatus decode(const unsigned char* data, std::size_t size, Command& out) noexcept;
DecodeStatus decode(const unsigned char* data, std::size_t size, Reply& out) noexcept;
DecodeStatus decode(const unsigned char* data, std::size_t size, RobotState& out) noexcept;

/// The wrap-safe signed distance from `from` to `to` (how the controller tells an old or duplicate
/// command, <= 0, from one ahead).
[[nodiscard]] constexpr std::int32_t sequence_ahead(std::uint32_t from, std::uint32_t to) noexcept {
  return static_cast<std::int32_t>(to - from);
}

}  // namespace deflex::motoros2_rt
