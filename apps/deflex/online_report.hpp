// What `deflex online` tells about its link, outside the cycle: a status line in which every field has
// one meaning (the figures "now" are the last cycle's, the figures "in the last N s" are maxima or
// counts over that interval and say so), and the final summary as text and as a JSON document. Fed
// with each handled cycle's record; the distributions are fixed histograms, so a long run does not
// grow memory.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "deflex/link/controller_link.hpp"

namespace deflex::cli {

/// Quantiles from a fixed histogram of `bins` bins of width `bin` (values beyond fall in the last).
class Histogram {
 public:
  Histogram(double bin, std::size_t bins) : bin_(bin), counts_(bins, 0) {}
  void add(double v);
  /// The value below which a fraction q of the samples lie (to a bin); NaN when empty.
  [[nodiscard]] double quantile(double q) const;
  [[nodiscard]] double max() const { return max_; }
  [[nodiscard]] std::uint64_t count() const { return n_; }

 private:
  double bin_;
  std::vector<std::uint64_t> counts_;
  std::uint64_t n_ = 0;
  double max_ = 0.0;
};

class OnlineReport {
 public:
  explicit OnlineReport(double start_s) : interval_start_s_(start_s) {}

  /// A cycle the link handled (answered or not).
  void on_cycle(const LinkCycleRecord& r);
  /// The status line (and a new interval begins). `extra`: the link's own part (may be empty).
  std::string status_line(double now_s, double elapsed_s, const ControllerLink& link, const std::string& extra);
  /// The counters and timing, as the final summary's JSON (`counters`, `timing` ...).
  [[nodiscard]] nlohmann::json json(const ControllerLink& link) const;
  /// The final summary's timing sentence.
  [[nodiscard]] std::string timing_text(const ControllerLink& link) const;
  [[nodiscard]] std::uint64_t cycles() const { return cycles_; }

 private:
  // Totals.
  std::uint64_t cycles_ = 0;
  Histogram compute_us_{1.0, 20000};          // 1 us bins to 20 ms
  Histogram arrival_ms_{0.01, 20000};         // 10 us bins to 200 ms
  double max_gap_s_ = 0.0, last_t_s_ = -1.0;
  // The interval since the last status line.
  double interval_start_s_;
  std::uint64_t window_cycles_ = 0, window_answers_ = 0;
  double window_compute_s_ = 0.0, window_gap_s_ = 0.0, window_dev_rad_ = 0.0, window_arrival_s_ = 0.0;
  LinkCounters at_window_start_;
};

/// Every counter of `c` by name, for JSON.
[[nodiscard]] nlohmann::json counters_json(const LinkCounters& c);

}  // namespace deflex::cli
