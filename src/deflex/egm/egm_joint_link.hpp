// ABB EGM position guidance in joint mode (RAPID: EGMActJoint + EGMRunJoint), deflex as the motion
// source. The controller follows the absolute joint target deflex sends through its own filter and
// gain, some 50 ms later, and reports that target back as "planned"; so deflex holds the nominal
// program itself (JointStream) and sends, every cycle,
//     target = program(p) + blend - dtheta,    |target_i - (program_i(p) + blend_i)| <= bound,
// with the target's velocity as the speed reference; nothing of the controller's echo enters the
// target, so the correction never integrates. The program time p moves on by one controller cycle
// for each answer sent (what the controller has consumed), so an outage, a stalled PC or a late
// answer never makes the program run ahead: after any of them the next target is one cycle further.
// Every session (the first message, a restart of the controller's sequence, a message after the
// restart silence) is anchored to the reference the controller reports (planned; the feedback when
// there is none): the first target is that reference and the offset to the program is blended out,
// the correction applied once. An anchor more than the start tolerance (1 deg) from the command is
// refused at the first session, and stops the link at a later one. The controller's own state ends
// the session: motors off, or EGM no longer running (mciState) after it ran: the planned end when
// the program had ended, a stop before.
#pragma once

#include <chrono>

#include <memory>

#include "deflex/egm/egm_receiver.hpp"
#include "deflex/link/controller_link.hpp"
#include "deflex/link/joint_stream.hpp"
#include "deflex/online/delay_estimator.hpp"

namespace deflex {

struct EgmJointLinkConfig {
  EgmReceiverConfig receiver;
  JointStreamConfig stream;
  LinkStopRules stop;
  bool send_speed_reference = true;   ///< the target's joint velocity in EgmSensor.speedRef
  std::size_t history_cycles = 1000;  ///< ring of the last cycles (4 s at 4 ms)
  double initial_delay_s = 0.05;      ///< the delay assumed until it is measured (ABB users: ~50 ms)
};

/// Thread safety: one thread at a time (the loop's), as every ControllerLink.
class EgmJointLink final : public ControllerLink {
 public:
  /// Every reference must outlive the link. The controller's cycle is the compensator's period_s.
  /// Throws InputError on a configuration that cannot work (a program for another number of joints,
  /// a bad setting, limits that do not fit: command_limits()).
  EgmJointLink(OnlineCompensator& compensator, OnlineStrategy& strategy, std::shared_ptr<const JointTrajectory> nominal,
               DatagramTransport& transport, const Clock& clock, const EgmJointLinkConfig& config = {});
  /// A temporary clock would dangle: it does not compile (docs/architecture.md, "Ownership").
  EgmJointLink(OnlineCompensator& compensator, OnlineStrategy& strategy, std::shared_ptr<const JointTrajectory> nominal,
               DatagramTransport& transport, const Clock&& clock, const EgmJointLinkConfig& config = {}) = delete;

  LinkPollResult poll(double timeout_s) noexcept override;
  [[nodiscard]] const char* name() const override { return "egm-joint"; }

  [[nodiscard]] const JointStream& stream() const { return stream_; }
  [[nodiscard]] const DelayEstimator& delay() const { return delay_; }
  [[nodiscard]] const DelayEstimator* delay_estimator() const override { return &delay_; }
  [[nodiscard]] const DatagramAddress& controller() const { return receiver_.controller(); }

 private:
  bool controller_state(const EgmRobotMessage& m) noexcept;
  // poll()'s stages.
  bool begin_session() noexcept;
  LinkPollResult send(double now, const JointVector& command, std::chrono::steady_clock::time_point t_read) noexcept;

  EgmJointLinkConfig config_;
  EgmReceiver receiver_;
  JointStream stream_;
  DelayEstimator delay_;
  double period_s_;
  bool egm_ran_ = false;  // the controller reported EGM running at least once

  // Preallocated per-cycle buffers.
  JointVector feedback_, planned_, program_, program_velocity_, blend_, blend_velocity_, nominal_;
  EgmSensorMessage reply_;
  std::vector<unsigned char> tx_;
  std::uint32_t reply_seq_ = 0;
};

}  // namespace deflex
