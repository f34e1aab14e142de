// KUKA RobotSensorInterface (RSI) documents over Ethernet (facts: docs/online.md, reference rsi.md), for
// both sides of the link:
//   robot -> sensor   <Rob Type="KUKA"> with <RIst .../> <RSol .../> (Cartesian, mm and degrees),
//                     <AIPos A1=".." .. A6=".."/> actual axes, <ASPos .../> setpoint axes (degrees),
//                     <Delay D=".."/> late answers counted so far, <IPOC>n</IPOC> the cycle's time stamp;
//   sensor -> robot   <Sen Type="SENTYPE"> with <AK A1=".." .. A6=".."/> axis corrections (degrees)
//                     and the echoed <IPOC>n</IPOC>.
// deflex's side decodes <Rob> and encodes <Sen>; the controller's side (the simulated cell, test
// stand-ins, the benchmark) encodes <Rob> and decodes <Sen>. Decoding runs the strict scanner of
// xml_scanner.hpp over the datagram in place, numbers go through std::from_chars and are written with
// std::to_chars: nothing allocates, locks or throws.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "deflex/model/types.hpp"

namespace deflex {

/// What deflex reads from a <Rob> document. Degrees and mm as on the wire; convert at the edge.
struct RsiRobotMessage {
  std::uint64_t ipoc = 0;    ///< the cycle's time stamp (ms counter), echoed in the answer
  JointVector actual_deg;    ///< AIPos: where the axes are
  JointVector setpoint_deg;  ///< ASPos: where the controller's own program puts them (has_setpoint)
  bool has_setpoint = false;
  std::uint64_t delay = 0;  ///< <Delay D>: answers the controller counted late so far (has_delay)
  bool has_delay = false;
  /// <RIst> and <RSol>: X Y Z (mm) A B C (degrees, KUKA's Z-Y'-X''), when sent.
  std::array<double, 6> rist{}, rsol{};
  bool has_rist = false, has_rsol = false;
};

/// The axis correction deflex answers with: whole offsets from where RSI started (absolute mode).
struct RsiSensorMessage {
  std::uint64_t ipoc = 0;
  JointVector correction_deg;  ///< AK A1..An
};

/// KDL's sign convention: 0 accepted, < 0 rejected (the datagram is counted and never answered).
enum class RsiDecodeStatus : int {
  kOk = 0,
  kMalformed = -1,       ///< not well-formed, outside the XML subset, a bad number, an element twice
  kTruncated = -2,       ///< the document ends before its root element is closed
  kMissingIpoc = -3,     ///< no <IPOC>
  kMissingAxes = -4,     ///< no AIPos (AK on the controller's side) or one of its axes missing
  kNonFinite = -5,       ///< a number beyond the range of double (1e999)
  kEmpty = -6,           ///< zero-length datagram
  kForeign = -7,         ///< well-formed so far but another document: another root element or Type
  kIpocOutOfRange = -8,  ///< an IPOC beyond 64 bits: rejected, never truncated
};
[[nodiscard]] const char* to_string(RsiDecodeStatus s);

/// The largest document deflex builds (<Sen> with 7 axes, or <Rob> with everything): a buffer of
/// this size always holds one.
inline constexpr std::size_t kRsiMaxEncodedBytes = 1024;

/// Decodes a <Rob Type="KUKA"> document with `axes` axes (A1..An of AIPos, and of ASPos when present).
/// Elements it does not use (custom SEND elements) are skipped, but must be well-formed.
RsiDecodeStatus decode_rsi_robot(const unsigned char* data, std::size_t size, int axes, RsiRobotMessage& out) noexcept;

/// Writes <Sen Type="sentype"><AK A1=".." ../><IPOC>n</IPOC></Sen> (AK in fixed notation, 6
/// decimals). Returns the size, 0 when a value is not finite or the document does not fit.
std::size_t encode_rsi_sensor(std::string_view sentype, const RsiSensorMessage& msg, unsigned char* out,
                              std::size_t capacity) noexcept;

/// The controller's side: a <Rob Type="KUKA"> with RIst/RSol (when set), AIPos, ASPos (when set),
/// Delay and IPOC, numbers with `decimals` digits after the point (the ETHERNET object's Precision).
std::size_t encode_rsi_robot(const RsiRobotMessage& msg, int decimals, unsigned char* out,
                             std::size_t capacity) noexcept;
/// The controller's side: a <Sen> whose Type is `sentype`, with AK A1..An and IPOC. Anything else
/// (another Type is kForeign) is refused.
RsiDecodeStatus decode_rsi_sensor(const unsigned char* data, std::size_t size, std::string_view sentype, int axes,
                                  RsiSensorMessage& out) noexcept;

/// True for a name the controller's Ethernet config can carry as <SENTYPE> and deflex can write as
/// the Type attribute unescaped: 1..32 of [A-Za-z0-9_-], starting with a letter.
[[nodiscard]] bool valid_rsi_sentype(std::string_view name) noexcept;

}  // namespace deflex
