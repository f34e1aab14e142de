// The offline job's one pass (see offline_job.hpp).
#include "deflex/offline/offline_job.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "deflex/force/ldbb_force_model.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

/// One load's state during the pass.
struct JobLoad {
  const OfflineLoad* load = nullptr;
  std::unique_ptr<PathCompensator> compensator;
  const LdbbForceModel* ldbb = nullptr;
  std::vector<OfflinePoint> points;
  std::optional<BarRange> bar;
};

void widen_bar(JobLoad& l, const Pose& pose) {
  const double length = l.ldbb->bar_length_m(pose), inclination = l.ldbb->inclination_rad(pose);
  if (!l.bar) {
    l.bar = BarRange{length, length, inclination, inclination};
    return;
  }
  l.bar->length_min_m = std::min(l.bar->length_min_m, length);
  l.bar->length_max_m = std::max(l.bar->length_max_m, length);
  l.bar->inclination_min_rad = std::min(l.bar->inclination_min_rad, inclination);
  l.bar->inclination_max_rad = std::max(l.bar->inclination_max_rad, inclination);
}

std::vector<JobLoad> job_loads(const RobotModel& model, const std::vector<OfflineLoad>& loads,
                               const OfflineOptions& compensation) {
  if (loads.empty()) throw InputError("offline: no load to compensate for");
  std::vector<JobLoad> out(loads.size());
  for (std::size_t k = 0; k < loads.size(); ++k) {
    if (loads[k].force == nullptr) throw InputError(fmt::format("offline: load {} has no force model", k + 1));
    out[k].load = &loads[k];
    out[k].compensator = std::make_unique<PathCompensator>(model, *loads[k].force, compensation);
    out[k].ldbb = dynamic_cast<const LdbbForceModel*>(loads[k].force);
  }
  return out;
}

}  // namespace

OfflineJobResult run_offline_job(const RobotModel& model, PoseSource& source, const std::vector<OfflineLoad>& loads,
                                 const OfflineJobOptions& options) {
  std::vector<JobLoad> job = job_loads(model, loads, options.compensation);
  // A path whose length is known up front (sampled, or held) is checked against each force table
  // before any point is solved; a streamed file is checked as it goes (PathCompensator).
  if (const auto n = source.size()) {
    for (const OfflineLoad& l : loads) {
      if (const auto force_points = l.force->points(); force_points && *force_points != *n) {
        throw InputError(fmt::format("offline compensation: the force model ({}) has {} points, the path {}",
                                     l.force->describe(), *force_points, *n));
      }
    }
  }
  const bool holds = options.keep_nominal ||
                     std::any_of(loads.begin(), loads.end(), [](const OfflineLoad& l) { return l.keep_points; });
  PathIkSolver ik(model, options.first);
  OfflineJobResult result;
  Pose pose;
  std::size_t i = 0;
  for (; source.next(pose); ++i) {
    const JointVector& q = ik.next(pose);
    if (holds) check_held_path_points(i);
    if (options.keep_nominal) {
      result.poses.push_back(pose);
      result.q_nominal.push_back(q);
    }
    for (JobLoad& l : job) {
      const OfflinePoint& pt = l.compensator->compensate(i, q, pose);
      if (l.load->csv != nullptr) l.load->csv->write(i, pt);
      if (l.load->keep_points) l.points.push_back(pt);
      if (l.ldbb != nullptr) widen_bar(l, pose);
    }
  }
  if (i == 0) throw InputError("path: no points");
  for (JobLoad& l : job) {
    result.loads.push_back(l.compensator->summary());  // a force table longer than the path fails here
    result.loads.back().points = std::move(l.points);
    result.bars.push_back(l.bar);
    if (l.load->csv != nullptr) l.load->csv->finish();
  }
  result.configuration = ik.configuration();
  result.points = i;
  return result;
}

std::vector<std::string> offline_load_labels(const std::vector<const ForceModel*>& forces) {
  std::vector<std::string> labels;
  for (std::size_t k = 0; k < forces.size(); ++k) {
    std::string label;
    for (const char c : forces[k]->label()) label += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
    // fmt rather than "_" + std::to_string(): GCC 12 warns falsely (-Wrestrict) on that inlined concatenation.
    if (std::find(labels.begin(), labels.end(), label) != labels.end()) label += fmt::format("_{}", k + 1);
    labels.push_back(label);
  }
  return labels;
}

std::string path_with_label(const std::string& path, const std::string& label) {
  const auto slash = path.find_last_of('/');
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return path + "_" + label;
  return path.substr(0, dot) + "_" + label + path.substr(dot);
}

RapidMotion parse_rapid_motion(const std::string& text, const std::string& what) {
  if (text == "absj") return RapidMotion::kMoveAbsJ;
  if (text == "movel") return RapidMotion::kMoveL;
  throw InputError(fmt::format("{}: '{}' is neither absj nor movel", what, text));
}

void check_trajectory_speed(double speed_mm_s, const std::string& what) {
  if (!std::isfinite(speed_mm_s) || !(speed_mm_s > 0.0) || speed_mm_s > 10000.0) {
    throw InputError(fmt::format("{}: must be a positive TCP speed up to 10000 mm/s (got {})", what, speed_mm_s));
  }
}

}  // namespace deflex
