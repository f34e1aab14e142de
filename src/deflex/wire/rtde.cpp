// RTDE packages (see rtde.hpp): a 3-byte header, then the payload, big-endian.
#include "deflex/wire/rtde.hpp"

#include <cmath>
#include <cstring>
#include <limits>

#include "deflex/wire/detail/byte_order.hpp"

namespace deflex::rtde {
namespace {

using wire_bytes::Order;
constexpr Order kBe = Order::kBig;
constexpr std::size_t kMaxPackageBytes = std::numeric_limits<std::uint16_t>::max();

struct TypeName {
  FieldType type;
  std::string_view name;
};
constexpr std::array<TypeName, 10> kTypeNames{{
    {FieldType::kBool, "BOOL"},
    {FieldType::kUint8, "UINT8"},
    {FieldType::kUint32, "UINT32"},
    {FieldType::kUint64, "UINT64"},
    {FieldType::kInt32, "INT32"},
    {FieldType::kDouble, "DOUBLE"},
    {FieldType::kVector3d, "VECTOR3D"},
    {FieldType::kVector6d, "VECTOR6D"},
    {FieldType::kVector6Int32, "VECTOR6INT32"},
    {FieldType::kVector6Uint32, "VECTOR6UINT32"},
}};

// The header and room for `payload` bytes; 0 when they do not fit.
std::size_t begin_package(PackageType type, std::size_t payload, unsigned char* out, std::size_t capacity) noexcept {
  const std::size_t total = kHeaderBytes + payload;
  if (total > kMaxPackageBytes || total > capacity) return 0;
  wire_bytes::store_u16(kBe, static_cast<std::uint16_t>(total), out);
  out[2] = static_cast<unsigned char>(type);
  return total;
}

bool is_ascii_text(std::string_view text) noexcept {
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u > 0x7e) return false;
  }
  return true;
}

// The package's payload when it is of `type`.
DecodeStatus payload_of(const unsigned char* package, std::size_t size, PackageType type, const unsigned char*& payload,
                        std::size_t& payload_bytes) noexcept {
  if (size < kHeaderBytes || wire_bytes::load_u16(kBe, package) != size) return DecodeStatus::kWrongSize;
  if (package[2] != static_cast<unsigned char>(type)) return DecodeStatus::kWrongType;
  payload = package + kHeaderBytes;
  payload_bytes = size - kHeaderBytes;
  return DecodeStatus::kOk;
}

std::size_t encode_text_payload(PackageType type, std::size_t prefix_bytes, const unsigned char* prefix,
                                std::string_view text, unsigned char* out, std::size_t capacity) noexcept {
  if (!is_ascii_text(text)) return 0;
  const std::size_t total = begin_package(type, prefix_bytes + text.size(), out, capacity);
  if (total == 0) return 0;
  if (prefix_bytes > 0) std::memcpy(out + kHeaderBytes, prefix, prefix_bytes);
  if (!text.empty()) std::memcpy(out + kHeaderBytes + prefix_bytes, text.data(), text.size());
  return total;
}

}  // namespace

bool known_package_type(std::uint8_t type) noexcept {
  switch (static_cast<PackageType>(type)) {
    case PackageType::kRequestProtocolVersion:
    case PackageType::kGetUrControlVersion:
    case PackageType::kTextMessage:
    case PackageType::kDataPackage:
    case PackageType::kSetupOutputs:
    case PackageType::kSetupInputs:
    case PackageType::kStart:
    case PackageType::kPause:
      return true;
  }
  return false;
}

std::size_t field_bytes(FieldType type) noexcept {
  switch (type) {
    case FieldType::kBool:
    case FieldType::kUint8:
      return 1;
    case FieldType::kUint32:
    case FieldType::kInt32:
      return 4;
    case FieldType::kUint64:
    case FieldType::kDouble:
      return 8;
    case FieldType::kVector3d:
      return 24;
    case FieldType::kVector6d:
      return 48;
    case FieldType::kVector6Int32:
    case FieldType::kVector6Uint32:
      return 24;
  }
  return 0;
}

const char* to_string(FieldType type) noexcept {
  for (const TypeName& t : kTypeNames) {
    if (t.type == type) return t.name.data();
  }
  return "unknown";
}

