// FANUC Stream Motion, deflex as the motion source (see fanuc_j519_link.hpp).
#include "deflex/fanuc/fanuc_j519_link.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "deflex/online/online_strategy.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

namespace j519 = fanuc_j519;

CommandLimits fanuc_limits(const OnlineCompensator& c, const JointTrajectory* program, const FanucJ519LinkConfig& f) {
  f.validate();
  if (program == nullptr) throw InputError("FANUC J519 link: no program to stream");
  if (program->dof() != c.model().dof()) {
    throw InputError(
        fmt::format("FANUC J519 link: the program has {} joints, the robot {}", program->dof(), c.model().dof()));
  }
  if (c.model().dof() > static_cast<int>(j519::kAxes)) {
    throw InputError(fmt::format("FANUC J519 link: the robot has {} joints, the protocol carries at most {}",
                                 c.model().dof(), j519::kAxes));
  }
  CommandLimits l = command_limits(CommandForm::kJointTarget, c.config(), c.model().dof(), program, &f.stream);
  l.rounding = f.version == 1 ? WireRounding::kFloat32Deg : WireRounding::kExact;
  return l;
}

using Limits = std::array<j519::AxisLimits, j519::kAxes>;

// The smoother's limits: the correction's share of the strictest joint's acceleration and jerk (rad),
// its step the compensator's rate bound over one interval.
SmootherLimits smoother_limits(const OnlineCompensator& c, const FanucJ519LinkConfig& f, const Limits& limits) {
  SmootherLimits s;
  s.cycle_s = c.config().period_s;
  s.step_rad = c.config().max_correction_rate_rad_s * s.cycle_s;
  double acc = std::numeric_limits<double>::infinity();
  double jerk = acc;
  for (int j = 0; j < c.model().dof(); ++j) {
    acc = std::min(acc, limits[static_cast<std::size_t>(j)].acceleration);
    jerk = std::min(jerk, limits[static_cast<std::size_t>(j)].jerk);
  }
  s.acceleration = deg_to_rad(acc) * f.correction_share;
  s.jerk = deg_to_rad(jerk) * f.correction_share;
  return s;
}

// The averaging CorrectionSmoother::taps_for() would choose (its closed forms), without its throw: the
// threshold phase runs in poll(), which must not throw.
double smoother_taps_needed(const SmootherLimits& s) noexcept {
  const double t = s.cycle_s;
  const double for_acceleration = 2.0 * s.step_rad / (s.acceleration * t * t);
  const double for_jerk = std::sqrt(4.0 * s.step_rad / (s.jerk * t * t * t));
  return std::ceil(std::max({1.0, for_acceleration, for_jerk}) - 1e-12);
}

// What the rest of the stream takes of each limit, per the closed forms (deg/s, deg/s^2, deg/s^3):
//   the correction: its rate bound's velocity and its share of the acceleration and jerk;
//   the ramp-in blend (a smoothstep of at most the start tolerance d over R): velocity 1.5 d/R,
//     acceleration 6 d/R^2, jerk 6 d/(R^2 T) where its acceleration starts (a finite difference) plus
//     12 d/R^3;
//   protocol 1's float32 degrees: rounding errors of half an ulp u at the largest joint value give up to
//     u/T, 2u/T^2 and 4u/T^3.
// The program may use what is left (nothing left: a ProgramFault naming the culprit).
j519::AxisLimits program_budget(const j519::AxisLimits& l, const OnlineCompensator& c, const FanucJ519LinkConfig& f,
                                double largest_deg) noexcept {
  const double t = c.config().period_s;
  const double d = rad_to_deg(f.stream.start_tolerance_rad);
  const double r = f.stream.ramp_in_s;
  const double u = f.version == 1
                       ? std::nextafter(static_cast<float>(largest_deg), HUGE_VALF) - static_cast<float>(largest_deg)
                       : 0.0;
  j519::AxisLimits b;
  b.velocity = l.velocity - rad_to_deg(c.config().max_correction_rate_rad_s) - (r > 0 ? 1.5 * d / r : 0.0) - u / t;
  b.acceleration = l.acceleration * (1.0 - f.correction_share) - (r > 0 ? 6.0 * d / (r * r) : 0.0) - 2.0 * u / (t * t);
  b.jerk = l.jerk * (1.0 - f.correction_share) - (r > 0 ? 6.0 * d / (r * r * t) + 12.0 * d / (r * r * r) : 0.0) -
           4.0 * u / (t * t * t);
  return b;
}

// Why a program cannot be streamed within the limits: nothing of a joint's limits left beside the rest of
// the stream (`budget`), or the program alone over what is left (`hit` on `joint` at `time_s`).
struct ProgramFault {
  bool budget = false;
  j519::LimitExceeded hit = j519::LimitExceeded::kNone;
  std::size_t joint = 0;  // 0-based
  double value = 0.0, limit = 0.0, time_s = 0.0;
  [[nodiscard]] bool any() const { return budget || hit != j519::LimitExceeded::kNone; }
};

