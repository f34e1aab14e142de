// Universal Robots over RTDE, deflex as the motion source (see ur_rtde_link.hpp).
#include "deflex/ur/ur_rtde_link.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <string>
#include <utility>

#include <fmt/format.h>

#include "deflex/online/online_strategy.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

// URControl major versions from 5 on are e-Series (and later) with a 500 Hz loop; older ones are CB3 at
// 125 Hz (the reference notes, from Universal Robots' client library).
double max_frequency_hz(const rtde::UrControlVersion& v) { return v.major >= 5 ? 500.0 : 125.0; }

const char* safety_mode_name(std::int32_t m) {
  switch (m) {
    case 3:
      return "a protective stop";
    case 4:
      return "recovery mode";
    case 5:
      return "a safeguard stop";
    case 6:
      return "a system emergency stop";
    case 7:
      return "a robot emergency stop";
    case 8:
      return "a safety violation";
    case 9:
      return "a safety fault";
    case 12:
      return "an automatic-mode safeguard stop";
    case 13:
    case 14:
      return "a three-position enabling stop";
    case 15:
      return "an IMMI emergency stop";
    default:
      return "a safety mode it does not run in";
  }
}

const char* runtime_state_name(std::uint32_t s) {
  switch (s) {
    case 0:
      return "stopping";
    case 1:
      return "stopped";
    case 3:
      return "pausing";
    case 4:
      return "paused";
    case 5:
      return "resuming";
    default:
      return "not playing";
  }
}

const char* phase_name(int phase) {
  constexpr const char* kNames[] = {"protocol version request",
                                    "controller version request",
                                    "output recipe",
                                    "input recipe",
                                    "start request",
                                    "data"};
  return phase >= 0 && phase < 6 ? kNames[phase] : "request";
}

CommandLimits ur_limits(const OnlineCompensator& c, const JointTrajectory* program, const UrRtdeLinkConfig& u) {
  u.validate();
  if (program == nullptr) throw InputError("UR RTDE link: no program to stream");
  if (c.model().dof() != 6 || program->dof() != 6) {
    throw InputError(fmt::format("UR RTDE link: servoj takes six joints (the robot has {}, the program {})",
                                 c.model().dof(), program->dof()));
  }
  return command_limits(CommandForm::kJointTarget, c.config(), 6, program, &u.stream);
}

}  // namespace

void UrRtdeLinkConfig::validate() const {
  stream.validate();
  stop.validate();
  if (!std::isfinite(lookahead_s) || lookahead_s < 0.03 - 1e-12 || lookahead_s > 0.2 + 1e-12) {
    throw InputError(fmt::format("setting ur_lookahead_s (--ur-lookahead-ms): servoj takes 30..200 ms (got {:g} ms)",
                                 lookahead_s * 1e3));
  }
  if (!std::isfinite(gain) || gain < 100.0 || gain > 2000.0) {
    throw InputError(fmt::format("setting ur_gain (--ur-gain): servoj takes 100..2000 (got {:g})", gain));
  }
  if (register_offset != 0 && register_offset != 24) {
    throw InputError(fmt::format(
        "setting ur_register_offset (--ur-register-offset): 0 or 24 (the upper range) (got {})", register_offset));
  }
  if (max_package_bytes < 256 || max_package_bytes > 65535) {
    throw InputError(fmt::format("setting ur max_package_bytes: 256..65535 (got {})", max_package_bytes));
  }
}

std::string ur_rtde_output_names(int o) {
  return fmt::format("timestamp,actual_q,target_q,robot_mode,safety_mode,runtime_state,output_int_register_{}", o);
}

std::string ur_rtde_input_names(int o) {
  std::string s = fmt::format("input_int_register_{},input_int_register_{}", o, o + 1);
  for (int k = 0; k < 8; ++k) s += fmt::format(",input_double_register_{}", o + k);
  return s;
}

