// `deflex online --fault-dump FILE`: the link's last cycles, written once per fault episode. An
// episode begins at the first cycle with a fault (a force fault, an invalid cycle, a guard stop) and
// ends after `quiet_s` without one; a spike that keeps the compensator faulted for half a second is
// one episode, one dump and two log lines, not a rewrite and a line on every faulted cycle. The dump
// is written on a thread of its own from a copy of the link's ring taken between two polls, so the
// file I/O never delays an answer; a failed write is logged and the run goes on (the path was
// checked for writability at start).
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>

#include <spdlog/logger.h>

#include "deflex/link/controller_link.hpp"

namespace deflex::cli {

class FaultDump {
 public:
  /// `path` empty: no file, but episodes are still counted and logged. Throws Error naming the path
  /// when it cannot be written.
  FaultDump(std::string path, double quiet_s, std::shared_ptr<spdlog::logger> log);
  ~FaultDump();
  FaultDump(const FaultDump&) = delete;
  FaultDump& operator=(const FaultDump&) = delete;

  /// After each handled cycle, between polls. Clears the link's pending fault.
  void on_cycle(double now_s, ControllerLink& link);
  /// Closes an open episode and waits for a dump still being written.
  void finish(double now_s);

  [[nodiscard]] std::uint64_t episodes() const { return episodes_; }
  [[nodiscard]] std::uint64_t faulted_cycles() const { return faulted_total_; }

 private:
  void end_episode(double now_s);
  void write(const ControllerLink& link);

  std::string path_;
  double quiet_s_;
  std::shared_ptr<spdlog::logger> log_;
  bool in_episode_ = false;
  double began_s_ = 0.0, last_fault_s_ = 0.0;
  std::uint64_t episodes_ = 0, faulted_ = 0, faulted_total_ = 0;
  std::thread writer_;
  std::atomic<bool> writing_{false};
};

}  // namespace deflex::cli
