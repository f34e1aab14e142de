// KUKA RobotSensorInterface axis correction (KRL: RSI_ON(#ABSOLUTE); an RSI context wiring ETHERNET to
// AXISCORR): the controller runs its own KRL program and, every RSI cycle (4 ms), sends a <Rob> with
// the actual axes (AIPos), its program's setpoint axes (ASPos) and an IPOC; deflex answers each, as
// fast as it can, with a <Sen> carrying the echoed IPOC and <AK>, the whole joint correction
//     AK = -dtheta (degrees),   |AK_i| <= max_joint_correction,   |J_p dtheta| <= max_tcp_correction,
// an absolute offset from where RSI started (never an increment, so nothing accumulates), computed by
// the same compensator and strategy as the EGM links at the setpoint (ASPos) with the sensor turned
// as the actual axes say. The nominal deflex holds is "no correction": zero force gives AK = 0.
// Malformed, truncated, oversized and foreign documents, non-finite values, axes beyond the robot's
// limits, duplicate, stale or stray IPOCs and other senders are counted and never answered; an
// unanswered cycle is one the controller counts late (it stops RSI at its Timeout), which is the safe
// side. A new RSI session (after a silence, or an IPOC jump the next documents confirm) starts from
// zero correction, as the controller's AXISCORR does.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "deflex/link/controller_gate.hpp"
#include "deflex/link/controller_link.hpp"
#include "deflex/link/link_history.hpp"
#include "deflex/online/delay_estimator.hpp"
#include "deflex/online/online_strategy.hpp"
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
  std::size_t history_cycles = 1000;  ///< ring of the last cycles (4 s at 4 ms)
  double initial_delay_s = 0.012;     ///< the delay assumed until it is measured
  /// Predictive strategy: latency of AXISCORR beyond the delay the link measures (ASPos to AIPos), s.
  double correction_latency_s = 0.0;
  /// Throws InputError naming the setting.
  void validate() const;
};

class RsiLink final : public ControllerLink {
 public:
  /// Every reference must outlive the link. `force` may be null. Throws InputError.
  RsiLink(OnlineCompensator& compensator, OnlineStrategy& strategy, DatagramTransport& transport, const Clock& clock,
          ForceSource* force, const RsiLinkConfig& config = {});

  LinkPollResult poll(double timeout_s) noexcept override;
  [[nodiscard]] const char* name() const override { return "rsi"; }
  [[nodiscard]] LinkState state() const override { return state_; }
  [[nodiscard]] const LinkCounters& counters() const override { return counters_; }
  [[nodiscard]] const LinkCycleRecord& last_cycle() const override { return last_; }
  [[nodiscard]] const JointVector& start_distance() const override { return no_distance_; }
  [[nodiscard]] bool fault_pending() const override { return fault_pending_; }
  void clear_fault() override { fault_pending_ = false; }
  void write_history_csv(const std::string& path) const override { history_.write_csv(path); }
  [[nodiscard]] const LinkHistory* history() const override { return &history_; }

  [[nodiscard]] const DelayEstimator& delay() const { return delay_; }
  [[nodiscard]] const DatagramAddress& controller() const { return gate_.controller(); }
  /// The controller's cycle as its IPOCs show it (s; 0 before two documents).
  [[nodiscard]] double period_s() const { return period_s_; }
  [[nodiscard]] const RsiLinkConfig& config() const { return config_; }

 private:
  enum class Drain { kNothing, kNoneUsable, kMessage };
  Drain drain(double timeout_s, bool& restarted) noexcept;
  [[nodiscard]] bool plausible(const RsiRobotMessage& m) const noexcept;

  OnlineCompensator& comp_;
  OnlineStrategy& strategy_;
  DatagramTransport& transport_;
  const Clock& clock_;
  ForceSource* force_;
  RsiLinkConfig config_;
  LinkCounters counters_;
  DelayEstimator delay_;
  LinkHistory history_;
  ControllerGate gate_;
  LinkState state_ = LinkState::kWaiting;
  bool fault_pending_ = false;

  // Receiving (preallocated).
  std::vector<unsigned char> rx_, tx_;
  RsiRobotMessage msg_, newest_;
  LinkArrival msg_arrival_, arrival_;
  bool answered_once_ = false;
  JointVector lower_, upper_;

  // The cycle (preallocated).
  CycleInput input_;
  JointVector feedback_, planned_, previous_feedback_, velocity_, target_, command_, no_distance_;
  double previous_t_s_ = 0.0, period_s_ = 0.0;
  bool have_previous_ = false;
  RsiSensorMessage reply_;
  LinkCycleRecord last_;
  Workspace ws_;
  Jacobian jac_;
};

}  // namespace deflex