UrRtdeLink::UrRtdeLink(OnlineCompensator& compensator, OnlineStrategy& strategy,
                       std::shared_ptr<const JointTrajectory> nominal, StreamTransport& transport, const Clock& clock,
                       const UrRtdeLinkConfig& config)
    : ControllerLink(compensator, strategy, clock, ur_limits(compensator, nominal.get(), config), config.stop,
                     config.history_cycles),
      config_(config),
      output_names_(ur_rtde_output_names(config.register_offset)),
      input_names_(ur_rtde_input_names(config.register_offset)),
      transport_(transport),
      stream_(std::move(nominal), config.stream),
      delay_(config.servoj_delay_s(compensator.config().period_s)),
      period_s_(compensator.config().period_s) {
  for (JointVector* q :
       {&feedback_, &program_, &program_velocity_, &blend_, &blend_velocity_, &nominal_, &last_sent_}) {
    *q = JointVector::Zero(6);
  }
  rx_.assign(2 * config_.max_package_bytes, 0);
  data_.assign(config_.max_package_bytes, 0);
  tx_.assign(4 * config_.max_package_bytes, 0);
}

void UrRtdeLink::protocol_fault(const char* what) noexcept {
  stop_link(LinkStopCause::kProtocol, "the controller's RTDE handshake failed: %s", what);
}

// The bytes of the package encoded at tx_end_ join what waits to be written.
bool UrRtdeLink::queue(std::size_t n) noexcept {
  if (n == 0) {
    ++counters_.send_errors;
    return false;
  }
  tx_end_ += n;
  return flush();
}

bool UrRtdeLink::flush() noexcept {
  while (tx_end_ > tx_begin_ && !closed_) {
    const long n = transport_.write(tx_.data() + tx_begin_, tx_end_ - tx_begin_);
    if (n == StreamTransport::kClosed) {
      closed_ = true;
      ++counters_.send_errors;
      return false;
    }
    if (n == 0) break;  // the window is full: the rest goes at the next poll
    if (static_cast<std::size_t>(n) < tx_end_ - tx_begin_) ++partial_writes_;
    tx_begin_ += static_cast<std::size_t>(n);
  }
  if (tx_begin_ == tx_end_) tx_begin_ = tx_end_ = 0;
  return true;
}

// The handshake's next request, once per phase.
bool UrRtdeLink::send_request() noexcept {
  if (requested_) return true;
  // A request waits behind unwritten bytes only if there is room for it.
  if (tx_.size() - tx_end_ < config_.max_package_bytes) return true;
  unsigned char* out = tx_.data() + tx_end_;
  const std::size_t cap = tx_.size() - tx_end_;
  std::size_t n = 0;
  switch (phase_) {
    case Phase::kVersion:
      n = rtde::encode_protocol_request(rtde::kProtocolVersion, out, cap);
      break;
    case Phase::kUrControl:
      n = rtde::encode_request(rtde::PackageType::kGetUrControlVersion, out, cap);
      break;
    case Phase::kOutputs:
      n = rtde::encode_setup_outputs(1.0 / period_s_, output_names_, out, cap);
      break;
    case Phase::kInputs:
      n = rtde::encode_setup_inputs(input_names_, out, cap);
      break;
    case Phase::kStart:
      n = rtde::encode_request(rtde::PackageType::kStart, out, cap);
      break;
    case Phase::kStreaming:
      return true;
  }
  requested_ = true;
  return queue(n);
}