bool parse_field_type(std::string_view name, FieldType& type) noexcept {
  for (const TypeName& t : kTypeNames) {
    if (t.name == name) {
      type = t.type;
      return true;
    }
  }
  return false;
}

const char* to_string(FrameStatus status) noexcept {
  switch (status) {
    case FrameStatus::kComplete:
      return "complete";
    case FrameStatus::kIncomplete:
      return "incomplete";
    case FrameStatus::kTooShort:
      return "size below the header";
    case FrameStatus::kOversized:
      return "oversized";
  }
  return "unknown";
}

const char* to_string(DecodeStatus status) noexcept {
  switch (status) {
    case DecodeStatus::kOk:
      return "ok";
    case DecodeStatus::kWrongType:
      return "wrong package type";
    case DecodeStatus::kWrongSize:
      return "wrong size";
    case DecodeStatus::kWrongRecipe:
      return "another recipe";
    case DecodeStatus::kFieldNotFound:
      return "field not found";
    case DecodeStatus::kFieldInUse:
      return "field in use by another client";
    case DecodeStatus::kBadField:
      return "bad field";
    case DecodeStatus::kNonFinite:
      return "non-finite value";
  }
  return "unknown";
}

FrameStatus peek_package(const unsigned char* data, std::size_t size, std::size_t max_package_bytes,
                         std::size_t& package_bytes, std::uint8_t& type) noexcept {
  if (size < kHeaderBytes) return FrameStatus::kIncomplete;
  package_bytes = wire_bytes::load_u16(kBe, data);
  type = data[2];
  if (package_bytes < kHeaderBytes) return FrameStatus::kTooShort;
  if (package_bytes > max_package_bytes) return FrameStatus::kOversized;
  return size >= package_bytes ? FrameStatus::kComplete : FrameStatus::kIncomplete;
}

std::size_t encode_protocol_request(std::uint16_t version, unsigned char* out, std::size_t capacity) noexcept {
  const std::size_t total = begin_package(PackageType::kRequestProtocolVersion, 2, out, capacity);
  if (total != 0) wire_bytes::store_u16(kBe, version, out + kHeaderBytes);
  return total;
}

std::size_t encode_request(PackageType type, unsigned char* out, std::size_t capacity) noexcept {
  if (type != PackageType::kGetUrControlVersion && type != PackageType::kStart && type != PackageType::kPause) {
    return 0;
  }
  return begin_package(type, 0, out, capacity);
}

std::size_t encode_setup_outputs(double frequency_hz, std::string_view names_csv, unsigned char* out,
                                 std::size_t capacity) noexcept {
  if (!std::isfinite(frequency_hz) || frequency_hz <= 0.0 || names_csv.empty()) return 0;
  unsigned char prefix[8];
  wire_bytes::store_f64(kBe, frequency_hz, prefix);
  return encode_text_payload(PackageType::kSetupOutputs, 8, prefix, names_csv, out, capacity);
}

std::size_t encode_setup_inputs(std::string_view names_csv, unsigned char* out, std::size_t capacity) noexcept {
  if (names_csv.empty()) return 0;
  return encode_text_payload(PackageType::kSetupInputs, 0, nullptr, names_csv, out, capacity);
}

std::size_t encode_accepted(PackageType type, bool accepted, unsigned char* out, std::size_t capacity) noexcept {
  if (type != PackageType::kRequestProtocolVersion && type != PackageType::kStart && type != PackageType::kPause) {
    return 0;
  }
  const std::size_t total = begin_package(type, 1, out, capacity);
  if (total != 0) out[kHeaderBytes] = accepted ? 1 : 0;
  return total;
}

std::size_t encode(const UrControlVersion& version, unsigned char* out, std::size_t capacity) noexcept {
  const std::size_t total = begin_package(PackageType::kGetUrControlVersion, 16, out, capacity);
  if (total == 0) return 0;
  wire_bytes::store_u32(kBe, version.major, out + 3);
  wire_bytes::store_u32(kBe, version.minor, out + 7);
  wire_bytes::store_u32(kBe, version.bugfix, out + 11);
  wire_bytes::store_u32(kBe, version.build, out + 15);
  return total;
}

