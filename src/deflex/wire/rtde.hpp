// Universal Robots' Real-Time Data Exchange (RTDE) on the wire: packages on one TCP connection to the
// controller (port 30004), each `uint16 size (header included), uint8 type, payload`, every field
// big-endian. The client asks for protocol version 2, sets up an output recipe (the fields it wants
// at a frequency, up to 500 Hz on e-Series, 125 Hz on CB3) and input recipes (the registers it
// writes), starts, then reads data packages and writes its inputs whenever it likes (they keep
// their last value). deflex's link writes joint targets into input registers that a URScript
// program on the controller hands to servoj each cycle.
//
// Written from Universal Robots' RTDE guide and the facts gathered with their sources in the
// project's reference notes, then checked field by field against the layouts UR's own client reads
// and writes (UniversalRobots/RTDE_Python_Client_Library, rtde/rtde.py and rtde/serialize.py; facts,
// not code). Recipes are set up once (parsing their text may run off the real-time path); data
// packages are read and written without allocating or throwing.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

namespace deflex::rtde {

inline constexpr std::uint16_t kDefaultPort = 30004;
inline constexpr std::uint16_t kProtocolVersion = 2;  ///< the version deflex speaks (recipe ids on outputs)
inline constexpr std::size_t kHeaderBytes = 3;

enum class PackageType : std::uint8_t {
  kRequestProtocolVersion = 'V',
  kGetUrControlVersion = 'v',
  kTextMessage = 'M',
  kDataPackage = 'U',
  kSetupOutputs = 'O',
  kSetupInputs = 'I',
  kStart = 'S',
  kPause = 'P',
};
[[nodiscard]] bool known_package_type(std::uint8_t type) noexcept;

enum class FieldType : std::uint8_t {
  kBool,
  kUint8,
  kUint32,
  kUint64,
  kInt32,
  kDouble,
  kVector3d,
  kVector6d,
  kVector6Int32,
  kVector6Uint32,
};
/// The field's size on the wire (no padding between fields).
[[nodiscard]] std::size_t field_bytes(FieldType type) noexcept;
/// The controller's name of the type ("DOUBLE", "VECTOR6D", ...).
[[nodiscard]] const char* to_string(FieldType type) noexcept;
/// False for a name that is not a type (the controller's NOT_FOUND and IN_USE among them).
[[nodiscard]] bool parse_field_type(std::string_view name, FieldType& type) noexcept;

inline constexpr std::size_t kMaxRecipeFields = 64;

/// A recipe as the controller confirmed it: its id and the types of its fields, in order.
struct Recipe {
  std::uint8_t id = 0;
  std::size_t count = 0;
  std::array<FieldType, kMaxRecipeFields> types{};
  std::array<std::size_t, kMaxRecipeFields> offsets{};  ///< each field's offset after the recipe id
  std::size_t payload_bytes = 0;                        ///< the fields' bytes together
};

enum class FrameStatus {
  kComplete,    ///< a whole package of `package_bytes`
  kIncomplete,  ///< wait for more bytes
  kTooShort,    ///< a size below the 3-byte header: the stream is out of step
  kOversized,   ///< a size above the caller's maximum
};
[[nodiscard]] const char* to_string(FrameStatus status) noexcept;

/// Looks at the start of a byte stream; `package_bytes` and `type` are set whenever the header is there.
FrameStatus peek_package(const unsigned char* data, std::size_t size, std::size_t max_package_bytes,
                         std::size_t& package_bytes, std::uint8_t& type) noexcept;

enum class DecodeStatus {
  kOk,
  kWrongType,      ///< another package type than the one asked for
  kWrongSize,      ///< a payload that is not the size its type and recipe give
  kWrongRecipe,    ///< a data package of another recipe id
  kFieldNotFound,  ///< a recipe reply naming NOT_FOUND: the controller has no such field
  kFieldInUse,     ///< a recipe reply naming IN_USE: another client writes that input
  kBadField,       ///< an unknown type name, too many fields, a name that is not ASCII, a text's unknown level
  kNonFinite,      ///< a NaN or infinite double in a data package
};
[[nodiscard]] const char* to_string(DecodeStatus status) noexcept;

struct UrControlVersion {
  std::uint32_t major = 0;
  std::uint32_t minor = 0;
  std::uint32_t bugfix = 0;
  std::uint32_t build = 0;
};

/// A text message: the texts point into the caller's buffer, bytes as the controller sent them (not
/// necessarily printable). Protocol 1 has no source (it is empty).
struct TextMessage {
  std::string_view message;
  std::string_view source;
  std::uint8_t level = 3;  ///< 0 exception, 1 error, 2 warning, 3 info
};

// Encoders, both directions (the link is the client; the cell's stand-in is the controller). Each
// returns the package's size, or 0 when `capacity` is too small or the package would exceed 65535
// bytes or a field is out of range.
std::size_t encode_protocol_request(std::uint16_t version, unsigned char* out, std::size_t capacity) noexcept;
/// A package with no payload: GET_URCONTROL_VERSION, START or PAUSE requests.
std::size_t encode_request(PackageType type, unsigned char* out, std::size_t capacity) noexcept;
std::size_t encode_setup_outputs(double frequency_hz, std::string_view names_csv, unsigned char* out,
                                 std::size_t capacity) noexcept;
std::size_t encode_setup_inputs(std::string_view names_csv, unsigned char* out, std::size_t capacity) noexcept;
/// The controller's answer to V, S or P: one byte, 1 accepted, 0 not (any byte but 0 reads as accepted).
std::size_t encode_accepted(PackageType type, bool accepted, unsigned char* out, std::size_t capacity) noexcept;
std::size_t encode(const UrControlVersion& version, unsigned char* out, std::size_t capacity) noexcept;
/// The controller's answer to a setup: the recipe id, then the types (or NOT_FOUND / IN_USE), comma separated.
std::size_t encode_setup_reply(PackageType type, std::uint8_t recipe_id, std::string_view types_csv, unsigned char* out,
                               std::size_t capacity) noexcept;
std::size_t encode(const TextMessage& text, unsigned char* out, std::size_t capacity) noexcept;

// Decoders of a complete package (peek_package said kComplete; `size` includes the header).
DecodeStatus decode_accepted(const unsigned char* package, std::size_t size, PackageType type, bool& accepted) noexcept;
DecodeStatus decode_protocol_request(const unsigned char* package, std::size_t size, std::uint16_t& version) noexcept;
DecodeStatus decode(const unsigned char* package, std::size_t size, UrControlVersion& out) noexcept;
/// A text message in protocol 2's layout (lengths before message and source, the level last).
DecodeStatus decode(const unsigned char* package, std::size_t size, TextMessage& out) noexcept;
/// A text message in the layout of the protocol in force: 1 (the level, then the message to the end)
/// until the controller accepted 2; kBadField for another version.
DecodeStatus decode_text(const unsigned char* package, std::size_t size, std::uint16_t protocol_version,
                         TextMessage& out) noexcept;
/// A setup reply into `recipe`; on kFieldNotFound / kFieldInUse / kBadField `field` is the index
/// of the field the controller refused (so the caller can name it).
DecodeStatus decode_setup_reply(const unsigned char* package, std::size_t size, PackageType type, Recipe& recipe,
                                std::size_t& field) noexcept;
/// A setup request (the stand-in's side): the frequency (outputs only, else 0) and the names.
DecodeStatus decode_setup_request(const unsigned char* package, std::size_t size, PackageType type,
                                  double& frequency_hz, std::string_view& names_csv) noexcept;

/// The recipe of a list of types (the stand-in builds its recipes so; the link takes them from the
/// controller's reply). False when there are more than kMaxRecipeFields.
bool make_recipe(std::uint8_t id, const FieldType* types, std::size_t count, Recipe& recipe) noexcept;

/// A data package's fields, read in place (they point into the caller's buffer).
class DataView {
 public:
  /// kOk when `package` is a data package of `recipe` (its id, its size) with every double finite.
  DecodeStatus reset(const Recipe& recipe, const unsigned char* package, std::size_t size) noexcept;
  /// The field's value; a field of another type reads as 0 (the caller checked its recipe once).
  [[nodiscard]] double get_double(std::size_t field) const noexcept;
  [[nodiscard]] std::int32_t get_int32(std::size_t field) const noexcept;
  [[nodiscard]] std::uint32_t get_uint32(std::size_t field) const noexcept;
  [[nodiscard]] std::array<double, 6> get_vector6d(std::size_t field) const noexcept;

 private:
  const Recipe* recipe_ = nullptr;
  const unsigned char* fields_ = nullptr;
};

/// Writes one data package of a recipe: fields left unset are zero.
class DataBuilder {
 public:
  DataBuilder(const Recipe& recipe, unsigned char* out, std::size_t capacity) noexcept;
  /// False (and the package void) when the field's type is not the value's or the value not finite.
  bool set(std::size_t field, double value) noexcept;
  bool set(std::size_t field, std::int32_t value) noexcept;
  bool set(std::size_t field, std::uint32_t value) noexcept;
  bool set(std::size_t field, const std::array<double, 6>& value) noexcept;
  /// The package's size, or 0 when the capacity was too small or a set() failed.
  [[nodiscard]] std::size_t finish() const noexcept;

 private:
  [[nodiscard]] unsigned char* slot(std::size_t field, FieldType type) noexcept;
  const Recipe& recipe_;
  unsigned char* out_;
  bool ok_;
};

}  // namespace deflex::rtde
