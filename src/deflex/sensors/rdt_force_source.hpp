// Force samples from an RDT sensor (ATI Net F/T and Ethernet Axia, Schunk FTN-Axia, OnRobot HEX
// through its Compute Box; wire/rdt.hpp): requests the stream, turns every record into a sample in
// N and Nm by the sensor's calibration (rdt_calibration.hpp), and watches the stream.
//
// - Every record is handed on, oldest first: each call that finds nothing queued drains the socket
//   completely, so a reader slower than the stream (a 7 kHz stream read by a 250 Hz loop: 28 records a
//   cycle) never lags behind it; records queued beyond `queue_s` of the stream (a reader that stalled)
//   are dropped oldest first and counted (`dropped_behind`). No decimation.
// - Order from rdt_sequence (1 at each request, +1 a record, wraps at 2^32): a gap counts the records
//   lost; a duplicate, a late record and a stray far ahead are dropped and counted. A record that was
//   counted lost and then arrives late is taken off `lost` again.
// - Time from ft_sequence, the sensor's own sample counter since power-up (wraps; a request does not
//   reset it), and the stated rate: t_s = (ft counts since the first record) / (rate x ft step), the
//   ft step being how far ft_sequence moves a record (1 when the RDT rate is the sensor's internal
//   rate; more on a Net F/T streaming below its internal rate), learned from the first two records.
//   A sensor that restarted (ft_sequence jumps back) keeps t_s increasing and is counted.
// - A set status bit, or counts at the int32 limits (saturation), gives a sample with valid = false:
//   the compensator never moves the robot on it. Counted as faulty.
// - The stream is requested again when it stops (no record for the stall time: another client took
//   it, the sensor restarted, a cable), with a back-off doubling from retry_min_s to retry_max_s, and
//   counted. A sensor that has never answered for answer_timeout_s after the first request is in state
//   kNoAnswer (RdtUdpForceSource::start() turns that into an error).
// - The software tare (wrench_tare.hpp) runs inside: while it collects, nothing is handed on.
//
// latest(), poll() and stats() never allocate, lock or throw; construction and the set-up calls
// (start_tare's validation) may throw.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "deflex/online/force_sample.hpp"
#include "deflex/sensors/rdt_calibration.hpp"
#include "deflex/sensors/wrench_tare.hpp"
#include "deflex/transport/clock.hpp"
#include "deflex/transport/datagram_transport.hpp"
#include "deflex/transport/sequence_tracker.hpp"
#include "deflex/transport/udp_transport.hpp"
#include "deflex/wire/rdt.hpp"

namespace deflex {

struct RdtStreamSettings {
  bool buffered = false;  ///< request buffered streaming (0x0003: up to 40 records a datagram) instead of 0x0002
  double answer_timeout_s = 1.0;  ///< no record this long after the first request: kNoAnswer
  double stall_timeout_s = 0.0;   ///< no record this long while streaming: request again; 0: max(0.1 s, 10 records)
  double retry_min_s = 0.1;       ///< first wait between requests while stalled (s), doubling ...
  double retry_max_s = 2.0;       ///< ... up to this
  double queue_s = 0.25;          ///< records kept for a reader that fell behind, as stream time (s)
  /// Throws InputError naming the field when a value is out of its domain.
  void validate() const;
};

enum class RdtStreamState {
  kIdle,       ///< not requested (before start(), after stop())
  kRequested,  ///< requested, no record yet, within answer_timeout_s
  kStreaming,  ///< records arriving
  kStalled,    ///< records stopped for stall_timeout_s: requesting again with back-off
  kNoAnswer,   ///< never a record in answer_timeout_s since the first request: requesting again with back-off
};
[[nodiscard]] const char* to_string(RdtStreamState s);

/// Everything the source counts (ForceSourceStats is the part every source shares).
struct RdtCounters {
  std::uint64_t datagrams = 0;          ///< datagrams read from the sensor's address
  std::uint64_t records = 0;            ///< records in well-formed datagrams
  std::uint64_t accepted = 0;           ///< samples handed on
  std::uint64_t malformed = 0;          ///< datagrams not a whole number of 1..40 records (wrong size)
  std::uint64_t foreign = 0;            ///< datagrams from another address (ignored)
  std::uint64_t lost = 0;               ///< records the rdt_sequence says were sent and never arrived
  std::uint64_t duplicates = 0;         ///< a record (or an ft sample) seen before: dropped
  std::uint64_t out_of_order = 0;       ///< a record older than one handed on: dropped
  std::uint64_t far_ahead = 0;          ///< far ahead of the stream (a stray, a jump not yet confirmed): dropped
  std::uint64_t faulty = 0;             ///< samples handed on invalid: status bit set or saturated
  std::uint64_t saturated = 0;          ///< of those, counts at the int32 limits
  std::uint64_t dropped_behind = 0;     ///< records dropped because the reader fell more than queue_s behind
  std::uint64_t held_by_tare = 0;       ///< samples the tare took (collecting) or held back (refused): not handed on
  std::uint64_t requests = 0;           ///< stream requests sent (the first one included)
  std::uint64_t re_requests = 0;        ///< of those, sent because the stream stopped or never came
  std::uint64_t sequence_restarts = 0;  ///< rdt_sequence restarted, not at our request (another client, a jump)
  std::uint64_t ft_restarts = 0;        ///< ft_sequence went back (the sensor restarted)
  /// Samples the sensor measured (by ft_sequence) while its stream was not ours: between the last
  /// record before a new stream and the first after it (a stall, another client, a stop)
  std::uint64_t unseen = 0;
  std::uint64_t send_failures = 0;  ///< requests the transport could not send
  std::uint32_t last_status = 0;    ///< the last non-zero status word seen (0: none)
};

/// An RDT sensor over any datagram transport: UDP on a cell, the in-memory network in tests and
/// simulations. The clock measures the stall and answer timeouts and the back-off.
/// Thread safety: one thread at a time (the loop's), with its transport and clock.
class RdtForceSource final : public ForceSource {
 public:
  /// `transport` and `clock` must outlive the source. `sensor`: its address and RDT port. Throws
  /// InputError when the calibration or the settings are invalid (an rdt source never starts
  /// without a calibration).
  RdtForceSource(DatagramTransport& transport, const Clock& clock, const DatagramAddress& sensor,
                 const RdtCalibration& calibration, const RdtStreamSettings& settings = {});
  /// A temporary clock would dangle: it does not compile (docs/architecture.md, "Ownership").
  RdtForceSource(DatagramTransport& transport, const Clock&& clock, const DatagramAddress& sensor,
                 const RdtCalibration& calibration, const RdtStreamSettings& settings = {}) = delete;