// The program alone, sampled at the interval as the controller will see it, against what the budget
// leaves it of `limits`. Allocates nothing (the threshold phase runs it inside poll()).
ProgramFault find_program_fault(const JointTrajectory& program, const OnlineCompensator& c,
                                const FanucJ519LinkConfig& f, const Limits& limits) noexcept {
  const double interval_s = c.config().period_s;
  double largest = 0.0;
  for (const JointVector& q : program.points()) largest = std::max(largest, rad_to_deg(q.cwiseAbs().maxCoeff()));
  largest += rad_to_deg(c.config().max_joint_correction_rad) + rad_to_deg(f.stream.start_tolerance_rad);
  ProgramFault fault;
  Limits rest = limits;
  for (std::size_t j = 0; j < static_cast<std::size_t>(program.dof()); ++j) {
    rest[j] = program_budget(limits[j], c, f, largest);
    if (rest[j].velocity <= 0.0 || rest[j].acceleration <= 0.0 || rest[j].jerk <= 0.0) {
      fault.budget = true;
      fault.joint = j;
      return fault;
    }
  }
  j519::MotionCheck check(interval_s, static_cast<std::size_t>(program.dof()), rest);
  JointVector q(program.dof());
  std::array<double, j519::kAxes> deg{};
  const auto to_deg = [&] {
    for (int j = 0; j < q.size(); ++j) deg[static_cast<std::size_t>(j)] = rad_to_deg(q[j]);
  };
  program.sample(program.start_time_s(), q);
  to_deg();
  check.reset(deg);
  const auto steps = static_cast<long>(std::ceil(program.duration_s() / interval_s));
  for (long k = 1; k <= steps + 3; ++k) {
    program.sample(std::min(program.start_time_s() + static_cast<double>(k) * interval_s, program.end_time_s()), q);
    to_deg();
    fault.hit = check.push(deg, fault.joint, fault.value);
    if (fault.hit == j519::LimitExceeded::kNone) continue;
    const j519::AxisLimits& l = rest[fault.joint];
    fault.limit = fault.hit == j519::LimitExceeded::kVelocity       ? l.velocity
                  : fault.hit == j519::LimitExceeded::kAcceleration ? l.acceleration
                                                                    : l.jerk;
    fault.value = std::abs(fault.value);
    fault.time_s = static_cast<double>(k) * interval_s;
    return fault;
  }
  return fault;
}

// The configured limits at construction: a program they cannot carry is an InputError naming the culprit.
void check_program(const JointTrajectory& program, const OnlineCompensator& c, const FanucJ519LinkConfig& f) {
  const ProgramFault fault = find_program_fault(program, c, f, f.limits);
  if (!fault.any()) return;
  const double t = c.config().period_s;
  if (fault.budget) {
    const j519::AxisLimits& l = f.limits[fault.joint];
    const double r = f.stream.ramp_in_s;
    throw InputError(fmt::format(
        "FANUC J519 link: at a {:g} ms interval the correction (--max-rate-deg-s, --fanuc-correction-share), the "
        "ramp-in blend (--ramp-in-s {:g} from up to {:g} deg away){} leave the program nothing of the limits "
        "{:g} deg/s, {:g} deg/s^2, {:g} deg/s^3: lengthen --ramp-in-s{}, lower --max-rate-deg-s",
        t * 1e3, r, rad_to_deg(f.stream.start_tolerance_rad),
        f.version == 1 ? " and protocol 1's float32 rounding" : "", l.velocity, l.acceleration, l.jerk,
        f.version == 1 ? ", use --fanuc-version 3" : ""));
  }
  throw InputError(fmt::format(
      "FANUC J519 link: the program alone reaches a {} of {:.6g} on joint {} at {:.3f} s, over the {:.6g} the "
      "controller's limit leaves it beside the correction ({:.0f} % of acceleration and jerk), the ramp-in blend "
      "and the wire's rounding at a {:.0f} ms interval: the controller would stop the stream; slow the program "
      "down (or give it more points where it turns) or give the controller's own limits",
      j519::to_string(fault.hit), fault.value, fault.joint + 1, fault.time_s, fault.limit, 100.0 * f.correction_share,
      t * 1e3));
}

}  // namespace

std::array<j519::AxisLimits, j519::kAxes> parse_fanuc_limits(const std::string& text, const char* option) {
  std::vector<std::string> joints;
  std::string rest = text;
  for (std::size_t at = rest.find(';'); at != std::string::npos; at = rest.find(';')) {
    joints.push_back(rest.substr(0, at));
    rest = rest.substr(at + 1);
  }
  joints.push_back(rest);
  if (joints.size() > j519::kAxes) {
    throw InputError(fmt::format("option {}: {} triples, at most {}", option, joints.size(), j519::kAxes));
  }
  std::array<j519::AxisLimits, j519::kAxes> limits = FanucJ519LinkConfig::default_limits();
  for (std::size_t j = 0; j < joints.size(); ++j) {
    double v[3] = {0.0, 0.0, 0.0};
    char extra = 0;
    if (std::sscanf(joints[j].c_str(), " %lf , %lf , %lf %c", &v[0], &v[1], &v[2], &extra) != 3) {
      throw InputError(fmt::format("option {}: '{}' is not VEL,ACC,JERK (deg/s, deg/s^2, deg/s^3), e.g. 120,265,1240",
                                   option, joints[j]));
    }
    for (const double x : v) {
      if (!std::isfinite(x) || x <= 0.0) {
        throw InputError(fmt::format("option {}: '{}': every limit must be positive", option, joints[j]));
      }
    }
    const j519::AxisLimits l{v[0], v[1], v[2]};
    if (joints.size() == 1) {
      limits.fill(l);
    } else {
      limits[j] = l;
    }
  }
  return limits;
}