// One reply of the handshake; false when it stopped the link.
bool UrRtdeLink::handshake(const unsigned char* p, std::size_t size, std::uint8_t type) noexcept {
  const auto t = static_cast<rtde::PackageType>(type);
  bool accepted = false;
  std::size_t field = 0;
  switch (phase_) {
    case Phase::kVersion:
      if (t != rtde::PackageType::kRequestProtocolVersion) break;
      if (rtde::decode_accepted(p, size, t, accepted) != rtde::DecodeStatus::kOk) break;
      if (!accepted) {
        protocol_fault("it does not speak RTDE protocol version 2 (a controller before PolyScope 3.10 / 5.4?)");
        return false;
      }
      phase_ = Phase::kUrControl;
      requested_ = false;
      return true;
    case Phase::kUrControl:
      if (t != rtde::PackageType::kGetUrControlVersion || rtde::decode(p, size, version_) != rtde::DecodeStatus::kOk) {
        break;
      }
      if (1.0 / period_s_ > max_frequency_hz(version_) * (1 + 1e-9)) {
        stop_link(LinkStopCause::kController,
                  "the controller (URControl %u.%u) runs at most %.0f Hz; the session's period of %.1f ms asks "
                  "%.0f Hz: give --period-ms %.0f",
                  version_.major, version_.minor, max_frequency_hz(version_), period_s_ * 1e3, 1.0 / period_s_,
                  1e3 / max_frequency_hz(version_));
        return false;
      }
      phase_ = Phase::kOutputs;
      requested_ = false;
      return true;
    case Phase::kOutputs:
    case Phase::kInputs: {
      const bool outputs = phase_ == Phase::kOutputs;
      rtde::Recipe& r = outputs ? out_recipe_ : in_recipe_;
      if (t != (outputs ? rtde::PackageType::kSetupOutputs : rtde::PackageType::kSetupInputs)) break;
      const rtde::DecodeStatus d = rtde::decode_setup_reply(p, size, t, r, field);
      if (d == rtde::DecodeStatus::kFieldNotFound || d == rtde::DecodeStatus::kFieldInUse) {
        stop_link(LinkStopCause::kController, "the controller refused %s field %zu of deflex's recipe (%s): %s",
                  outputs ? "output" : "input", field + 1, outputs ? output_names_.c_str() : input_names_.c_str(),
                  d == rtde::DecodeStatus::kFieldInUse
                      ? "IN_USE: another RTDE client or a fieldbus writes that register (try --ur-register-offset)"
                      : "NOT_FOUND: this controller has no such field (upper registers need PolyScope 3.9 / 5.3)");
        return false;
      }
      if (d != rtde::DecodeStatus::kOk) break;
      if (r.count != (outputs ? static_cast<std::size_t>(kOutputs) : static_cast<std::size_t>(kInputs))) {
        protocol_fault("the recipe reply has another number of fields than deflex asked for");
        return false;
      }
      phase_ = outputs ? Phase::kInputs : Phase::kStart;
      requested_ = false;
      return true;
    }
    case Phase::kStart:
      if (t != rtde::PackageType::kStart || rtde::decode_accepted(p, size, t, accepted) != rtde::DecodeStatus::kOk) {
        break;
      }
      if (!accepted) {
        protocol_fault("it did not accept the start of the data exchange");
        return false;
      }
      phase_ = Phase::kStreaming;
      return true;
    case Phase::kStreaming:
      break;
  }
  ++counters_.malformed;  // a reply of another type, or one that does not decode
  return true;
}

// A text message: exceptions and errors end the session (the controller is telling why it will not
// go on), warnings and information are counted and the last kept. Until the controller accepted
// protocol 2 its messages are in protocol 1's layout. The text is the controller's bytes: any that
// would not print is kept as '?', so the reason stays one readable line.
bool UrRtdeLink::text(const unsigned char* p, std::size_t size) noexcept {
  rtde::TextMessage m;
  const std::uint16_t protocol = phase_ == Phase::kVersion ? 1 : rtde::kProtocolVersion;
  if (rtde::decode_text(p, size, protocol, m) != rtde::DecodeStatus::kOk) {
    ++counters_.malformed;
    return true;
  }
  const std::size_t level = std::min<std::size_t>(m.level, 3);
  ++texts_[level];
  const std::size_t n = std::min(m.message.size(), last_text_.size() - 1);
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = static_cast<unsigned char>(m.message[i]);
    last_text_[i] = c >= 0x20 && c <= 0x7e ? static_cast<char>(c) : '?';
  }
  last_text_[n] = '\0';
  if (level > 1) return true;
  stop_link(LinkStopCause::kController, "the controller sent an RTDE %s message: %s",
            level == 0 ? "exception" : "error", last_text_.data());
  return false;
}

