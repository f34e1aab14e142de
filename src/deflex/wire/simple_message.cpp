// ROS-Industrial simple message wire format (see simple_message.hpp). Every field is assembled byte by
// byte in the chosen order, never by casting onto a struct, so the host's own order does not matter.
#include "deflex/wire/simple_message.hpp"

#include <cmath>
#include <cstring>
#include <limits>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"
#include "deflex/wire/detail/byte_order.hpp"

namespace deflex::simple_message {
namespace {

wire_bytes::Order order_of(ByteOrder order) noexcept {
  return order == ByteOrder::kLittle ? wire_bytes::Order::kLittle : wire_bytes::Order::kBig;
}
std::uint32_t read_u32(ByteOrder order, const unsigned char* p) noexcept {
  return wire_bytes::load_u32(order_of(order), p);
}
void write_u32(ByteOrder order, std::uint32_t v, unsigned char* p) noexcept {
  wire_bytes::store_u32(order_of(order), v, p);
}

void write_header(ByteOrder order, const Header& h, std::size_t data_bytes, unsigned char* out) noexcept {
  write_int32(order, static_cast<std::int32_t>(kHeaderBytes + data_bytes), out);
  write_int32(order, h.msg_type, out + 4);
  write_int32(order, h.comm_type, out + 8);
  write_int32(order, h.reply_code, out + 12);
}

DecodeStatus size_status(std::size_t bytes, std::size_t wanted) noexcept {
  if (bytes < wanted) return DecodeStatus::kTruncated;
  if (bytes > wanted) return DecodeStatus::kTooLong;
  return DecodeStatus::kOk;
}

}  // namespace

const char* to_string(ByteOrder order) { return order == ByteOrder::kLittle ? "little" : "big"; }

ByteOrder parse_byte_order(const std::string& text) {
  if (text == "little") return ByteOrder::kLittle;
  if (text == "big") return ByteOrder::kBig;
  throw InputError(fmt::format("byte order '{}' is not little or big", text));
}

std::int32_t read_int32(ByteOrder order, const unsigned char* data) noexcept {
  const std::uint32_t u = read_u32(order, data);
  std::int32_t v;
  std::memcpy(&v, &u, 4);
  return v;
}

float read_float32(ByteOrder order, const unsigned char* data) noexcept {
  const std::uint32_t u = read_u32(order, data);
  float v;
  std::memcpy(&v, &u, 4);
  return v;
}

void write_int32(ByteOrder order, std::int32_t value, unsigned char* out) noexcept {
  std::uint32_t u;
  std::memcpy(&u, &value, 4);
  write_u32(order, u, out);
}

void write_float32(ByteOrder order, float value, unsigned char* out) noexcept {
  static_assert(std::numeric_limits<float>::is_iec559 && sizeof(float) == 4, "the wire's floats are IEEE float32");
  std::uint32_t u;
  std::memcpy(&u, &value, 4);
  write_u32(order, u, out);
}

std::size_t encode_frame(ByteOrder order, const Header& header, const unsigned char* data, std::size_t data_bytes,
                         unsigned char* out, std::size_t capacity) noexcept {
  const std::size_t total = kLengthBytes + kHeaderBytes + data_bytes;
  constexpr auto kMaxData = static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()) - kHeaderBytes;
  if (total > capacity || data_bytes > kMaxData) {
    return 0;
  }
  write_header(order, header, data_bytes, out);
  if (data_bytes > 0) std::memcpy(out + kLengthBytes + kHeaderBytes, data, data_bytes);
  return total;
}

std::size_t encode(ByteOrder order, const Header& header, const JointTrajPt& point, unsigned char* out,
                   std::size_t capacity) noexcept {
  const std::size_t total = kLengthBytes + kHeaderBytes + kJointTrajPtBytes;
  if (total > capacity) return 0;
  write_header(order, header, kJointTrajPtBytes, out);
  unsigned char* d = out + kLengthBytes + kHeaderBytes;
  write_int32(order, point.sequence, d);
  for (std::size_t j = 0; j < kWireJoints; ++j) write_float32(order, point.joints_rad[j], d + 4 + 4 * j);
  write_float32(order, point.velocity, d + 4 + 4 * kWireJoints);
  write_float32(order, point.duration_s, d + 8 + 4 * kWireJoints);
  return total;
}

std::size_t encode(ByteOrder order, const Header& header, const JointPosition& position, unsigned char* out,
                   std::size_t capacity) noexcept {
  const std::size_t total = kLengthBytes + kHeaderBytes + kJointPositionBytes;
  if (total > capacity) return 0;
  write_header(order, header, kJointPositionBytes, out);
  unsigned char* d = out + kLengthBytes + kHeaderBytes;
  write_int32(order, position.sequence, d);
  for (std::size_t j = 0; j < kWireJoints; ++j) write_float32(order, position.joints_rad[j], d + 4 + 4 * j);
  return total;
}

