// RTDE packages against images written here by hand from Universal Robots' RTDE guide, the facts in
// ../shared/reference/ur_rtde.md and the layouts of UR's own client (UniversalRobots/
// RTDE_Python_Client_Library, rtde/rtde.py and rtde/serialize.py, cited at each test that relies on
// them): uint16 size (header included), uint8 type ('V' 56, 'O' 4F, 'I' 49, 'U' 55, 'S' 53, 'P' 50,
// 'M' 4D, 'v' 76), big-endian payloads, doubles as their IEEE bit patterns (125.0 = 405F400000000000,
// 0.5 = 3FE0000000000000, -1.5 = BFF8000000000000). The handshake both ways, recipes with refusals
// named by field, data packages read and written in place, framing on a stream cut anywhere, garbage
// refused; no allocation on the data path.
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>

#include <gtest/gtest.h>

#include "deflex/wire/rtde.hpp"
#include "hex_bytes.hpp"
#include "support/allocation_guard.hpp"

namespace deflex {
namespace {

using test::Bytes;
using test::hex;

Bytes ascii(std::string_view text) { return Bytes(text.begin(), text.end()); }
Bytes cat(Bytes a, const Bytes& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

TEST(Rtde, HandshakeRequestsAsTheGuideLaysThemOut) {
  unsigned char out[256];
  ASSERT_EQ(rtde::encode_protocol_request(2, out, sizeof out), 5u);
  EXPECT_EQ(Bytes(out, out + 5), hex("0005 56 0002"));
  ASSERT_EQ(rtde::encode_request(rtde::PackageType::kGetUrControlVersion, out, sizeof out), 3u);
  EXPECT_EQ(Bytes(out, out + 3), hex("0003 76"));
  ASSERT_EQ(rtde::encode_request(rtde::PackageType::kStart, out, sizeof out), 3u);
  EXPECT_EQ(Bytes(out, out + 3), hex("0003 53"));
  ASSERT_EQ(rtde::encode_request(rtde::PackageType::kPause, out, sizeof out), 3u);
  EXPECT_EQ(Bytes(out, out + 3), hex("0003 50"));
  EXPECT_EQ(rtde::encode_request(rtde::PackageType::kDataPackage, out, sizeof out), 0u);

  const std::string_view outputs = "timestamp,actual_q";
  ASSERT_EQ(rtde::encode_setup_outputs(125.0, outputs, out, sizeof out), 3u + 8 + outputs.size());
  EXPECT_EQ(Bytes(out, out + 29), cat(hex("001D 4F 405F400000000000"), ascii(outputs)));
  const std::string_view inputs = "input_int_register_24,input_double_register_24";
  const std::size_t n = rtde::encode_setup_inputs(inputs, out, sizeof out);
  ASSERT_EQ(n, 3u + inputs.size());
  EXPECT_EQ(Bytes(out, out + n), cat(hex("0031 49"), ascii(inputs)));

  double frequency = 0.0;
  std::string_view names;
  ASSERT_EQ(rtde::decode_setup_request(out, n, rtde::PackageType::kSetupInputs, frequency, names),
            rtde::DecodeStatus::kOk);
  EXPECT_EQ(names, inputs);
  EXPECT_EQ(frequency, 0.0);
  std::uint16_t version = 0;
  const Bytes v = hex("0005 56 0002");
  ASSERT_EQ(rtde::decode_protocol_request(v.data(), v.size(), version), rtde::DecodeStatus::kOk);
  EXPECT_EQ(version, 2);
}

TEST(Rtde, ControllerRepliesDecoded) {
  bool accepted = false;
  const Bytes yes = hex("0004 56 01");
  ASSERT_EQ(rtde::decode_accepted(yes.data(), yes.size(), rtde::PackageType::kRequestProtocolVersion, accepted),
            rtde::DecodeStatus::kOk);
  EXPECT_TRUE(accepted);
  const Bytes no = hex("0004 53 00");
  ASSERT_EQ(rtde::decode_accepted(no.data(), no.size(), rtde::PackageType::kStart, accepted), rtde::DecodeStatus::kOk);
  EXPECT_FALSE(accepted);
  EXPECT_EQ(rtde::decode_accepted(no.data(), no.size(), rtde::PackageType::kPause, accepted),
            rtde::DecodeStatus::kWrongType);

  const Bytes version = hex("0013 76 00000005 0000000F 00000001 000013C4");
  rtde::UrControlVersion v;
  ASSERT_EQ(rtde::decode(version.data(), version.size(), v), rtde::DecodeStatus::kOk);
  EXPECT_EQ(v.major, 5u);
  EXPECT_EQ(v.minor, 15u);
  EXPECT_EQ(v.bugfix, 1u);
  EXPECT_EQ(v.build, 5060u);
  unsigned char out[64];
  ASSERT_EQ(rtde::encode(v, out, sizeof out), version.size());
  EXPECT_EQ(Bytes(out, out + version.size()), version);

  // "C204A3", source "Controller", level 1 (error).
  const Bytes text = cat(cat(cat(hex("0016 4D 06"), ascii("C204A3")), cat(hex("0A"), ascii("Controller"))), hex("01"));
  rtde::TextMessage t;
  ASSERT_EQ(rtde::decode(text.data(), text.size(), t), rtde::DecodeStatus::kOk);
  EXPECT_EQ(t.message, "C204A3");
  EXPECT_EQ(t.source, "Controller");
  EXPECT_EQ(t.level, 1);
  ASSERT_EQ(rtde::encode(t, out, sizeof out), text.size());
  EXPECT_EQ(Bytes(out, out + text.size()), text);
  Bytes short_source = text;
  short_source[3 + 1 + 6] = 11;  // the source's length runs past the package
  EXPECT_EQ(rtde::decode(short_source.data(), short_source.size(), t), rtde::DecodeStatus::kWrongSize);
}

// UR's client takes the reply byte of a protocol version, start or pause request as a truth value:
// any byte but 0 is accepted (UniversalRobots/RTDE_Python_Client_Library, rtde/serialize.py,
// ReturnValue: bool of a '>B').
TEST(Rtde, AnyNonZeroReplyByteIsAccepted) {
  bool accepted = false;
  const Bytes two = hex("0004 56 02");
  ASSERT_EQ(rtde::decode_accepted(two.data(), two.size(), rtde::PackageType::kRequestProtocolVersion, accepted),
            rtde::DecodeStatus::kOk);
  EXPECT_TRUE(accepted);
  accepted = false;
  const Bytes all_ones = hex("0004 53 FF");
  ASSERT_EQ(rtde::decode_accepted(all_ones.data(), all_ones.size(), rtde::PackageType::kStart, accepted),
            rtde::DecodeStatus::kOk);
  EXPECT_TRUE(accepted);
  const Bytes zero = hex("0004 50 00");
  ASSERT_EQ(rtde::decode_accepted(zero.data(), zero.size(), rtde::PackageType::kPause, accepted),
            rtde::DecodeStatus::kOk);
  EXPECT_FALSE(accepted);
}

// A text message's texts are bytes of the lengths given, taken as sent (UR's client slices them
// without looking at them: UniversalRobots/RTDE_Python_Client_Library, rtde/serialize.py, Message):
// a controller's error naming a temperature in degrees is still the controller's error.
TEST(Rtde, TextMessageBytesAreTakenAsSent) {
  // "J3 71\xB0C\n" (8 bytes), source "URControl" (9), level 1: 3 + 1 + 8 + 1 + 9 + 1 = 23.
  const Bytes text =
      cat(cat(cat(hex("0017 4D 08"), ascii("J3 71")), hex("B0 43 0A 09")), cat(ascii("URControl"), hex("01")));
  ASSERT_EQ(text.size(), 23u);
  rtde::TextMessage t;
  ASSERT_EQ(rtde::decode(text.data(), text.size(), t), rtde::DecodeStatus::kOk);
  EXPECT_EQ(t.message, std::string_view("J3 71\xB0"
                                        "C\n"));
  EXPECT_EQ(t.source, "URControl");
  EXPECT_EQ(t.level, 1);
  Bytes level_4 = text;
  level_4.back() = 4;
  EXPECT_EQ(rtde::decode(level_4.data(), level_4.size(), t), rtde::DecodeStatus::kBadField)
      << "levels are 0 exception, 1 error, 2 warning, 3 info; another is not one of them";
}

// Protocol 1's text message is a level, then the message to the package's end, no source; protocol 2's
// has a length before the message and the source and the level last (UniversalRobots/
// RTDE_Python_Client_Library, rtde/serialize.py, MessageV1 and Message; rtde/rtde.py reads protocol 1
// until the controller accepted protocol 2).
TEST(Rtde, TextMessageInEachProtocolVersion) {
  const Bytes v1 = cat(hex("000A 4D 01"), ascii("C204A3"));  // error "C204A3": 3 + 1 + 6 = 10
  rtde::TextMessage t;
  ASSERT_EQ(rtde::decode_text(v1.data(), v1.size(), 1, t), rtde::DecodeStatus::kOk);
  EXPECT_EQ(t.level, 1);
  EXPECT_EQ(t.message, "C204A3");
  EXPECT_EQ(t.source, "");
  EXPECT_NE(rtde::decode_text(v1.data(), v1.size(), 2, t), rtde::DecodeStatus::kOk)
      << "read as protocol 2, its first byte would be a length";
  const Bytes v1_empty = hex("0004 4D 03");
  ASSERT_EQ(rtde::decode_text(v1_empty.data(), v1_empty.size(), 1, t), rtde::DecodeStatus::kOk);
  EXPECT_EQ(t.level, 3);
  EXPECT_EQ(t.message, "");
  const Bytes v1_nothing = hex("0003 4D");
  EXPECT_EQ(rtde::decode_text(v1_nothing.data(), v1_nothing.size(), 1, t), rtde::DecodeStatus::kWrongSize);
  Bytes v1_level_9 = v1;
  v1_level_9[3] = 9;
  EXPECT_EQ(rtde::decode_text(v1_level_9.data(), v1_level_9.size(), 1, t), rtde::DecodeStatus::kBadField);

  const Bytes v2 = cat(cat(hex("0014 4D 06"), ascii("C204A3")), cat(cat(hex("08"), ascii("URScript")), hex("00")));
  ASSERT_EQ(rtde::decode_text(v2.data(), v2.size(), 2, t), rtde::DecodeStatus::kOk);
  EXPECT_EQ(t.level, 0);
  EXPECT_EQ(t.message, "C204A3");
  EXPECT_EQ(t.source, "URScript");
  EXPECT_EQ(rtde::decode_text(v2.data(), v2.size(), 3, t), rtde::DecodeStatus::kBadField)
      << "a protocol deflex does not speak";
}

TEST(Rtde, RecipeRepliesGiveTypesAndOffsetsOrNameTheRefusedField) {
  const Bytes reply = cat(hex("0019 4F 01"), ascii("DOUBLE,VECTOR6D,INT32"));
  rtde::Recipe recipe;
  std::size_t field = 99;
  ASSERT_EQ(rtde::decode_setup_reply(reply.data(), reply.size(), rtde::PackageType::kSetupOutputs, recipe, field),
            rtde::DecodeStatus::kOk);
  EXPECT_EQ(recipe.id, 1);
  ASSERT_EQ(recipe.count, 3u);
  EXPECT_EQ(recipe.types[1], rtde::FieldType::kVector6d);
  EXPECT_EQ(recipe.offsets[1], 8u);
  EXPECT_EQ(recipe.offsets[2], 56u);
  EXPECT_EQ(recipe.payload_bytes, 60u);

  const Bytes in_use = cat(hex("0017 49 02"), ascii("INT32,IN_USE,DOUBLE"));
  EXPECT_EQ(rtde::decode_setup_reply(in_use.data(), in_use.size(), rtde::PackageType::kSetupInputs, recipe, field),
            rtde::DecodeStatus::kFieldInUse);
  EXPECT_EQ(field, 1u);
  const Bytes not_found = cat(hex("000D 4F 01"), ascii("NOT_FOUND"));
  EXPECT_EQ(
      rtde::decode_setup_reply(not_found.data(), not_found.size(), rtde::PackageType::kSetupOutputs, recipe, field),
      rtde::DecodeStatus::kFieldNotFound);
  EXPECT_EQ(field, 0u);
  const Bytes empty_name = cat(hex("000F 4F 01"), ascii("DOUBLE,,INT"));
  EXPECT_EQ(
      rtde::decode_setup_reply(empty_name.data(), empty_name.size(), rtde::PackageType::kSetupOutputs, recipe, field),
      rtde::DecodeStatus::kBadField);
  EXPECT_EQ(field, 1u);
  EXPECT_EQ(rtde::decode_setup_reply(reply.data(), reply.size(), rtde::PackageType::kSetupInputs, recipe, field),
            rtde::DecodeStatus::kWrongType);
}

TEST(Rtde, DataPackagesReadAndWrittenInPlace) {
  const std::array<rtde::FieldType, 3> types{rtde::FieldType::kDouble, rtde::FieldType::kVector6d,
                                             rtde::FieldType::kInt32};
  rtde::Recipe recipe;
  ASSERT_TRUE(rtde::make_recipe(1, types.data(), types.size(), recipe));
  Bytes package = hex("0040 55 01 3FE0000000000000");  // size 64, recipe 1, timestamp 0.5 s
  package = cat(package, hex("BFF8000000000000"));     // q[0] = -1.5 rad
  package = test::zeros_after(package, 4 * 8);
  package = cat(package, hex("3FE0000000000000 FFFFFFFE"));  // q[5] = 0.5 rad, register -2
  ASSERT_EQ(package.size(), 64u);

  rtde::DataView view;
  ASSERT_EQ(view.reset(recipe, package.data(), package.size()), rtde::DecodeStatus::kOk);
  EXPECT_EQ(view.get_double(0), 0.5);
  const std::array<double, 6> q = view.get_vector6d(1);
  EXPECT_EQ(q[0], -1.5);
  EXPECT_EQ(q[5], 0.5);
  EXPECT_EQ(view.get_int32(2), -2);
  EXPECT_EQ(view.get_int32(0), 0) << "a field read as another type reads 0";

  unsigned char out[128];
  rtde::DataBuilder builder(recipe, out, sizeof out);
  EXPECT_TRUE(builder.set(0, 0.5));
  EXPECT_TRUE(builder.set(1, q));
  EXPECT_TRUE(builder.set(2, std::int32_t{-2}));
  ASSERT_EQ(builder.finish(), package.size());
  EXPECT_EQ(Bytes(out, out + package.size()), package);

  rtde::DataBuilder wrong(recipe, out, sizeof out);
  EXPECT_FALSE(wrong.set(2, 1.0)) << "field 2 is an INT32";
  EXPECT_EQ(wrong.finish(), 0u);
  rtde::DataBuilder nan(recipe, out, sizeof out);
  EXPECT_FALSE(nan.set(0, std::numeric_limits<double>::quiet_NaN()));
  EXPECT_EQ(nan.finish(), 0u);
  rtde::DataBuilder small(recipe, out, 63);
  EXPECT_EQ(small.finish(), 0u);

  Bytes other_recipe = package;
  other_recipe[3] = 2;
  EXPECT_EQ(view.reset(recipe, other_recipe.data(), other_recipe.size()), rtde::DecodeStatus::kWrongRecipe);
  Bytes nan_q = package;
  nan_q[12] = 0x7F;
  nan_q[13] = 0xF8;
  EXPECT_EQ(view.reset(recipe, nan_q.data(), nan_q.size()), rtde::DecodeStatus::kNonFinite);
  Bytes shorter = package;
  shorter.pop_back();
  shorter[1] = 63;
  EXPECT_EQ(view.reset(recipe, shorter.data(), shorter.size()), rtde::DecodeStatus::kWrongSize);
}

// Every type the controller names, at its offset: the sizes are the struct formats UR's own client
// builds from a recipe reply, big-endian with standard sizes and no padding, the recipe id first
// (UniversalRobots/RTDE_Python_Client_Library, rtde/serialize.py, DataConfig.unpack_recipe: BOOL '?',
// UINT8 'B', UINT32 'I', UINT64 'Q', INT32 'i', DOUBLE 'd', VECTOR3D 3 'd', VECTOR6D 6 'd',
// VECTOR6INT32 6 'i', VECTOR6UINT32 6 'I', after '>B'). Offsets after the id: 0 1 2 6 14 18 26 50 98 122.
TEST(Rtde, EveryTypeAtItsOffsetInADataPackage) {
  const std::string_view names = "BOOL,UINT8,UINT32,UINT64,INT32,DOUBLE,VECTOR3D,VECTOR6D,VECTOR6INT32,VECTOR6UINT32";
  ASSERT_EQ(names.size(), 82u);
  const Bytes reply = cat(hex("0056 4F 05"), ascii(names));  // 3 + 1 + 82 = 86
  rtde::Recipe recipe;
  std::size_t field = 99;
  ASSERT_EQ(rtde::decode_setup_reply(reply.data(), reply.size(), rtde::PackageType::kSetupOutputs, recipe, field),
            rtde::DecodeStatus::kOk);
  EXPECT_EQ(recipe.id, 5);
  ASSERT_EQ(recipe.count, 10u);
  const std::array<std::size_t, 10> offsets{0, 1, 2, 6, 14, 18, 26, 50, 98, 122};
  for (std::size_t i = 0; i < offsets.size(); ++i) EXPECT_EQ(recipe.offsets[i], offsets[i]) << "field " << i;
  EXPECT_EQ(recipe.payload_bytes, 146u);

  Bytes package = hex("0096 55 05");                                                  // 3 + 1 + 146 = 150, recipe 5
  package = cat(package, hex("01 7F DEADBEEF 0000000100000002 FFFFFF85"));            // true, 127, uint32, uint64, -123
  package = cat(package, hex("4000000000000000"));                                    // DOUBLE 2.0
  package = cat(package, hex("3FF0000000000000 BFF0000000000000 0000000000000000"));  // VECTOR3D 1, -1, 0
  package = cat(package, hex("3FE0000000000000"));                                    // VECTOR6D 0.5, 0, 0, 0, 0, -2
  package = test::zeros_after(package, 4 * 8);
  package = cat(package, hex("C000000000000000"));
  package = cat(package, hex("00000001 FFFFFFFF 00000000 00000000 00000000 7FFFFFFF"));  // VECTOR6INT32
  package = cat(package, hex("FFFFFFFF 00000000 00000000 00000000 00000000 00000000"));  // VECTOR6UINT32
  ASSERT_EQ(package.size(), 150u);

  rtde::DataView view;
  ASSERT_EQ(view.reset(recipe, package.data(), package.size()), rtde::DecodeStatus::kOk);
  EXPECT_EQ(view.get_uint32(2), 0xDEADBEEFu);
  EXPECT_EQ(view.get_int32(4), -123);
  EXPECT_EQ(view.get_double(5), 2.0);
  EXPECT_EQ(view.get_vector6d(7), (std::array<double, 6>{0.5, 0, 0, 0, 0, -2.0}));

  // The fields deflex writes, the others left zero, give the same bytes.
  Bytes expected = package;
  for (const std::size_t at : {0u, 1u, 6u, 7u, 8u, 9u, 10u, 11u, 12u, 13u})
    expected[4 + at] = 0;                                          // BOOL, UINT8, UINT64
  for (std::size_t at = 26; at < 50; ++at) expected[4 + at] = 0;   // VECTOR3D
  for (std::size_t at = 98; at < 146; ++at) expected[4 + at] = 0;  // VECTOR6INT32, VECTOR6UINT32
  unsigned char out[256];
  rtde::DataBuilder builder(recipe, out, sizeof out);
  EXPECT_TRUE(builder.set(2, std::uint32_t{0xDEADBEEF}));
  EXPECT_TRUE(builder.set(4, std::int32_t{-123}));
  EXPECT_TRUE(builder.set(5, 2.0));
  EXPECT_TRUE(builder.set(7, std::array<double, 6>{0.5, 0, 0, 0, 0, -2.0}));
  ASSERT_EQ(builder.finish(), expected.size());
  EXPECT_EQ(Bytes(out, out + expected.size()), expected);

  // Doubles inside a VECTOR3D are checked; a NaN's bit pattern in integer fields is just an integer.
  Bytes nan_in_vector3d = package;
  nan_in_vector3d[4 + 26 + 8] = 0x7F;
  nan_in_vector3d[4 + 26 + 9] = 0xF8;
  EXPECT_EQ(view.reset(recipe, nan_in_vector3d.data(), nan_in_vector3d.size()), rtde::DecodeStatus::kNonFinite);
  Bytes nan_bits_in_ints = package;
  nan_bits_in_ints[4 + 98 + 4] = 0x7F;
  nan_bits_in_ints[4 + 98 + 5] = 0xF8;
  nan_bits_in_ints[4 + 6] = 0x7F;  // UINT64
  nan_bits_in_ints[4 + 7] = 0xF8;
  EXPECT_EQ(view.reset(recipe, nan_bits_in_ints.data(), nan_bits_in_ints.size()), rtde::DecodeStatus::kOk);
}

// The setup requests as UR's client sends them (UniversalRobots/RTDE_Python_Client_Library,
// rtde/rtde.py: send_output_setup packs the frequency as '>d' then the names joined by commas;
// send_input_setup the names alone; negotiate_protocol_version '>H'), read on the controller's side.
TEST(Rtde, SetupRequestsReadOnTheControllersSide) {
  const Bytes outputs = cat(hex("0014 4F 407F400000000000"), ascii("timestamp"));  // 500 Hz, 3 + 8 + 9 = 20
  double frequency = 0.0;
  std::string_view names;
  ASSERT_EQ(
      rtde::decode_setup_request(outputs.data(), outputs.size(), rtde::PackageType::kSetupOutputs, frequency, names),
      rtde::DecodeStatus::kOk);
  EXPECT_EQ(frequency, 500.0);
  EXPECT_EQ(names, "timestamp");
  unsigned char out[64];
  ASSERT_EQ(rtde::encode_setup_outputs(500.0, "timestamp", out, sizeof out), outputs.size());
  EXPECT_EQ(Bytes(out, out + outputs.size()), outputs);
  const Bytes no_names = hex("000B 4F 407F400000000000");
  EXPECT_EQ(
      rtde::decode_setup_request(no_names.data(), no_names.size(), rtde::PackageType::kSetupOutputs, frequency, names),
      rtde::DecodeStatus::kWrongSize);
  const Bytes version_1 = hex("0005 56 0001");
  std::uint16_t version = 0;
  ASSERT_EQ(rtde::decode_protocol_request(version_1.data(), version_1.size(), version), rtde::DecodeStatus::kOk);
  EXPECT_EQ(version, 1);
  ASSERT_EQ(rtde::encode_protocol_request(1, out, sizeof out), version_1.size());
  EXPECT_EQ(Bytes(out, out + version_1.size()), version_1);
  // Start and pause replies as the controller sends them: one byte each, both ways.
  ASSERT_EQ(rtde::encode_accepted(rtde::PackageType::kPause, true, out, sizeof out), 4u);
  EXPECT_EQ(Bytes(out, out + 4), hex("0004 50 01"));
  ASSERT_EQ(rtde::encode_accepted(rtde::PackageType::kStart, false, out, sizeof out), 4u);
  EXPECT_EQ(Bytes(out, out + 4), hex("0004 53 00"));
  const Bytes two_bytes = hex("0005 53 0100");
  bool accepted = false;
  EXPECT_EQ(rtde::decode_accepted(two_bytes.data(), two_bytes.size(), rtde::PackageType::kStart, accepted),
            rtde::DecodeStatus::kWrongSize)
      << "the reply is exactly one byte (rtde.py: 'Wrong payload size' otherwise)";
}

TEST(Rtde, FramingOnAStreamCutAnywhere) {
  const Bytes a = hex("0004 56 01");
  const Bytes b = cat(hex("000D 4F 01"), ascii("NOT_FOUND"));
  const Bytes stream = cat(a, b);
  for (std::size_t cut = 0; cut <= stream.size(); ++cut) {
    std::size_t bytes = 0;
    std::uint8_t type = 0;
    const rtde::FrameStatus s = rtde::peek_package(stream.data(), cut, 4096, bytes, type);
    if (cut < a.size()) {
      EXPECT_EQ(s, rtde::FrameStatus::kIncomplete) << cut;
    } else {
      EXPECT_EQ(s, rtde::FrameStatus::kComplete) << cut;
      EXPECT_EQ(bytes, a.size());
      EXPECT_EQ(type, 'V');
    }
  }
  std::size_t bytes = 0;
  std::uint8_t type = 0;
  ASSERT_EQ(rtde::peek_package(stream.data() + a.size(), b.size(), 4096, bytes, type), rtde::FrameStatus::kComplete);
  EXPECT_EQ(bytes, b.size());
  const Bytes too_short = hex("0002 56");
  EXPECT_EQ(rtde::peek_package(too_short.data(), too_short.size(), 4096, bytes, type), rtde::FrameStatus::kTooShort);
  const Bytes big = hex("FFFF 55 00");
  EXPECT_EQ(rtde::peek_package(big.data(), big.size(), 4096, bytes, type), rtde::FrameStatus::kOversized);
  EXPECT_EQ(bytes, 0xFFFFu) << "the size is reported so the caller can name it";
  EXPECT_TRUE(rtde::known_package_type('U'));
  EXPECT_FALSE(rtde::known_package_type('X'));
  // READ_PROPERTIES ('R' 82) is protocol 3's (UniversalRobots/RTDE_Python_Client_Library, rtde/rtde.py);
  // deflex asks for protocol 2, so a controller never sends it one.
  EXPECT_FALSE(rtde::known_package_type('R'));
}

TEST(Rtde, FieldTypeNamesBothWays) {
  for (const rtde::FieldType t :
       {rtde::FieldType::kBool, rtde::FieldType::kUint8, rtde::FieldType::kUint32, rtde::FieldType::kUint64,
        rtde::FieldType::kInt32, rtde::FieldType::kDouble, rtde::FieldType::kVector3d, rtde::FieldType::kVector6d,
        rtde::FieldType::kVector6Int32, rtde::FieldType::kVector6Uint32}) {
    rtde::FieldType back = rtde::FieldType::kBool;
    ASSERT_TRUE(rtde::parse_field_type(rtde::to_string(t), back)) << rtde::to_string(t);
    EXPECT_EQ(back, t);
  }
  EXPECT_EQ(rtde::field_bytes(rtde::FieldType::kVector6Int32), 24u);
  EXPECT_EQ(rtde::field_bytes(rtde::FieldType::kUint64), 8u);
  rtde::FieldType t = rtde::FieldType::kBool;
  EXPECT_FALSE(rtde::parse_field_type("double", t)) << "the controller's names are upper case";
  EXPECT_FALSE(rtde::parse_field_type("IN_USE", t));
}

TEST(Rtde, NonAsciiOrOversizedTextIsNotSent) {
  unsigned char out[70000];
  EXPECT_EQ(rtde::encode_setup_inputs("input_double_register_24\n", out, sizeof out), 0u);
  const std::string names(70000, 'a');
  EXPECT_EQ(rtde::encode_setup_inputs(names, out, sizeof out), 0u) << "a package holds at most 65535 bytes";
  EXPECT_EQ(rtde::encode_setup_outputs(0.0, "timestamp", out, sizeof out), 0u);
  EXPECT_EQ(rtde::encode_setup_outputs(std::nan(""), "timestamp", out, sizeof out), 0u);
}

TEST(Rtde, DataPathDoesNotAllocate) {
  const std::array<rtde::FieldType, 2> types{rtde::FieldType::kVector6d, rtde::FieldType::kUint32};
  rtde::Recipe recipe;
  ASSERT_TRUE(rtde::make_recipe(3, types.data(), types.size(), recipe));
  unsigned char out[128];
  rtde::DataView view;
  test::AllocationGuard guard;
  for (int i = 0; i < 100; ++i) {
    rtde::DataBuilder builder(recipe, out, sizeof out);
    builder.set(0, std::array<double, 6>{0.1, 0.2, 0.3, 0.4, 0.5, 0.6});
    builder.set(1, static_cast<std::uint32_t>(i));
    const std::size_t n = builder.finish();
    ASSERT_EQ(view.reset(recipe, out, n), rtde::DecodeStatus::kOk);
    ASSERT_EQ(view.get_uint32(1), static_cast<std::uint32_t>(i));
  }
  EXPECT_EQ(guard.allocations(), 0u);
}

}  // namespace
}  // namespace deflex
