// Force sources by their text (see force_source_spec.hpp).
#include "deflex/sensors/force_source_spec.hpp"

#include <fmt/format.h>

#include "deflex/sensors/detail/csv_force_replay.hpp"
#include "deflex/sensors/detail/udp_force_source.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/parse_number.hpp"

namespace deflex {

const char* force_source_kinds() {
  return "udp:PORT (deflex's force datagram), csv:FILE (a recorded replay) or rdt:HOST[:PORT] (an ATI, Schunk or "
         "OnRobot sensor in its own RDT protocol; needs --rdt-calibration)";
}

namespace {

std::uint16_t port_of(const std::string& text, const std::string& spec) {
  const std::optional<std::int64_t> port = parse_int64(text);
  if (!port || *port < 0 || *port > 65535) {
    throw InputError(fmt::format("option --force-source: '{}' in '{}' is not a UDP port 0..65535", text, spec));
  }
  return static_cast<std::uint16_t>(*port);
}

}  // namespace

OpenedForceSource open_force_source(const std::string& spec, const ForceSourceOptions& options) {
  const std::size_t colon = spec.find(':');
  const std::string kind = spec.substr(0, colon);
  const std::string arg = colon == std::string::npos ? "" : spec.substr(colon + 1);
  OpenedForceSource out;
  if (kind == "udp" && !arg.empty()) {
    auto src = std::make_unique<UdpForceSource>(port_of(arg, spec), options.bind_address);
    out.description = fmt::format("UDP force samples on {}:{}", options.bind_address, src->port());
    out.source = std::move(src);
    return out;
  }
  if (kind == "csv" && !arg.empty()) {
    auto src = std::make_unique<CsvForceReplay>(arg, options.loop);
    out.description = fmt::format("CSV replay of {} ({} samples{})", arg, src->size(), options.loop ? ", looped" : "");
    out.source = std::move(src);
    return out;
  }
  if (kind == "rdt" && !arg.empty()) {
    RdtSourceOptions o;
    o.endpoint = arg;
    o.calibration = options.rdt_calibration;
    o.stream = options.rdt_stream;
    o.bind_address = options.rdt_bind_address;
    auto src = open_rdt_force_source(o);
    const RdtForceSource& s = src->source();
    const RdtCalibration& c = s.calibration();
    out.sample_rate_hz = s.sample_rate_hz();
    out.description = fmt::format("RDT sensor at {}, {} streaming: {}", arg,
                                  options.rdt_stream.buffered ? "buffered" : "real-time", c.describe());
    out.rdt = src.get();
    out.source = std::move(src);
    return out;
  }
  throw InputError(fmt::format("option --force-source: '{}' is not {}", spec, force_source_kinds()));
}

}  // namespace deflex
