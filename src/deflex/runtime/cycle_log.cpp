// The cycle log's CSV (see cycle_log.hpp).
#include "deflex/runtime/cycle_log.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex::runtime {

std::string cycle_log_preamble(const CycleLogInfo& info) {
  std::string out = fmt::format("{} link={} period_ms={:g} force_components={} force_fault_N={:g}\n", kCycleLogPreamble,
                                info.link.empty() ? "unknown" : info.link, info.period_s * 1e3, info.force_components,
                                info.force_fault_n);
  for (const ShownSetting& s : info.settings) {
    // One line each: a value is the option's text (a path may hold anything but a line break).
    std::string value = s.value;
    std::replace(value.begin(), value.end(), '\n', ' ');
    std::replace(value.begin(), value.end(), '\r', ' ');
    fmt::format_to(std::back_inserter(out), "{}{}={}\n", kCycleLogSetting, s.option, value);
  }
  return out;
}

std::string cycle_log_header(int joints) {
  std::string h = "t_s,program_t_s,sequence,status,replied,session_start,step_limited";
  for (const char* name : {"q_nominal", "q_blend", "q_feedback", "q_command", "dtheta"}) {
    for (int j = 1; j <= joints; ++j) h += fmt::format(",{}{}_deg", name, j);
  }
  h += ",corr_x_mm,corr_y_mm,corr_z_mm,rot_uncorrected_mrad,fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm,meas_fx_N,meas_fy_N,"
       "meas_fz_N,deviation_deg,deviation_mm,step_deg,step_mm,delay_ms,compute_us,answer_ms,stamp_ms,"
       "arrival_delay_ms,jitter_ms,missed_before,duplicates,superseded,rejected,restarts,late,controller_late,silences,"
       "guard_trips,step_limited_total,joint_bound_deg,tcp_bound_mm\n";
  return h;
}

namespace {
void number(std::string& out, double v, int digits) {
  if (!std::isfinite(v)) {
    out += ",";
    return;
  }
  fmt::format_to(std::back_inserter(out), ",{:.{}f}", v, digits);
}
void general(std::string& out, double v) {
  if (!std::isfinite(v)) {
    out += ",";
    return;
  }
  fmt::format_to(std::back_inserter(out), ",{:.10g}", v);
}
}  // namespace

void append_cycle_row(std::string& out, const SessionEntry& e, int joints, const CycleLogBounds& bounds) {
  const LinkCycleRecord& r = e.record;
  const LinkCounters& c = e.counters;
  fmt::format_to(std::back_inserter(out), "{:.6f},{:.9f},{},{},{},{},{}", r.t_s, r.program_time_s, r.sequence,
                 static_cast<int>(r.status), r.replied ? 1 : 0, r.session_start ? 1 : 0, r.step_limited ? 1 : 0);
  for (const JointVector* q : {&r.q_nominal, &r.q_blend, &r.q_feedback, &r.q_command, &r.dtheta}) {
    for (int j = 0; j < joints; ++j) general(out, j < q->size() ? rad_to_deg((*q)[j]) : 0.0);
  }
  for (int k = 0; k < 3; ++k) number(out, r.tcp_correction_m[k] * 1e3, 6);
  number(out, r.rotation_uncorrected_rad * 1e3, 6);
  for (int k = 0; k < 6; ++k) general(out, r.wrench_base[k]);
  for (int k = 0; k < 3; ++k) general(out, r.wrench_measured_base[k]);
  general(out, rad_to_deg(r.deviation_rad));
  number(out, r.deviation_m * 1e3, 6);
  general(out, rad_to_deg(r.step_rad));
  number(out, r.step_m * 1e3, 6);
  number(out, r.delay_s * 1e3, 3);
  number(out, r.compute_s * 1e6, 2);
  number(out, r.answer_s * 1e3, 4);
  number(out, r.arrival.stamp_s * 1e3, 0);
  number(out, r.arrival.arrival_delay_s * 1e3, 3);
  number(out, r.arrival.jitter_s * 1e3, 3);
  fmt::format_to(std::back_inserter(out), ",{},{},{},{},{},{},{},{},{},{}", r.arrival.missed_before, c.duplicate,
                 c.superseded, c.rejected(), c.restarts, c.late, c.controller_late, c.silences, c.guard_trips,
                 c.step_limited);
  general(out, bounds.joint_deg);
  general(out, bounds.tcp_mm);
  out += '\n';
}

CycleLogFile::CycleLogFile(const std::string& path, int joints, const CycleLogBounds& bounds, const CycleLogInfo& info)
    : file_(path, "option --log"), joints_(joints), bounds_(bounds) {
  file_.write(cycle_log_preamble(info) + cycle_log_header(joints));
  row_.reserve(4096);
}

void CycleLogFile::write(const SessionEntry& e) {
  if (closed_ || e.kind != SessionEntry::Kind::kCycle) return;
  row_.clear();
  append_cycle_row(row_, e, joints_, bounds_);
  file_.write(row_);
  ++rows_;
}

void CycleLogFile::close(const std::string& stop_reason) {
  if (closed_) return;
  closed_ = true;
  if (!stop_reason.empty()) {
    std::string line = kCycleLogStop;
    for (char ch : stop_reason) line += (ch == '\n' || ch == '\r') ? ' ' : ch;  // one line whatever the text
    file_.write(line + "\n");
  }
  file_.commit();
}

void write_fault_dump(const std::string& path, const std::string& text) {
  write_output_file(path, text, "option --fault-dump");
}

void check_fault_dump_path(const std::string& path) {
  const OutputFile probe(path, "option --fault-dump");  // uncommitted: its temporary file goes with it
}

}  // namespace deflex::runtime
