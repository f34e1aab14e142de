// CSV force replay (see csv_force_replay.hpp).
#include "deflex/sensors/detail/csv_force_replay.hpp"

#include <fmt/format.h>

#include "deflex/text/csv_table.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {

CsvForceReplay::CsvForceReplay(const std::string& csv_path, bool loop) : loop_(loop) {
  const CsvTable t = CsvTable::read_file(csv_path);
  t.require({"t_s", "fx_N", "fy_N", "fz_N"});
  t.allow_only({"t_s", "fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm"});
  const bool moments = t.has("mx_Nm") || t.has("my_Nm") || t.has("mz_Nm");
  if (moments) {
    t.require({"mx_Nm", "my_Nm", "mz_Nm"});
  }
  if (t.rows() == 0) {
    throw DataError(csv_path + ": no force samples");
  }
  samples_.reserve(t.rows());
  for (std::size_t r = 0; r < t.rows(); ++r) {
    ForceSample s;
    s.t_s = t.at(r, "t_s");
    s.wrench_sensor << t.at(r, "fx_N"), t.at(r, "fy_N"), t.at(r, "fz_N"), 0.0, 0.0, 0.0;
    if (moments) {
      s.wrench_sensor.tail<3>() << t.at(r, "mx_Nm"), t.at(r, "my_Nm"), t.at(r, "mz_Nm");
    }
    if (!samples_.empty() && !(s.t_s > samples_.back().t_s)) {
      t.fail(r, "t_s", fmt::format("time {} s does not increase (previous {} s)", s.t_s, samples_.back().t_s));
    }
    samples_.push_back(s);
  }
  // One sample period beyond the last sample, so a looped replay keeps its spacing.
  const double step = samples_.size() > 1
                          ? (samples_.back().t_s - samples_.front().t_s) / static_cast<double>(samples_.size() - 1)
                          : 0.001;
  duration_s_ = samples_.back().t_s - samples_.front().t_s + step;
}

void CsvForceReplay::advance_to(double elapsed_s) noexcept {
  manual_ = true;
  elapsed_s_ = elapsed_s;
}

bool CsvForceReplay::latest(ForceSample& out) noexcept {
  if (!manual_) {
    const auto now = std::chrono::steady_clock::now();
    if (!started_) {
      started_ = true;
      start_ = now;
    }
    elapsed_s_ = std::chrono::duration<double>(now - start_).count();
  }
  if (next_ >= samples_.size()) {
    if (!loop_) {
      return false;
    }
    next_ = 0;
    lap_offset_s_ += duration_s_;
  }
  const ForceSample& s = samples_[next_];
  const double due_s = s.t_s - samples_.front().t_s + lap_offset_s_;
  if (due_s > elapsed_s_) {
    return false;
  }
  out = s;
  out.t_s = s.t_s + lap_offset_s_;
  ++next_;
  ++served_;
  return true;
}

}  // namespace deflex