void FanucJ519LinkConfig::validate() const {
  if (!j519::known_version(version)) {
    throw InputError(fmt::format("FANUC J519 link: protocol version {} is not 1, 3 or 4", version));
  }
  if (!(correction_share > 0.0 && correction_share < 1.0)) {
    throw InputError(fmt::format("FANUC J519 link: the correction's share of the limits must be in (0, 1), got {}",
                                 correction_share));
  }
  for (std::size_t i = 0; i < limits.size(); ++i) {
    const j519::AxisLimits& l = limits[i];
    for (const double v : {l.velocity, l.acceleration, l.jerk}) {
      if (!std::isfinite(v) || v <= 0.0) {
        throw InputError(
            fmt::format("FANUC J519 link: joint {}'s limits must be positive (velocity {} deg/s, "
                        "acceleration {} deg/s^2, jerk {} deg/s^3)",
                        i + 1, l.velocity, l.acceleration, l.jerk));
      }
    }
  }
  if (!(start_resend_s > 0.0) || max_catch_up < 0 || max_catch_up > 9) {
    throw InputError("FANUC J519 link: start_resend_s must be > 0 and max_catch_up (--fanuc-catch-up) in 0..9");
  }
  if (!(capability_timeout_s > 0.0 && capability_timeout_s <= 10.0) || capability_retries < 0 ||
      capability_retries > 10) {
    throw InputError(
        "FANUC J519 link: capability_timeout_s must be in (0, 10] s and capability_retries in 0..10 (the capability "
        "request)");
  }
  if (!(threshold_timeout_s > 0.0 && threshold_timeout_s <= 10.0) || threshold_retries < 0 || threshold_retries > 10) {
    throw InputError(
        "FANUC J519 link: threshold_timeout_s must be in (0, 10] s and threshold_retries in 0..10 (the threshold "
        "tables' requests)");
  }
}

FanucJ519Link::FanucJ519Link(OnlineCompensator& compensator, OnlineStrategy& strategy,
                             std::shared_ptr<const JointTrajectory> nominal, DatagramTransport& transport,
                             const Clock& clock, const FanucJ519LinkConfig& config)
    : ControllerLink(compensator, strategy, clock, fanuc_limits(compensator, nominal.get(), config), config.stop,
                     config.history_cycles),
      config_(config),
      transport_(transport),
      gate_([&] {
        ControllerGateConfig g;
        g.period_s = compensator.config().period_s;
        return g;
      }()),
      stream_(std::move(nominal), config.stream),
      smoother_(smoother_limits(compensator, config, config.limits), compensator.model().dof()),
      delay_(config.initial_delay_s),
      period_s_(compensator.config().period_s),
      limits_(config.limits) {
  check_program(stream_.trajectory(), compensator, config_);
  if (!config_.read_thresholds) tables_done_ = true;
  capability_counters_.asked = config_.version >= 3;
  capability_done_ = !capability_counters_.asked;
  const int n = compensator.model().dof();
  for (JointVector* q : {&feedback_, &program_, &program_velocity_, &blend_, &blend_velocity_, &nominal_}) {
    *q = JointVector::Zero(n);
  }
  rx_.assign(config_.max_packet_bytes + 1, 0);
  tx_.assign(j519::kMaxDatagramBytes, 0);
  cycle_.shape_with(&smoother_);
}

bool FanucJ519Link::send_command(std::uint32_t sequence, const JointVector& target_rad, bool last) noexcept {
  command_.sequence = sequence;
  command_.last = last;
  command_.joint_style = true;
  command_.target = aux_deg_;  // axes beyond the arm's (E1..E3) stay where the controller had them
  for (int i = 0; i < target_rad.size(); ++i) command_.target[static_cast<std::size_t>(i)] = rad_to_deg(target_rad[i]);
  const std::size_t n = j519::encode(config_.version, command_, tx_.data(), tx_.size());
  if (n == 0 || !transport_.send_to(tx_.data(), n, config_.controller)) {
    ++counters_.send_errors;
    return false;
  }
  ++counters_.replies;
  return true;
}

bool FanucJ519Link::drain(double timeout_s, j519::Status& newest, bool& session_start) noexcept {
  bool got = false;
  DatagramAddress from;
  if (!transport_.wait_readable(timeout_s)) return false;
  for (int i = 0; i < 1024; ++i) {  // a flood cannot hold the cycle
    const long n = transport_.receive(rx_.data(), rx_.size(), from);
    if (n < 0) break;
    ++counters_.datagrams;
    const double now = clock_.now_s();
    if (!(from == config_.controller)) {
      ++counters_.foreign_sender;
      continue;
    }
    gate_.heard(from, now);
    if (static_cast<std::size_t>(n) > config_.max_packet_bytes) {
      ++counters_.oversized;
      continue;
    }
    const j519::DecodeStatus d = j519::decode(rx_.data(), static_cast<std::size_t>(n), status_);
    if (d != j519::DecodeStatus::kOk) {
      if (d == j519::DecodeStatus::kNonFinite) {
        ++counters_.non_finite;
      } else if (d == j519::DecodeStatus::kWrongSize) {
        ++counters_.truncated;
      } else {
        ++counters_.malformed;
      }
      continue;
    }
    if (status_.version != config_.version) {
      stop_link(LinkStopCause::kProtocol,
                "the controller streams protocol version %u, deflex was set to version %u (FANUC's MOTN-607): give "
                "--fanuc-version %u",
                status_.version, config_.version, status_.version);
      return false;
    }
    bool starts = false;
    LinkArrival arrival;
    if (!gate_.take(from, status_.sequence, status_.time_stamp_ms, now, counters_, starts, arrival)) continue;
    if (got) ++counters_.superseded;
    newest = status_;
    receipt_age_s_ = transport_.since_receipt_s();
    taken_at_s_ = clock_.now_s();
    arrival_ = arrival;
    session_start = session_start || starts;
    got = true;
  }
  return got;
}

