// What `deflex online` tells about its link (see online_report.hpp).
#include "online_report.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

namespace deflex::cli {

void Histogram::add(double v) {
  if (!std::isfinite(v)) return;
  const double slot = std::max(0.0, v / bin_);
  const auto i = std::min(counts_.size() - 1, static_cast<std::size_t>(slot));
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

void OnlineReport::on_cycle(const LinkCycleRecord& r) {
  ++cycles_;
  ++window_cycles_;
  compute_us_.add(r.compute_s * 1e6);
  arrival_ms_.add(r.arrival.arrival_delay_s * 1e3);
  if (last_t_s_ >= 0.0) {
    max_gap_s_ = std::max(max_gap_s_, r.t_s - last_t_s_);
    window_gap_s_ = std::max(window_gap_s_, r.t_s - last_t_s_);
  }
  last_t_s_ = r.t_s;
  window_compute_s_ = std::max(window_compute_s_, r.compute_s);
  window_arrival_s_ = std::max(window_arrival_s_, r.arrival.arrival_delay_s);
  if (r.replied) {
    ++window_answers_;
    window_dev_rad_ = std::max(window_dev_rad_, (r.q_command - r.q_nominal).cwiseAbs().maxCoeff());
  }
}

std::string OnlineReport::status_line(double now_s, double elapsed_s, const ControllerLink& link,
                                      const std::string& extra) {
  const LinkCounters& c = link.counters();
  const LinkCounters& w = at_window_start_;
  const LinkCycleRecord& r = link.last_cycle();
  const std::string line = fmt::format(
      "t={:.1f} s {} | now: status {}, |F| {:.1f} N, TCP correction {:.3f} mm, loop delay {:.1f} ms, jitter {:.2f} ms{}{}"
      " | in the last {:.1f} s: {} cycles, {} answered, max |command-nominal| {:.4f} deg, max compute {:.0f} us, max "
      "gap {:.1f} ms, max arrival delay {:.1f} ms, late {}, missed {}, duplicates {}, superseded {}, rejected {}, "
      "restarts {}",
      elapsed_s, to_string(link.state()), to_string(r.status), r.wrench_measured_base.head<3>().norm(),
      r.tcp_correction_m.norm() * 1e3, r.delay_s * 1e3, c.jitter_s * 1e3, extra.empty() ? "" : " | ", extra,
      now_s - interval_start_s_, window_cycles_, window_answers_, rad_to_deg(window_dev_rad_),
      window_compute_s_ * 1e6, window_gap_s_ * 1e3, window_arrival_s_ * 1e3, c.late - w.late, c.missed - w.missed,
      c.duplicate - w.duplicate, c.superseded - w.superseded, c.rejected() - w.rejected(), c.restarts - w.restarts);
  at_window_start_ = c;
  interval_start_s_ = now_s;
  window_cycles_ = window_answers_ = 0;
  window_compute_s_ = window_gap_s_ = window_dev_rad_ = window_arrival_s_ = 0.0;
  return line;
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
          {"invalid_cycles", c.invalid_cycles},
          {"guard_trips", c.guard_trips},
          {"refused", c.refused},
          {"send_errors", c.send_errors}};
}

nlohmann::json OnlineReport::json(const ControllerLink& link) const {
  const auto number = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  return {{"cycles", cycles_},
          {"counters", counters_json(link.counters())},
          {"timing",
           {{"compute_us", {{"p50", number(compute_us_.quantile(0.5))}, {"p99", number(compute_us_.quantile(0.99))},
                            {"max", compute_us_.max()}}},
            {"arrival_delay_ms",
             {{"p50", number(arrival_ms_.quantile(0.5))}, {"p99", number(arrival_ms_.quantile(0.99))},
              {"max", link.counters().max_arrival_delay_s * 1e3}}},
            {"jitter_ms", link.counters().jitter_s * 1e3},
            {"largest_gap_ms", max_gap_s_ * 1e3},
            {"loop_delay_ms", link.last_cycle().delay_s * 1e3}}}};
}

std::string OnlineReport::timing_text(const ControllerLink& link) const {
  const LinkCounters& c = link.counters();
  if (cycles_ == 0) return "no cycles";
  return fmt::format(
      "compute p50 {:.0f} us, p99 {:.0f} us, max {:.0f} us; arrival delay p50 {:.2f} ms, p99 {:.2f} ms, max {:.2f} "
      "ms; largest gap {:.1f} ms; jitter {:.2f} ms; missed {}, late {}, superseded {}",
      compute_us_.quantile(0.5), compute_us_.quantile(0.99), compute_us_.max(), arrival_ms_.quantile(0.5),
      arrival_ms_.quantile(0.99), c.max_arrival_delay_s * 1e3, max_gap_s_ * 1e3, c.jitter_s * 1e3, c.missed, c.late,
      c.superseded);
}

}  // namespace deflex::cli