std::size_t encode_setup_reply(PackageType type, std::uint8_t recipe_id, std::string_view types_csv, unsigned char* out,
                               std::size_t capacity) noexcept {
  if (type != PackageType::kSetupOutputs && type != PackageType::kSetupInputs) return 0;
  return encode_text_payload(type, 1, &recipe_id, types_csv, out, capacity);
}

std::size_t encode(const TextMessage& text, unsigned char* out, std::size_t capacity) noexcept {
  if (text.message.size() > 255 || text.source.size() > 255 || text.level > 3) return 0;
  if (!is_ascii_text(text.message) || !is_ascii_text(text.source)) return 0;
  const std::size_t payload = 1 + text.message.size() + 1 + text.source.size() + 1;
  const std::size_t total = begin_package(PackageType::kTextMessage, payload, out, capacity);
  if (total == 0) return 0;
  unsigned char* p = out + kHeaderBytes;
  *p++ = static_cast<unsigned char>(text.message.size());
  if (!text.message.empty()) std::memcpy(p, text.message.data(), text.message.size());
  p += text.message.size();
  *p++ = static_cast<unsigned char>(text.source.size());
  if (!text.source.empty()) std::memcpy(p, text.source.data(), text.source.size());
  p += text.source.size();
  *p = text.level;
  return total;
}

DecodeStatus decode_accepted(const unsigned char* package, std::size_t size, PackageType type,
                             bool& accepted) noexcept {
  const unsigned char* payload = nullptr;
  std::size_t bytes = 0;
  const DecodeStatus status = payload_of(package, size, type, payload, bytes);
  if (status != DecodeStatus::kOk) return status;
  if (bytes != 1) return DecodeStatus::kWrongSize;
  accepted = payload[0] != 0;  // a truth value, as UR's own client reads it
  return DecodeStatus::kOk;
}

DecodeStatus decode_protocol_request(const unsigned char* package, std::size_t size, std::uint16_t& version) noexcept {
  const unsigned char* payload = nullptr;
  std::size_t bytes = 0;
  const DecodeStatus status = payload_of(package, size, PackageType::kRequestProtocolVersion, payload, bytes);
  if (status != DecodeStatus::kOk) return status;
  if (bytes != 2) return DecodeStatus::kWrongSize;
  version = wire_bytes::load_u16(kBe, payload);
  return DecodeStatus::kOk;
}

DecodeStatus decode(const unsigned char* package, std::size_t size, UrControlVersion& out) noexcept {
  const unsigned char* payload = nullptr;
  std::size_t bytes = 0;
  const DecodeStatus status = payload_of(package, size, PackageType::kGetUrControlVersion, payload, bytes);
  if (status != DecodeStatus::kOk) return status;
  if (bytes != 16) return DecodeStatus::kWrongSize;
  out.major = wire_bytes::load_u32(kBe, payload);
  out.minor = wire_bytes::load_u32(kBe, payload + 4);
  out.bugfix = wire_bytes::load_u32(kBe, payload + 8);
  out.build = wire_bytes::load_u32(kBe, payload + 12);
  return DecodeStatus::kOk;
}

DecodeStatus decode(const unsigned char* package, std::size_t size, TextMessage& out) noexcept {
  const unsigned char* payload = nullptr;
  std::size_t bytes = 0;
  const DecodeStatus status = payload_of(package, size, PackageType::kTextMessage, payload, bytes);
  if (status != DecodeStatus::kOk) return status;
  if (bytes < 3) return DecodeStatus::kWrongSize;
  const std::size_t message_bytes = payload[0];
  if (1 + message_bytes + 1 > bytes) return DecodeStatus::kWrongSize;
  const std::size_t source_bytes = payload[1 + message_bytes];
  if (1 + message_bytes + 1 + source_bytes + 1 != bytes) return DecodeStatus::kWrongSize;
  const auto* chars = reinterpret_cast<const char*>(payload);
  TextMessage t;
  t.message = std::string_view(chars + 1, message_bytes);
  t.source = std::string_view(chars + 2 + message_bytes, source_bytes);
  t.level = payload[bytes - 1];
  if (t.level > 3) return DecodeStatus::kBadField;
  out = t;
  return DecodeStatus::kOk;
}