bool FanucJ519Link::controller_state(const j519::Status& s) noexcept {
  const double program_s = stream_.program_time_s() - stream_.trajectory().start_time_s();
  if (s.version >= 3 && s.in_error()) {
    stop_link(LinkStopCause::kController,
              "the controller reports an error (robot status 0x%02x: in error or e-stopped) at program time %.3f s",
              static_cast<unsigned>(s.robot_status), program_s);
    return false;
  }
  if (!s.ready()) {
    if (!ready_seen_) {
      ++counters_.not_running;  // the TP program is not waiting in IBGN yet: nothing is consumed
      return false;
    }
    const auto unanswered = static_cast<std::int32_t>(s.sequence - next_sequence_);
    if (unanswered > 1) {
      stop_link(LinkStopCause::kController,
                "the controller cleared its ready bit at program time %.3f s, after %d of its statuses deflex did not "
                "answer in time (the PC stalled or the network lost them): its command queue ran dry (MOTN-603)",
                program_s, unanswered);
    } else {
      stop_link(LinkStopCause::kController,
                "the controller cleared its ready bit at program time %.3f s: it stopped the stream (an alarm such "
                "as MOTN-603 receiving interval over or a joint limit MOTN-609..611, or the TP program left IBGN)",
                program_s);
    }
    return false;
  }
  return true;
}

// The first ready status: its joints (in feedback_) are where the arm is, the anchor of the stream. It
// is the only session a link runs (a new one stops it, poll_once), so nothing was sent before.
bool FanucJ519Link::start_session(const j519::Status& s) noexcept {
  if (!stream_.begin(feedback_, cycle_.correction())) {
    refuse_start(stream_.distance());
    return false;
  }
  cycle_.anchor_joints(feedback_, true);
  for (std::size_t i = 0; i < j519::kAxes; ++i) aux_deg_[i] = s.joints_deg[i];
  next_sequence_ = s.sequence;
  ready_seen_ = true;
  state_ = LinkState::kRunning;
  return true;
}

// ---- The capability (protocol 3 and 4), before the threshold tables ---------------------------------------
// FANUC's own driver asks it first (the reference notes, "Session flow"); a controller's reply names the
// newest protocol it speaks and its interval. Version 1 documents no capability packet, so a version-1
// link asks nothing. One request in flight, as for the tables; its id is 1, as in the reference's layout.

namespace {
constexpr std::uint32_t kCapabilityId = 1;

// The newest version deflex speaks that a controller offering `available` has.
std::uint32_t speakable(std::uint32_t available) noexcept { return available >= 4 ? 4 : available >= 3 ? 3 : 1; }
}  // namespace

void FanucJ519Link::send_capability_request(double now) noexcept {
  j519::Capability rq;
  rq.type = j519::kTypeCapabilityGet;
  rq.version = config_.version;
  rq.id = kCapabilityId;
  send_request(j519::encode(rq, tx_.data(), tx_.size()), capability_request_, capability_counters_.resent, now);
}

void FanucJ519Link::send_request(std::size_t n, PendingRequest& request, std::uint64_t& resent, double now) noexcept {
  if (n == 0 || !transport_.send_to(tx_.data(), n, config_.controller)) ++counters_.send_errors;
  if (request.attempts > 0) ++resent;
  ++request.attempts;
  request.sent_s = now;
}

// A datagram from the controller in the capability phase (in rx_): a reply to the get (type 7, 28 bytes,
// id 1) whose read-only fields are a version and an interval is taken; anything else is rejected and
// counted, never used. The header's version is not judged: what a controller writes there in a reply is
// not published, and available_version is the field that names what it speaks.
bool FanucJ519Link::take_capability_reply(std::size_t size) noexcept {
  j519::Capability c;
  if (j519::decode(rx_.data(), size, c) != j519::DecodeStatus::kOk || c.type != j519::kTypeCapabilityGet ||
      c.id != kCapabilityId || c.available_version < 1 || c.available_version > 99 || c.sampling_rate_ms < 1 ||
      c.sampling_rate_ms > 100) {
    ++capability_counters_.rejected;
    return false;
  }
  capability_ = c;
  capability_counters_.read = true;
  return true;
}

// What the reply says against what deflex was told: an older protocol than --fanuc-version (the controller
// would raise MOTN-607 at the start packet) or another interval than --period-ms stops the link, nothing
// sent yet.
void FanucJ519Link::judge_capability() noexcept {
  const j519::Capability& c = capability_;
  if (c.available_version < config_.version) {
    stop_link(LinkStopCause::kController,
              "the controller's capability reply offers J519 protocol version %u, deflex was set to version %u: its "
              "start packet would raise MOTN-607 (ST: Protocol version mismatch PC %u, Rob %u); nothing was sent: "
              "give --fanuc-version %u",
              c.available_version, config_.version, config_.version, c.available_version,
              speakable(c.available_version));
    return;
  }
  if (std::abs(static_cast<double>(c.sampling_rate_ms) - period_s_ * 1e3) > 1e-6) {
    stop_link(LinkStopCause::kProtocol,
              "the controller's capability reply gives a sampling rate of %u ms, deflex runs at %g ms (--period-ms): "
              "set it to the controller's $STMO.$COM_INT; nothing was sent",
              c.sampling_rate_ms, period_s_ * 1e3);
  }
}

