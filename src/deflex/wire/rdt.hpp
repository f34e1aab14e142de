// RDT (Raw Data Transfer): the UDP protocol of ATI Net F/T and Ethernet Axia force/torque sensors
// (ATI manuals 9620-05 section 10 and 9610-05 section 12.1), Schunk FTN-Axia (an ATI Axia) and
// OnRobot HEX through its Compute Box. Everything is big-endian ("high byte first"):
//
//   request, 8 bytes:  0 uint16 header 0x1234   2 uint16 command   4 uint32 sample_count (0: until stopped)
//   record, 36 bytes:  0 uint32 rdt_sequence    4 uint32 ft_sequence   8 uint32 status
//                      12 int32 Fx Fy Fz Tx Ty Tz, counts (divide by the calibration's counts per unit)
//
// A datagram from the sensor holds 1 record (real-time streaming) or up to 40 back to back (buffered /
// multi-block streaming, the sensor's "RDT buffer size"). Both sequence numbers are 32 bits and wrap.
// Records carry no header of their own: a datagram is well-formed when its size is a whole number of
// 1..40 records; the sequence numbers tell the rest. Fields are assembled byte by byte, never by
// casting onto a struct, so the host's byte order does not matter. Nothing here allocates or throws.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace deflex {

inline constexpr std::uint16_t kRdtRequestHeader = 0x1234;
inline constexpr std::size_t kRdtRequestBytes = 8;
inline constexpr std::size_t kRdtRecordBytes = 36;
inline constexpr std::size_t kRdtMaxRecordsPerDatagram = 40;  ///< the manuals' largest RDT buffer size
inline constexpr std::size_t kRdtMaxDatagramBytes = kRdtRecordBytes * kRdtMaxRecordsPerDatagram;
inline constexpr std::uint16_t kRdtDefaultPort = 49152;

/// Request commands. The values are the manuals'; OnRobot's Compute Box adds its filter and rate.
enum class RdtCommand : std::uint16_t {
  kStop = 0x0000,             ///< stop streaming
  kStartRealTime = 0x0002,    ///< one record a datagram (Axia: 0x0001 single block, 0x0002 accepted)
  kStartBuffered = 0x0003,    ///< several records a datagram (Axia: multi-block)
  kSetSoftwareBias = 0x0042,  ///< the sensor's own bias; OnRobot: sample_count 255 on, 0 off
  /// OnRobot only: low-pass filter, sample_count 0 none, 1 = 500 Hz, 2 = 150, 3 = 50, 4 = 15, 5 = 5, 6 = 1.5 Hz
  kOnRobotFilter = 0x0081,
  kOnRobotRate = 0x0082,  ///< OnRobot only: output rate 1000 / sample_count Hz
};

struct RdtRequest {
  std::uint16_t header = kRdtRequestHeader;
  std::uint16_t command = 0;
  std::uint32_t sample_count = 0;
};

/// One record as it stands on the wire (counts, not yet scaled).
struct RdtRecord {
  std::uint32_t rdt_sequence = 0;        ///< 1 for the first record of each request, +1 a record
  std::uint32_t ft_sequence = 0;         ///< the sensor's own sample counter since power-up (not reset by a request)
  std::uint32_t status = 0;              ///< 0: healthy; any set bit: a condition the sensor reports
  std::array<std::int32_t, 6> counts{};  ///< Fx Fy Fz Tx Ty Tz
};

/// True when any axis stands at an int32 limit: the sensor's converter or arithmetic saturated, and
/// the value is not a measurement.
[[nodiscard]] bool rdt_counts_saturated(const RdtRecord& record) noexcept;

void encode_rdt_request(const RdtRequest& request, std::array<unsigned char, kRdtRequestBytes>& out) noexcept;
/// False when the size is not 8 or the header is not 0x1234 (`out` then holds what could be read).
bool decode_rdt_request(const unsigned char* data, std::size_t size, RdtRequest& out) noexcept;

/// Writes one 36-byte record at `out` (a sensor stand-in's and the tests' side).
void encode_rdt_record(const RdtRecord& record, unsigned char* out) noexcept;
/// Reads one 36-byte record at `data`.
void decode_rdt_record(const unsigned char* data, RdtRecord& out) noexcept;

/// How many records a datagram of `size` bytes holds: 1..40, or 0 when the size is not a whole number
/// of records in that range (a malformed datagram).
[[nodiscard]] std::size_t rdt_record_count(std::size_t size) noexcept;

}  // namespace deflex