std::size_t encode(ByteOrder order, const Header& header, const RobotStatus& status, unsigned char* out,
                   std::size_t capacity) noexcept {
  const std::size_t total = kLengthBytes + kHeaderBytes + kRobotStatusBytes;
  if (total > capacity) return 0;
  write_header(order, header, kRobotStatusBytes, out);
  unsigned char* d = out + kLengthBytes + kHeaderBytes;
  const std::int32_t fields[7] = {status.drives_powered, status.e_stopped, status.error_code,     status.in_error,
                                  status.in_motion,      status.mode,      status.motion_possible};
  for (std::size_t i = 0; i < 7; ++i) write_int32(order, fields[i], d + 4 * i);
  return total;
}

const char* to_string(FrameStatus status) {
  switch (status) {
    case FrameStatus::kComplete:
      return "complete";
    case FrameStatus::kIncomplete:
      return "incomplete";
    case FrameStatus::kTooShort:
      return "length below the 12-byte header";
    case FrameStatus::kOversized:
      return "length beyond the maximum";
  }
  return "unknown";
}

FrameStatus peek_frame(ByteOrder order, const unsigned char* data, std::size_t size, std::size_t max_frame_bytes,
                       std::size_t& frame_bytes, std::int64_t& length) noexcept {
  frame_bytes = 0;
  if (size < kLengthBytes) return FrameStatus::kIncomplete;
  length = read_int32(order, data);
  // LENGTH counts the header and the data, not itself; a negative one is as wrong as a short one.
  if (length < static_cast<std::int64_t>(kHeaderBytes)) return FrameStatus::kTooShort;
  if (static_cast<std::uint64_t>(length) > max_frame_bytes) return FrameStatus::kOversized;
  const std::size_t total = kLengthBytes + static_cast<std::size_t>(length);
  if (size < total) return FrameStatus::kIncomplete;
  frame_bytes = total;
  return FrameStatus::kComplete;
}

FrameView view_frame(ByteOrder order, const unsigned char* frame, std::size_t frame_bytes) noexcept {
  FrameView v;
  v.header.msg_type = read_int32(order, frame + 4);
  v.header.comm_type = read_int32(order, frame + 8);
  v.header.reply_code = read_int32(order, frame + 12);
  v.data = frame + kLengthBytes + kHeaderBytes;
  v.data_bytes = frame_bytes - kLengthBytes - kHeaderBytes;
  return v;
}

const char* to_string(DecodeStatus status) {
  switch (status) {
    case DecodeStatus::kOk:
      return "ok";
    case DecodeStatus::kTruncated:
      return "truncated";
    case DecodeStatus::kTooLong:
      return "longer than the message";
    case DecodeStatus::kNonFinite:
      return "non-finite value";
  }
  return "unknown";
}

DecodeStatus decode(ByteOrder order, const unsigned char* data, std::size_t bytes, JointTrajPt& out) noexcept {
  const DecodeStatus s = size_status(bytes, kJointTrajPtBytes);
  if (s != DecodeStatus::kOk) return s;
  out.sequence = read_int32(order, data);
  bool finite = true;
  for (std::size_t j = 0; j < kWireJoints; ++j) {
    out.joints_rad[j] = read_float32(order, data + 4 + 4 * j);
    finite = finite && std::isfinite(out.joints_rad[j]);
  }
  out.velocity = read_float32(order, data + 4 + 4 * kWireJoints);
  out.duration_s = read_float32(order, data + 8 + 4 * kWireJoints);
  finite = finite && std::isfinite(out.velocity) && std::isfinite(out.duration_s);
  return finite ? DecodeStatus::kOk : DecodeStatus::kNonFinite;
}

DecodeStatus decode(ByteOrder order, const unsigned char* data, std::size_t bytes, JointPosition& out) noexcept {
  const DecodeStatus s = size_status(bytes, kJointPositionBytes);
  if (s != DecodeStatus::kOk) return s;
  out.sequence = read_int32(order, data);
  bool finite = true;
  for (std::size_t j = 0; j < kWireJoints; ++j) {
    out.joints_rad[j] = read_float32(order, data + 4 + 4 * j);
    finite = finite && std::isfinite(out.joints_rad[j]);
  }
  return finite ? DecodeStatus::kOk : DecodeStatus::kNonFinite;
}

DecodeStatus decode(ByteOrder order, const unsigned char* data, std::size_t bytes, RobotStatus& out) noexcept {
  const DecodeStatus s = size_status(bytes, kRobotStatusBytes);
  if (s != DecodeStatus::kOk) return s;
  std::int32_t* fields[7] = {&out.drives_powered, &out.e_stopped, &out.error_code,     &out.in_error,
                             &out.in_motion,      &out.mode,      &out.motion_possible};
  for (std::size_t i = 0; i < 7; ++i) *fields[i] = read_int32(order, data + 4 * i);
  return DecodeStatus::kOk;
}

const char* message_type_name(std::int32_t msg_type) noexcept {
  switch (msg_type) {
    case kPing:
      return "PING";
    case kJointPosition:
      return "JOINT_POSITION";
    case kJointTrajPt:
      return "JOINT_TRAJ_PT";
    case kJointTraj:
      return "JOINT_TRAJ";
    case kRobotStatus:
      return "ROBOT_STATUS";
    default:
      return "unknown";
  }
}

}  // namespace deflex::simple_message
