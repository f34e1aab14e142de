// ABB EGM messages as plain deflex structs, and the codec between them and the protobuf wire format
// (egm.proto), for both sides of the link: deflex's sensor side (decode EgmRobot, encode EgmSensor or
// EgmSensorPathCorr) and the controller's side (the simulated cell and test stand-ins). The codec
// owns preallocated protobuf messages and reuses them, so decoding and encoding in steady state never
// allocate; nothing here throws after construction.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "deflex/model/types.hpp"

namespace deflex {

/// What deflex reads from an EgmRobot message (controller -> sensor). Joints in DEGREES as on the
/// wire; convert at the edge (EgmSensorEndpoint does).
struct EgmRobotMessage {
  std::uint32_t seqno = 0;
  std::uint32_t tm_ms = 0;
  JointVector feedback_joints_deg;  ///< the joints the robot has (motor side), degrees
  /// In position guidance, the reference the controller follows: the sensor's own last target. In
  /// path correction, the controller's planned path. Optional on the wire (has_planned).
  JointVector planned_joints_deg;
  bool has_planned = false;
  int motor_state = 0;       ///< EgmMotorState: 0 undefined, 1 on, 2 off
  int mci_state = 0;         ///< EgmMCIState: 0 undefined, 1 error, 2 stopped, 3 running
  int rapid_exec_state = 0;  ///< 0 undefined, 1 stopped, 2 running
  bool mci_convergence_met = false;
};

/// What deflex sends back in an EgmSensor message: position guidance in joint mode.
struct EgmSensorMessage {
  std::uint32_t seqno = 0;
  std::uint32_t tm_ms = 0;
  JointVector planned_joints_deg;  ///< the absolute joint target, degrees
  /// Joint speed reference, deg/s; empty: none sent (the controller then follows positions only).
  JointVector speed_ref_joints_deg_s;
};

/// What deflex sends in path correction (EGMActMove + EGMMoveL/EGMMoveC): the whole current TCP
/// position correction, never an increment.
struct EgmPathCorrMessage {
  std::uint32_t seqno = 0;
  std::uint32_t tm_ms = 0;
  Vector3 pos_mm = Vector3::Zero();  ///< correction in the controller's correction frame, mm
  std::uint32_t age_ms = 0;          ///< age of the data the correction comes from, ms
};

/// KDL's sign convention: 0 accepted, < 0 rejected (the packet is counted and ignored).
enum class EgmDecodeStatus : int {
  kOk = 0,
  kMalformed = -1,           ///< not a valid protobuf message (bad wire type, bad nesting, bad enum ...)
  kTruncated = -2,           ///< a field runs past the end of the packet
  kMissingHeader = -3,       ///< no header or no sequence number
  kMissingJoints = -4,       ///< feedback joints absent, or feedback or planned joints of another count
  kNonFinite = -5,           ///< NaN or infinite joint values
  kEmpty = -6,               ///< zero-length packet
  kSequenceOutOfRange = -7,  ///< header.seqno wider than its uint32 field (protobuf would truncate it)
  kMissingRequired = -8,     ///< a field proto2 requires is missing (protobuf would print an error line)
};
[[nodiscard]] const char* to_string(EgmDecodeStatus s);

/// Thread safety: one thread at a time (it reuses its own protobuf messages); codecs on different
/// threads are independent.
class EgmCodec {
 public:
  /// `expected_joints`: the robot's joint count; packets with another count are rejected.
  explicit EgmCodec(int expected_joints);
  ~EgmCodec();
  EgmCodec(const EgmCodec&) = delete;
  EgmCodec& operator=(const EgmCodec&) = delete;

  // The sensor's side (deflex's links).
  EgmDecodeStatus decode_robot(const unsigned char* data, std::size_t size, EgmRobotMessage& out) noexcept;
  /// Returns the encoded size, 0 if it does not fit in `capacity` or a value is non-finite.
  std::size_t encode_sensor(const EgmSensorMessage& msg, unsigned char* out, std::size_t capacity) noexcept;
  std::size_t encode_path_corr(const EgmPathCorrMessage& msg, unsigned char* out, std::size_t capacity) noexcept;

  // The controller's side (the simulated cell's controllers, test stand-ins).
  std::size_t encode_robot(const EgmRobotMessage& msg, unsigned char* out, std::size_t capacity) noexcept;
  /// False for anything that is not an EgmSensor with finite joints of the expected count.
  bool decode_sensor(const unsigned char* data, std::size_t size, EgmSensorMessage& out) noexcept;
  /// False for anything that is not an EgmSensorPathCorr with a finite position.
  bool decode_path_corr(const unsigned char* data, std::size_t size, EgmPathCorrMessage& out) noexcept;

  [[nodiscard]] int expected_joints() const { return expected_joints_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  int expected_joints_;
};

/// EgmHeader.tm for a clock reading t_s (s): whole milliseconds modulo 2^32, as the uint32 field
/// wraps (after 49.7 days); 0 for a negative or non-finite time. A plain cast of t_s * 1000 to
/// uint32 would be undefined behaviour past the wrap.
[[nodiscard]] std::uint32_t egm_time_stamp_ms(double t_s) noexcept;

/// Protobuf messages its own library printed (on stderr, before deflex took them over) since start:
/// every EgmCodec routes protobuf's log to this counter instead, so a flood of bad packets cannot
/// flood the log. Parsing never logs in the first place (required fields are checked by deflex).
[[nodiscard]] std::uint64_t egm_protobuf_log_messages() noexcept;

/// Walks the top level of a protobuf buffer: kTruncated when a field runs past the end, kMalformed on
/// an impossible tag or wire type, kOk otherwise. Independent of protobuf's parser, so a truncated
/// packet is told apart from a garbled one.
[[nodiscard]] EgmDecodeStatus scan_wire_format(const unsigned char* data, std::size_t size) noexcept;

}  // namespace deflex