// A data package: kept if it is the newest usable one.
void UrRtdeLink::take_data(const unsigned char* p, std::size_t size) noexcept {
  if (phase_ != Phase::kStreaming) {
    ++counters_.malformed;
    return;
  }
  rtde::DataView v;
  const rtde::DecodeStatus d = v.reset(out_recipe_, p, size);
  if (d != rtde::DecodeStatus::kOk) {
    ++(d == rtde::DecodeStatus::kNonFinite                                           ? counters_.non_finite
       : d == rtde::DecodeStatus::kWrongSize && size < out_recipe_.payload_bytes + 4 ? counters_.truncated
                                                                                     : counters_.malformed);
    return;
  }
  const double ts = v.get_double(kTimestamp);
  if (ts <= last_timestamp_) {
    ++counters_.out_of_order;
    return;
  }
  last_timestamp_ = ts;
  if (have_data_) ++counters_.superseded;
  std::memcpy(data_.data(), p, size);
  data_size_ = size;
  have_data_ = true;
}

bool UrRtdeLink::handle(const unsigned char* p, std::size_t size, std::uint8_t type) noexcept {
  ++counters_.datagrams;
  const auto t = static_cast<rtde::PackageType>(type);
  if (t == rtde::PackageType::kTextMessage) return text(p, size);
  if (t == rtde::PackageType::kDataPackage) {
    take_data(p, size);
    return true;
  }
  if (!rtde::known_package_type(type)) {
    ++counters_.malformed;
    return true;
  }
  return handshake(p, size, type);
}

// Reads what the stream holds and handles every whole package; false when the link stopped.
bool UrRtdeLink::read_stream() noexcept {
  for (int round = 0; round < 64; ++round) {  // a flood cannot hold the cycle
    const long n = transport_.read(rx_.data() + rx_size_, rx_.size() - rx_size_);
    if (n == StreamTransport::kClosed) {
      closed_ = true;
      stop_link(LinkStopCause::kConnection, "the controller closed the RTDE connection (or it broke)%s",
                state_ == LinkState::kFinished ? " after the program's end" : "");
      return false;
    }
    if (n == 0) return true;
    rx_size_ += static_cast<std::size_t>(n);
    std::size_t at = 0;
    for (;;) {
      if (skip_ > 0) {  // the rest of an oversized package: its size framed it, its bytes are dropped
        const std::size_t k = std::min(skip_, rx_size_ - at);
        skip_ -= k;
        at += k;
        if (skip_ > 0) break;
      }
      std::size_t bytes = 0;
      std::uint8_t type = 0;
      const rtde::FrameStatus f =
          rtde::peek_package(rx_.data() + at, rx_size_ - at, config_.max_package_bytes, bytes, type);
      if (f == rtde::FrameStatus::kIncomplete) break;
      if (f == rtde::FrameStatus::kOversized) {
        ++counters_.datagrams;
        ++counters_.oversized;
        skip_ = bytes;
        continue;
      }
      if (f != rtde::FrameStatus::kComplete) {
        // A size below the header's own: the stream cannot be re-framed, the connection is of no more use.
        ++counters_.malformed;
        stop_link(LinkStopCause::kProtocol, "the controller's RTDE stream is out of step: a package header %s",
                  rtde::to_string(f));
        return false;
      }
      if (!handle(rx_.data() + at, bytes, type)) return false;
      at += bytes;
    }
    std::memmove(rx_.data(), rx_.data() + at, rx_size_ - at);
    rx_size_ -= at;
  }
  return true;
}

bool UrRtdeLink::send_targets(const JointVector& q, std::int32_t mode) noexcept {
  if (tx_.size() - tx_end_ < config_.max_package_bytes) {
    ++counters_.send_errors;  // the controller has not read the last packages: this one is not queued
    return false;
  }
  rtde::DataBuilder b(in_recipe_, tx_.data() + tx_end_, tx_.size() - tx_end_);
  const std::int32_t next = counter_ == 2147483647 ? 1 : counter_ + 1;
  b.set(kCounter, next);
  b.set(kMode, mode);
  for (std::size_t j = 0; j < 6; ++j) b.set(kQ0 + j, q[static_cast<int>(j)]);
  b.set(kLookahead, config_.lookahead_s);
  b.set(kGain, config_.gain);
  if (!queue(b.finish())) return false;
  counter_ = next;
  last_sent_ = q;
  ++counters_.replies;
  return true;
}

