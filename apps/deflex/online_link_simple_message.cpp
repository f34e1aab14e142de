// `deflex online --link simple-message`: the paper's kind of link for cells without a real-time
// option. deflex connects over TCP to the robot program's ROS-Industrial simple message servers
// (motion and state ports), streams --program minus the bounded correction one point a cycle
// (--period-ms, the paper's 100 ms), keeps --buffer-depth points queued on the controller, and stops the
// motion with STOP_TRAJECTORY on any fault, a lost connection or Ctrl-C.
#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "deflex/link/simple_message_link.hpp"
#include "deflex/model/errors.hpp"
#include "deflex/transport/tcp_stream.hpp"
#include "online_links.hpp"

namespace deflex::cli {
namespace {

struct SimpleMessageOptions {
  std::string robot_host, byte_order = "little";
  int motion_port = 11000, state_port = 11002, buffer_depth = 2, max_failures = 3, max_frame_bytes = 1024;
  double connect_timeout_s = 5.0, reply_timeout_s = 1.0, state_timeout_s = 1.0;
  CLI::App* app = nullptr;  // to read --ramp-in-s, which the streaming links share
};
auto g_sm = std::make_shared<SimpleMessageOptions>();

// The robot-program servers read one point per pass of their loop (Fanuc's relay runs at 42 Hz, ABB's
// RAPID server takes a point per socket read): a faster cycle only fills their buffers.
constexpr double kMinPeriodS = 0.02;

void add_simple_message_options(CLI::App& sub) {
  g_sm->app = &sub;
  sub.add_option("--robot-host", g_sm->robot_host,
                 "simple-message: the controller's address (its motion and state servers listen there)");
  sub.add_option("--motion-port", g_sm->motion_port, "simple-message: TCP port of the motion server (JOINT_TRAJ_PT)")
      ->capture_default_str();
  sub.add_option("--state-port", g_sm->state_port, "simple-message: TCP port of the state server (JOINT_POSITION)")
      ->capture_default_str();
  sub.add_option("--byte-order", g_sm->byte_order,
                 "simple-message: the server's byte order: little (ABB RAPID, Motoman DX100/DX200/YRC1000) or big "
                 "(Fanuc KAREL, Motoman FS100)")
      ->capture_default_str();
  sub.add_option("--buffer-depth", g_sm->buffer_depth,
                 "simple-message: points kept queued on the controller; each adds one cycle of lag (reported; the "
                 "predictive strategy leads by the measured delay)")
      ->capture_default_str();
  sub.add_option("--connect-timeout-s", g_sm->connect_timeout_s,
                 "simple-message: wait this long for each connection, s")
      ->capture_default_str();
  sub.add_option("--reply-timeout-s", g_sm->reply_timeout_s,
                 "simple-message: a point unanswered this long stops the motion, s")
      ->capture_default_str();
  sub.add_option("--state-timeout-s", g_sm->state_timeout_s,
                 "simple-message: no JOINT_POSITION this long stops the motion, s")
      ->capture_default_str();
  sub.add_option("--max-failures", g_sm->max_failures,
                 "simple-message: FAILURE replies in a row (buffer full, point refused) before the motion is stopped")
      ->capture_default_str();
  sub.add_option("--max-frame-bytes", g_sm->max_frame_bytes,
                 "simple-message: the largest frame LENGTH accepted; a larger one means the stream is out of step")
      ->capture_default_str();
}

std::uint16_t port_option(int port, const char* option) {
  if (port < 1 || port > 65535) {
    throw InputError(fmt::format("option {}: must be a TCP port 1..65535 (got {})", option, port));
  }
  return static_cast<std::uint16_t>(port);
}

SimpleMessageLinkConfig link_config(const OnlineContext& c) {
  const SimpleMessageOptions& o = *g_sm;
  if (o.robot_host.empty()) {
    throw InputError("option --robot-host: the simple-message link needs the controller's address");
  }
  if (!(c.period_s >= kMinPeriodS)) {
    throw InputError(fmt::format(
        "option --period-ms: simple-message sends one point a cycle to a robot program; give its cycle (the "
        "paper's: 100), at least {:g} ms (got {:g} ms)",
        kMinPeriodS * 1e3, c.period_s * 1e3));
  }
  const auto positive = [](double v, const char* option) {
    if (!std::isfinite(v) || !(v > 0.0)) {
      throw InputError(fmt::format("option {}: must be a number > 0 (got {})", option, v));
    }
  };
  positive(o.connect_timeout_s, "--connect-timeout-s");
  positive(o.reply_timeout_s, "--reply-timeout-s");
  positive(o.state_timeout_s, "--state-timeout-s");
  if (o.buffer_depth < 1 || o.buffer_depth > 64) {
    throw InputError(fmt::format("option --buffer-depth: must be 1..64 points (got {})", o.buffer_depth));
  }
  if (o.max_failures < 1) throw InputError(fmt::format("option --max-failures: must be >= 1 (got {})", o.max_failures));
  if (o.max_frame_bytes < 64 || o.max_frame_bytes > (1 << 20)) {
    throw InputError(fmt::format("option --max-frame-bytes: must be 64..1048576 (got {})", o.max_frame_bytes));
  }
  SimpleMessageLinkConfig lc;
  try {
    lc.byte_order = simple_message::parse_byte_order(o.byte_order);
  } catch (const InputError& e) {
    throw InputError(fmt::format("option --byte-order: {}", e.what()));
  }
  lc.buffer_depth = o.buffer_depth;
  lc.reply_timeout_s = o.reply_timeout_s;
  lc.state_timeout_s = o.state_timeout_s;
  lc.max_failures = o.max_failures;
  lc.max_frame_bytes = static_cast<std::size_t>(o.max_frame_bytes);
  // --ramp-in-s belongs to whichever streaming link registered it first; it applies here too.
  if (o.app != nullptr) {
    if (const CLI::Option* ramp = o.app->get_option_no_throw("--ramp-in-s"); ramp != nullptr && ramp->count() > 0) {
      lc.stream.ramp_in_s = ramp->as<double>();
      if (!std::isfinite(lc.stream.ramp_in_s) || lc.stream.ramp_in_s < 0.0) {
        throw InputError(fmt::format("option --ramp-in-s: must be a number >= 0 (got {})", lc.stream.ramp_in_s));
      }
    }
  }
  return lc;
}

class SimpleMessageSession final : public LinkSession {
 public:
  explicit SimpleMessageSession(const OnlineContext& c)
      : config_(link_config(c)),
        motion_port_(port_option(g_sm->motion_port, "--motion-port")),
        state_port_(port_option(g_sm->state_port, "--state-port")),
        motion_(TcpStream::connect(g_sm->robot_host, motion_port_, g_sm->connect_timeout_s)),
        state_(TcpStream::connect(g_sm->robot_host, state_port_, g_sm->connect_timeout_s)),
        link_(c.compensator, c.strategy, c.program, *motion_, *state_, c.clock, c.force, config_) {}

