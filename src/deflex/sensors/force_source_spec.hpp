// The force sources a session can read, by the text users give them (`deflex online --force-source`,
// `deflex identify-payload`, Python): udp:PORT (deflex's own 64-byte datagram, for custom DAQ
// programs: docs/online.md), csv:FILE (a recorded replay) and rdt:HOST[:PORT] (ATI, Schunk and
// OnRobot sensors in their own protocol, RDT: rdt_force_source.hpp). One place that turns the text
// into a source, so the command line, Python and the tests open sources the same way.
#pragma once

#include <memory>
#include <string>

#include "deflex/online/force_sample.hpp"
#include "deflex/sensors/rdt_force_source.hpp"

namespace deflex {

struct ForceSourceOptions {
  bool loop = false;                       ///< csv: start the replay again after its last sample
  std::string bind_address = "127.0.0.1";  ///< udp: the address the port is bound on
  // rdt: the calibration (--rdt-calibration, --rdt-rate-hz) and the stream (--rdt-buffered).
  RdtCalibrationOptions rdt_calibration;
  RdtStreamSettings rdt_stream;
  std::string rdt_bind_address = "0.0.0.0";
};

struct OpenedForceSource {
  std::unique_ptr<ForceSource> source;
  /// "UDP force samples on 127.0.0.1:6600", "CSV replay of f.csv (500 samples, looped)", "RDT sensor
  /// ATI Net F/T FT12345 at 192.168.1.1:49152 (1000 Hz, real-time, N and Nm from its page)".
  std::string description;
  /// The rate the source states itself (RDT: the sensor's), Hz; 0: the source does not know (the
  /// sensor configuration's sample_rate_hz stands).
  double sample_rate_hz = 0.0;
  /// The RDT source, for the tare (null for the others).
  RdtUdpForceSource* rdt = nullptr;
};

/// Opens the source `spec` names (rdt: resolves the calibration and starts the stream, waiting for
/// its first record). Throws InputError naming --force-source (or the rdt option at fault) for a spec
/// it does not know, a bad port or a missing calibration, DataError naming the file and line for a
/// bad replay, ModelError for a bad calibration page, Error for a port that cannot be bound or a
/// sensor that does not answer.
[[nodiscard]] OpenedForceSource open_force_source(const std::string& spec, const ForceSourceOptions& options = {});

/// "udp:PORT, csv:FILE, rdt:HOST[:PORT]" (for option help and errors).
[[nodiscard]] const char* force_source_kinds();

}  // namespace deflex
