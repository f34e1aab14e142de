// The CSV of an online session's cycles, one format for `--log` (every cycle) and `--fault-dump` (the
// last cycles before a fault): the time, the program time and the controller's sequence number, then
// per joint the nominal (the program, un-blended), the blend, the feedback, the command as the wire
// carried it and the correction, in degrees; the TCP correction in mm; the wrenches in N and Nm; the
// command against its two invariants (deviation from the nominal held, step from the previous
// command); the delay, compute and answer times; how the message arrived and the link's running
// counts. Written on the reporter's thread, never on the loop's.
#pragma once

#include <string>
#include <vector>

#include "deflex/runtime/record_queue.hpp"
#include "deflex/runtime/shown_setting.hpp"
#include "deflex/text/output_file.hpp"

namespace deflex::runtime {

/// The bounds a session's commands were held to, in every row (the last two columns, joint_bound_deg
/// and tcp_bound_mm), so a log read back on its own (`deflex monitor --log`) draws them.
struct CycleLogBounds {
  double joint_deg = 0.0;
  double tcp_mm = 0.0;
};

/// What a log's first line says of its session, so a log read back on its own (`deflex monitor --log`)
/// names its link, the cycle its answers are measured against and what the sensor measures:
/// "# deflex cycle log: link=egm-joint period_ms=4 force_components=6 force_fault_N=5000", then a line
/// per setting the session ran with: "# setting: --max-joint-correction-deg=0.5". Its last line,
/// written when the session ends, says why: "# stop: REASON". CSV readers that skip '#' lines
/// (deflex's own, pandas with comment='#') read the columns alone.
struct CycleLogInfo {
  std::string link;
  double period_s = 0.0;
  int force_components = 0;
  double force_fault_n = 0.0;          ///< |F| above this is a force fault (the sensor's threshold)
  std::vector<ShownSetting> settings;  ///< as the session ran (settings_shown())
};
inline constexpr char kCycleLogPreamble[] = "# deflex cycle log:";
inline constexpr char kCycleLogStop[] = "# stop: ";
inline constexpr char kCycleLogSetting[] = "# setting: ";
/// The first line and the settings' (each with its newline).
[[nodiscard]] std::string cycle_log_preamble(const CycleLogInfo& info);

/// The header line (with its newline) for a robot of `joints` joints.
[[nodiscard]] std::string cycle_log_header(int joints);
/// One row (with its newline).
void append_cycle_row(std::string& out, const SessionEntry& e, int joints, const CycleLogBounds& bounds);

/// The cycle log as an output of deflex (model/output_file.hpp): written into a temporary file beside
/// the path and put in place when the session ends (whatever ended it: the log is the record of what
/// happened), never truncating the path before then; a session that dies leaves the path as it was.
/// Thread safety: one thread at a time (the session's reporter).
class CycleLogFile {
 public:
  /// Prepares `path` now, so a path that cannot be an output is an error at the session's start, and
  /// writes the first line and the header. Throws InputError naming the option and the path.
  CycleLogFile(const std::string& path, int joints, const CycleLogBounds& bounds, const CycleLogInfo& info = {});

  void write(const SessionEntry& e);
  /// Ends the log with "# stop: REASON" (when `stop_reason` is not empty) and puts it in place; throws
  /// OutputError naming the path when a write failed (a full disk).
  void close(const std::string& stop_reason = "");
  [[nodiscard]] const std::string& path() const { return file_.path(); }
  [[nodiscard]] std::uint64_t rows() const { return rows_; }

 private:
  OutputFile file_;
  int joints_;
  CycleLogBounds bounds_;
  std::string row_;
  std::uint64_t rows_ = 0;
  bool closed_ = false;
};

/// `text` as the fault dump at `path`, put in place at once (a temporary file renamed over the
/// previous dump). Throws InputError or OutputError naming the path.
void write_fault_dump(const std::string& path, const std::string& text);
/// Refuses now a dump path that could not be written later (InputError naming it); leaves no trace.
void check_fault_dump_path(const std::string& path);

}  // namespace deflex::runtime
