// deflex as the sensor side of ABB EGM: owns the UDP socket, drains it every cycle and keeps the
// newest valid EgmRobot packet, runs the online compensator on its joints, and answers the sender
// with an EgmSensor message carrying the compensated joints. Bad packets are counted and never
// answered; a controller restart (sequence numbers starting again) is recognised; the last cycles
// stay in a preallocated ring buffer that is written out when a fault stops the loop.
// Two ways to run it: poll() from your own loop, or run() with a callback per cycle.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <netinet/in.h>

#include "deflex/egm/egm_codec.hpp"
#include "deflex/egm/udp_socket.hpp"
#include "deflex/online/online_compensator.hpp"

namespace deflex {

struct EgmEndpointConfig {
  std::string bind_address = "127.0.0.1";
  std::uint16_t port = 6510;            ///< 0: ephemeral (tests); read it back with port()
  std::size_t max_packet_bytes = 1400;  ///< larger datagrams are "oversized" and ignored
  std::size_t history_cycles = 1000;    ///< ring buffer of the last cycles (4 s at 4 ms)
  /// Silence after which any sequence number starts a new session (controller restarted).
  double restart_silence_s = 0.5;
  /// A backwards jump to a sequence number at most this is a restart, not a stale packet.
  std::uint32_t restart_seqno_max = 16;
};

struct EgmCounters {
  std::uint64_t datagrams = 0;    ///< everything received
  std::uint64_t replies = 0;      ///< EgmSensor messages sent
  std::uint64_t malformed = 0, truncated = 0, oversized = 0, empty = 0;
  std::uint64_t missing_header = 0, missing_joints = 0, non_finite = 0;
  std::uint64_t duplicate = 0, out_of_order = 0;
  std::uint64_t out_of_limits = 0;  ///< finite joints beyond the robot's limits (plus 1 deg): never answered
  std::uint64_t superseded = 0;   ///< valid but a newer one arrived in the same drain: not answered
  std::uint64_t restarts = 0;     ///< controller restarts recognised
  std::uint64_t invalid_cycles = 0;  ///< the compensator refused the input: not answered
  std::uint64_t send_errors = 0;
  [[nodiscard]] std::uint64_t rejected() const {
    return malformed + truncated + oversized + empty + missing_header + missing_joints + non_finite + duplicate +
           out_of_order + out_of_limits;
  }
};

/// One cycle as it went (SI units: rad, N, Nm, s).
struct EgmCycleRecord {
  double t_s = 0.0;                 ///< endpoint clock (steady, from construction)
  std::uint32_t seqno = 0;
  std::uint32_t tm_ms = 0;          ///< controller's time stamp
  JointVector q_planned, q_feedback, q_command, dtheta;
  Wrench wrench_base = Wrench::Zero();
  CycleStatus status = CycleStatus::kNoForceYet;
  bool replied = false;
  double compute_s = 0.0;           ///< from the datagram read to the reply sent
};

enum class EgmPollResult : int {
  kReplied = 0,     ///< a packet was handled and answered
  kTimeout = 1,     ///< nothing arrived
  kRejected = 2,    ///< packets arrived but none was usable (counted)
  kNotAnswered = -1,  ///< a packet was usable but the compensator refused it (invalid cycle)
};

class EgmSensorEndpoint {
 public:
  /// Binds the socket. The compensator must outlive the endpoint. Throws Error / InputError.
  EgmSensorEndpoint(OnlineCompensator& compensator, const EgmEndpointConfig& config);

  [[nodiscard]] std::uint16_t port() const { return socket_.port(); }
  /// Force input drained each cycle before the compensator steps (may be null: push forces into the
  /// compensator yourself).
  void set_force_source(ForceSource* source) { source_ = source; }

  /// Waits up to timeout_s for packets, drains the socket, handles the newest valid packet and
  /// replies. Never allocates, locks or throws.
  EgmPollResult poll(double timeout_s) noexcept;

  /// Callback style: loops on poll() until `stop` is set or the callback returns false. The callback
  /// sees every answered (or refused) cycle. On a fault (a force fault or an invalid cycle) the
  /// history is written to `fault_dump_csv` if it is not empty. Returns the number of cycles.
  using CycleCallback = std::function<bool(const EgmCycleRecord&)>;
  std::uint64_t run(const std::atomic<bool>& stop, const CycleCallback& callback, double poll_timeout_s = 0.05,
                    const std::string& fault_dump_csv = "");

  [[nodiscard]] const EgmCounters& counters() const { return counters_; }
  [[nodiscard]] const EgmCycleRecord& last_cycle() const { return last_; }
  /// True after a cycle with a force fault or an invalid input, until clear_fault().
  [[nodiscard]] bool fault_pending() const { return fault_pending_; }
  void clear_fault() { fault_pending_ = false; }
  /// The ring buffer, oldest first, as CSV (setup-time I/O; allocates; throws Error).
  void write_history_csv(const std::string& path) const;
  [[nodiscard]] std::size_t history_size() const { return history_count_; }

 private:
  bool accept_sequence(std::uint32_t seqno, double now_s) noexcept;
  [[nodiscard]] bool joints_plausible(const EgmRobotMessage& m) const noexcept;
  void record(const EgmCycleRecord& r) noexcept;
  [[nodiscard]] double now_s() const noexcept;

  OnlineCompensator& comp_;
  EgmEndpointConfig config_;
  UdpSocket socket_;
  EgmCodec codec_;
  ForceSource* source_ = nullptr;
  std::chrono::steady_clock::time_point start_;

  std::vector<unsigned char> rx_, tx_;  // sized once
  EgmRobotMessage msg_, newest_;
  sockaddr_in from_{}, newest_from_{};
  EgmSensorMessage reply_;
  CycleInput input_;

  bool have_seq_ = false;
  std::uint32_t last_seq_ = 0;
  double last_accept_s_ = 0.0;
  std::uint32_t reply_seq_ = 0;

  std::vector<EgmCycleRecord> history_;  // ring, preallocated
  std::size_t history_head_ = 0, history_count_ = 0;
  EgmCycleRecord last_;
  bool fault_pending_ = false;
  EgmCounters counters_;
};

}  // namespace deflex
