// FANUC Stream Motion (controller option J519) on the wire: fixed-size UDP datagrams, every numeric
// field big-endian. The PC sends a start packet to the controller (port 60015); the controller then
// sends one status packet per communication interval (8, 4 or 1 ms) and the PC answers each with one
// command packet that carries the status's sequence number and an absolute target (joints in
// degrees). Version 1 is what FANUC's manual documents (float32 targets); versions 3 and 4 (R-30iB
// Plus V9.40P and later, R-50iA) carry float64 targets, a robot-status byte and, in 4, the force
// sensor's wrench. The threshold tables (per axis: velocity, acceleration, jerk against Cartesian
// speed, no load and full load) are what the controller holds a command stream to.
//
// Written from the protocol facts gathered with their sources in the project's reference notes
// (the Wireshark dissector of the v1 layout, FANUC's own ROS 2 driver's packet definitions for v3/4),
// not from any implementation's code. Nothing here allocates or throws: a datagram that is not what
// it claims to be is a status, and the caller decides what that means.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace deflex::fanuc_j519 {

inline constexpr std::uint16_t kDefaultPort = 60015;
inline constexpr std::size_t kAxes = 9;  ///< every position array: group 1's six axes + three auxiliary

// Packet types (offset 0, uint32).
inline constexpr std::uint32_t kTypeStart = 0;    ///< v1 start (PC -> robot, 8 bytes); v1 status shares it
inline constexpr std::uint32_t kTypeCommand = 1;  ///< v1 command
inline constexpr std::uint32_t kTypeStop = 2;     ///< every version
inline constexpr std::uint32_t kTypeThreshold = 3;
inline constexpr std::uint32_t kTypeCapabilityGet = 7;
inline constexpr std::uint32_t kTypeCapabilitySet = 8;
inline constexpr std::uint32_t kTypeStartV3 = 200;
inline constexpr std::uint32_t kTypeCommandV3 = 201;
inline constexpr std::uint32_t kTypeStatusV3 = 202;
inline constexpr std::uint32_t kTypeStatusV4 = 204;

// Datagram sizes (bytes).
inline constexpr std::size_t kStartStopBytes = 8;
inline constexpr std::size_t kCommandV1Bytes = 64;
inline constexpr std::size_t kCommandV3Bytes = 344;
inline constexpr std::size_t kStatusV1Bytes = 132;
inline constexpr std::size_t kStatusV3Bytes = 388;
inline constexpr std::size_t kStatusV4Bytes = 416;
inline constexpr std::size_t kThresholdRequestBytes = 16;
inline constexpr std::size_t kThresholdReplyBytes = 184;
inline constexpr std::size_t kCapabilityBytes = 28;
inline constexpr std::size_t kIoBytes = 256;  ///< v3/v4 I/O arrays (deflex sends zeros, reads none)
inline constexpr std::size_t kMaxDatagramBytes = kStatusV4Bytes;

/// The protocol versions deflex speaks (2, double positions without the v3 timing, is not sourced).
[[nodiscard]] constexpr bool known_version(std::uint32_t version) noexcept {
  return version == 1 || version == 3 || version == 4;
}

/// A command: an absolute target (joints in degrees; or X Y Z mm, W P R deg, E1..E3), answering
/// the status of the same sequence number.
struct Command {
  std::uint32_t sequence = 0;
  bool last = false;        ///< the last command of the session (the TP program leaves IBGN)
  bool joint_style = true;  ///< v1 data style: joints (1) or Cartesian (0); v3 sends joints only
  std::array<double, kAxes> target{};
};

/// Status bits (byte 12 of every version's status).
inline constexpr std::uint8_t kStatusReady = 0x01;            ///< ready for commands (TP waits in IBGN)
inline constexpr std::uint8_t kStatusCommandReceived = 0x02;  ///< at least one command arrived
inline constexpr std::uint8_t kStatusSysReady = 0x04;         ///< servo ready
inline constexpr std::uint8_t kStatusInMotion = 0x08;
// Robot-status bits (byte 13, v3 and v4).
inline constexpr std::uint8_t kRobotInError = 0x01;
inline constexpr std::uint8_t kRobotTpEnabled = 0x02;
inline constexpr std::uint8_t kRobotEStopped = 0x04;

/// A status packet of any known version. Fields a version lacks stay at their defaults.
struct Status {
  std::uint32_t version = 1;
  std::uint32_t sequence = 0;
  std::uint8_t status_bits = 0;
  std::uint8_t robot_status = 0;          ///< v3/v4
  std::uint8_t contact_stop = 0;          ///< v3/v4: 0 none, 1 SAFE, 2 STOP, 3 DSBL, 4 ESCP
  std::uint32_t time_stamp_ms = 0;        ///< when the positions were sampled (2 ms resolution)
  std::array<float, kAxes> cartesian{};   ///< X Y Z mm, W P R deg, E1..E3
  std::array<float, kAxes> joints_deg{};  ///< the actual joints
  std::array<float, kAxes> currents_a{};
  float safety_scale = 1.0f;      ///< v3/v4
  bool has_wrench = false;        ///< v4
  std::array<float, 6> wrench{};  ///< v4: Fx Fy Fz N, Mx My Mz Nm
  std::uint32_t sensor_type = 0;  ///< v4: 0 unselected, 1 embedded, 2 external

  [[nodiscard]] bool ready() const noexcept { return (status_bits & kStatusReady) != 0; }
  [[nodiscard]] bool in_motion() const noexcept { return (status_bits & kStatusInMotion) != 0; }
  [[nodiscard]] bool in_error() const noexcept { return (robot_status & (kRobotInError | kRobotEStopped)) != 0; }
};

