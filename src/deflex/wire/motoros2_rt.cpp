// MotoROS2 real-time datagrams (see motoros2_rt.hpp): packed, little-endian, field by field.
#include "deflex/wire/motoros2_rt.hpp"

#include <cmath>
#include <cstring>

#include "deflex/wire/detail/byte_order.hpp"

namespace deflex::motoros2_rt {
namespace {

using wire_bytes::Order;
constexpr Order kLe = Order::kLittle;
constexpr std::size_t kGroupAxesBytes = kGroups * kAxesPerGroup * 8;  // 512

void put_axes(const GroupAxes& axes, unsigned char* out) noexcept {
  for (std::size_t g = 0; g < kGroups; ++g) {
    for (std::size_t a = 0; a < kAxesPerGroup; ++a) {
      wire_bytes::store_f64(kLe, axes[g][a], out + 8 * (g * kAxesPerGroup + a));
    }
  }
}

bool get_axes(const unsigned char* in, GroupAxes& axes) noexcept {
  bool finite = true;
  for (std::size_t g = 0; g < kGroups; ++g) {
    for (std::size_t a = 0; a < kAxesPerGroup; ++a) {
      axes[g][a] = wire_bytes::load_f64(kLe, in + 8 * (g * kAxesPerGroup + a));
      finite = finite && std::isfinite(axes[g][a]);
    }
  }
  return finite;
}

bool finite_axes(const GroupAxes& axes) noexcept {
  for (const auto& group : axes) {
    for (const double v : group) {
      if (!std::isfinite(v)) return false;
    }
  }
  return true;
}

bool valid_tool(std::int32_t tool) noexcept { return tool >= 0 && tool <= 63; }

// A MotoPlus BOOL is a 4-byte int; anything but 0 or 1 is not a status this decoder trusts.
bool get_bool32(const unsigned char* in, bool& out) noexcept {
  const std::uint32_t v = wire_bytes::load_u32(kLe, in);
  out = v == 1;
  return v <= 1;
}

}  // namespace

const char* to_string(DecodeStatus status) noexcept {
  switch (status) {
    case DecodeStatus::kOk:
      return "ok";
    case DecodeStatus::kWrongSize:
      return "wrong size";
    case DecodeStatus::kUnknownVersion:
      return "unknown version";
    case DecodeStatus::kBadField:
      return "field out of range";
    case DecodeStatus::kNonFinite:
      return "non-finite value";
  }
  return "unknown";
}

std::size_t encode(const Command& command, unsigned char* out, std::size_t capacity) noexcept {
  if (capacity < kCommandBytes || !finite_axes(command.delta)) return 0;
  for (const std::int32_t tool : command.tool) {
    if (!valid_tool(tool)) return 0;
  }
  std::memset(out, 0, kCommandBytes);  // the reserved tail stays zero
  wire_bytes::store_i32(kLe, kVersion, out);
  wire_bytes::store_i32(kLe, static_cast<std::int32_t>(command.kind), out + 4);
  wire_bytes::store_u32(kLe, command.sequence, out + 8);
  put_axes(command.delta, out + 12);
  for (std::size_t g = 0; g < kGroups; ++g) wire_bytes::store_i32(kLe, command.tool[g], out + 524 + 4 * g);
  return kCommandBytes;
}

std::size_t encode(const Reply& reply, unsigned char* out, std::size_t capacity) noexcept {
  if (capacity < kReplyBytes) return 0;
  wire_bytes::store_u32(kLe, reply.sequence_echo, out);
  put_axes(reply.feedback_joints, out + 4);
  put_axes(reply.feedback_cartesian, out + 4 + kGroupAxesBytes);
  put_axes(reply.command_joints, out + 4 + 2 * kGroupAxesBytes);
  put_axes(reply.command_cartesian, out + 4 + 3 * kGroupAxesBytes);
  out[2052] = reply.fsu_truncated ? 1 : 0;
  return kReplyBytes;
}

std::size_t encode(const RobotState& state, unsigned char* out, std::size_t capacity) noexcept {
  if (capacity < kRobotStateBytes) return 0;
  const bool flags[] = {state.drives_powered, state.e_stopped,       state.in_motion,
                        state.play_mode,      state.motion_possible, state.error};
  for (std::size_t i = 0; i < 6; ++i) wire_bytes::store_u32(kLe, flags[i] ? 1U : 0U, out + 4 * i);
  wire_bytes::store_i32(kLe, state.error_code, out + 24);
  return kRobotStateBytes;
}

DecodeStatus decode(const unsigned char* data, std::size_t size, Command& out) noexcept {
  if (size != kCommandBytes) return DecodeStatus::kWrongSize;
  if (wire_bytes::load_i32(kLe, data) != kVersion) return DecodeStatus::kUnknownVersion;
  const std::int32_t kind = wire_bytes::load_i32(kLe, data + 4);
  if (kind != 0 && kind != 1) return DecodeStatus::kBadField;
  Command c;
  c.kind = static_cast<IncrementKind>(kind);
  c.sequence = wire_bytes::load_u32(kLe, data + 8);
  if (!get_axes(data + 12, c.delta)) return DecodeStatus::kNonFinite;
  for (std::size_t g = 0; g < kGroups; ++g) {
    c.tool[g] = wire_bytes::load_i32(kLe, data + 524 + 4 * g);
    if (!valid_tool(c.tool[g])) return DecodeStatus::kBadField;
  }
  out = c;
  return DecodeStatus::kOk;
}

DecodeStatus decode(const unsigned char* data, std::size_t size, Reply& out) noexcept {
  if (size != kReplyBytes) return DecodeStatus::kWrongSize;
  if (data[2052] > 1) return DecodeStatus::kBadField;
  Reply r;
  r.sequence_echo = wire_bytes::load_u32(kLe, data);
  const bool finite = get_axes(data + 4, r.feedback_joints) &&
                      get_axes(data + 4 + kGroupAxesBytes, r.feedback_cartesian) &&
                      get_axes(data + 4 + 2 * kGroupAxesBytes, r.command_joints) &&
                      get_axes(data + 4 + 3 * kGroupAxesBytes, r.command_cartesian);
  if (!finite) return DecodeStatus::kNonFinite;
  r.fsu_truncated = data[2052] == 1;
  out = r;
  return DecodeStatus::kOk;
}

DecodeStatus decode(const unsigned char* data, std::size_t size, RobotState& out) noexcept {
  if (size != kRobotStateBytes) return DecodeStatus::kWrongSize;
  RobotState s;
  const bool ok = get_bool32(data, s.drives_powered) && get_bool32(data + 4, s.e_stopped) &&
                  get_bool32(data + 8, s.in_motion) && get_bool32(data + 12, s.play_mode) &&
                  get_bool32(data + 16, s.motion_possible) && get_bool32(data + 20, s.error);
  if (!ok) return DecodeStatus::kBadField;
  s.error_code = wire_bytes::load_i32(kLe, data + 24);
  out = s;
  return DecodeStatus::kOk;
}

}  // namespace deflex::motoros2_rt
