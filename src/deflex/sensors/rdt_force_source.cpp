// Force samples from an RDT sensor (see rdt_force_source.hpp).
#include "deflex/sensors/rdt_force_source.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "deflex/text/errors.hpp"
#include "deflex/text/parse_number.hpp"

namespace deflex {
namespace {

// A flood must not hold the caller's cycle: one drain reads at most this many datagrams (at 7 kHz
// unbuffered, over half a second of stream).
constexpr int kMaxDatagramsPerDrain = 4096;
// The seen-bitmap covers this many numbers behind the running one (duplicate versus late).
constexpr std::int64_t kSeenWindow = 64;

const RdtCalibration& validated(const RdtCalibration& c) {
  c.validate();  // an rdt source never starts without a usable calibration
  return c;
}

SequenceRules rdt_sequence_rules(double rate_hz) {
  SequenceRules r;
  r.bits = 32;
  // A gap of up to 2 s of records (at least 1000) is loss; beyond it, 3 records in a row confirm a
  // new sequence (a stray alone never captures the stream).
  r.max_ahead = static_cast<std::uint64_t>(std::max(1000.0, std::ceil(2.0 * rate_hz)));
  r.restart_max = 16;  // rdt_sequence starts at 1 at each request
  r.confirm = 3;
  r.validate();
  return r;
}

}  // namespace

void RdtStreamSettings::validate() const {
  auto check = [](bool ok, const char* field, double v) {
    if (!ok) throw InputError(fmt::format("rdt stream settings: {} out of range: {}", field, number_text(v)));
  };
  check(answer_timeout_s > 0.0 && std::isfinite(answer_timeout_s), "answer_timeout_s (> 0 s)", answer_timeout_s);
  check(stall_timeout_s >= 0.0 && std::isfinite(stall_timeout_s), "stall_timeout_s (>= 0 s, 0: automatic)",
        stall_timeout_s);
  check(retry_min_s > 0.0 && std::isfinite(retry_min_s), "retry_min_s (> 0 s)", retry_min_s);
  check(retry_max_s >= retry_min_s && std::isfinite(retry_max_s), "retry_max_s (>= retry_min_s)", retry_max_s);
  check(queue_s > 0.0 && queue_s <= 10.0, "queue_s (0..10 s)", queue_s);
}

const char* to_string(RdtStreamState s) {
  switch (s) {
    case RdtStreamState::kIdle:
      return "idle";
    case RdtStreamState::kRequested:
      return "requested";
    case RdtStreamState::kStreaming:
      return "streaming";
    case RdtStreamState::kStalled:
      return "stalled";
    case RdtStreamState::kNoAnswer:
      return "no_answer";
  }
  return "?";
}

RdtForceSource::RdtForceSource(DatagramTransport& transport, const Clock& clock, const DatagramAddress& sensor,
                               const RdtCalibration& calibration, const RdtStreamSettings& settings)
    : transport_(transport),
      clock_(clock),
      sensor_(sensor),
      calibration_(validated(calibration)),
      settings_(settings),
      order_(rdt_sequence_rules(calibration_.rate_hz)) {
  settings_.validate();
  force_n_per_count_ = calibration_.force_n_per_count();
  torque_nm_per_count_ = calibration_.torque_nm_per_count();
  stall_timeout_s_ =
      settings_.stall_timeout_s > 0.0 ? settings_.stall_timeout_s : std::max(0.1, 10.0 / calibration_.rate_hz);
  const auto capacity = static_cast<std::size_t>(std::ceil(settings_.queue_s * calibration_.rate_hz));
  ring_.resize(std::max<std::size_t>(2 * kRdtMaxRecordsPerDatagram, capacity));
  buffer_.resize(kRdtMaxDatagramBytes + 1);
}

bool RdtForceSource::send(RdtCommand command, std::uint32_t sample_count) noexcept {
  std::array<unsigned char, kRdtRequestBytes> bytes{};
  encode_rdt_request(RdtRequest{kRdtRequestHeader, static_cast<std::uint16_t>(command), sample_count}, bytes);
  if (!transport_.send_to(bytes.data(), bytes.size(), sensor_)) {
    ++counters_.send_failures;
    return false;
  }
  return true;
}

bool RdtForceSource::request_stream() noexcept {
  ++counters_.requests;
  expect_restart_ = true;  // the answer numbers its records from 1 again
  bool ok = true;
  if (calibration_.onrobot) {
    // Sent with every request: a Compute Box that restarted has forgotten it.
    const auto divisor = static_cast<std::uint32_t>(std::lround(1000.0 / calibration_.rate_hz));
    ok = send(RdtCommand::kOnRobotRate, divisor);
  }
  const RdtCommand start = settings_.buffered ? RdtCommand::kStartBuffered : RdtCommand::kStartRealTime;
  return send(start, 0) && ok;  // 0: stream until stopped
}

bool RdtForceSource::start() noexcept {
  const double now = clock_.now_s();
  state_ = RdtStreamState::kRequested;
  first_request_s_ = now;
  backoff_s_ = settings_.retry_min_s;
  next_request_s_ = now + settings_.answer_timeout_s;
  ever_received_ = false;
  return request_stream();
}

bool RdtForceSource::stop() noexcept {
  state_ = RdtStreamState::kIdle;
  return send(RdtCommand::kStop, 0);
}

bool RdtForceSource::request_sensor_bias() noexcept {
  // Net F/T and Axia ignore the count; OnRobot reads it as on (255) / off (0).
  return send(RdtCommand::kSetSoftwareBias, calibration_.onrobot ? 255u : 0u);
}

void RdtForceSource::start_tare(const TareSettings& settings) { tare_.start(settings, calibration_.rate_hz); }

bool RdtForceSource::latest(ForceSample& out) noexcept {
  if (count_ == 0) {
    drain();
  }
  supervise();
  if (count_ == 0) {
    return false;
  }
  out = ring_[head_];
  head_ = (head_ + 1) % ring_.size();
  --count_;
  ++counters_.accepted;
  return true;
}

void RdtForceSource::poll() noexcept {
  drain();
  supervise();
}

ForceSourceStats RdtForceSource::stats() const noexcept {
  ForceSourceStats s;
  s.received = counters_.records;
  s.accepted = counters_.accepted;
  s.malformed = counters_.malformed;
  s.out_of_order = counters_.out_of_order + counters_.far_ahead;
  s.duplicates = counters_.duplicates;
  s.lost = counters_.lost;
  s.faulty = counters_.faulty;
  s.restarts = counters_.re_requests + counters_.sequence_restarts + counters_.ft_restarts;
  s.re_requests = counters_.re_requests;
  s.saturated = counters_.saturated;
  s.last_status = counters_.last_status;
  return s;
}

void RdtForceSource::drain() noexcept {
  DatagramAddress from;
  for (int i = 0; i < kMaxDatagramsPerDrain; ++i) {
    const long n = transport_.receive(buffer_.data(), buffer_.size(), from);
    if (n < 0) {
      return;
    }
    // The sensor sends from its own address; anything else (a stray sender on the port) is not ours.
    if (from.ipv4 != sensor_.ipv4) {
      ++counters_.foreign;
      continue;
    }
    ++counters_.datagrams;
    const auto size = static_cast<std::size_t>(n);
    const std::size_t records = size < buffer_.size() ? rdt_record_count(size) : 0;
    if (records == 0) {
      ++counters_.malformed;
      continue;
    }
    const double now = clock_.now_s();
    last_record_s_ = now;
    ever_received_ = true;
    if (state_ == RdtStreamState::kRequested || state_ == RdtStreamState::kStalled ||
        state_ == RdtStreamState::kNoAnswer) {
      state_ = RdtStreamState::kStreaming;
      backoff_s_ = settings_.retry_min_s;
    }
    RdtRecord record;
    for (std::size_t r = 0; r < records; ++r) {
      decode_rdt_record(buffer_.data() + r * kRdtRecordBytes, record);
      take(record);
    }
  }
}

bool RdtForceSource::in_order(std::uint32_t rdt_sequence) noexcept {
  if (expect_restart_ && order_.started() && rdt_sequence <= order_.rules().restart_max &&
      order_.distance(rdt_sequence) < 0) {
    // Our request's new stream, numbered from 1 again, even when the old one had not gone far (the
    // tracker's own rule takes a jump back to a small number only from a number well above it).
    // Not reset at the request itself: when the request is lost and the old stream comes back, its
    // gap is loss and must be counted.
    order_.reset();
    expect_restart_ = false;
  }
  const std::int64_t d = order_.started() ? order_.distance(rdt_sequence) : 0;
  switch (order_.observe(rdt_sequence)) {
    case SequenceVerdict::kFirst:
      seen_ = 1;
      rdt_step_ = 0;
      return true;
    case SequenceVerdict::kRestart:
      // Our own request restarts the numbering at 1; any other restart is someone else's doing.
      if (!expect_restart_) ++counters_.sequence_restarts;
      expect_restart_ = false;
      seen_ = 1;
      rdt_step_ = 0;
      return true;
    case SequenceVerdict::kNext:
      // Well into the new stream: a restart from here on is not our request's.
      if (rdt_sequence > 2 * order_.rules().restart_max) expect_restart_ = false;
      counters_.lost += static_cast<std::uint64_t>(d - 1);
      seen_ = (d >= kSeenWindow ? 0 : seen_ << d) | 1u;
      rdt_step_ = d;
      return true;
    case SequenceVerdict::kDuplicate:
      ++counters_.duplicates;
      return false;
    case SequenceVerdict::kOutOfOrder: {
      const std::int64_t back = -d;
      if (back < kSeenWindow && ((seen_ >> back) & 1u) != 0) {
        ++counters_.duplicates;
      } else {
        ++counters_.out_of_order;
        if (back < kSeenWindow) {
          // It was counted lost when the gap opened; it did arrive, only too late to hand on.
          seen_ |= std::uint64_t{1} << back;
          if (counters_.lost > 0) --counters_.lost;
        }
      }
      return false;
    }
    case SequenceVerdict::kFarAhead:
      ++counters_.far_ahead;
      return false;
  }
  return false;
}

bool RdtForceSource::advance_time(std::uint32_t ft_sequence, std::int64_t rdt_step) noexcept {
  if (!have_ft_) {
    have_ft_ = true;
    last_ft_ = ft_sequence;
    return true;
  }
  const std::uint32_t forward = ft_sequence - last_ft_;  // wraps at 2^32
  if (forward == 0) {
    ++counters_.duplicates;  // the same measurement again under a new rdt number
    return false;
  }
  const std::uint32_t step = std::max<std::uint32_t>(ft_step_, 1u);
  if (forward < 0x80000000u) {
    if (ft_step_ == 0 && rdt_step > 0) {
      ft_step_ =
          std::max<std::uint32_t>(1u, static_cast<std::uint32_t>(forward / static_cast<std::uint64_t>(rdt_step)));
    }
    if (rdt_step <= 0 && ft_step_ > 0 && forward > ft_step_) {
      // A new stream: rdt_sequence started again and cannot tell the gap; the sensor's own counter can.
      counters_.unseen += forward / ft_step_ - 1;
    }
    ft_ticks_ += forward;
    last_ft_ = ft_sequence;
    return true;
  }
  // Backwards. A little (within 2 s of the stream): a record older than the stream, from before our
  // last request. Far: the sensor's counter started again (it was restarted); time goes on by a record.
  const std::uint32_t back = 0u - forward;
  const double window = std::min(1073741824.0, 2.0 * calibration_.rate_hz * step);
  if (back <= static_cast<std::uint32_t>(window)) {
    ++counters_.out_of_order;
    return false;
  }
  ++counters_.ft_restarts;
  ft_ticks_ += step;
  last_ft_ = ft_sequence;
  return true;
}

void RdtForceSource::take(const RdtRecord& record) noexcept {
  ++counters_.records;
  if (!in_order(record.rdt_sequence) || !advance_time(record.ft_sequence, rdt_step_)) {
    return;
  }
  ForceSample s;
  const double step = static_cast<double>(std::max<std::uint32_t>(ft_step_, 1u));
  s.t_s = static_cast<double>(ft_ticks_) / (calibration_.rate_hz * step);
  for (int i = 0; i < 3; ++i) {
    s.wrench_sensor(i) = force_n_per_count_ * record.counts[static_cast<std::size_t>(i)];
    s.wrench_sensor(i + 3) = torque_nm_per_count_ * record.counts[static_cast<std::size_t>(i) + 3];
  }
  const bool saturated = rdt_counts_saturated(record);
  s.valid = record.status == 0 && !saturated;
  if (!s.valid) {
    ++counters_.faulty;
    if (saturated) ++counters_.saturated;
    if (record.status != 0) counters_.last_status = record.status;
  }
  switch (tare_.result().state) {
    case TareState::kCollecting:
    case TareState::kRejected:
      tare_.add(s);
      ++counters_.held_by_tare;
      return;
    case TareState::kDone:
      s.wrench_sensor = tare_.apply(s.wrench_sensor);
      break;
    case TareState::kOff:
      break;
  }
  push(s);
}

void RdtForceSource::push(const ForceSample& sample) noexcept {
  if (count_ == ring_.size()) {
    head_ = (head_ + 1) % ring_.size();
    --count_;
    ++counters_.dropped_behind;
  }
  ring_[(head_ + count_) % ring_.size()] = sample;
  ++count_;
}

void RdtForceSource::supervise() noexcept {
  if (state_ == RdtStreamState::kIdle) {
    return;
  }
  const double now = clock_.now_s();
  switch (state_) {
    case RdtStreamState::kRequested:
      if (now - first_request_s_ >= settings_.answer_timeout_s) {
        state_ = RdtStreamState::kNoAnswer;
        next_request_s_ = now;
      }
      break;
    case RdtStreamState::kStreaming:
      if (now - last_record_s_ >= stall_timeout_s_) {
        state_ = RdtStreamState::kStalled;
        backoff_s_ = settings_.retry_min_s;
        next_request_s_ = now;
      }
      break;
    default:
      break;
  }
  if ((state_ == RdtStreamState::kStalled || state_ == RdtStreamState::kNoAnswer) && now >= next_request_s_) {
    ++counters_.re_requests;
    request_stream();
    next_request_s_ = now + backoff_s_;
    backoff_s_ = std::min(2.0 * backoff_s_, settings_.retry_max_s);
  }
}

DatagramAddress parse_rdt_endpoint(const std::string& text) {
  const auto colon = text.rfind(':');
  std::string host = text;
  std::uint16_t port = kRdtDefaultPort;
  if (colon != std::string::npos) {
    host = text.substr(0, colon);
    const auto p = parse_int64(text.substr(colon + 1));
    if (!p || *p < 1 || *p > 65535) {
      throw InputError(fmt::format("rdt:{}: the port must be 1..65535, not '{}'", text, text.substr(colon + 1)));
    }
    port = static_cast<std::uint16_t>(*p);
  }
  if (host.empty()) {
    throw InputError(fmt::format("rdt:{}: give the sensor's IPv4 address, rdt:HOST[:PORT] (port {} by default)", text,
                                 kRdtDefaultPort));
  }
  return make_datagram_address(host, port);
}

RdtUdpForceSource::RdtUdpForceSource(const DatagramAddress& sensor, const RdtCalibration& calibration,
                                     const RdtStreamSettings& settings, const std::string& bind_address)
    : transport_(bind_address, 0), source_(transport_, clock_, sensor, calibration, settings) {}

RdtUdpForceSource::~RdtUdpForceSource() {
  if (source_.state() != RdtStreamState::kIdle) {
    source_.stop();
  }
}

void RdtUdpForceSource::start() {
  source_.start();
  const double t0 = clock_.now_s();
  while (clock_.now_s() - t0 < source_.settings().answer_timeout_s) {
    transport_.wait_readable(0.01);
    source_.poll();
    if (source_.counters().records > 0) {
      return;
    }
  }
  source_.poll();  // the state reads kNoAnswer from here on
  const RdtCounters& c = source_.counters();
  throw Error(fmt::format(
      "rdt sensor {}: no record within {} s of the stream request ({} datagrams from other addresses, {} malformed, "
      "{} requests not sent). Check: the address and port; that the sensor's RDT interface is enabled; that no "
      "firewall drops UDP from the sensor to this host (port {}); that the sensor and this host share a subnet",
      to_string(source_.sensor()), number_text(source_.settings().answer_timeout_s), c.foreign, c.malformed,
      c.send_failures, transport_.port()));
}

const TareResult& RdtUdpForceSource::tare(const TareSettings& settings) {
  source_.start_tare(settings);
  const double limit_s = settings.window_s + source_.settings().answer_timeout_s;
  const double t0 = clock_.now_s();
  while (source_.tare_result().state == TareState::kCollecting && clock_.now_s() - t0 < limit_s) {
    transport_.wait_readable(0.01);
    source_.poll();
  }
  const TareResult& r = source_.tare_result();
  if (r.state == TareState::kCollecting) {
    throw Error(fmt::format("rdt sensor {}: tare: only {} of {} samples in {} s (stream {})",
                            to_string(source_.sensor()), r.samples + r.faulty, r.samples_wanted, number_text(limit_s),
                            to_string(source_.state())));
  }
  if (r.state == TareState::kRejected) {
    throw InputError(fmt::format("rdt sensor {}: {}", to_string(source_.sensor()), describe(r, settings)));
  }
  return r;
}

std::unique_ptr<RdtUdpForceSource> open_rdt_force_source(const RdtSourceOptions& options) {
  const DatagramAddress sensor = parse_rdt_endpoint(options.endpoint);
  const std::string host = options.endpoint.substr(0, options.endpoint.rfind(':'));
  auto source = std::make_unique<RdtUdpForceSource>(sensor, resolve_rdt_calibration(options.calibration, host),
                                                    options.stream, options.bind_address);
  source->start();
  return source;
}

}  // namespace deflex