/// Which limit table a threshold request asks for.
enum class LimitKind : std::uint32_t { kVelocity = 0, kAcceleration = 1, kJerk = 2 };
[[nodiscard]] const char* to_string(LimitKind kind) noexcept;

struct ThresholdRequest {
  std::uint32_t axis = 1;  ///< 1..9
  LimitKind kind = LimitKind::kVelocity;
};

/// One axis's limit table for one kind: deg/s, deg/s^2 or deg/s^3 at 5, 10, ..., 100 % of the
/// maximum Cartesian speed, with no payload and with the full payload.
struct ThresholdReply {
  std::uint32_t axis = 1;
  LimitKind kind = LimitKind::kVelocity;
  std::uint32_t max_cartesian_speed_mm_s = 0;
  std::uint32_t interval_ms = 0;
  std::array<float, 20> no_load{};
  std::array<float, 20> full_load{};
  /// The strictest of the table (the limit that holds at every speed and payload): what a stream
  /// that does not track its Cartesian speed must stay under.
  [[nodiscard]] float strictest() const noexcept;
};

/// The v3 capability exchange (get: the controller fills the read-only fields; set: start_move).
struct Capability {
  std::uint32_t type = kTypeCapabilityGet;
  std::uint32_t version = 3;
  std::uint32_t id = 1;
  std::uint32_t sampling_rate_ms = 0;   ///< read-only: the communication interval
  std::uint32_t start_move = 0;         ///< commands buffered before motion starts, 0..9
  std::uint32_t available_version = 0;  ///< read-only: the controller's protocol version
  std::uint32_t status_uses_tcp = 0;    ///< 0 faceplate, 1 TCP
};

enum class DecodeStatus {
  kOk,
  kWrongSize,       ///< not the size its type and version have
  kWrongType,       ///< a packet type this decoder does not read
  kUnknownVersion,  ///< a version deflex does not speak
  kNonFinite,       ///< a NaN or infinite float
  kBadField,        ///< a field outside its range (an axis of 0 or 10, an unknown limit kind)
};
[[nodiscard]] const char* to_string(DecodeStatus status) noexcept;

/// One axis's limits on the command stream, in the stream's units (deg/s, deg/s^2, deg/s^3 for joints).
struct AxisLimits {
  double velocity = 0.0;
  double acceleration = 0.0;
  double jerk = 0.0;
};

enum class LimitExceeded { kNone, kVelocity, kAcceleration, kJerk };
[[nodiscard]] const char* to_string(LimitExceeded limit) noexcept;

/// What the controller holds a command stream to: each axis's velocity, acceleration and jerk from
/// the finite differences of successive targets at the communication interval (first, second and
/// third differences over interval^1, ^2, ^3), against its limits; the stream stops at the first
/// exceeded. The stand-in of the controller stops on it, and a link's tests check what it sent with it.
class MotionCheck {
 public:
  /// Limits per axis for the first `axes` axes (the others are not checked). `interval_s` > 0.
  MotionCheck(double interval_s, std::size_t axes, const std::array<AxisLimits, kAxes>& limits) noexcept;
  /// The arm at rest at `position` (the stream's first target is measured from there).
  void reset(const std::array<double, kAxes>& position) noexcept;
  /// The next target: the first limit it exceeds, its axis (0-based) and the value it reached.
  LimitExceeded push(const std::array<double, kAxes>& target, std::size_t& axis, double& value) noexcept;
  /// The largest |velocity|, |acceleration| and |jerk| seen on any checked axis since reset().
  [[nodiscard]] const AxisLimits& peak() const noexcept { return peak_; }

 private:
  double interval_s_;
  std::size_t axes_;
  std::array<AxisLimits, kAxes> limits_;
  std::array<std::array<double, kAxes>, 3> history_{};  // the last three targets, newest first
  AxisLimits peak_;
};

// Encoders: the datagram into `out`; return its size, or 0 when `capacity` is too small, the version
// is unknown, or a target is not finite (never a half-written datagram to send).
std::size_t encode_start(std::uint32_t version, unsigned char* out, std::size_t capacity) noexcept;
std::size_t encode_stop(std::uint32_t version, unsigned char* out, std::size_t capacity) noexcept;
std::size_t encode(std::uint32_t version, const Command& command, unsigned char* out, std::size_t capacity) noexcept;
std::size_t encode(std::uint32_t version, const Status& status, unsigned char* out, std::size_t capacity) noexcept;
std::size_t encode(const ThresholdRequest& request, unsigned char* out, std::size_t capacity) noexcept;
std::size_t encode(const ThresholdReply& reply, unsigned char* out, std::size_t capacity) noexcept;
std::size_t encode(const Capability& capability, unsigned char* out, std::size_t capacity) noexcept;

/// The packet type and version of any datagram of at least 8 bytes; false for a shorter one.
bool peek_header(const unsigned char* data, std::size_t size, std::uint32_t& type, std::uint32_t& version) noexcept;

// Decoders, both directions (the link reads status, threshold and capability replies; the cell's
// stand-in reads commands, starts, stops and requests).
DecodeStatus decode(const unsigned char* data, std::size_t size, Status& out) noexcept;
/// `version` is set to the command's version (1: float32 targets, 3/4: float64).
DecodeStatus decode(const unsigned char* data, std::size_t size, Command& out, std::uint32_t& version) noexcept;
DecodeStatus decode(const unsigned char* data, std::size_t size, ThresholdRequest& out) noexcept;
DecodeStatus decode(const unsigned char* data, std::size_t size, ThresholdReply& out) noexcept;
DecodeStatus decode(const unsigned char* data, std::size_t size, Capability& out) noexcept;

}  // namespace deflex::fanuc_j519
