// The CSV of an online session's cycles, one format for `--log` (every cycle) and `--fault-dump` (the
// last cycles before a fault): the time, the program time and the controller's sequence number, then
// per joint the nominal (the program, un-blended), the blend, the feedback, the command as the wire
// carried it and the correction, in degrees; the TCP correction in mm; the wrenches in N and Nm; the
// command against its two invariants (deviation from the nominal held, step from the previous
// command); the delay, compute and answer times; how the message arrived and the link's running
// counts. Written on the reporter's thread, never on the loop's.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include "deflex/runtime/record_queue.hpp"

namespace deflex::runtime {

/// The header line (with its newline) for a robot of `joints` joints.
[[nodiscard]] std::string cycle_log_header(int joints);
/// One row (with its newline).
void append_cycle_row(std::string& out, const SessionEntry& e, int joints);

class CycleLogFile {
 public:
  /// Opens `path` for writing now, so an unwritable path is an error at the session's start, and
  /// writes the header. Throws Error naming the path.
  CycleLogFile(const std::string& path, int joints);
  ~CycleLogFile();
  CycleLogFile(const CycleLogFile&) = delete;
  CycleLogFile& operator=(const CycleLogFile&) = delete;

  void write(const SessionEntry& e);
  /// Flushes and closes; throws Error naming the path when any write failed (a full disk).
  void close();
  [[nodiscard]] const std::string& path() const { return path_; }
  [[nodiscard]] std::uint64_t rows() const { return rows_; }

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
  int joints_;
  std::string row_;
  std::vector<char> buffer_;
  std::uint64_t rows_ = 0;
  bool failed_ = false;
};

}  // namespace deflex::runtime