template <typename Take>
void FanucJ519Link::receive_before_stream(double wait_s, Take&& take) noexcept {
  if (!transport_.wait_readable(std::max(0.0, wait_s))) return;
  DatagramAddress from;
  for (int i = 0; i < 64; ++i) {  // a flood cannot hold the poll
    const long n = transport_.receive(rx_.data(), rx_.size(), from);
    if (n < 0) break;
    ++counters_.datagrams;
    if (!(from == config_.controller)) {
      ++counters_.foreign_sender;
    } else if (static_cast<std::size_t>(n) > config_.max_packet_bytes) {
      ++counters_.oversized;
    } else if (!take(static_cast<std::size_t>(n))) {
      break;
    }
  }
}

// True once the phase is over: the reply taken (and judged), or the link stopped.
bool FanucJ519Link::read_capability(double timeout_s) noexcept {
  double now = clock_.now_s();
  if (capability_request_.attempts == 0) {
    // A stop packet first, as FANUC's own protocol-3 driver begins (the reference notes, "Session flow"):
    // a session whose PC went away (a crash, a pulled cable) leaves the controller sending statuses to
    // it, and while it does it answers no capability request and takes no new start. Before any start
    // packet of this link, so nothing of this session is stopped by it.
    transmit_stop();
    capability_counters_.cleared = true;
    send_capability_request(now);
  }
  receive_before_stream(std::min(timeout_s, capability_request_.sent_s + config_.capability_timeout_s - now),
                        [this](std::size_t size) { return !take_capability_reply(size); });
  if (capability_counters_.read) {
    capability_done_ = true;
    judge_capability();
    return true;
  }
  now = clock_.now_s();
  if (now - capability_request_.sent_s < config_.capability_timeout_s) return false;
  if (capability_request_.attempts <= config_.capability_retries) {
    send_capability_request(now);
    return false;
  }
  // No reply at all is read the strict way: a controller that has protocol 3 answers the request (FANUC's
  // own driver relies on it), and a v3 client on one that does not gets MOTN-607 "ST: Protocol version
  // mismatch PC 3, Rob 1" (reference notes, "Versions 2, 3 and 4": fanuc_driver issue #39). Guessing the
  // version could start a stream the controller refuses, so the link stops and names the choice.
  capability_counters_.unanswered = true;
  capability_done_ = true;
  stop_link(LinkStopCause::kController,
            "the controller answered no capability request (%d tries of %g s): a controller without J519 protocol "
            "3 does not, and a version %u start packet on it raises MOTN-607 (ST: Protocol version mismatch PC %u, "
            "Rob 1); nothing was sent: give --fanuc-version 1 if the controller has only version 1",
            config_.capability_retries + 1, config_.capability_timeout_s, config_.version, config_.version);
  return true;
}

// ---- The threshold tables, before the start packet ------------------------------------------------------
// One request in flight at a time, as FANUC's own driver asks (it sends each and waits for its reply
// before the next): nothing published says the controller queues several, and a reply names its axis and
// kind anyway, so a late one is told apart. The tables are read at their strictest column (the lowest
// value at any Cartesian speed, with or without payload): a stream held to that is within the table
// whatever speed and payload the controller computes its limit for ($LMT_MODE), at the price of some
// margin at low speed.

void FanucJ519Link::send_threshold_request(double now) noexcept {
  j519::ThresholdRequest rq;
  rq.axis = static_cast<std::uint32_t>(table_next_ / 3 + 1);
  rq.kind = static_cast<j519::LimitKind>(table_next_ % 3);
  send_request(j519::encode(rq, tx_.data(), tx_.size()), table_request_, thresholds_.resent, now);
}

// A datagram from the controller in the threshold phase (in rx_): the table asked for is taken; any other
// threshold reply (another axis or kind, a wrong size, a value not finite or not > 0) is rejected and
// counted; anything else is not answered (nothing is before the start packet).
void FanucJ519Link::take_threshold_reply(std::size_t size) noexcept {
  std::uint32_t type = 0;
  std::uint32_t version = 0;
  if (!j519::peek_header(rx_.data(), size, type, version) || type != j519::kTypeThreshold) {
    ++counters_.not_running;
    return;
  }
  j519::ThresholdReply reply;
  if (j519::decode(rx_.data(), size, reply) != j519::DecodeStatus::kOk ||
      reply.axis != static_cast<std::uint32_t>(table_next_ / 3 + 1) ||
      static_cast<std::size_t>(reply.kind) != table_next_ % 3) {
    ++thresholds_.rejected;
    return;
  }
  const auto value = static_cast<double>(reply.strictest());
  if (!std::isfinite(value) || value <= 0.0) {  // decode() refuses these already; never a limit of 0
    ++thresholds_.rejected;
    return;
  }
  j519::AxisLimits& t = tables_[table_next_ / 3];
  (reply.kind == j519::LimitKind::kVelocity       ? t.velocity
   : reply.kind == j519::LimitKind::kAcceleration ? t.acceleration
                                                  : t.jerk) = value;
  ++thresholds_.read;
  ++table_next_;
  table_request_.attempts = 0;
}

