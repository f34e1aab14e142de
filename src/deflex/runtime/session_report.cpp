// What an online session tells about itself (see session_report.hpp).
#include "deflex/runtime/session_report.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "deflex/text/errors.hpp"

namespace deflex::runtime {

void Histogram::add(double v) {
  if (!std::isfinite(v)) return;
  const double slot = std::max(0.0, v / bin_);
  const auto i = std::min(counts_.size() - 1, static_cast<std::size_t>(std::min(slot, 1e18)));
  ++counts_[i];
  ++n_;
  max_ = std::max(max_, v);
}

double Histogram::quantile(double q) const {
  if (n_ == 0) return std::numeric_limits<double>::quiet_NaN();
  const auto rank = static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(n_)));
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < counts_.size(); ++i) {
    seen += counts_[i];
    if (seen >= std::max<std::uint64_t>(rank, 1)) return std::min(max_, static_cast<double>(i + 1) * bin_);
  }
  return max_;
}

SessionReporter::SessionReporter(ReportSetup setup) : setup_(std::move(setup)) {
  if (!setup_.log_path.empty()) log_ = std::make_unique<CycleLogFile>(setup_.log_path, setup_.joints, bounds(), info());
  // Checked now: a path that cannot be written must not end a run at its first fault.
  if (!setup_.dump_path.empty()) check_fault_dump_path(setup_.dump_path);
  SessionEntry blank;
  blank.record.q_nominal = blank.record.q_blend = blank.record.q_feedback = blank.record.q_command =
      blank.record.dtheta = JointVector::Zero(setup_.joints);
  ring_.assign(std::max<std::size_t>(setup_.dump_cycles, 1), blank);
  last_ = blank;
}

void SessionReporter::log(LogLevel level, const std::string& text) const {
  if (setup_.sink) setup_.sink(level, text);
}

void SessionReporter::consume(const SessionEntry& e) {
  if (interval_start_s_ < 0.0) {
    interval_start_s_ = e.t_s;
    next_status_s_ = e.t_s + setup_.status_interval_s;
  }
  if (e.kind == SessionEntry::Kind::kCycle) on_cycle(e);
  on_force_source(e);
  if (setup_.monitor) {
    setup_.monitor->add(e);
    if (!have_last_ || last_.state != e.state) setup_.monitor->set_state(to_string(e.state));
  }
  last_ = e;
  have_last_ = true;
}

// What the force source flagged, named in the log when it happens: samples the sensor marked faulty
// (its status word), and a stream that stopped or never came and was requested again. At most a line
// a second each, with the counts so far.
void SessionReporter::on_force_source(const SessionEntry& e) {
  const ForceSourceStats& f = e.force;
  if (f.faulty > force_logged_.faulty && e.t_s - faulty_logged_s_ >= 1.0) {
    log(LogLevel::kWarn,
        fmt::format("the force sensor flagged {} sample{} faulty so far ({} at its range limits; last status word "
                    "0x{:08X}): the compensator does not move the robot on them",
                    f.faulty, f.faulty == 1 ? "" : "s", f.saturated, f.last_status));
    force_logged_.faulty = f.faulty;
    faulty_logged_s_ = e.t_s;
  }
  if (f.re_requests > force_logged_.re_requests && e.t_s - re_request_logged_s_ >= 1.0) {
    log(LogLevel::kWarn, fmt::format("the force stream stopped or never came: requested again ({} re-request{} so "
                                     "far, {} samples accepted)",
                                     f.re_requests, f.re_requests == 1 ? "" : "s", f.accepted));
    force_logged_.re_requests = f.re_requests;
    re_request_logged_s_ = e.t_s;
  }
}

// Each cycle: written to the log and the ring, counted, checked for a silence or a restart worth a
// line, and for the start or end of a fault episode.
void SessionReporter::on_cycle(const SessionEntry& e) {
  ++cycles_;
  ++window_cycles_;
  keep(e);
  tally(e.record);
  note_silence_and_restart(e);
  track_faults(e);
}

void SessionReporter::keep(const SessionEntry& e) {
  const LinkCycleRecord& r = e.record;
  if (log_) {
    try {
      log_->write(e);
    } catch (const std::exception& ex) {
      // A half-written log is never put in place: its temporary file goes, the path stays as it was.
      log_error_ =
          fmt::format("{} (the cycle log was not put in place: its path is as it was before the session)", ex.what());
      log_.reset();
      output_failed(log_error_);
    }
  }
  if (setup_.collect) collected_.push_back(r);
  ring_[ring_head_] = e;
  ring_head_ = (ring_head_ + 1) % ring_.size();
  ring_count_ = std::min(ring_count_ + 1, ring_.size());
}

