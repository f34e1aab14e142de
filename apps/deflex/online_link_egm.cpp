// `deflex online --link egm-joint|egm-path`: ABB Externally Guided Motion over UDP, position guidance
// (deflex streams --program) and path correction (the controller runs its own program).
#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "deflex/egm/egm_joint_link.hpp"
#include "deflex/egm/egm_path_link.hpp"
#include "deflex/model/errors.hpp"
#include "deflex/transport/udp_transport.hpp"
#include "online_links.hpp"

namespace deflex::cli {
namespace {

struct EgmOptions {
  int port = -1;
  double ramp_in_s = 1.0, correction_latency_ms = 0.0, rotation_warning_mrad = 0.1;
  bool no_speed_ref = false;
  std::string path_frame = "tool";
};
auto g_egm = std::make_shared<EgmOptions>();

void add_egm_options(CLI::App& sub) {
  if (sub.get_option_no_throw("--egm-port") != nullptr) return;  // shared by both EGM kinds
  sub.add_option("--egm-port", g_egm->port, "EGM: UDP port the controller's EGM messages arrive on (ABB examples: 6510)");
  sub.add_option("--ramp-in-s", g_egm->ramp_in_s,
                 "egm-joint, simple-message: blend from where the arm is to the program over this time, s")
      ->capture_default_str();
  sub.add_flag("--no-speed-reference", g_egm->no_speed_ref, "egm-joint: do not send the target's joint speeds");
  sub.add_option("--path-corr-frame", g_egm->path_frame,
                 "egm-path: the frame EGMActMove was given: tool (tool.tframe), flange (tool0) or path (path "
                 "coordinates)")
      ->capture_default_str();
  sub.add_option("--correction-latency-ms", g_egm->correction_latency_ms,
                 "egm-path, predictive: the controller's correction latency beyond the measured servo delay, ms")
      ->capture_default_str();
  sub.add_option("--rotation-warning-mrad", g_egm->rotation_warning_mrad,
                 "egm-path: report when the model predicts a TCP rotation above this (it cannot be corrected), mrad")
      ->capture_default_str();
}

std::uint16_t egm_port() {
  if (g_egm->port < 0 || g_egm->port > 65535) {
    throw InputError(g_egm->port == -1 ? "option --egm-port: the EGM links need the port the controller sends to"
                                       : "option --egm-port: must be 0..65535");
  }
  return static_cast<std::uint16_t>(g_egm->port);
}

void non_negative(double v, const char* option) {
  if (!std::isfinite(v) || v < 0.0) {
    throw InputError(fmt::format("option {}: must be a number >= 0 (got {})", option, v));
  }
}

class EgmJointSession final : public LinkSession {
 public:
  explicit EgmJointSession(const OnlineContext& c)
      : transport_(c.bind_address, egm_port()), link_(c.compensator, c.strategy, c.program, transport_, c.clock, c.force,
                                                     config()) {}
  ControllerLink& link() override { return link_; }
  [[nodiscard]] std::string where() const override {
    return fmt::format("EGM on {}", to_string(transport_.local_address()));
  }
  [[nodiscard]] std::string status() const override {
    const JointTrajectory& p = link_.stream().trajectory();
    return fmt::format("program {:.1f}/{:.1f} s", link_.stream().program_time_s() - p.start_time_s(), p.duration_s());
  }

 private:
  static EgmJointLinkConfig config() {
    non_negative(g_egm->ramp_in_s, "--ramp-in-s");
    EgmJointLinkConfig lc;
    lc.stream.ramp_in_s = g_egm->ramp_in_s;
    lc.send_speed_reference = !g_egm->no_speed_ref;
    return lc;
  }
  UdpTransport transport_;
  EgmJointLink link_;
};

class EgmPathSession final : public LinkSession {
 public:
  explicit EgmPathSession(const OnlineContext& c)
      : transport_(c.bind_address, egm_port()), link_(c.compensator, c.strategy, transport_, c.clock, c.force, config()) {}
  ControllerLink& link() override { return link_; }
  [[nodiscard]] std::string where() const override {
    return fmt::format("EGM on {} (corrections in the {} frame)", to_string(transport_.local_address()),
                       g_egm->path_frame);
  }
  [[nodiscard]] std::string status() const override {
    if (link_.max_rotation_rad() <= g_egm->rotation_warning_mrad * 1e-3) return "";
    return fmt::format("uncorrected TCP rotation up to {:.3f} mrad (path correction cannot rotate)",
                       link_.max_rotation_rad() * 1e3);
  }
  [[nodiscard]] std::string summary() const override {
    return fmt::format("largest TCP rotation the model predicted {:.3f} mrad ({} cycles above {:g} mrad; path "
                       "correction cannot rotate)",
                       link_.max_rotation_rad() * 1e3, link_.rotation_warnings(), g_egm->rotation_warning_mrad);
  }

 private:
  static EgmPathLinkConfig config() {
    non_negative(g_egm->correction_latency_ms, "--correction-latency-ms");
    non_negative(g_egm->rotation_warning_mrad, "--rotation-warning-mrad");
    EgmPathLinkConfig lc;
    lc.frame = parse_path_corr_frame(g_egm->path_frame);
    lc.correction_latency_s = g_egm->correction_latency_ms * 1e-3;
    lc.rotation_warning_rad = g_egm->rotation_warning_mrad * 1e-3;
    return lc;
  }
  UdpTransport transport_;
  EgmPathLink link_;
};

}  // namespace

DEFLEX_LINK_KIND(LinkKindInfo{"egm-joint",
                              "ABB EGM position guidance (EGMActJoint/EGMRunJoint): deflex streams --program",
                              true, add_egm_options,
                              [](const OnlineContext& c) { return std::make_unique<EgmJointSession>(c); }});
DEFLEX_LINK_KIND(LinkKindInfo{"egm-path",
                              "ABB EGM path correction (EGMActMove + EGMMoveL/EGMMoveC): the controller runs its own "
                              "program, deflex sends absolute offsets",
                              false, add_egm_options,
                              [](const OnlineContext& c) { return std::make_unique<EgmPathSession>(c); }});

}  // namespace deflex::cli