// True once the phase is over (the start packet may go out in this poll).
bool FanucJ519Link::read_thresholds(double timeout_s) noexcept {
  const std::size_t total = 3 * static_cast<std::size_t>(compensator().model().dof());
  thresholds_.asked = total;
  double now = clock_.now_s();
  if (table_request_.attempts == 0) send_threshold_request(now);
  receive_before_stream(std::min(timeout_s, table_request_.sent_s + config_.threshold_timeout_s - now),
                        [this, total](std::size_t size) {
                          const std::size_t before = table_next_;
                          take_threshold_reply(size);
                          if (table_next_ != before && table_next_ < total) send_threshold_request(clock_.now_s());
                          return table_next_ < total;
                        });
  now = clock_.now_s();
  if (table_next_ < total && now - table_request_.sent_s >= config_.threshold_timeout_s) {
    if (table_request_.attempts <= config_.threshold_retries) {
      send_threshold_request(now);
    } else {
      thresholds_.unanswered = true;  // older system software: no tables; the limits given hold
    }
  }
  if (table_next_ < total && !thresholds_.unanswered) return false;
  apply_tables();
  return true;
}

// Per joint and kind, the stricter of the configured limit and the table's; stricter than configured
// changes what the program may use and what the smoother is sized from, so both are done again (without
// allocating: the program's check and the smoother are fixed-size).
void FanucJ519Link::apply_tables() noexcept {
  tables_done_ = true;
  const auto dof = static_cast<std::size_t>(compensator().model().dof());
  bool stricter = false;
  for (std::size_t j = 0; j < dof; ++j) {
    const j519::AxisLimits& t = tables_[j];
    j519::AxisLimits& l = limits_[j];
    for (auto [limit, table] :
         {std::pair{&l.velocity, t.velocity}, std::pair{&l.acceleration, t.acceleration}, std::pair{&l.jerk, t.jerk}}) {
      if (table > 0.0 && table < *limit) {
        *limit = table;
        stricter = true;
      }
    }
  }
  if (!stricter) return;
  const ProgramFault fault = find_program_fault(stream_.trajectory(), compensator(), config_, limits_);
  if (fault.any()) {
    const j519::AxisLimits& l = limits_[fault.joint];
    if (fault.budget) {
      stop_link(LinkStopCause::kController,
                "the controller's threshold tables limit joint %zu to %.6g deg/s, %.6g deg/s^2, %.6g deg/s^3: the "
                "correction and the ramp-in blend leave the program nothing of them; nothing was sent",
                fault.joint + 1, l.velocity, l.acceleration, l.jerk);
    } else {
      stop_link(LinkStopCause::kController,
                "the controller's threshold tables: the program alone reaches a %s of %.6g on joint %zu at %.3f s, "
                "over the %.6g its limit leaves it beside the correction; nothing was sent: slow the program down",
                j519::to_string(fault.hit), fault.value, fault.joint + 1, fault.time_s, fault.limit);
    }
    return;
  }
  const SmootherLimits sl = smoother_limits(compensator(), config_, limits_);
  if (smoother_taps_needed(sl) > static_cast<double>(CorrectionSmoother::kMaxTaps)) {
    stop_link(LinkStopCause::kController,
              "the controller's threshold tables (acceleration %.6g deg/s^2, jerk %.6g deg/s^3 at their strictest) "
              "would need more than %zu intervals of smoothing for the correction's rate bound: lower "
              "--max-rate-deg-s; nothing was sent",
              rad_to_deg(sl.acceleration / config_.correction_share), rad_to_deg(sl.jerk / config_.correction_share),
              CorrectionSmoother::kMaxTaps);
    return;
  }
  smoother_ = CorrectionSmoother(sl, static_cast<int>(dof));
}

LinkPollResult FanucJ519Link::poll(double timeout_s) noexcept {
  const LinkPollResult r = poll_once(timeout_s);
  // However the link stopped, the controller's status output ends with the stop packet.
  if ((state_ == LinkState::kStopped || state_ == LinkState::kRefused) && start_sent_ && !stop_sent_) {
    send_stop_packet();
  }
  return r;
}

void FanucJ519Link::send_stop_packet() noexcept {
  stop_sent_ = true;
  transmit_stop();
}

void FanucJ519Link::transmit_stop() noexcept {
  const std::size_t n = j519::encode_stop(config_.version, tx_.data(), tx_.size());
  if (n == 0 || !transport_.send_to(tx_.data(), n, config_.controller)) ++counters_.send_errors;
}

// FANUC's time stamps (2 ms resolution) tell the interval the controller runs: a session does not
// start on a controller whose interval is not deflex's period (its program would run at another speed
// and its jerk budget be off by the cube of the ratio).
bool FanucJ519Link::interval_agrees(const j519::Status& s) noexcept {
  if (!have_previous_status_) return false;
  const auto cycles = static_cast<std::int32_t>(s.sequence - previous_sequence_);
  if (cycles < 1 || cycles > 16) return false;
  const double interval_ms = static_cast<double>(static_cast<std::int32_t>(s.time_stamp_ms - previous_stamp_ms_)) /
                             static_cast<double>(cycles);
  if (std::abs(interval_ms - period_s_ * 1e3) > 2.0 / static_cast<double>(cycles) + 1e-9) {
    stop_link(LinkStopCause::kProtocol,
              "the controller's statuses come every %.1f ms by their time stamps, deflex runs at %.0f ms "
              "(--period-ms): set it to the controller's $STMO.$COM_INT",
              interval_ms, period_s_ * 1e3);
    return false;
  }
  return true;
}

