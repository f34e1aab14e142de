// The force sources a session can read, by the text users give them (`deflex online --force-source`,
// Python): udp:PORT (deflex's own 64-byte datagram, for custom DAQ programs: docs/online.md) and
// csv:FILE (a recorded replay). One place that turns the text into a source, so the command line,
// Python and the tests open sources the same way.
#pragma once

#include <memory>
#include <string>

#include "deflex/online/force_sample.hpp"

namespace deflex {

struct ForceSourceOptions {
  bool loop = false;                       ///< csv: start the replay again after its last sample
  std::string bind_address = "127.0.0.1";  ///< udp: the address the port is bound on
};

struct OpenedForceSource {
  std::unique_ptr<ForceSource> source;
  std::string description;  ///< "UDP force samples on port 6600", "CSV replay of f.csv (500 samples, looped)"
};

/// Opens the source `spec` names. Throws InputError naming --force-source for a spec it does not
/// know or a bad port, DataError naming the file and line for a bad replay, Error for a port that
/// cannot be bound.
[[nodiscard]] OpenedForceSource open_force_source(const std::string& spec, const ForceSourceOptions& options = {});

/// "udp:PORT, csv:FILE" (for option help and errors).
[[nodiscard]] const char* force_source_kinds();

}  // namespace deflex
