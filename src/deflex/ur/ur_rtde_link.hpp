// Universal Robots over RTDE, deflex as the motion source. deflex is an RTDE client (TCP 30004): it
// asks for protocol 2, reads the controller's version (URControl 5 and later: e-Series, 500 Hz; older:
// CB3, 125 Hz), sets up an output recipe at the session's rate
//     timestamp, actual_q, target_q, robot_mode, safety_mode, runtime_state, output_int_register_<o>
// and one input recipe
//     input_int_register_<o>       a counter, one more every package (the script's watchdog)
//     input_int_register_<o+1>     1 servo, 2 the stream has ended (the script holds the last target)
//     input_double_register_<o>..  the six joint targets (rad), then servoj's lookahead (s) and gain
// (o: the register offset, 24 by default, the upper range), starts, and answers every output package
// with one input package. A URScript program on the controller (controller setup writes it) hands the
// newest targets to servoj(q, t = its step time, lookahead_time, gain) every cycle; it echoes the counter
// it took in output_int_register_<o>, and stops itself (rtde_set_watchdog) when the counter stops
// changing.
//
// servoj's lookahead smooths the target by delaying it: command to motion takes about the lookahead
// plus a servo lag of 1/gain plus a cycle (~34 ms at 0.03 s, gain 1200 on a UR10e). The link's delay
// estimator starts from that figure and measures it from actual_q; the predictive strategy's lead is
// the measured delay.
//
// The program's clock is the controller's: it moves on one controller cycle for each output package
// answered (RTDE keeps order and loses nothing; a package the controller skipped, or one deflex did not
// answer, makes the program wait, never skip). deflex holds the absolute target
//     target = program(p) + blend - dtheta,   |target_i - (program_i(p) + blend_i)| <= bound,
// and every target on the wire is within the per-cycle step limit of the one before.
//
// A package is taken only when it frames (a size within max_package_bytes, a known type), decodes
// against its recipe, is finite and its timestamp moves on; anything else is counted and never
// answered (an oversized package's bytes are dropped by its size; a size below the header's own stops
// the link: the stream cannot be re-framed). The session ends on: a safety mode other than normal or reduced (a
// protective stop, an e-stop, a violation, a fault), a robot mode other than running, the program not playing once it
// was (stopped, paused, the script's watchdog), a text message of exception or error level, a closed connection, a
// refused handshake (a field NOT_FOUND or IN_USE, a rate the controller cannot give), a handshake not completed within
// the stop silence (at least 2 s).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "deflex/link/controller_link.hpp"
#include "deflex/link/joint_stream.hpp"
#include "deflex/online/delay_estimator.hpp"
#include "deflex/transport/stream_transport.hpp"
#include "deflex/wire/rtde.hpp"

namespace deflex {

struct UrRtdeLinkConfig {
  JointStreamConfig stream;
  LinkStopRules stop;
  std::size_t history_cycles = 1000;
  /// servoj's lookahead_time (s, 0.03..0.2) and gain (100..2000), sent every cycle: Universal Robots'
  /// client library's defaults, the shortest delay servoj allows.
  double lookahead_s = 0.03;
  double gain = 2000.0;
  /// The first input and output register of deflex's layout: 0 or 24 (the upper range).
  int register_offset = 24;
  std::size_t max_package_bytes = 4096;
  /// Throws InputError naming the setting.
  void validate() const;
  /// Command to motion through servoj (s): the lookahead, the lag 1/gain, one controller cycle.
  [[nodiscard]] double servoj_delay_s(double period_s) const { return lookahead_s + 1.0 / gain + period_s; }
};

/// The recipes' field lists for a register offset (what controller setup's script and the stand-in see).
[[nodiscard]] std::string ur_rtde_output_names(int register_offset);
[[nodiscard]] std::string ur_rtde_input_names(int register_offset);

/// Thread safety: one thread at a time (the loop's), as every ControllerLink.
class UrRtdeLink final : public ControllerLink {
 public:
  /// Fields of the output recipe, in order.
  enum Output : std::size_t { kTimestamp, kActualQ, kTargetQ, kRobotMode, kSafetyMode, kRuntimeState, kEcho, kOutputs };
  /// Fields of the input recipe, in order.
  enum Input : std::size_t { kCounter, kMode, kQ0, kLookahead = kQ0 + 6, kGain, kInputs };
  static constexpr std::int32_t kModeServo = 1, kModeEnd = 2;

