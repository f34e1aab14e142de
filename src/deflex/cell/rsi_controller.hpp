// The controller side of KUKA RSI axis correction (KRL: RSI_CREATE, RSI_ON(#ABSOLUTE), the program's
// own motion; an RSI context wiring ETHERNET to AXISCORR and AXISCORRMON), as the real controller
// behaves, never more kindly (facts: reference rsi.md, docs/online.md):
//   - every RSI cycle (4 ms in IPO_FAST, 12 ms in IPO) it sends a <Rob Type="KUKA"> with AIPos (the
//     axes as the motors have them), ASPos (its program's axis setpoints, without the correction),
//     RIst/RSol (the same as Cartesian poses), Delay (the late answers counted so far) and the IPOC
//     (a millisecond time stamp that grows by the cycle);
//   - a cycle's answer must be a <Sen> of the configured SENTYPE carrying that cycle's IPOC, from the
//     sensor's address, and must have arrived when the next cycle starts. Anything else (no answer, a
//     wrong or old IPOC, another Type, a document it cannot read, another sender) leaves the cycle
//     late. The late count is never reset within the session; when it reaches the ETHERNET object's
//     Timeout, RSI stops and so do the program and the arm, where they are;
//   - AXISCORR in absolute mode: the AK values are the whole offset from where RSI started, each
//     axis clamped to [LowerLimAi, UpperLimAi], applied after a dead time; an answer never adds to
//     the previous one. AXISCORRMON stops RSI when an axis's applied offset exceeds MaxAi;
//   - the KRL program's own motion runs underneath: the axes are at program(t) + offset.
// It knows nothing of deflex: only the wire format, over a datagram transport.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "deflex/cell/robot_controller.hpp"
#include "deflex/model/kinematics.hpp"
#include "deflex/transport/datagram_transport.hpp"
#include "deflex/wire/rsi_xml.hpp"

namespace deflex::cell {

struct RsiControllerConfig {
  double cycle_s = 0.004;                 ///< IPO_FAST 4 ms (IPO: 12 ms)
  int timeout = 100;                      ///< ETHERNET Timeout: late answers that stop RSI
  std::string sentype = "ImFree";         ///< <SENTYPE>: the Type every answer must carry
  double lower_limit_deg = -0.5;          ///< AXISCORR LowerLimA1..A6 (offset from where RSI started)
  double upper_limit_deg = 0.5;           ///< AXISCORR UpperLimA1..A6
  double max_correction_deg = 1.0;        ///< AXISCORRMON MaxA1..A6: beyond it RSI stops
  double correction_dead_time_s = 0.008;  ///< from an answer taken to the axes moving by it
  int precision = 4;                      ///< ETHERNET Precision: decimals of the numbers it sends
  std::uint64_t first_ipoc = 1000000;     ///< IPOC of the first cycle
  /// The IPOC counter's width: 64, or 32 (it wraps at 2^32 ms). No public source states the KR C4's
  /// own; the drivers read it as an unsigned 64-bit number, so deflex is tried against both.
  int ipoc_bits = 64;
};

enum class RsiStop {
  kRunning = 0,
  kTimeout,        ///< the late count reached Timeout
  kMaxCorrection,  ///< AXISCORRMON: an axis's offset beyond MaxAi
};
[[nodiscard]] const char* to_string(RsiStop s);

struct RsiControllerCounters {
  std::uint64_t sent = 0;     ///< <Rob> documents
  std::uint64_t answers = 0;  ///< answers taken in time (the right IPOC, Type and sender)
  std::uint64_t late = 0;     ///< cycles without such an answer (the <Delay> it reports)
  std::uint64_t stale = 0;    ///< readable answers with an IPOC that was not the awaited one
  std::uint64_t ignored = 0;  ///< datagrams that were no readable answer of its SENTYPE from the sensor
  std::uint64_t clamped = 0;  ///< answers with an axis beyond AXISCORR's limits (clamped)
  RsiStop stopped = RsiStop::kRunning;
};

/// Thread safety: one thread at a time (the simulation's), with its transport.
class RsiController final : public RobotController {
 public:
  /// `kinematics`: the controller's own model (for RIst/RSol). `program`: the KRL motion it runs.
  /// The sensor (deflex) listens at `sensor`. Throws InputError on a bad configuration.
  RsiController(const RsiControllerConfig& config, const RobotModel& kinematics,
                std::shared_ptr<const JointTrajectory> program, DatagramTransport& transport,
                const DatagramAddress& sensor);

  const JointVector& tick(double t_s) override;
  /// AIPos and RIst are the encoders' (behind the command by the servo's following error), as on the
  /// real controller; without a reading (no arm in the loop) they are the commanded axes.
  void encoders(const JointVector& q_motor_rad) override;
  [[nodiscard]] const char* name() const override { return "KUKA RSI axis correction"; }
  [[nodiscard]] const RsiControllerCounters& counters() const { return counters_; }
  /// The offset the axes have now (rad), from where RSI started.
  [[nodiscard]] const JointVector& applied_offset_rad() const { return applied_; }
  /// The IPOC of the last <Rob> sent.
  [[nodiscard]] std::uint64_t last_ipoc() const { return robot_.ipoc; }
  [[nodiscard]] bool running() const { return counters_.stopped == RsiStop::kRunning; }
  /// RSI switched off (RSI_OFF, or stopped) and on again (RSI_ON) at the next cycle: a new session,
  /// its IPOC `ipoc_jump_ms` further on, the late count and the applied offset back to zero.
  void restart(std::uint64_t ipoc_jump_ms = 60000);
  /// RSI is off in [from_s, to_s): no documents, no late count (the KRL program runs without RSI).
  void pause(double from_s, double to_s);

 private:
  void stop(RsiStop why) {
    if (counters_.stopped == RsiStop::kRunning) counters_.stopped = why;
  }
  void pose_of(const JointVector& q, std::array<double, 6>& xyzabc);

  RsiControllerConfig config_;
  RobotModel model_;
  Workspace ws_;
  std::shared_ptr<const JointTrajectory> program_;
  DatagramTransport& transport_;
  DatagramAddress sensor_;
  std::vector<unsigned char> buffer_;
  RsiRobotMessage robot_;
  RsiSensorMessage answer_;
  struct Pending {
    double due_s = 0.0;
    JointVector offset_rad;
  };
  std::vector<Pending> pending_;
  std::size_t pending_head_ = 0, pending_count_ = 0;
  JointVector applied_, planned_, position_;
  void send_robot_message();
  JointVector encoders_;  // the last encoder reading: what AIPos reports
  bool have_encoders_ = false;
  double next_cycle_s_ = 0.0, program_t_s_ = 0.0, last_t_s_ = 0.0;
  bool started_ = false, awaiting_ = false, answered_ = false;
  double pause_from_s_ = 0.0, pause_to_s_ = 0.0;
  std::uint64_t next_ipoc_ = 0;
  RsiControllerCounters counters_;
};

}  // namespace deflex::cell