LinkPollResult FanucJ519Link::poll_once(double timeout_s) noexcept {
  if (state_ == LinkState::kStopped || state_ == LinkState::kRefused) {
    j519::Status ignored;
    bool starts = false;
    if (drain(0.0, ignored, starts) && state_ == LinkState::kRefused) ++counters_.refused;
    return announce_terminal();
  }
  if (!capability_done_) {
    const std::uint64_t before = counters_.datagrams;
    if (!read_capability(timeout_s))
      return counters_.datagrams > before ? LinkPollResult::kRejected : LinkPollResult::kIdle;
    if (state_ == LinkState::kStopped) return announce_terminal();
    timeout_s = 0.0;  // this poll has waited already
  }
  if (!tables_done_) {
    const std::uint64_t before = counters_.datagrams;
    if (!read_thresholds(timeout_s)) {
      // A table taken is not a message answered (no cycle record): as the poll loop sees it, datagrams came.
      return counters_.datagrams > before ? LinkPollResult::kRejected : LinkPollResult::kIdle;
    }
    if (state_ == LinkState::kStopped) return announce_terminal();
    timeout_s = 0.0;  // this poll has waited already
  }
  double now = clock_.now_s();
  if (!ready_seen_ && now - last_start_s_ >= config_.start_resend_s) {
    const std::size_t n = j519::encode_start(config_.version, tx_.data(), tx_.size());
    if (n == 0 || !transport_.send_to(tx_.data(), n, config_.controller)) ++counters_.send_errors;
    last_start_s_ = now;
    start_sent_ = true;
  }
  j519::Status s;
  bool session_start = false;
  const std::uint64_t before = counters_.datagrams;
  if (!drain(timeout_s, s, session_start)) {
    if (state_ == LinkState::kStopped) return announce_terminal();
    now = clock_.now_s();
    if (apply_silence_rules(now)) return announce_terminal();
    return counters_.datagrams > before ? LinkPollResult::kRejected : LinkPollResult::kIdle;
  }
  now = clock_.now_s();
  heard(now);
  for (int i = 0; i < feedback_.size(); ++i) feedback_[i] = deg_to_rad(s.joints_deg[static_cast<std::size_t>(i)]);
  if (state_ == LinkState::kFinished) return finish(s, now);
  if (!ready_seen_) {
    // Every status before the session times the controller's interval.
    const bool agrees = interval_agrees(s);
    previous_sequence_ = s.sequence;
    previous_stamp_ms_ = s.time_stamp_ms;
    have_previous_status_ = true;
    if (state_ == LinkState::kStopped) return announce_terminal();
    if (!agrees) {
      ++counters_.not_running;
      return LinkPollResult::kNotAnswered;
    }
  }
  if (!controller_state(s)) return state_ == LinkState::kStopped ? announce_terminal() : LinkPollResult::kNotAnswered;
  if (ready_seen_ && session_start) {
    // A stream cannot be resumed: the controller's new session starts from rest while deflex's program
    // and smoother are moving.
    stop_link(LinkStopCause::kController,
              "the controller began a new session (its statuses numbered afresh, or after a silence) while the "
              "stream ran: a FANUC stream is not resumed; start deflex online again");
    return announce_terminal();
  }
  if (!ready_seen_) {
    if (!start_session(s)) return announce_terminal();
    session_start = true;
  }
  return answer(s.sequence, now, session_start);
}

LinkPollResult FanucJ519Link::answer(std::uint32_t sequence, double now, bool session_start) noexcept {
  const auto t_read = std::chrono::steady_clock::now();
  const auto missing = static_cast<std::int32_t>(sequence - next_sequence_);
  if (missing < 0) return LinkPollResult::kRejected;  // answered already (the gate refuses most of these)
  if (missing > config_.max_catch_up) {
    stop_link(LinkStopCause::kTooSlow,
              "%d controller statuses went unanswered in a row (%.0f ms), more than the %d deflex catches up: the "
              "controller's command buffer will have run dry (MOTN-603)",
              missing, missing * period_s_ * 1e3, config_.max_catch_up);
    return announce_terminal();
  }
  delay_.observe_feedback(now, feedback_);
  const auto compute = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t_read).count(); };
  for (std::int32_t k = 0; k <= missing; ++k) {
    if (ramping_down_) stream_.begin_stop(ramp_down_s_);
    stream_.sample(program_, program_velocity_, blend_, blend_velocity_);
    nominal_ = program_ + blend_;
    CycleRequest rq;
    // A caught-up command stands for an interval already past.
    const double t_k = now - static_cast<double>(missing - k) * period_s_;
    rq.t_s = t_k;
    rq.sequence = next_sequence_;
    rq.program_time_s = stream_.program_time_s();
    rq.nominal = &program_;
    rq.blend = &blend_;
    rq.feedback = &feedback_;
    rq.target = &nominal_;
    rq.delay_s = rq.lead_s = delay_.delay_s() + smoother_.delay_s();
    rq.session_start = session_start && k == 0;
    rq.arrival = arrival_;
    const LinkCycle::Verdict verdict = cycle_.run(rq);
    if (verdict != LinkCycle::Verdict::kSend) return cycle_not_passed(verdict, compute());
    if (!send_command(next_sequence_, cycle_.joint_command(), false)) {
      cycle_.not_sent(compute());
      return LinkPollResult::kNotAnswered;
    }
    cycle_.sent(compute(), receipt_age_s_ + (clock_.now_s() - taken_at_s_));
    delay_.record_reference(t_k, cycle_.joint_command());
    stream_.consumed(period_s_);
    ++next_sequence_;
    if (k > 0) ++caught_up_;
  }
  // At the program's end (or a planned stop at rest) the correction is held and the smoother settles:
  // the last-data command freezes a stream already at rest, adding no acceleration or jerk.
  if ((ramping_down_ && stream_.at_standstill()) || stream_.finished()) {
    smoother_.hold();
    if (smoother_.settled()) state_ = LinkState::kFinished;
  }
  return LinkPollResult::kAnswered;
}