  ControllerLink& link() override { return link_; }
  [[nodiscard]] std::string where() const override {
    return fmt::format("simple message to {} (motion {}, state {}, {}-endian)", g_sm->robot_host, motion_port_,
                       state_port_, simple_message::to_string(config_.byte_order));
  }
  [[nodiscard]] std::string status() const override {
    const JointTrajectory& p = link_.stream().trajectory();
    const SimpleMessageCounters& s = link_.protocol_counters();
    return fmt::format("program {:.1f}/{:.1f} s | points {} taken, {} FAILURE | buffer {} points ({:.0f} ms of lag)",
                       link_.stream().program_time_s() - p.start_time_s(), p.duration_s(), s.points_accepted,
                       s.failures, config_.buffer_depth, link_.buffer_lag_s() * 1e3);
  }
  [[nodiscard]] std::string summary() const override {
    const SimpleMessageCounters& s = link_.protocol_counters();
    return fmt::format(
        "simple message: {} points sent, {} taken, {} FAILURE replies; buffer {} points = {:.0f} ms of lag, measured "
        "command-to-feedback delay {:.0f} ms ({} measurements); JOINT_POSITION {}, ROBOT_STATUS {}; unknown types {}, "
        "unexpected {}, wrong sequence {}; STOP_TRAJECTORY sent {}",
        s.points_sent, s.points_accepted, s.failures, config_.buffer_depth, link_.buffer_lag_s() * 1e3,
        link_.delay().delay_s() * 1e3, link_.delay().measurements(), s.joint_positions, s.robot_statuses,
        s.unknown_type, s.unexpected, s.wrong_sequence, s.stops_sent);
  }

 private:
  SimpleMessageLinkConfig config_;
  std::uint16_t motion_port_, state_port_;
  std::unique_ptr<TcpStream> motion_, state_;
  SimpleMessageLink link_;
};

}  // namespace

DEFLEX_LINK_KIND(LinkKindInfo{"simple-message",
                              "ROS-Industrial simple message over TCP to a robot program (ABB RAPID, Fanuc KAREL "
                              "servers): deflex streams --program one point a cycle",
                              true, add_simple_message_options,
                              [](const OnlineContext& c) { return std::make_unique<SimpleMessageSession>(c); }});

}  // namespace deflex::cli
