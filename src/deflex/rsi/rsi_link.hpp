// KUKA RobotSensorInterface axis correction (KRL: RSI_ON(#ABSOLUTE); an RSI context wiring ETHERNET to
// AXISCORR): the controller runs its own KRL program and, every RSI cycle (4 ms), sends a <Rob> with
// the actual axes (AIPos), its program's setpoint axes (ASPos) and an IPOC; deflex answers each, as
// fast as it can, with a <Sen> carrying the echoed IPOC and <AK>, the whole joint correction
//     AK = -dtheta (degrees),   |AK_i| <= max_joint_correction,   |J_p dtheta| <= max_tcp_correction,
// an absolute offset from where RSI started (never an increment, so nothing accumulates), computed by
// the one link cycle at the setpoint (ASPos) with the sensor turned as the actual axes say, its change
// from one answer to the next within the rate bound times the cycle, rounded to the 6 decimals the
// answer carries before the final guard checks it. The nominal deflex holds is "no correction": zero
// force gives AK = 0. Malformed, truncated, oversized and foreign documents, non-finite values, axes
// beyond the robot's limits, duplicate, stale or stray IPOCs and other senders are counted and never
// answered; an unanswered cycle is one the controller counts late (it stops RSI at its Timeout),
// which is the safe side. A new RSI session (after a silence, or an IPOC jump the next documents
// confirm) starts from zero correction, as the controller's AXISCORR does. RSI stopped by its Timeout
// is recognised from the late count the controller reports (<Delay>, one short of the Timeout) and the
// missing document after it, within two cycles; any other silence longer than the stop silence stops
// the link too (or ends the session as planned, with end_on_silence, when the count was below it).
#pragma once

#include <chrono>

#include <cstdint>
#include <string>
#include <vector>

#include "deflex/link/controller_gate.hpp"
#include "deflex/link/controller_link.hpp"
#include "deflex/online/delay_estimator.hpp"
#include "deflex/transport/clock.hpp"
#include "deflex/transport/datagram_transport.hpp"
#include "deflex/wire/rsi_xml.hpp"

namespace deflex {

struct RsiLinkConfig {
  std::string sentype = "ImFree";         ///< the controller's <SENTYPE>: the Type of every answer
  std::size_t max_document_bytes = 4096;  ///< larger datagrams are "oversized" and never answered
  /// A silence this long (from the controller's last datagram) ends the session: the next document
  /// starts a new one (and another sender may take the link over).
  double restart_silence_s = 0.5;
  /// An IPOC more than this ahead of the running one is a stray, unless `confirm_jump` documents
  /// in a row continue it (a new RSI session that came without a silence).
  std::uint64_t ipoc_max_ahead_ms = 1000;
  int confirm_jump = 3;
  /// The ETHERNET object's Timeout on the controller (deflex controller-setup writes the same): late
  /// answers that stop RSI. With the <Delay> the controller reports, it tells an RSI stopped by its
  /// Timeout from a network outage.
  int controller_timeout = 100;
  LinkStopRules stop{1.0, 2.0, false};
  std::size_t history_cycles = 1000;  ///< ring of the last cycles (4 s at 4 ms)
  double initial_delay_s = 0.012;     ///< the delay assumed until it is measured
  /// Predictive strategy: latency of AXISCORR beyond the delay the link measures (ASPos to AIPos), s.
  double correction_latency_s = 0.0;
  /// Throws InputError naming the setting.
  void validate() const;
};

/// Thread safety: one thread at a time (the loop's), as every ControllerLink.
class RsiLink final : public ControllerLink {
 public:
  /// Every reference must outlive the link. Throws InputError.
  RsiLink(OnlineCompensator& compensator, OnlineStrategy& strategy, DatagramTransport& transport, const Clock& clock,
          const RsiLinkConfig& config = {});
  /// A temporary clock would dangle: it does not compile (docs/architecture.md, "Ownership").
  RsiLink(OnlineCompensator& compensator, OnlineStrategy& strategy, DatagramTransport& transport, const Clock&& clock,
          const RsiLinkConfig& config = {}) = delete;

  LinkPollResult poll(double timeout_s) noexcept override;
  [[nodiscard]] const char* name() const override { return "rsi"; }

  [[nodiscard]] const DelayEstimator& delay() const { return delay_; }
  [[nodiscard]] const DelayEstimator* delay_estimator() const override { return &delay_; }
  [[nodiscard]] std::string protocol_summary() const override;
  [[nodiscard]] const DatagramAddress& controller() const { return gate_.controller(); }
  /// The controller's cycle as its IPOCs show it (s; 0 before two documents).
  [[nodiscard]] double period_s() const { return cycle_.motion().period_s(); }
  [[nodiscard]] const RsiLinkConfig& config() const { return config_; }

 protected:
  /// A silence is the planned end (--end-on-silence) only when RSI was not stopped by its Timeout.
  [[nodiscard]] bool silence_is_planned_end() const override;

 private:
  LinkPollResult answer(const RsiRobotMessage& m, double now, bool session_start,
                        std::chrono::steady_clock::time_point t_read) noexcept;
  enum class Drain { kNothing, kNoneUsable, kMessage };
  Drain drain(double timeout_s, bool& restarted) noexcept;
  [[nodiscard]] bool plausible(const RsiRobotMessage& m) const noexcept;
  bool timeout_reached(double now) noexcept;

  DatagramTransport& transport_;
  RsiLinkConfig config_;
  DelayEstimator delay_;
  ControllerGate gate_;

  // Receiving (preallocated).
  std::vector<unsigned char> rx_, tx_;
  RsiRobotMessage msg_, newest_;
  LinkArrival msg_arrival_, arrival_;
  double receipt_age_s_ = 0.0, taken_at_s_ = 0.0;  // the taken document's age when it was read, and when
  JointVector lower_, upper_;

  // The cycle (preallocated).
  JointVector feedback_, planned_;
  JointVector reference_;  // ASPos + the last AK answered: where the axes are commanded to, for the delay
  RsiSensorMessage reply_;
};

}  // namespace deflex