void SessionReporter::tally(const LinkCycleRecord& r) {
  compute_us_.add(r.compute_s * 1e6);
  arrival_ms_.add(r.arrival.arrival_delay_s * 1e3);
  window_compute_s_ = std::max(window_compute_s_, r.compute_s);
  if (r.replied) {
    ++answers_;
    ++window_answers_;
    answer_ms_.add(r.answer_s * 1e3);
    if (std::isfinite(r.answer_s)) window_answer_s_ = std::max(window_answer_s_, r.answer_s);
    if (r.answer_s > setup_.period_s) {
      ++late_answers_;
      ++window_late_;
    }
    window_dev_rad_ = std::max(window_dev_rad_, r.deviation_rad);
    window_dev_m_ = std::max(window_dev_m_, r.deviation_m);
    window_step_fraction_ = std::max(window_step_fraction_, r.step_fraction);
    if (setup_.limits.form == CommandForm::kJointTarget) {
      window_program_dev_rad_ = std::max(window_program_dev_rad_, (r.q_command - r.q_nominal).cwiseAbs().maxCoeff());
    }
  }
  // How far behind real time the program runs (streaming links, while it runs).
  if (setup_.streams_program && r.replied) {
    if (first_t_s_ < 0.0) {
      first_t_s_ = r.t_s;
      first_program_s_ = r.program_time_s;
    } else if (r.program_time_s < setup_.program_start_s + setup_.program_duration_s) {
      behind_s_ = std::max(0.0, (r.t_s - first_t_s_) - (r.program_time_s - first_program_s_));
    }
  }
}

void SessionReporter::note_silence_and_restart(const SessionEntry& e) {
  const LinkCycleRecord& r = e.record;
  // A gap between cycles longer than a few controller cycles: a silence the link rode through.
  if (last_t_s_ >= 0.0) {
    const double gap = r.t_s - last_t_s_;
    max_gap_s_ = std::max(max_gap_s_, gap);
    window_gap_s_ = std::max(window_gap_s_, gap);
    if (gap > std::max(10.0 * setup_.period_s, 0.05)) {
      log(LogLevel::kWarn,
          setup_.streams_program
              ? fmt::format("the controller was silent for {:.3f} s; the program waited at {:.3f} s and goes on one "
                            "cycle at a time (largest step since: {:.0f}% of its limit)",
                            gap, r.program_time_s - setup_.program_start_s, r.step_fraction * 100.0)
              : fmt::format("the controller was silent for {:.3f} s; the correction goes on from where it was "
                            "(largest step since: {:.0f}% of its limit)",
                            gap, r.step_fraction * 100.0));
    }
  }
  last_t_s_ = r.t_s;
  if (e.counters.restarts > last_restarts_) {
    log(LogLevel::kWarn,
        setup_.limits.form == CommandForm::kJointTarget
            ? fmt::format("the controller restarted (sequence {}): the command goes on from the reference it reports "
                          "(blend {:.4f} deg, taken out over the ramp-in)",
                          r.sequence, rad_to_deg(r.q_blend.cwiseAbs().maxCoeff()))
            : fmt::format("the controller restarted (sequence {}): its correction starts again from zero, and so does "
                          "deflex's (ramping in at the rate bound)",
                          r.sequence));
    last_restarts_ = e.counters.restarts;
  }
}

void SessionReporter::track_faults(const SessionEntry& e) {
  const LinkCycleRecord& r = e.record;
  // Fault episodes: a force fault, an invalid cycle, a guard trip or a message not answered.
  const bool guard = e.counters.guard_trips > last_guard_trips_;
  last_guard_trips_ = e.counters.guard_trips;
  const bool fault = r.status == CycleStatus::kForceFault || static_cast<int>(r.status) < 0 || guard;
  if (in_episode_ && !fault && r.t_s - last_fault_s_ > setup_.fault_quiet_s) {
    in_episode_ = false;
    log(LogLevel::kInfo, fmt::format("fault episode {} ended: {} faulted cycles over {:.2f} s", episodes_, faulted_,
                                     last_fault_s_ - episode_began_s_));
  }
  if (!fault) return;
  ++faulted_total_;
  last_fault_s_ = r.t_s;
  if (in_episode_) {
    ++faulted_;
    return;
  }
  begin_episode(e);
}