  /// Every reference must outlive the link. The controller's cycle is the compensator's period_s
  /// (0.002 on e-Series, 0.008 on CB3). Throws InputError on a bad setting or a program for a robot
  /// that is not six-jointed.
  UrRtdeLink(OnlineCompensator& compensator, OnlineStrategy& strategy, std::shared_ptr<const JointTrajectory> nominal,
             StreamTransport& transport, const Clock& clock, const UrRtdeLinkConfig& config);
  UrRtdeLink(OnlineCompensator& compensator, OnlineStrategy& strategy, std::shared_ptr<const JointTrajectory> nominal,
             StreamTransport& transport, const Clock&& clock, const UrRtdeLinkConfig& config) = delete;

  LinkPollResult poll(double timeout_s) noexcept override;
  void stop() noexcept override;
  [[nodiscard]] const char* name() const override { return "ur-rtde"; }
  [[nodiscard]] const DelayEstimator* delay_estimator() const override { return &delay_; }
  [[nodiscard]] std::string protocol_summary() const override;
  [[nodiscard]] bool winding_down() const override { return tx_end_ > tx_begin_ && !closed_; }

  [[nodiscard]] const JointStream& stream() const { return stream_; }
  [[nodiscard]] bool handshake_done() const { return phase_ == Phase::kStreaming; }
  [[nodiscard]] const rtde::UrControlVersion& controller_version() const { return version_; }
  /// Text messages by level (0 exception, 1 error, 2 warning, 3 info); the last one's text.
  [[nodiscard]] const std::array<std::uint64_t, 4>& text_messages() const { return texts_; }
  [[nodiscard]] const char* last_text() const { return last_text_.data(); }
  /// Output packages superseded by a newer one in the same read (not answered), packages written in
  /// part (the rest went at the next poll).
  [[nodiscard]] std::uint64_t partial_writes() const { return partial_writes_; }

 private:
  LinkPollResult wind_down() noexcept;
  bool handshake_overdue() noexcept;
  void take_state() noexcept;
  enum class Phase { kVersion, kUrControl, kOutputs, kInputs, kStart, kStreaming };

  bool read_stream() noexcept;
  bool handle(const unsigned char* package, std::size_t size, std::uint8_t type) noexcept;
  bool handshake(const unsigned char* package, std::size_t size, std::uint8_t type) noexcept;
  bool text(const unsigned char* package, std::size_t size) noexcept;
  void take_data(const unsigned char* package, std::size_t size) noexcept;
  bool queue(std::size_t n) noexcept;
  bool flush() noexcept;
  bool send_request() noexcept;
  bool send_targets(const JointVector& q, std::int32_t mode) noexcept;
  bool controller_ok(double now) noexcept;
  LinkPollResult start_session(double now) noexcept;
  LinkPollResult answer(double now) noexcept;
  void protocol_fault(const char* what) noexcept;

  UrRtdeLinkConfig config_;
  std::string output_names_, input_names_;
  StreamTransport& transport_;
  JointStream stream_;
  DelayEstimator delay_;
  double period_s_;
  Phase phase_ = Phase::kVersion;
  bool requested_ = false, closed_ = false, have_data_ = false, playing_seen_ = false;
  rtde::UrControlVersion version_;
  rtde::Recipe out_recipe_, in_recipe_;
  std::int32_t counter_ = 0;
  double last_timestamp_ = -1e300;
  std::array<std::uint64_t, 4> texts_{};
  std::array<char, 160> last_text_{};
  std::uint64_t partial_writes_ = 0;

  // Preallocated buffers: the stream's bytes, the newest data package, what waits to be written.
  std::vector<unsigned char> rx_, data_, tx_;
  std::size_t rx_size_ = 0, data_size_ = 0, tx_begin_ = 0, tx_end_ = 0;
  std::size_t skip_ = 0;  // bytes of an oversized package still to drop
  JointVector feedback_, program_, program_velocity_, blend_, blend_velocity_, nominal_, last_sent_;
  std::int32_t robot_mode_ = 0, safety_mode_ = 0;
  std::uint32_t runtime_state_ = 0;
  double receipt_s_ = 0.0;
  double handshake_start_s_ = -1.0;  // < 0: the first poll has not come
};

}  // namespace deflex