// The controller's state in the newest package; false when it stopped the link.
bool UrRtdeLink::controller_ok(double now) noexcept {
  (void)now;
  const double pt = stream_.program_time_s() - stream_.trajectory().start_time_s();
  if (safety_mode_ != 1 && safety_mode_ != 2) {
    stop_link(LinkStopCause::kController,
              "the controller reports %s (safety_mode %d) at program time %.3f s: the arm stopped; clear it on the "
              "pendant and start the program again",
              safety_mode_name(safety_mode_), safety_mode_, pt);
    return false;
  }
  if (robot_mode_ != 7) {
    stop_link(LinkStopCause::kController, "the controller reports robot_mode %d (not running) at program time %.3f s",
              robot_mode_, pt);
    return false;
  }
  return true;
}

// A link that stopped reads what still comes (counted as refused when it refused to start) and says so.
LinkPollResult UrRtdeLink::wind_down() noexcept {
  (void)flush();
  if (!closed_) {
    unsigned char sink[512];
    for (long n = transport_.read(sink, sizeof(sink)); n > 0; n = transport_.read(sink, sizeof(sink))) {
      if (state_ == LinkState::kRefused) ++counters_.refused;
    }
  }
  return announce_terminal();
}

// A handshake the controller does not finish in time ends the link (a port that is not RTDE's).
bool UrRtdeLink::handshake_overdue() noexcept {
  if (phase_ == Phase::kStreaming) return false;
  const double now = clock_.now_s();
  if (handshake_start_s_ < 0.0) handshake_start_s_ = now;
  const double limit = std::max(2.0, rules_.stop_silence_s);
  if (now - handshake_start_s_ <= limit) return false;
  stop_link(LinkStopCause::kSilent,
            "the controller did not complete the RTDE handshake within %.1f s (no answer to deflex's %s): is this port "
            "RTDE's (30004)?",
            limit, phase_name(static_cast<int>(phase_)));
  return true;
}

// The output package's fields the link reads: the actual joints and the controller's modes.
void UrRtdeLink::take_state() noexcept {
  rtde::DataView v;
  (void)v.reset(out_recipe_, data_.data(), data_size_);
  const std::array<double, 6> q = v.get_vector6d(kActualQ);
  for (int j = 0; j < 6; ++j) feedback_[j] = q[static_cast<std::size_t>(j)];
  robot_mode_ = v.get_int32(kRobotMode);
  safety_mode_ = v.get_int32(kSafetyMode);
  runtime_state_ = v.get_uint32(kRuntimeState);
}

LinkPollResult UrRtdeLink::poll(double timeout_s) noexcept {
  if (state_ == LinkState::kStopped || state_ == LinkState::kRefused) return wind_down();
  if (!flush() || !send_request()) {
    stop_link(LinkStopCause::kConnection, "the RTDE connection is closed (a write failed)");
    return announce_terminal();
  }
  if (handshake_overdue()) return announce_terminal();
  if (!transport_.wait_readable(timeout_s) && rx_size_ == 0) {
    if (phase_ == Phase::kStreaming && apply_silence_rules(clock_.now_s())) return announce_terminal();
    return LinkPollResult::kIdle;
  }
  const std::uint64_t before = counters_.datagrams;
  have_data_ = false;
  if (!read_stream()) return announce_terminal();
  if (!have_data_) {
    if (phase_ == Phase::kStreaming && apply_silence_rules(clock_.now_s())) return announce_terminal();
    return counters_.datagrams > before ? LinkPollResult::kRejected : LinkPollResult::kIdle;
  }
  const double now = clock_.now_s();
  receipt_s_ = now;
  take_state();
  if (!controller_ok(now)) return announce_terminal();
  if (runtime_state_ != 2) {
    if (playing_seen_) {
      stop_link(LinkStopCause::kController,
                "the program on the controller is %s (runtime_state %u) at program time %.3f s: it stopped servoing "
                "(stopped on the pendant, or its watchdog saw no new target)",
                runtime_state_name(runtime_state_), runtime_state_,
                stream_.program_time_s() - stream_.trajectory().start_time_s());
      return announce_terminal();
    }
    ++counters_.not_running;  // the program is not started yet: nothing to servo
    return LinkPollResult::kNotAnswered;
  }
  playing_seen_ = true;
  heard(now);
  if (state_ == LinkState::kWaiting) return start_session(now);
  if (state_ == LinkState::kFinished) {
    stop_link(LinkStopCause::kEnded, "the program ended: the script holds its last target and ends its servo loop");
    return announce_terminal();
  }
  return answer(now);
}