void SessionReporter::begin_episode(const SessionEntry& e) {
  in_episode_ = true;
  episode_began_s_ = e.record.t_s;
  faulted_ = 1;
  ++episodes_;
  const LinkCycleRecord& r = e.record;
  log(LogLevel::kWarn,
      fmt::format("fault episode {} began: status {}, |F| {:.1f} N{}", episodes_, to_string(r.status),
                  r.wrench_measured_base.head<3>().norm(), r.replied ? "" : " (that message was not answered)"));
  write_dump(fmt::format("fault episode {}", episodes_));
}

void SessionReporter::write_dump(const std::string& why) {
  if (setup_.dump_path.empty()) return;
  std::string text = cycle_log_preamble(info()) + cycle_log_header(setup_.joints);
  const std::size_t first = (ring_head_ + ring_.size() - ring_count_) % ring_.size();
  for (std::size_t k = 0; k < ring_count_; ++k)
    append_cycle_row(text, ring_[(first + k) % ring_.size()], setup_.joints, bounds());
  try {
    write_fault_dump(setup_.dump_path, text);
  } catch (const std::exception& e) {
    log(LogLevel::kError, fmt::format("{}: {}", why, e.what()));
    output_failed(fmt::format("the fault dump could not be written: {}", e.what()));
    return;
  }
  log(LogLevel::kWarn, fmt::format("{}: the last {} cycles written to {}", why, ring_count_, setup_.dump_path));
}

void SessionReporter::output_failed(const std::string& text) {
  log(LogLevel::kError, text);
  if (setup_.on_output_failure) setup_.on_output_failure(text);
}

void SessionReporter::end(double now_s, StopReason reason, const std::string& reason_text) {
  if (setup_.monitor) setup_.monitor->set_state("ended", reason_text);
  if (in_episode_) {
    in_episode_ = false;
    log(LogLevel::kInfo, fmt::format("fault episode {} ended with the session: {} faulted cycles over {:.2f} s",
                                     episodes_, faulted_, last_fault_s_ - episode_began_s_));
  }
  if (exit_code(reason) != 0 && reason != StopReason::kStartRefused)
    write_dump("the session stopped (" + reason_text + ")");
  if (log_) {
    try {
      log_->close(reason_text);
    } catch (const Error& e) {
      log_error_ = e.what();
      log(LogLevel::kError, log_error_);
    }
  }
  (void)now_s;
}

void SessionReporter::status_if_due(double now_s) {
  if (next_status_s_ < 0.0 || now_s < next_status_s_) return;
  log(LogLevel::kInfo, status_line(now_s));
  next_status_s_ = now_s + setup_.status_interval_s;
}

std::string SessionReporter::status_line(double now_s) {
  const LinkCounters& c = last_.counters;
  const LinkCounters& w = at_window_start_;
  const LinkCycleRecord& r = last_.record;
  std::string line;
  if (!have_cycle_ && cycles_ == 0) {
    line = fmt::format("waiting for the controller (received {}, rejected {})", c.datagrams, c.rejected());
  } else {
    const bool silent = last_t_s_ >= 0.0 && now_s - last_t_s_ > std::max(2.0 * setup_.period_s, 0.02);
    std::string now_part = silent
                               ? fmt::format("SILENT for {:.2f} s (nothing consumed: the {} waits)", now_s - last_t_s_,
                                             setup_.streams_program ? "program" : "correction")
                               : fmt::format("status {}, |F| {:.1f} N, TCP correction {:.3f} mm, loop delay {:.1f} ms",
                                             to_string(r.status), r.wrench_measured_base.head<3>().norm(),
                                             r.tcp_correction_m.norm() * 1e3, r.delay_s * 1e3);
    std::string program;
    if (setup_.streams_program) {
      program = fmt::format(" | program {:.1f}/{:.1f} s, {:.2f} s behind real time",
                            r.program_time_s - setup_.program_start_s, setup_.program_duration_s, behind_s_);
    }
    std::string invariants;
    if (setup_.limits.form == CommandForm::kTcpOffset) {
      invariants =
          fmt::format("max TCP offset {:.4f} mm (bound {:g} mm)", window_dev_m_ * 1e3, setup_.limits.tcp_bound_m * 1e3);
    } else {
      invariants = fmt::format("max |command-nominal| {:.4f} deg (bound {:g} deg)", rad_to_deg(window_dev_rad_),
                               rad_to_deg(setup_.limits.joint_bound_rad));
      if (setup_.limits.form == CommandForm::kJointTarget) {
        invariants += fmt::format(", max |command-program| {:.4f} deg (the ramp-in blend included)",
                                  rad_to_deg(window_program_dev_rad_));
      }
    }
    const double span = now_s - interval_start_s_;
    line = fmt::format(
        "t={:.1f} s {} | now: {}{} | in the last {:.1f} s: {} cycles, {} answered, {}, largest step {:.0f}% of its "
        "limit, max answer time {:.2f} ms ({} late), max compute {:.0f} us, longest gap {:.1f} ms, missed {}, "
        "duplicates {}, superseded {}, rejected {}, restarts {}, guard trips {}",
        now_s, to_string(last_.state), now_part, program, span, window_cycles_, window_answers_, invariants,
        window_step_fraction_ * 100.0, window_answer_s_ * 1e3, window_late_, window_compute_s_ * 1e6,
        window_gap_s_ * 1e3, c.missed - w.missed, c.duplicate - w.duplicate, c.superseded - w.superseded,
        c.rejected() - w.rejected(), c.restarts - w.restarts, c.guard_trips - w.guard_trips);
  }
  at_window_start_ = c;
  interval_start_s_ = now_s;
  have_cycle_ = cycles_ > 0;
  window_cycles_ = window_answers_ = window_late_ = 0;
  window_compute_s_ = window_gap_s_ = window_dev_rad_ = window_dev_m_ = window_program_dev_rad_ = 0.0;
  window_step_fraction_ = window_answer_s_ = 0.0;
  return line;
}

