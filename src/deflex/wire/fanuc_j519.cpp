// FANUC Stream Motion datagrams (see fanuc_j519.hpp): every field at its offset, big-endian.
#include "deflex/wire/fanuc_j519.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>

#include "deflex/wire/detail/byte_order.hpp"

namespace deflex::fanuc_j519 {
namespace {

using wire_bytes::Order;
constexpr Order kBe = Order::kBig;

void put_header(std::uint32_t type, std::uint32_t version, unsigned char* out) noexcept {
  wire_bytes::store_u32(kBe, type, out);
  wire_bytes::store_u32(kBe, version, out + 4);
}

template <std::size_t N>
void put_floats(const std::array<float, N>& values, unsigned char* out) noexcept {
  for (std::size_t i = 0; i < N; ++i) wire_bytes::store_f32(kBe, values[i], out + 4 * i);
}

// Reads N float32; false when one is not finite (the array is then partly written, and the caller
// returns a status that says the whole packet is void).
template <std::size_t N>
bool get_floats(const unsigned char* in, std::array<float, N>& values) noexcept {
  for (std::size_t i = 0; i < N; ++i) {
    values[i] = wire_bytes::load_f32(kBe, in + 4 * i);
    if (!std::isfinite(values[i])) return false;
  }
  return true;
}

bool finite_target(const Command& command) noexcept {
  return std::all_of(command.target.begin(), command.target.end(), [](double v) { return std::isfinite(v); });
}

// The status type and size of a version (0 for an unknown version).
std::uint32_t status_type(std::uint32_t version) noexcept {
  switch (version) {
    case 1:
      return kTypeStart;
    case 3:
      return kTypeStatusV3;
    case 4:
      return kTypeStatusV4;
    default:
      return 0xffffffffU;
  }
}
std::size_t status_bytes(std::uint32_t version) noexcept {
  switch (version) {
    case 1:
      return kStatusV1Bytes;
    case 3:
      return kStatusV3Bytes;
    case 4:
      return kStatusV4Bytes;
    default:
      return 0;
  }
}

bool known_kind(std::uint32_t kind) noexcept { return kind <= 2; }
bool known_axis(std::uint32_t axis) noexcept { return axis >= 1 && axis <= kAxes; }

}  // namespace

const char* to_string(LimitKind kind) noexcept {
  switch (kind) {
    case LimitKind::kVelocity:
      return "velocity";
    case LimitKind::kAcceleration:
      return "acceleration";
    case LimitKind::kJerk:
      return "jerk";
  }
  return "unknown";
}

const char* to_string(DecodeStatus status) noexcept {
  switch (status) {
    case DecodeStatus::kOk:
      return "ok";
    case DecodeStatus::kWrongSize:
      return "wrong size";
    case DecodeStatus::kWrongType:
      return "wrong packet type";
    case DecodeStatus::kUnknownVersion:
      return "unknown protocol version";
    case DecodeStatus::kNonFinite:
      return "non-finite value";
    case DecodeStatus::kBadField:
      return "field out of range";
  }
  return "unknown";
}

float ThresholdReply::strictest() const noexcept {
  const float a = *std::min_element(no_load.begin(), no_load.end());
  const float b = *std::min_element(full_load.begin(), full_load.end());
  return std::min(a, b);
}

std::size_t encode_start(std::uint32_t version, unsigned char* out, std::size_t capacity) noexcept {
  if (!known_version(version) || capacity < kStartStopBytes) return 0;
  put_header(version == 1 ? kTypeStart : kTypeStartV3, version, out);
  return kStartStopBytes;
}

std::size_t encode_stop(std::uint32_t version, unsigned char* out, std::size_t capacity) noexcept {
  if (!known_version(version) || capacity < kStartStopBytes) return 0;
  put_header(kTypeStop, version, out);
  return kStartStopBytes;
}

std::size_t encode(std::uint32_t version, const Command& command, unsigned char* out, std::size_t capacity) noexcept {
  if (!known_version(version) || !finite_target(command)) return 0;
  if (version == 1) {
    if (capacity < kCommandV1Bytes) return 0;
    const bool fits_f32 = std::all_of(command.target.begin(), command.target.end(),
                                      [](double v) { return std::isfinite(static_cast<float>(v)); });
    if (!fits_f32) return 0;
    std::memset(out, 0, kCommandV1Bytes);  // no I/O read or written
    put_header(kTypeCommand, 1, out);
    wire_bytes::store_u32(kBe, command.sequence, out + 8);
    out[12] = command.last ? 1 : 0;
    out[18] = command.joint_style ? 1 : 0;
    for (std::size_t i = 0; i < kAxes; ++i) {
      wire_bytes::store_f32(kBe, static_cast<float>(command.target[i]), out + 28 + 4 * i);
    }
    return kCommandV1Bytes;
  }
  if (capacity < kCommandV3Bytes || !command.joint_style) return 0;
  std::memset(out, 0, kCommandV3Bytes);
  put_header(kTypeCommandV3, version, out);
  wire_bytes::store_u32(kBe, command.sequence, out + 8);
  out[12] = command.last ? 1 : 0;
  out[13] = 1;               // motion, not I/O only
  out[14] = out[15] = 0xFF;  // unused: FANUC's own driver writes 0xFFFF
  for (std::size_t i = 0; i < kAxes; ++i) wire_bytes::store_f64(kBe, command.target[i], out + 16 + 8 * i);
  return kCommandV3Bytes;
}

std::size_t encode(std::uint32_t version, const Status& status, unsigned char* out, std::size_t capacity) noexcept {
  const std::size_t bytes = status_bytes(version);
  if (bytes == 0 || capacity < bytes) return 0;
  std::memset(out, 0, bytes);
  put_header(status_type(version), version, out);
  wire_bytes::store_u32(kBe, status.sequence, out + 8);
  out[12] = status.status_bits;
  if (version == 1) {
    wire_bytes::store_u32(kBe, status.time_stamp_ms, out + 20);
    put_floats(status.cartesian, out + 24);
    put_floats(status.joints_deg, out + 60);
    put_floats(status.currents_a, out + 96);
    return bytes;
  }
  out[13] = status.robot_status;
  out[14] = status.contact_stop;
  wire_bytes::store_u32(kBe, status.time_stamp_ms, out + 16);
  put_floats(status.cartesian, out + 20);
  put_floats(status.joints_deg, out + 56);
  put_floats(status.currents_a, out + 92);
  wire_bytes::store_f32(kBe, status.safety_scale, out + 128);
  if (version == 4) {
    put_floats(status.wrench, out + 132);
    wire_bytes::store_u32(kBe, status.sensor_type, out + 156);
  }
  return bytes;
}

std::size_t encode(const ThresholdRequest& request, unsigned char* out, std::size_t capacity) noexcept {
  if (capacity < kThresholdRequestBytes || !known_axis(request.axis)) return 0;
  put_header(kTypeThreshold, 1, out);
  wire_bytes::store_u32(kBe, request.axis, out + 8);
  wire_bytes::store_u32(kBe, static_cast<std::uint32_t>(request.kind), out + 12);
  return kThresholdRequestBytes;
}

std::size_t encode(const ThresholdReply& reply, unsigned char* out, std::size_t capacity) noexcept {
  if (capacity < kThresholdReplyBytes || !known_axis(reply.axis)) return 0;
  put_header(kTypeThreshold, 1, out);
  wire_bytes::store_u32(kBe, reply.axis, out + 8);
  wire_bytes::store_u32(kBe, static_cast<std::uint32_t>(reply.kind), out + 12);
  wire_bytes::store_u32(kBe, reply.max_cartesian_speed_mm_s, out + 16);
  wire_bytes::store_u32(kBe, reply.interval_ms, out + 20);
  put_floats(reply.no_load, out + 24);
  put_floats(reply.full_load, out + 104);
  return kThresholdReplyBytes;
}

std::size_t encode(const Capability& capability, unsigned char* out, std::size_t capacity) noexcept {
  if (capacity < kCapabilityBytes) return 0;
  if (capability.type != kTypeCapabilityGet && capability.type != kTypeCapabilitySet) return 0;
  put_header(capability.type, capability.version, out);
  wire_bytes::store_u32(kBe, capability.id, out + 8);
  wire_bytes::store_u32(kBe, capability.sampling_rate_ms, out + 12);
  wire_bytes::store_u32(kBe, capability.start_move, out + 16);
  wire_bytes::store_u32(kBe, capability.available_version, out + 20);
  wire_bytes::store_u32(kBe, capability.status_uses_tcp, out + 24);
  return kCapabilityBytes;
}

bool peek_header(const unsigned char* data, std::size_t size, std::uint32_t& type, std::uint32_t& version) noexcept {
  if (size < kStartStopBytes) return false;
  type = wire_bytes::load_u32(kBe, data);
  version = wire_bytes::load_u32(kBe, data + 4);
  return true;
}

DecodeStatus decode(const unsigned char* data, std::size_t size, Status& out) noexcept {
  std::uint32_t type = 0;
  std::uint32_t version = 0;
  if (!peek_header(data, size, type, version)) return DecodeStatus::kWrongSize;
  if (!known_version(version)) return DecodeStatus::kUnknownVersion;
  if (type != status_type(version)) return DecodeStatus::kWrongType;
  if (size != status_bytes(version)) return DecodeStatus::kWrongSize;
  Status s;
  s.version = version;
  s.sequence = wire_bytes::load_u32(kBe, data + 8);
  s.status_bits = data[12];
  bool finite = true;
  if (version == 1) {
    s.time_stamp_ms = wire_bytes::load_u32(kBe, data + 20);
    finite = get_floats(data + 24, s.cartesian) && get_floats(data + 60, s.joints_deg) &&
             get_floats(data + 96, s.currents_a);
  } else {
    s.robot_status = data[13];
    s.contact_stop = data[14];
    s.time_stamp_ms = wire_bytes::load_u32(kBe, data + 16);
    s.safety_scale = wire_bytes::load_f32(kBe, data + 128);
    finite = get_floats(data + 20, s.cartesian) && get_floats(data + 56, s.joints_deg) &&
             get_floats(data + 92, s.currents_a) && std::isfinite(s.safety_scale);
    if (version == 4) {
      s.has_wrench = true;
      finite = finite && get_floats(data + 132, s.wrench);
      s.sensor_type = wire_bytes::load_u32(kBe, data + 156);
    }
  }
  if (!finite) return DecodeStatus::kNonFinite;
  out = s;
  return DecodeStatus::kOk;
}

DecodeStatus decode(const unsigned char* data, std::size_t size, Command& out, std::uint32_t& version) noexcept {
  std::uint32_t type = 0;
  if (!peek_header(data, size, type, version)) return DecodeStatus::kWrongSize;
  if (!known_version(version)) return DecodeStatus::kUnknownVersion;
  Command c;
  c.sequence = wire_bytes::load_u32(kBe, data + 8);
  if (version == 1) {
    if (type != kTypeCommand) return DecodeStatus::kWrongType;
    if (size != kCommandV1Bytes) return DecodeStatus::kWrongSize;
    if (data[12] > 1 || data[18] > 1) return DecodeStatus::kBadField;
    c.last = data[12] == 1;
    c.joint_style = data[18] == 1;
    for (std::size_t i = 0; i < kAxes; ++i) c.target[i] = wire_bytes::load_f32(kBe, data + 28 + 4 * i);
  } else {
    if (type != kTypeCommandV3) return DecodeStatus::kWrongType;
    if (size != kCommandV3Bytes) return DecodeStatus::kWrongSize;
    if (data[12] > 1 || data[13] > 1) return DecodeStatus::kBadField;
    c.last = data[12] == 1;
    for (std::size_t i = 0; i < kAxes; ++i) c.target[i] = wire_bytes::load_f64(kBe, data + 16 + 8 * i);
  }
  if (!finite_target(c)) return DecodeStatus::kNonFinite;
  out = c;
  return DecodeStatus::kOk;
}

DecodeStatus decode(const unsigned char* data, std::size_t size, ThresholdRequest& out) noexcept {
  std::uint32_t type = 0;
  std::uint32_t version = 0;
  if (!peek_header(data, size, type, version)) return DecodeStatus::kWrongSize;
  if (type != kTypeThreshold) return DecodeStatus::kWrongType;
  if (size != kThresholdRequestBytes) return DecodeStatus::kWrongSize;
  const std::uint32_t axis = wire_bytes::load_u32(kBe, data + 8);
  const std::uint32_t kind = wire_bytes::load_u32(kBe, data + 12);
  if (!known_axis(axis) || !known_kind(kind)) return DecodeStatus::kBadField;
  out.axis = axis;
  out.kind = static_cast<LimitKind>(kind);
  return DecodeStatus::kOk;
}

DecodeStatus decode(const unsigned char* data, std::size_t size, ThresholdReply& out) noexcept {
  std::uint32_t type = 0;
  std::uint32_t version = 0;
  if (!peek_header(data, size, type, version)) return DecodeStatus::kWrongSize;
  if (type != kTypeThreshold) return DecodeStatus::kWrongType;
  if (size != kThresholdReplyBytes) return DecodeStatus::kWrongSize;
  ThresholdReply r;
  r.axis = wire_bytes::load_u32(kBe, data + 8);
  const std::uint32_t kind = wire_bytes::load_u32(kBe, data + 12);
  if (!known_axis(r.axis) || !known_kind(kind)) return DecodeStatus::kBadField;
  r.kind = static_cast<LimitKind>(kind);
  r.max_cartesian_speed_mm_s = wire_bytes::load_u32(kBe, data + 16);
  r.interval_ms = wire_bytes::load_u32(kBe, data + 20);
  if (!get_floats(data + 24, r.no_load) || !get_floats(data + 104, r.full_load)) return DecodeStatus::kNonFinite;
  // A limit is a positive rate; zero or less would make any motion a violation.
  if (r.strictest() <= 0.0f) return DecodeStatus::kBadField;
  out = r;
  return DecodeStatus::kOk;
}

DecodeStatus decode(const unsigned char* data, std::size_t size, Capability& out) noexcept {
  std::uint32_t type = 0;
  std::uint32_t version = 0;
  if (!peek_header(data, size, type, version)) return DecodeStatus::kWrongSize;
  if (type != kTypeCapabilityGet && type != kTypeCapabilitySet) return DecodeStatus::kWrongType;
  if (size != kCapabilityBytes) return DecodeStatus::kWrongSize;
  Capability c;
  c.type = type;
  c.version = version;
  c.id = wire_bytes::load_u32(kBe, data + 8);
  c.sampling_rate_ms = wire_bytes::load_u32(kBe, data + 12);
  c.start_move = wire_bytes::load_u32(kBe, data + 16);
  c.available_version = wire_bytes::load_u32(kBe, data + 20);
  c.status_uses_tcp = wire_bytes::load_u32(kBe, data + 24);
  if (c.start_move > 9 || c.status_uses_tcp > 1) return DecodeStatus::kBadField;
  out = c;
  return DecodeStatus::kOk;
}

const char* to_string(LimitExceeded limit) noexcept {
  switch (limit) {
    case LimitExceeded::kNone:
      return "none";
    case LimitExceeded::kVelocity:
      return "joint velocity";
    case LimitExceeded::kAcceleration:
      return "joint acceleration";
    case LimitExceeded::kJerk:
      return "joint jerk";
  }
  return "unknown";
}

MotionCheck::MotionCheck(double interval_s, std::size_t axes, const std::array<AxisLimits, kAxes>& limits) noexcept
    : interval_s_(interval_s), axes_(std::min(axes, kAxes)), limits_(limits) {}

void MotionCheck::reset(const std::array<double, kAxes>& position) noexcept {
  history_.fill(position);
  peak_ = AxisLimits{};
}

LimitExceeded MotionCheck::push(const std::array<double, kAxes>& target, std::size_t& axis, double& value) noexcept {
  const double t = interval_s_;
  LimitExceeded first = LimitExceeded::kNone;
  for (std::size_t i = 0; i < axes_; ++i) {
    const double p0 = target[i];
    const double p1 = history_[0][i];
    const double p2 = history_[1][i];
    const double p3 = history_[2][i];
    const double v = (p0 - p1) / t;
    const double a = (p0 - 2.0 * p1 + p2) / (t * t);
    const double j = (p0 - 3.0 * p1 + 3.0 * p2 - p3) / (t * t * t);
    peak_.velocity = std::max(peak_.velocity, std::abs(v));
    peak_.acceleration = std::max(peak_.acceleration, std::abs(a));
    peak_.jerk = std::max(peak_.jerk, std::abs(j));
    if (first != LimitExceeded::kNone) continue;
    const AxisLimits& l = limits_[i];
    const std::array<std::pair<LimitExceeded, double>, 3> checks{
        {{LimitExceeded::kVelocity, std::abs(v) - l.velocity},
         {LimitExceeded::kAcceleration, std::abs(a) - l.acceleration},
         {LimitExceeded::kJerk, std::abs(j) - l.jerk}}};
    const double values[] = {v, a, j};
    for (std::size_t k = 0; k < checks.size(); ++k) {
      if (checks[k].second > 0.0 || !std::isfinite(values[k])) {
        first = checks[k].first;
        axis = i;
        value = values[k];
        break;
      }
    }
  }
  history_[2] = history_[1];
  history_[1] = history_[0];
  history_[0] = target;
  return first;
}

}  // namespace deflex::fanuc_j519