DecodeStatus decode_text(const unsigned char* package, std::size_t size, std::uint16_t protocol_version,
                         TextMessage& out) noexcept {
  if (protocol_version == 2) return decode(package, size, out);
  if (protocol_version != 1) return DecodeStatus::kBadField;
  const unsigned char* payload = nullptr;
  std::size_t bytes = 0;
  const DecodeStatus status = payload_of(package, size, PackageType::kTextMessage, payload, bytes);
  if (status != DecodeStatus::kOk) return status;
  if (bytes < 1) return DecodeStatus::kWrongSize;
  if (payload[0] > 3) return DecodeStatus::kBadField;
  TextMessage t;
  t.level = payload[0];
  t.message = std::string_view(reinterpret_cast<const char*>(payload + 1), bytes - 1);
  out = t;
  return DecodeStatus::kOk;
}

bool make_recipe(std::uint8_t id, const FieldType* types, std::size_t count, Recipe& recipe) noexcept {
  if (count > kMaxRecipeFields) return false;
  Recipe r;
  r.id = id;
  r.count = count;
  for (std::size_t i = 0; i < count; ++i) {
    r.types[i] = types[i];
    r.offsets[i] = r.payload_bytes;
    r.payload_bytes += field_bytes(types[i]);
  }
  recipe = r;
  return true;
}