std::string SessionReporter::timing_text() const {
  if (cycles_ == 0) return "no cycles";
  return fmt::format(
      "answer time p50 {:.3f} ms, p99 {:.3f} ms, max {:.3f} ms ({} of {} answers later than the {:g} ms cycle); "
      "compute p50 {:.0f} us, p99 {:.0f} us, max {:.0f} us; arrival delay p50 {:.2f} ms, p99 {:.2f} ms; largest gap "
      "{:.1f} ms",
      answer_ms_.quantile(0.5), answer_ms_.quantile(0.99), answer_ms_.max(), late_answers_, answers_,
      setup_.period_s * 1e3, compute_us_.quantile(0.5), compute_us_.quantile(0.99), compute_us_.max(),
      arrival_ms_.quantile(0.5), arrival_ms_.quantile(0.99), max_gap_s_ * 1e3);
}

nlohmann::json SessionReporter::timing_json() const {
  const auto number = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  const auto q = [&](const Histogram& h) {
    return nlohmann::json{{"p50", number(h.quantile(0.5))}, {"p99", number(h.quantile(0.99))}, {"max", h.max()}};
  };
  return {{"answer_ms", q(answer_ms_)},
          {"late_answers", late_answers_},
          {"compute_us", q(compute_us_)},
          {"arrival_delay_ms", q(arrival_ms_)},
          {"largest_gap_ms", max_gap_s_ * 1e3}};
}

nlohmann::json counters_json(const LinkCounters& c) {
  return {{"datagrams", c.datagrams},
          {"replies", c.replies},
          {"rejected", c.rejected()},
          {"malformed", c.malformed},
          {"truncated", c.truncated},
          {"oversized", c.oversized},
          {"empty", c.empty},
          {"missing_header", c.missing_header},
          {"missing_joints", c.missing_joints},
          {"missing_required", c.missing_required},
          {"non_finite", c.non_finite},
          {"duplicate", c.duplicate},
          {"out_of_order", c.out_of_order},
          {"far_ahead", c.far_ahead},
          {"sequence_out_of_range", c.sequence_out_of_range},
          {"out_of_limits", c.out_of_limits},
          {"foreign_sender", c.foreign_sender},
          {"foreign_document", c.foreign_document},
          {"superseded", c.superseded},
          {"restarts", c.restarts},
          {"missed", c.missed},
          {"late", c.late},
          {"controller_late", c.controller_late},
          {"silences", c.silences},
          {"clock_jumps", c.clock_jumps},
          {"longest_silence_s", c.longest_silence_s},
          {"invalid_cycles", c.invalid_cycles},
          {"guard_trips", c.guard_trips},
          {"step_limited", c.step_limited},
          {"refused", c.refused},
          {"not_running", c.not_running},
          {"send_errors", c.send_errors}};
}

}  // namespace deflex::runtime
