// Replays recorded force samples from CSV (`t_s,fx_N,fy_N,fz_N`, optional `mx_Nm,my_Nm,mz_Nm`,
// sensor frame), in real time from the first call or driven by a caller's clock (tests, simulation).
#pragma once

#include <chrono>
#include <string>
#include <vector>

#include "deflex/online/force_sample.hpp"

namespace deflex {

class CsvForceReplay final : public ForceSource {
 public:
  /// Loads the whole file (setup time). Throws DataError naming file:line on bad cells or on times
  /// that do not increase. `loop`: start again after the last sample.
  explicit CsvForceReplay(const std::string& csv_path, bool loop = false);

  /// Real-time mode (default): samples become due at (their t_s - first t_s) after the first call.
  bool latest(ForceSample& out) noexcept override;
  /// Manual clock: from now on, samples are due when (t_s - first t_s) <= elapsed_s.
  void advance_to(double elapsed_s) noexcept;

  [[nodiscard]] std::size_t size() const { return samples_.size(); }
  [[nodiscard]] const std::vector<ForceSample>& samples() const { return samples_; }
  [[nodiscard]] bool finished() const { return !loop_ && next_ >= samples_.size(); }
  /// Samples read and handed on (every one is: a file has no sequence to lose, and its invalid rows
  /// are refused when it is loaded).
  [[nodiscard]] ForceSourceStats stats() const noexcept override {
    ForceSourceStats s;
    s.received = s.accepted = served_;
    return s;
  }

 private:
  std::vector<ForceSample> samples_;
  bool loop_ = false;
  std::size_t next_ = 0;
  std::uint64_t served_ = 0;
  double duration_s_ = 0.0;
  double lap_offset_s_ = 0.0;
  bool manual_ = false;
  bool started_ = false;
  double elapsed_s_ = 0.0;
  std::chrono::steady_clock::time_point start_{};
};

}  // namespace deflex
