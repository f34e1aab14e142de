// EGM messages as plain deflex structs, and the codec between them and the protobuf wire format
// (egm.proto). The codec owns preallocated protobuf messages and reuses them, so decoding and
// encoding in steady state never allocate; nothing here throws after construction.
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
  JointVector feedback_joints_deg;
  JointVector planned_joints_deg;
  int motor_state = 0;       ///< EgmMotorState: 0 undefined, 1 on, 2 off
  int mci_state = 0;         ///< EgmMCIState: 0 undefined, 1 error, 2 stopped, 3 running
  int rapid_exec_state = 0;  ///< 0 undefined, 1 stopped, 2 running
  bool mci_convergence_met = false;
};

/// What deflex sends back in an EgmSensor message: position guidance in joint mode.
struct EgmSensorMessage {
  std::uint32_t seqno = 0;
  std::uint32_t tm_ms = 0;
  JointVector planned_joints_deg;  ///< the compensated configuration, degrees
};

/// KDL's sign convention: 0 accepted, < 0 rejected (the packet is counted and ignored).
enum class EgmDecodeStatus : int {
  kOk = 0,
  kMalformed = -1,      ///< not a valid protobuf message (bad wire type, bad nesting, bad enum ...)
  kTruncated = -2,      ///< a field runs past the end of the packet
  kMissingHeader = -3,  ///< no header or no sequence number
  kMissingJoints = -4,  ///< feedback or planned joints absent, or a different count than expected
  kNonFinite = -5,      ///< NaN or infinite joint values
  kEmpty = -6,          ///< zero-length packet
};
[[nodiscard]] const char* to_string(EgmDecodeStatus s);

class EgmCodec {
 public:
  /// `expected_joints`: the robot's joint count; packets with another count are rejected.
  explicit EgmCodec(int expected_joints);
  ~EgmCodec();
  EgmCodec(const EgmCodec&) = delete;
  EgmCodec& operator=(const EgmCodec&) = delete;

  EgmDecodeStatus decode_robot(const unsigned char* data, std::size_t size, EgmRobotMessage& out) noexcept;
  /// Returns the encoded size, 0 if it does not fit in `capacity` or the joints are non-finite.
  std::size_t encode_sensor(const EgmSensorMessage& msg, unsigned char* out, std::size_t capacity) noexcept;

  // The controller's side (EgmRobotPeer, tests, the simulated cell).
  std::size_t encode_robot(const EgmRobotMessage& msg, unsigned char* out, std::size_t capacity) noexcept;
  bool decode_sensor(const unsigned char* data, std::size_t size, EgmSensorMessage& out) noexcept;

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

/// Walks the top level of a protobuf buffer: kTruncated when a field runs past the end, kMalformed on
/// an impossible tag or wire type, kOk otherwise. Independent of protobuf's parser, so a truncated
/// packet is told apart from a garbled one.
[[nodiscard]] EgmDecodeStatus scan_wire_format(const unsigned char* data, std::size_t size) noexcept;

}  // namespace deflex
