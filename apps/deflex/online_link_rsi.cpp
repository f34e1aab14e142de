// `deflex online --link rsi`: KUKA RobotSensorInterface axis correction over UDP (the controller runs
// its own KRL program with RSI_ON(#ABSOLUTE); deflex answers every <Rob> with absolute AK offsets).
#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "deflex/model/errors.hpp"
#include "deflex/rsi/rsi_link.hpp"
#include "deflex/transport/udp_transport.hpp"
#include "online_links.hpp"

namespace deflex::cli {
namespace {

struct RsiOptions {
  int port = -1;
  std::string sentype = "ImFree";
  double correction_latency_ms = 0.0;
  int max_document_bytes = 4096;
};
auto g_rsi = std::make_shared<RsiOptions>();

void add_rsi_options(CLI::App& sub) {
  sub.add_option("--rsi-port", g_rsi->port,
                 "rsi: UDP port the controller's <Rob> documents arrive on (its Ethernet config's <PORT>; ROS "
                 "examples: 49152 or 59152)");
  sub.add_option("--rsi-sentype", g_rsi->sentype,
                 "rsi: the Type of every answer, the controller's <SENTYPE> (letters, digits, '_', '-')")
      ->capture_default_str();
  sub.add_option("--rsi-correction-latency-ms", g_rsi->correction_latency_ms,
                 "rsi, predictive: AXISCORR's latency beyond the delay the link measures (ASPos to AIPos), ms")
      ->capture_default_str();
  sub.add_option("--rsi-max-document-bytes", g_rsi->max_document_bytes,
                 "rsi: larger datagrams are counted oversized and never answered")
      ->capture_default_str();
}

RsiLinkConfig rsi_config() {
  if (g_rsi->port < 0 || g_rsi->port > 65535) {
    throw InputError(g_rsi->port == -1 ? "option --rsi-port: the RSI link needs the port the controller sends to"
                                       : "option --rsi-port: must be 0..65535");
  }
  if (!std::isfinite(g_rsi->correction_latency_ms) || g_rsi->correction_latency_ms < 0.0) {
    throw InputError(
        fmt::format("option --rsi-correction-latency-ms: must be a number >= 0 (got {})", g_rsi->correction_latency_ms));
  }
  if (g_rsi->max_document_bytes < 64 || g_rsi->max_document_bytes > 65507) {
    throw InputError("option --rsi-max-document-bytes: must be 64..65507");
  }
  RsiLinkConfig c;
  c.sentype = g_rsi->sentype;
  if (!valid_rsi_sentype(c.sentype)) {
    throw InputError(fmt::format("option --rsi-sentype: '{}' must be 1..32 letters, digits, '_' or '-', starting "
                                 "with a letter",
                                 c.sentype));
  }
  c.correction_latency_s = g_rsi->correction_latency_ms * 1e-3;
  c.max_document_bytes = static_cast<std::size_t>(g_rsi->max_document_bytes);
  return c;
}

class RsiSession final : public LinkSession {
 public:
  explicit RsiSession(const OnlineContext& c)
      : config_(rsi_config()),
        transport_(c.bind_address, static_cast<std::uint16_t>(g_rsi->port)),
        link_(c.compensator, c.strategy, transport_, c.clock, c.force, config_) {}
  ControllerLink& link() override { return link_; }
  [[nodiscard]] std::string where() const override {
    return fmt::format("RSI on {}; answers <Sen Type=\"{}\">", to_string(transport_.local_address()), config_.sentype);
  }
  [[nodiscard]] std::string status() const override {
    return fmt::format("the controller counts {} answers late (RSI stops at its Timeout)",
                       link_.counters().controller_late);
  }
  [[nodiscard]] std::string summary() const override {
    return fmt::format("the controller counted {} answers late (its <Delay>)", link_.counters().controller_late);
  }

 private:
  RsiLinkConfig config_;
  UdpTransport transport_;
  RsiLink link_;
};

}  // namespace

DEFLEX_LINK_KIND(LinkKindInfo{"rsi",
                              "KUKA RSI axis correction (RSI_ON(#ABSOLUTE), ETHERNET to AXISCORR): the controller runs "
                              "its own KRL program, deflex answers each <Rob> with absolute AK offsets",
                              false, add_rsi_options,
                              [](const OnlineContext& c) { return std::make_unique<RsiSession>(c); }});

}  // namespace deflex::cli