  /// Requests the stream (OnRobot: sets the Compute Box's rate first). False when the transport
  /// could not send (counted).
  bool start() noexcept;
  /// Asks the sensor to stop streaming (a tidy end: it would otherwise keep sending to this address).
  bool stop() noexcept;
  /// Sends the sensor's own bias command (0x0042; OnRobot: on). This changes the sensor's zero for
  /// every program reading it, until it is power-cycled or biased again: a payload identification and
  /// a tare made before it no longer hold. Set-up time only, never on the cycle.
  bool request_sensor_bias() noexcept;

  /// Starts the software tare over the next settings.window_s of samples (throws InputError on bad
  /// settings). Until it is done nothing is handed on; when refused, nothing is handed on either
  /// (tare_result() says why) until start_tare() again or clear_tare().
  void start_tare(const TareSettings& settings);
  void clear_tare() noexcept { tare_.clear(); }
  [[nodiscard]] const TareResult& tare_result() const { return tare_.result(); }
  [[nodiscard]] const TareSettings& tare_settings() const { return tare_.settings(); }

  /// The next sample, oldest first; false when none is new. Drains the transport when nothing is
  /// queued, and watches the stream (requests it again when it stopped).
  bool latest(ForceSample& out) noexcept override;
  /// Drains and watches without handing anything on (for a caller that waits for the tare or the
  /// first record).
  void poll() noexcept;
  [[nodiscard]] ForceSourceStats stats() const noexcept override;

  [[nodiscard]] RdtStreamState state() const { return state_; }
  [[nodiscard]] const RdtCounters& counters() const { return counters_; }
  [[nodiscard]] const RdtCalibration& calibration() const { return calibration_; }
  [[nodiscard]] const RdtStreamSettings& settings() const { return settings_; }
  /// The rate the samples come at (Hz): what the compensator's filter must be designed for.
  [[nodiscard]] double sample_rate_hz() const { return calibration_.rate_hz; }
  /// Seconds since the last record arrived, on the source's clock (0 before the first): the
  /// age of the stream as this host sees it.
  [[nodiscard]] double since_last_record_s() const noexcept {
    return ever_received_ ? clock_.now_s() - last_record_s_ : 0.0;
  }
  /// Samples queued, not yet handed on.
  [[nodiscard]] std::size_t queued() const { return count_; }
  [[nodiscard]] const DatagramAddress& sensor() const { return sensor_; }

 private:
  bool send(RdtCommand command, std::uint32_t sample_count) noexcept;
  bool request_stream() noexcept;
  void drain() noexcept;
  void take(const RdtRecord& record) noexcept;
  bool in_order(std::uint32_t rdt_sequence) noexcept;
  bool advance_time(std::uint32_t ft_sequence, std::int64_t rdt_step) noexcept;
  void push(const ForceSample& sample) noexcept;
  void supervise() noexcept;