// The program has ended (or a planned stop came to rest): the next status gets the last target again,
// flagged last-data; once the controller reports the session over (the ready or in-motion bit clear, as
// the TP program leaves IBGN), or after a second, the stop packet ends its status output.
LinkPollResult FanucJ519Link::finish(const j519::Status& s, double now) noexcept {
  if (!last_data_sent_) {
    if (!send_command(s.sequence, cycle_.last_command(), true)) return LinkPollResult::kNotAnswered;
    last_data_sent_ = true;
    last_data_s_ = now;
    return LinkPollResult::kAnswered;
  }
  // The stop packet once the TP program has left IBGN (the ready bit clear): the last-data command
  // may wait in the controller's queue until then. At most a second.
  if (s.ready() && now - last_data_s_ < 1.0) return LinkPollResult::kNotAnswered;
  send_stop_packet();
  if (ramping_down_) {
    stop_link(LinkStopCause::kRequested,
              "stopped on request: the program was brought to rest on its path over %.2f s; the last command went "
              "out flagged last-data, then the stop packet",
              ramp_down_s_);
  } else {
    stop_link(LinkStopCause::kEnded,
              "the program ended: the last command went out flagged last-data, then the stop packet");
  }
  return announce_terminal();
}

void FanucJ519Link::stop() noexcept {
  // Without the last-data flag the controller stops the stream itself (MOTN-603, a controlled stop);
  // the stop packet ends its status output.
  if (state_ != LinkState::kStopped && start_sent_ && !stop_sent_) send_stop_packet();
  stop_link(LinkStopCause::kRequested, "stop requested: the stop packet went out");
}

namespace {

// What the threshold phase gave: which limits the stream was held to and where they came from.
std::string fanuc_threshold_summary(const FanucJ519LinkConfig& config, const FanucThresholdCounters& t, bool done,
                                    const std::array<j519::AxisLimits, j519::kAxes>& limits, std::size_t dof) {
  j519::AxisLimits strictest{1e300, 1e300, 1e300};
  for (std::size_t j = 0; j < dof; ++j) {
    strictest = {std::min(strictest.velocity, limits[j].velocity),
                 std::min(strictest.acceleration, limits[j].acceleration), std::min(strictest.jerk, limits[j].jerk)};
  }
  std::string where;
  if (!config.read_thresholds) {
    where = "the threshold tables were not asked for: the limits given (--fanuc-limits) hold";
  } else if (!done) {
    where = fmt::format("the link stopped while the threshold tables were read ({} of {})", t.read, t.asked);
  } else if (t.read == t.asked) {
    where = fmt::format(
        "the controller's {} threshold tables were read: each joint's limit is the stricter of the table's strictest "
        "value and the one given",
        t.read);
  } else if (t.read == 0) {
    where = fmt::format(
        "the controller answered no threshold request ({} tries of {:g} s; older system software does not): the "
        "limits given (--fanuc-limits) hold",
        config.threshold_retries + 1, config.threshold_timeout_s);
  } else {
    where = fmt::format(
        "{} of the controller's {} threshold tables were read before it stopped answering: the limits given hold "
        "for the rest",
        t.read, t.asked);
  }
  if (t.rejected > 0) where += fmt::format(", {} threshold replies rejected", t.rejected);
  return fmt::format("{} (the strictest over the joints: {:g} deg/s, {:g} deg/s^2, {:g} deg/s^3)", where,
                     strictest.velocity, strictest.acceleration, strictest.jerk);
}

// What the capability exchange gave (protocol 3 and 4).
std::string fanuc_capability_summary(const FanucJ519LinkConfig& config, const FanucCapabilityCounters& k,
                                     const j519::Capability& c) {
  std::string out;
  if (!k.asked) {
    out = "protocol 1 has no capability exchange";
  } else if (k.read) {
    out = fmt::format(
        "the controller's capability: protocol {} available, sampling rate {} ms, start_move {}, status at the {}",
        c.available_version, c.sampling_rate_ms, c.start_move, c.status_uses_tcp == 1 ? "TCP" : "faceplate");
  } else if (k.unanswered) {
    out = fmt::format("the controller answered no capability request ({} tries of {:g} s)",
                      config.capability_retries + 1, config.capability_timeout_s);
  } else {
    out = "the link stopped while the controller's capability was asked";
  }
  if (k.rejected > 0) out += fmt::format(", {} capability replies rejected", k.rejected);
  return out;
}

}  // namespace

std::string FanucJ519Link::protocol_summary() const {
  return fmt::format(
      "FANUC J519 (protocol {}): {} commands sent, {} to catch up lost statuses; the correction smoothed over {} "
      "intervals ({:.0f} ms) to stay within {:.0f} % of the acceleration and jerk limits; {}; {}",
      config_.version, counters_.replies, caught_up_, smoother_.taps(), smoother_.delay_s() * 1e3,
      100.0 * config_.correction_share, fanuc_capability_summary(config_, capability_counters_, capability_),
      fanuc_threshold_summary(config_, thresholds_, tables_done_, limits_,
                              static_cast<std::size_t>(compensator().model().dof())));
}

}  // namespace deflex
