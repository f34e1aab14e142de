// What an online session is configured with: the link and its controller's address, the strategy,
// the bounds and rates, the stop rules, the outputs, the force source and its tare. Plain structs;
// session_settings.hpp is the table that names, documents and validates every field a user sets.
#pragma once

#include <optional>
#include <string>

#include "deflex/egm/egm_joint_link.hpp"
#include "deflex/egm/egm_path_link.hpp"
#include "deflex/fanuc/fanuc_j519_link.hpp"
#include "deflex/motoros2/motoros2_rt_link.hpp"
#include "deflex/online/online_strategy.hpp"
#include "deflex/rsi/rsi_link.hpp"
#include "deflex/runtime/link_table.hpp"
#include "deflex/runtime/realtime.hpp"
#include "deflex/simple_message/simple_message_link.hpp"
#include "deflex/ur/ur_rtde_link.hpp"

namespace deflex::runtime {

/// Where a real cell's controller is reached (the sockets the session opens when it is given none).
struct NetworkConfig {
  std::string bind_address = "127.0.0.1";  ///< UDP links bind here (0.0.0.0 or the cell network's address on a cell)
  int egm_port = -1;                       ///< EGM links: the UDP port the controller sends to (required)
  int rsi_port = -1;                       ///< rsi: the UDP port the controller sends to (required)
  std::string robot_host;  ///< simple message, fanuc-j519, motoros2-rt, ur-rtde: the controller's address
  /// fanuc-j519, motoros2-rt: its UDP port, ur-rtde: its RTDE TCP port (-1: the protocol's, 60015, 22000 or 30004)
  int robot_port = -1;
  int motion_port = 11000, state_port = 11002;
  double connect_timeout_s = 5.0;
};

/// Where the force samples come from, and the tare taken before the session starts
/// (session_force.hpp opens the source and takes it).
struct ForceConfig {
  std::string source;             ///< udp:PORT, csv:FILE or rdt:HOST[:PORT]
  bool loop = false;              ///< csv: replay again after the last sample
  std::string rdt_calibration;    ///< rdt: counts to N and Nm (sensor, FILE.xml, http://URL, onrobot-hex, counts:...)
  double rdt_rate_hz = 0.0;       ///< rdt: its rate, Hz (0: the page's)
  bool rdt_buffered = false;      ///< rdt: several records a datagram
  bool tare = false;              ///< rdt: take the sensor's offset at start, arm still
  double tare_window_s = 0.5;     ///< the tare's averaging window, s
  double tare_max_std_n = 0.5;    ///< the largest standard deviation of a force axis over it, N
  double tare_max_std_nm = 0.05;  ///< the same for a torque axis, Nm
  std::string tare_pose_deg;      ///< the joints held during the tare, deg, "q1,...,qN" ("" the program's start)
};

struct SessionConfig {
  LinkKind link = LinkKind::kEgmJoint;
  StrategyKind strategy = StrategyKind::kOnline;
  OnlineConfig online;                   ///< bounds, rates, watchdog; period_s is the controller's cycle
  std::optional<double> stop_silence_s;  ///< default: the link's (link_table.hpp)
  double end_silence_s = 2.0;            ///< streaming links: silence after the program's end that ends the session
  bool end_on_silence = false;           ///< correcting links: a silence after a healthy session is the planned end
  NetworkConfig network;
  // Each link's own settings (the session sets their stop rules from the fields above).
  EgmJointLinkConfig egm_joint;
  EgmPathLinkConfig egm_path;
  RsiLinkConfig rsi;
  SimpleMessageLinkConfig simple_message;
  FanucJ519LinkConfig fanuc_j519;    ///< its controller address comes from NetworkConfig (or is given with a transport)
  Motoros2RtLinkConfig motoros2_rt;  ///< as fanuc_j519
  UrRtdeLinkConfig ur_rtde;          ///< its controller address comes from NetworkConfig (or is given with a stream)
  double duration_s = 0.0;           ///< > 0: the session ends (planned) after this long
  /// A planned stop (request_stop(), the time limit) while the arm moves: a streaming link brings the
  /// program to rest on its path over this long, a correcting link ramps its correction out at the rate
  /// bound; then the session ends. s, 0.05..10.
  double stop_ramp_s = 0.5;
  double status_interval_s = 1.0;     ///< a status line this often (0: none)
  std::string log_path;               ///< the cycle log CSV ("" none)
  std::string fault_dump_path;        ///< the fault dump CSV ("" none)
  std::size_t history_cycles = 1000;  ///< cycles kept for a fault dump
  double fault_quiet_s = 1.0;         ///< a fault episode ends after this long without a fault
  std::size_t queue_entries = 8192;   ///< the loop-to-reporter ring (32 s of 4 ms cycles)
  bool collect_cycles = false;        ///< keep every cycle in memory (Python's cycle log)
  bool monitor = false;               ///< feed the live monitor page (monitor_feed() gives its data)
  double monitor_window_s = 30.0;     ///< the history the page keeps and shows
  RealtimeOptions realtime;
  ForceConfig force;  ///< what front ends open with open_session_force(); the session itself is handed a source
};

}  // namespace deflex::runtime