  DatagramTransport& transport_;
  const Clock& clock_;
  DatagramAddress sensor_;
  RdtCalibration calibration_;
  RdtStreamSettings settings_;
  double force_n_per_count_ = 0.0;
  double torque_nm_per_count_ = 0.0;
  double stall_timeout_s_ = 0.1;

  // Samples decoded, not yet handed on: a ring, newest overwriting oldest when full.
  std::vector<ForceSample> ring_;
  std::size_t head_ = 0, count_ = 0;
  std::vector<unsigned char> buffer_;  // one datagram (one byte more than the largest, to see oversized ones)

  // Order (rdt_sequence) and time (ft_sequence).
  SequenceTracker order_;
  std::uint64_t seen_ = 0;  // bit k: the number k behind the running one arrived
  bool have_ft_ = false;
  std::uint32_t last_ft_ = 0;
  std::uint64_t ft_ticks_ = 0;
  std::uint32_t ft_step_ = 0;  // 0: not learned yet
  std::int64_t rdt_step_ = 0;  // how far the last taken record moved rdt_sequence

  // The stream's supervision.
  RdtStreamState state_ = RdtStreamState::kIdle;
  double first_request_s_ = 0.0, last_record_s_ = 0.0, next_request_s_ = 0.0, backoff_s_ = 0.0;
  bool ever_received_ = false;
  bool expect_restart_ = false;  // we asked again: the next rdt_sequence restart is ours

  WrenchTare tare_;
  RdtCounters counters_;
};

/// "HOST[:PORT]" (the part after "rdt:") as an address; the port defaults to 49152. HOST is an IPv4
/// address. Throws InputError naming the text.
[[nodiscard]] DatagramAddress parse_rdt_endpoint(const std::string& text);

/// An RDT sensor over its own UDP socket, on the wall clock: what `--force-source rdt:HOST[:PORT]`
/// builds. Set-up calls block and throw; latest() is the source's.
/// Thread safety: one thread at a time: the set-up calls, then latest() on the loop's thread.
class RdtUdpForceSource final : public ForceSource {
 public:
  /// Binds an ephemeral UDP port on `bind_address` (the sensor answers to the address and port the
  /// request came from). Throws InputError (calibration, settings, address) or Error (socket).
  RdtUdpForceSource(const DatagramAddress& sensor, const RdtCalibration& calibration,
                    const RdtStreamSettings& settings = {}, const std::string& bind_address = "0.0.0.0");
  /// Asks the sensor to stop streaming.
  ~RdtUdpForceSource() override;
  RdtUdpForceSource(const RdtUdpForceSource&) = delete;
  RdtUdpForceSource& operator=(const RdtUdpForceSource&) = delete;

  /// Requests the stream and waits for its first record, up to settings.answer_timeout_s. Throws
  /// Error naming the sensor and what to check when none comes.
  void start();
  /// Tares (start() first): waits up to window + answer timeout for the window to fill. Returns the
  /// result when done; throws InputError with describe()'s reason when refused, Error when the
  /// samples stopped coming.
  const TareResult& tare(const TareSettings& settings);

  bool latest(ForceSample& out) noexcept override { return source_.latest(out); }
  [[nodiscard]] ForceSourceStats stats() const noexcept override { return source_.stats(); }
  [[nodiscard]] RdtForceSource& source() { return source_; }
  [[nodiscard]] const RdtForceSource& source() const { return source_; }
  [[nodiscard]] std::uint16_t local_port() const { return transport_.port(); }

 private:
  UdpTransport transport_;
  SteadyClock clock_;
  RdtForceSource source_;
};

/// Everything a command line gives for `--force-source rdt:HOST[:PORT]`.
struct RdtSourceOptions {
  std::string endpoint;               ///< "HOST[:PORT]", the part after "rdt:"
  RdtCalibrationOptions calibration;  ///< --rdt-calibration, --rdt-rate-hz
  RdtStreamSettings stream;           ///< --rdt-buffered and the timeouts
  std::string bind_address = "0.0.0.0";
};

/// Resolves the calibration (fetching the sensor's page for "sensor"), opens the socket and starts
/// the stream, waiting for its first record. Throws InputError (options, calibration), ModelError (a
/// bad page) or Error (no answer, socket). The tare is the caller's next step (it needs the arm's
/// pose for the payload's weight).
[[nodiscard]] std::unique_ptr<RdtUdpForceSource> open_rdt_force_source(const RdtSourceOptions& options);

}  // namespace deflex
