// ABB EGM position guidance in joint mode (RAPID: EGMActJoint + EGMRunJoint), deflex as the motion
// source. The controller follows the absolute joint target deflex sends through its own filter and
// gain, some 50 ms later, and reports that target back as "planned"; so deflex holds the nominal
// program itself (JointStream) and sends, every cycle,
//     target = nominal(t) - dtheta,    |target_i - nominal_i(t)| <= max_joint_correction_rad,
// with the target's velocity (the nominal's, less the correction's rate) as the speed reference. Nothing of the controller's echo enters the
// target, so the correction can never integrate. The first message must find the arm within 1 deg of
// the program's start, or the link refuses and never answers; a silence pauses the program clock.
#pragma once

#include <memory>

#include "deflex/egm/egm_receiver.hpp"
#include "deflex/link/controller_link.hpp"
#include "deflex/link/joint_stream.hpp"
#include "deflex/link/link_history.hpp"
#include "deflex/online/delay_estimator.hpp"
#include "deflex/online/online_strategy.hpp"

namespace deflex {

struct EgmJointLinkConfig {
  EgmReceiverConfig receiver;
  JointStreamConfig stream;
  bool send_speed_reference = true;  ///< the target's joint velocity in EgmSensor.speedRef
  std::size_t history_cycles = 1000;  ///< ring of the last cycles (4 s at 4 ms)
  double initial_delay_s = 0.05;      ///< the delay assumed until it is measured (ABB users: ~50 ms)
};

class EgmJointLink final : public ControllerLink {
 public:
  /// Every reference must outlive the link. `force` may be null (push samples into the compensator
  /// yourself). Throws InputError on a configuration that cannot work (a trajectory for another
  /// number of joints, a bad setting).
  EgmJointLink(OnlineCompensator& compensator, OnlineStrategy& strategy, std::shared_ptr<const JointTrajectory> nominal,
               DatagramTransport& transport, const Clock& clock, ForceSource* force,
               const EgmJointLinkConfig& config = {});

  LinkPollResult poll(double timeout_s) noexcept override;
  [[nodiscard]] const char* name() const override { return "egm-joint"; }
  [[nodiscard]] LinkState state() const override { return state_; }
  [[nodiscard]] const LinkCounters& counters() const override { return counters_; }
  [[nodiscard]] const LinkCycleRecord& last_cycle() const override { return last_; }
  [[nodiscard]] const JointVector& start_distance() const override { return stream_.distance(); }
  [[nodiscard]] bool fault_pending() const override { return fault_pending_; }
  void clear_fault() override { fault_pending_ = false; }
  void write_history_csv(const std::string& path) const override { history_.write_csv(path); }
  [[nodiscard]] const LinkHistory* history() const override { return &history_; }

  [[nodiscard]] const JointStream& stream() const { return stream_; }
  [[nodiscard]] const DelayEstimator& delay() const { return delay_; }
  [[nodiscard]] const DatagramAddress& controller() const { return receiver_.controller(); }

 private:
  OnlineCompensator& comp_;
  OnlineStrategy& strategy_;
  const Clock& clock_;
  ForceSource* force_;
  EgmJointLinkConfig config_;
  LinkCounters counters_;
  EgmReceiver receiver_;
  JointStream stream_;
  DelayEstimator delay_;
  LinkHistory history_;
  LinkState state_ = LinkState::kWaiting;
  bool fault_pending_ = false;

  // Preallocated per-cycle buffers.
  CycleInput input_;
  JointVector nominal_, nominal_velocity_, feedback_, command_, previous_dtheta_;
  double previous_reply_s_ = 0.0;
  bool have_previous_reply_ = false;
  EgmSensorMessage reply_;
  std::vector<unsigned char> tx_;
  std::uint32_t reply_seq_ = 0;
  LinkCycleRecord last_;
};

}  // namespace deflex