// The first package with the program playing: what the controller's servo holds is the anchor.
LinkPollResult UrRtdeLink::start_session(double now) noexcept {
  rtde::DataView v;
  (void)v.reset(out_recipe_, data_.data(), data_size_);
  const std::array<double, 6> t = v.get_vector6d(kTargetQ);
  JointVector anchor(6);
  for (int j = 0; j < 6; ++j) anchor[j] = t[static_cast<std::size_t>(j)];
  if (!stream_.begin(anchor, cycle_.correction())) {
    refuse_start(stream_.distance());
    return announce_terminal();
  }
  cycle_.anchor_joints(anchor, true);
  state_ = LinkState::kRunning;
  return answer(now);
}

LinkPollResult UrRtdeLink::answer(double now) noexcept {
  const auto t_read = std::chrono::steady_clock::now();
  const auto compute = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t_read).count(); };
  delay_.observe_feedback(now, feedback_);
  if (ramping_down_) stream_.begin_stop(ramp_down_s_);
  stream_.sample(program_, program_velocity_, blend_, blend_velocity_);
  nominal_ = program_ + blend_;
  CycleRequest rq;
  rq.t_s = now;
  rq.sequence = static_cast<std::uint64_t>(counter_) + 1U;
  rq.program_time_s = stream_.program_time_s();
  rq.nominal = &program_;
  rq.blend = &blend_;
  rq.feedback = &feedback_;
  rq.target = &nominal_;
  // servoj's lookahead is in the measured delay (feedback is actual_q): the strategy leads by it.
  rq.delay_s = rq.lead_s = delay_.delay_s();
  rq.session_start = counters_.replies == 0;
  const LinkCycle::Verdict verdict = cycle_.run(rq);
  if (verdict != LinkCycle::Verdict::kSend) return cycle_not_passed(verdict, compute());
  const bool last = (ramping_down_ && stream_.at_standstill()) || stream_.finished();
  const JointVector& command = cycle_.joint_command();
  if (!send_targets(command, last ? kModeEnd : kModeServo)) {
    cycle_.not_sent(compute());
    return LinkPollResult::kNotAnswered;
  }
  cycle_.sent(compute(), clock_.now_s() - receipt_s_);
  delay_.record_reference(now, command);
  stream_.consumed(period_s_);
  if (last) {
    if (ramping_down_) {
      stop_link(LinkStopCause::kRequested,
                "stopped on request: the program was brought to rest on its path over %.2f s; the script holds the "
                "last target and ends its servo loop",
                ramp_down_s_);
    } else {
      state_ = LinkState::kFinished;
    }
  }
  return LinkPollResult::kAnswered;
}

void UrRtdeLink::stop() noexcept {
  // The script is told the stream ended (it holds the last target and ends), if anything was sent.
  if (state_ == LinkState::kRunning && counters_.replies > 0 && !closed_) (void)send_targets(last_sent_, kModeEnd);
  stop_link(LinkStopCause::kRequested,
            "stop requested: the script was told the stream ended; it holds the last target and ends its servo loop "
            "(its watchdog stops it otherwise)");
}

std::string UrRtdeLink::protocol_summary() const {
  return fmt::format(
      "UR RTDE (URControl {}.{}, {:.0f} Hz, servoj lookahead {:.0f} ms gain {:.0f}): {} targets sent, {} written in "
      "part; text messages: {} exceptions, {} errors, {} warnings{}{}",
      version_.major, version_.minor, 1.0 / period_s_, config_.lookahead_s * 1e3, config_.gain, counters_.replies,
      partial_writes_, texts_[0], texts_[1], texts_[2], last_text_[0] != '\0' ? "; last: " : "", last_text_.data());
}

}  // namespace deflex