DecodeStatus decode_setup_reply(const unsigned char* package, std::size_t size, PackageType type, Recipe& recipe,
                                std::size_t& field) noexcept {
  if (type != PackageType::kSetupOutputs && type != PackageType::kSetupInputs) return DecodeStatus::kWrongType;
  const unsigned char* payload = nullptr;
  std::size_t bytes = 0;
  const DecodeStatus status = payload_of(package, size, type, payload, bytes);
  if (status != DecodeStatus::kOk) return status;
  if (bytes < 2) return DecodeStatus::kWrongSize;
  const std::string_view text(reinterpret_cast<const char*>(payload + 1), bytes - 1);
  std::array<FieldType, kMaxRecipeFields> types{};
  std::size_t count = 0;
  std::size_t start = 0;
  field = 0;
  while (start <= text.size()) {
    const std::size_t comma = text.find(',', start);
    const std::string_view name = text.substr(start, comma == std::string_view::npos ? text.npos : comma - start);
    if (name == "NOT_FOUND") return DecodeStatus::kFieldNotFound;
    if (name == "IN_USE") return DecodeStatus::kFieldInUse;
    if (count == kMaxRecipeFields || !parse_field_type(name, types[count])) return DecodeStatus::kBadField;
    ++count;
    ++field;
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  make_recipe(payload[0], types.data(), count, recipe);
  return DecodeStatus::kOk;
}

DecodeStatus decode_setup_request(const unsigned char* package, std::size_t size, PackageType type,
                                  double& frequency_hz, std::string_view& names_csv) noexcept {
  if (type != PackageType::kSetupOutputs && type != PackageType::kSetupInputs) return DecodeStatus::kWrongType;
  const unsigned char* payload = nullptr;
  std::size_t bytes = 0;
  const DecodeStatus status = payload_of(package, size, type, payload, bytes);
  if (status != DecodeStatus::kOk) return status;
  frequency_hz = 0.0;
  if (type == PackageType::kSetupOutputs) {
    if (bytes < 9) return DecodeStatus::kWrongSize;
    frequency_hz = wire_bytes::load_f64(kBe, payload);
    if (!std::isfinite(frequency_hz) || frequency_hz <= 0.0) return DecodeStatus::kBadField;
    payload += 8;
    bytes -= 8;
  } else if (bytes < 1) {
    return DecodeStatus::kWrongSize;
  }
  const std::string_view names(reinterpret_cast<const char*>(payload), bytes);
  if (!is_ascii_text(names)) return DecodeStatus::kBadField;
  names_csv = names;
  return DecodeStatus::kOk;
}

DecodeStatus DataView::reset(const Recipe& recipe, const unsigned char* package, std::size_t size) noexcept {
  const unsigned char* payload = nullptr;
  std::size_t bytes = 0;
  const DecodeStatus status = payload_of(package, size, PackageType::kDataPackage, payload, bytes);
  if (status != DecodeStatus::kOk) return status;
  if (bytes < 1) return DecodeStatus::kWrongSize;
  if (payload[0] != recipe.id) return DecodeStatus::kWrongRecipe;
  if (bytes != 1 + recipe.payload_bytes) return DecodeStatus::kWrongSize;
  const unsigned char* fields = payload + 1;
  for (std::size_t i = 0; i < recipe.count; ++i) {
    const FieldType t = recipe.types[i];
    if (t != FieldType::kDouble && t != FieldType::kVector3d && t != FieldType::kVector6d) continue;
    for (std::size_t k = 0; k < field_bytes(t) / 8; ++k) {
      if (!std::isfinite(wire_bytes::load_f64(kBe, fields + recipe.offsets[i] + 8 * k))) {
        return DecodeStatus::kNonFinite;
      }
    }
  }
  recipe_ = &recipe;
  fields_ = fields;
  return DecodeStatus::kOk;
}

double DataView::get_double(std::size_t field) const noexcept {
  if (recipe_ == nullptr || field >= recipe_->count || recipe_->types[field] != FieldType::kDouble) return 0.0;
  return wire_bytes::load_f64(kBe, fields_ + recipe_->offsets[field]);
}

std::int32_t DataView::get_int32(std::size_t field) const noexcept {
  if (recipe_ == nullptr || field >= recipe_->count || recipe_->types[field] != FieldType::kInt32) return 0;
  return wire_bytes::load_i32(kBe, fields_ + recipe_->offsets[field]);
}

std::uint32_t DataView::get_uint32(std::size_t field) const noexcept {
  if (recipe_ == nullptr || field >= recipe_->count || recipe_->types[field] != FieldType::kUint32) return 0;
  return wire_bytes::load_u32(kBe, fields_ + recipe_->offsets[field]);
}

std::array<double, 6> DataView::get_vector6d(std::size_t field) const noexcept {
  std::array<double, 6> v{};
  if (recipe_ == nullptr || field >= recipe_->count || recipe_->types[field] != FieldType::kVector6d) return v;
  for (std::size_t k = 0; k < 6; ++k) v[k] = wire_bytes::load_f64(kBe, fields_ + recipe_->offsets[field] + 8 * k);
  return v;
}

DataBuilder::DataBuilder(const Recipe& recipe, unsigned char* out, std::size_t capacity) noexcept
    : recipe_(recipe), out_(out), ok_(false) {
  const std::size_t total = begin_package(PackageType::kDataPackage, 1 + recipe.payload_bytes, out, capacity);
  if (total == 0) return;
  std::memset(out + kHeaderBytes, 0, 1 + recipe.payload_bytes);
  out[kHeaderBytes] = recipe.id;
  ok_ = true;
}

unsigned char* DataBuilder::slot(std::size_t field, FieldType type) noexcept {
  if (!ok_ || field >= recipe_.count || recipe_.types[field] != type) {
    ok_ = false;
    return nullptr;
  }
  return out_ + kHeaderBytes + 1 + recipe_.offsets[field];
}

bool DataBuilder::set(std::size_t field, double value) noexcept {
  unsigned char* p = std::isfinite(value) ? slot(field, FieldType::kDouble) : nullptr;
  if (p == nullptr) return ok_ = false;
  wire_bytes::store_f64(kBe, value, p);
  return true;
}

bool DataBuilder::set(std::size_t field, std::int32_t value) noexcept {
  unsigned char* p = slot(field, FieldType::kInt32);
  if (p == nullptr) return false;
  wire_bytes::store_i32(kBe, value, p);
  return true;
}

bool DataBuilder::set(std::size_t field, std::uint32_t value) noexcept {
  unsigned char* p = slot(field, FieldType::kUint32);
  if (p == nullptr) return false;
  wire_bytes::store_u32(kBe, value, p);
  return true;
}

bool DataBuilder::set(std::size_t field, const std::array<double, 6>& value) noexcept {
  for (const double v : value) {
    if (!std::isfinite(v)) return ok_ = false;
  }
  unsigned char* p = slot(field, FieldType::kVector6d);
  if (p == nullptr) return false;
  for (std::size_t k = 0; k < 6; ++k) wire_bytes::store_f64(kBe, value[k], p + 8 * k);
  return true;
}

std::size_t DataBuilder::finish() const noexcept { return ok_ ? kHeaderBytes + 1 + recipe_.payload_bytes : 0; }

}  // namespace deflex::rtde
