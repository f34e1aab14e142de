// The toolpath job's one pass (see toolpath_job.hpp).
#include "deflex/offline/toolpath_job.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <optional>

#include <fmt/format.h>

#include "deflex/model/compliance.hpp"
#include "deflex/model/opw_ik.hpp"
#include "deflex/paths/pose_source.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

/// The wrench of the point being compensated, handed to PathCompensator as a force model.
class PointWrench final : public ForceModel {
 public:
  explicit PointWrench(std::string description) : description_(std::move(description)) {}
  [[nodiscard]] Wrench wrench_at(std::size_t /*index*/, const Pose& /*base_T_tcp*/) const override { return current; }
  [[nodiscard]] std::string describe() const override { return description_; }
  [[nodiscard]] std::string label() const override { return "milling"; }
  Wrench current = Wrench::Zero();

 private:
  std::string description_;
};

/// A point read, its force, waiting for its spin.
struct Pending {
  ToolpathPoint source;
  MillingPointForce force;
  Vector3 reference_x = Vector3::UnitX();  // workpiece frame
  double s_m = 0.0;                        // path length, workpiece frame
};

/// Every k-th sample, k doubling whenever twice the wanted count is held: bounded memory, even cover.
class ChartSampler {
 public:
  explicit ChartSampler(std::size_t wanted) : wanted_(wanted) {}
  void add(const ToolpathChartSample& s) {
    if (wanted_ == 0) return;
    if (count_++ % stride_ == 0) samples_.push_back(s);
    if (samples_.size() >= 2 * wanted_) {
      std::size_t k = 0;
      for (std::size_t i = 0; i < samples_.size(); i += 2) samples_[k++] = samples_[i];
      samples_.resize(k);
      stride_ *= 2;
    }
  }
  std::vector<ToolpathChartSample> take() { return std::move(samples_); }

 private:
  std::size_t wanted_, count_ = 0, stride_ = 1;
  std::vector<ToolpathChartSample> samples_;
};

// The G-code residual (what a position-only program leaves) is evaluated at every this many cutting points.
constexpr std::size_t kGcodeResidualEvery = 10;

double rotation_angle(const Matrix3& a, const Matrix3& b) { return Eigen::AngleAxisd(a.transpose() * b).angle(); }

class Job {
 public:
  Job(const RobotModel& model, ToolpathReader& reader, const MillingForceModel& force, Stock* stock,
      const ToolpathJobOptions& options, const ToolpathSinks& sinks)
      : model_(model),
        reader_(reader),
        force_(force),
        stock_(stock),
        o_(options),
        sinks_(sinks),
        process_(force, stock),
        planner_(model, options.spin, options.first),
        wrench_(force.describe()),
        compensator_(model, wrench_, options.compensation),
        ws_(model),
        chart_(options.chart_samples) {
    base_R_wp_ = o_.base_T_workpiece.linear();
  }

  ToolpathJobResult run();

 private:
  [[nodiscard]] std::string where(std::size_t line) const {
    return fmt::format("{}: line {}", reader_.summary().source, line);
  }
  void read_point(const ToolpathPoint& tp);
  void drain();
  void commit(const Pending& pd, double spin);
  void record(const Pending& pd, double spin, const OfflinePoint& pt);
  [[noreturn]] void explain_ik_failure(const Pending& pd, double spin, const std::string& reason);
  double gcode_residual(const OfflinePoint& pt);
  void check_cutter(const ToolpathPoint& tp);
  void finish_checks();

  const RobotModel& model_;
  ToolpathReader& reader_;
  const MillingForceModel& force_;
  Stock* stock_;
  const ToolpathJobOptions& o_;
  const ToolpathSinks& sinks_;
  MillingProcess process_;
  ToolSpinPlanner planner_;
  PointWrench wrench_;
  PathCompensator compensator_;
  std::optional<PathIkSolver> ik_;
  Workspace ws_;
  OpwSolutions solutions_;
  SpinReference reference_;
  Matrix3 base_R_wp_;
  std::deque<Pending> pending_;
  std::optional<Vector3> previous_tip_;
  double s_m_ = 0.0;
  std::size_t index_ = 0;
  std::optional<double> previous_spin_;
  double previous_s_ = 0.0;
  bool cutter_checked_ = false;
  double sum_cutting_ = 0.0, sum_gcode_ = 0.0;
  std::size_t cutting_points_ = 0, gcode_samples_ = 0;
  ChartSampler chart_;
  ToolpathJobResult r_;
};

void Job::check_cutter(const ToolpathPoint& tp) {
  cutter_checked_ = true;
  const auto& stated = reader_.summary().cutter;
  const Cutter& c = force_.cutter();
  if (stated && std::abs(stated->diameter_m - c.diameter_m) > 1e-6) {
    throw InputError(fmt::format("{}: the program's cutter is {:g} mm across, --cutter says {:g} mm",
                                 where(stated->line != 0 ? stated->line : tp.line), stated->diameter_m * 1e3,
                                 c.diameter_m * 1e3));
  }
}

void Job::read_point(const ToolpathPoint& tp) {
  if (!cutter_checked_) check_cutter(tp);
  MillingPointInput in;
  in.tip_m = tp.position_m;
  in.tool_axis = tp.tool_axis;
  in.feed_mm_min = tp.feed_m_s * 6e4;
  in.spindle_rpm = tp.spindle_rpm;
  if (tp.spindle != SpindleState::kOff) {
    in.turn = tp.spindle == SpindleState::kClockwise ? SpindleTurn::kClockwise : SpindleTurn::kCounterClockwise;
  }
  in.rapid = tp.motion == MotionKind::kRapid;
  in.tool = tp.tool;
  in.line = tp.line;
  Pending pd;
  pd.source = tp;
  try {
    pd.force = process_.next(in);
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: {}", reader_.summary().source, e.what()));
  }
  const double move = previous_tip_ ? (tp.position_m - *previous_tip_).norm() : 0.0;
  previous_tip_ = tp.position_m;
  s_m_ += move;
  pd.s_m = s_m_;
  pd.reference_x = reference_.next(tp.tool_axis);
  SpinPoint sp;
  sp.tip_m = o_.base_T_workpiece * tp.position_m;
  sp.tool_axis = base_R_wp_ * tp.tool_axis;
  sp.reference_x = base_R_wp_ * pd.reference_x;
  sp.wrench.head<3>() = base_R_wp_ * pd.force.wrench.head<3>();
  sp.wrench.tail<3>() = base_R_wp_ * pd.force.wrench.tail<3>();
  sp.cutting = pd.force.state == MillingPointState::kCut;
  sp.move_m = move;
  sp.line = tp.line;
  pending_.push_back(pd);
  try {
    planner_.push(sp);
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: {}", reader_.summary().source, e.what()));
  }
  drain();
}

void Job::drain() {
  double spin = 0.0;
  while (planner_.pop(spin)) {
    commit(pending_.front(), spin);
    pending_.pop_front();
  }
}

void Job::explain_ik_failure(const Pending& pd, double spin, const std::string& reason) {
  // Is the point out of reach whatever the spin, or only at the one chosen?
  int reachable = 0;
  const int n = 72;
  for (int k = 0; k < n; ++k) {
    Pose t = Pose::Identity();
    t.linear() = base_R_wp_ * tcp_rotation(pd.source.tool_axis, pd.reference_x, k * 2.0 * kPi / n);
    t.translation() = o_.base_T_workpiece * pd.source.position_m;
    if (inverse_kinematics(model_, ws_, t).ok()) ++reachable;
  }
  if (reachable == 0) {
    throw InputError(fmt::format("{}: the arm cannot reach this point at any spindle angle (every 5 deg): {}",
                                 where(pd.source.line), reason));
  }
  throw InputError(
      fmt::format("{}: at the spindle angle {:.1f} deg: {}", where(pd.source.line), rad_to_deg(spin), reason));
}

void Job::commit(const Pending& pd, double spin) {
  const ToolpathPoint& tp = pd.source;
  Pose pose = Pose::Identity();
  pose.linear() = base_R_wp_ * tcp_rotation(tp.tool_axis, pd.reference_x, spin);
  pose.translation() = o_.base_T_workpiece * tp.position_m;
  if (!ik_) ik_.emplace(model_, planner_.path_request(), o_.ik);
  const JointVector* q = nullptr;
  try {
    q = &ik_->next(pose);
  } catch (const InputError& e) {
    std::string reason = e.what();
    if (const auto colon = reason.find(": "); reason.rfind("path point", 0) == 0 && colon != std::string::npos) {
      reason = reason.substr(colon + 2);
    }
    explain_ik_failure(pd, spin, reason);
  }
  wrench_.current.head<3>() = base_R_wp_ * pd.force.wrench.head<3>();
  wrench_.current.tail<3>() = base_R_wp_ * pd.force.wrench.tail<3>();
  try {
    const OfflinePoint& pt = compensator_.compensate(index_, *q, pose);
    record(pd, spin, pt);
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: {}", where(tp.line), e.what()));
  }
  ++index_;
}

void Job::record(const Pending& pd, double spin, const OfflinePoint& pt) {
  const ToolpathPoint& tp = pd.source;
  const MillingPointForce& f = pd.force;
  const bool cutting = f.state == MillingPointState::kCut;
  const Vector3 tip_cmd = o_.base_T_workpiece.inverse() * pt.tcp_command.translation();
  const double deflection = pt.predicted_deflection.head<3>().norm();
  double gcode = 0.0;
  if (cutting) {
    ++cutting_points_;
    sum_cutting_ += deflection;
    r_.max_cutting_deflection_m = std::max(r_.max_cutting_deflection_m, deflection);
    r_.max_force_n = std::max(r_.max_force_n, f.wrench.head<3>().norm());
    r_.max_peak_force_n = std::max(r_.max_peak_force_n, f.peak_force_n);
    r_.tooth_passing_hz = std::max(r_.tooth_passing_hz, f.tooth_passing_hz);
    r_.cutting_length_m += pd.s_m - previous_s_;
  }
  if (sinks_.gcode != nullptr) {
    r_.max_orientation_correction_rad =
        std::max(r_.max_orientation_correction_rad, rotation_angle(pt.tcp_desired.linear(), pt.tcp_command.linear()));
    // Every tenth cutting point: an IK and a deflection solve each (some 3 us), for a figure that
    // changes slowly along the path.
    if (cutting && o_.compensation.predict && (cutting_points_ - 1) % kGcodeResidualEvery == 0) {
      gcode = gcode_residual(pt);
      sum_gcode_ += gcode;
      ++gcode_samples_;
      r_.max_gcode_residual_m = std::max(r_.max_gcode_residual_m, gcode);
    }
    sinks_.gcode->add(tp, tip_cmd);
  }
  if (index_ == 0) r_.spin_min_rad = r_.spin_max_rad = spin;
  r_.spin_min_rad = std::min(r_.spin_min_rad, spin);
  r_.spin_max_rad = std::max(r_.spin_max_rad, spin);
  if (previous_spin_ && tp.motion != MotionKind::kRapid && pd.s_m - previous_s_ > 1e-9) {
    r_.max_spin_rate_rad_per_m =
        std::max(r_.max_spin_rate_rad_per_m,
                 std::abs(std::remainder(spin - *previous_spin_, 2.0 * kPi)) / (pd.s_m - previous_s_));
  }
  previous_spin_ = spin;
  previous_s_ = pd.s_m;
  if (sinks_.csv != nullptr) {
    const double extra[] = {static_cast<double>(tp.line),
                            cutting ? 1.0 : 0.0,
                            tp.feed_m_s * 6e4,
                            tp.spindle_rpm,
                            f.ae_m * 1e3,
                            f.ap_m * 1e3,
                            rad_to_deg(spin),
                            f.peak_force_n,
                            f.tooth_passing_hz,
                            tip_cmd.x() * 1e3,
                            tip_cmd.y() * 1e3,
                            tip_cmd.z() * 1e3};
    sinks_.csv->write(index_, pt, extra);
  }
  if (sinks_.program != nullptr) sinks_.program->add(tp, pt);
  if (sinks_.keep != nullptr) {
    check_held_path_points(sinks_.keep->size());
    sinks_.keep->push_back({tp, f, spin, pt, tip_cmd});
  }
  chart_.add({pd.s_m, f.wrench.head<3>().norm(), f.peak_force_n, deflection, pt.predicted_residual.head<3>().norm(),
              gcode, spin});
}

/// The tip's residual when a position-only program is run: the compensated position at the desired
/// orientation (spin included), solved in the path's configuration, deflected under the same wrench.
double Job::gcode_residual(const OfflinePoint& pt) {
  Pose target = pt.tcp_desired;
  target.translation() = pt.tcp_command.translation();
  JointVector q = pt.q_command;
  if (model_.opw() != nullptr) {
    opw_solutions(model_, target, &pt.q_command, solutions_);
    double best = std::numeric_limits<double>::infinity();
    for (int k = 0; k < solutions_.count; ++k) {
      const OpwSolution& s = solutions_.solution[static_cast<std::size_t>(k)];
      const double step = (s.q - pt.q_command).cwiseAbs().maxCoeff();
      if (step < best) {
        best = step;
        q = s.q;
      }
    }
  } else {
    IkRequest request;
    request.seed = pt.q_command;
    const IkResult r = inverse_kinematics(model_, ws_, target, request);
    if (r.ok()) q = r.q;
  }
  JointVector q_actual(model_.dof());
  const JointVector start = q + (pt.q_desired - pt.q_command);
  if (deflected_configuration_from(model_, ws_, q, pt.wrench_base, start, q_actual) != DeflectionStatus::kConverged) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  return (tcp_pose(model_, ws_, q_actual).translation() - pt.tcp_desired.translation()).norm();
}

void Job::finish_checks() {
  const std::string& source = reader_.summary().source;
  if (stock_ != nullptr && process_.removed_volume_m3() <= 0.0) {
    throw InputError(fmt::format(
        "{}: the tool never touches the stock ({}): nothing is cut, so there is no force to compensate; check --stock "
        "against the program's workpiece frame",
        source, stock_->describe()));
  }
  if (process_.counts().cut == 0) {
    throw InputError(
        fmt::format("{}: no point of the program cuts (every move is a rapid, a plunge or in the air)", source));
  }
}

ToolpathJobResult Job::run() {
  ToolpathPoint tp;
  while (reader_.next(tp)) read_point(tp);
  try {
    planner_.finish();
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: {}", reader_.summary().source, e.what()));
  }
  drain();
  finish_checks();
  r_.summary = compensator_.summary();
  r_.toolpath = reader_.summary();
  r_.counts = process_.counts();
  r_.removed_volume_m3 = process_.removed_volume_m3();
  r_.points = index_;
  r_.mean_cutting_deflection_m = cutting_points_ > 0 ? sum_cutting_ / static_cast<double>(cutting_points_) : 0.0;
  r_.mean_gcode_residual_m = gcode_samples_ > 0 ? sum_gcode_ / static_cast<double>(gcode_samples_) : 0.0;
  r_.path_length_m = s_m_;
  r_.spin = planner_.stats();
  r_.configuration = ik_ ? ik_->configuration() : ArmConfiguration{};
  r_.chart = chart_.take();
  return r_;
}

}  // namespace

std::vector<std::string> toolpath_csv_columns() {
  return {"line",          "cutting",      "feed_mm_min",      "spindle_rpm", "ae_mm",       "ap_mm",
          "tool_spin_deg", "peak_force_N", "tooth_passing_Hz", "x_cmd_wp_mm", "y_cmd_wp_mm", "z_cmd_wp_mm"};
}

ToolpathJobResult run_toolpath_job(const RobotModel& model, ToolpathReader& reader, const MillingForceModel& force,
                                   Stock* stock, const ToolpathJobOptions& options, const ToolpathSinks& sinks) {
  Job job(model, reader, force, stock, options, sinks);
  return job.run();
}

std::string toolpath_summary_text(const ToolpathJobResult& r, bool gcode) {
  const MillingRunCounts& c = r.counts;
  std::string s = fmt::format(
      "toolpath: {} points ({} cutting, {} in the air, {} plunges, {} rapids), path {:.1f} mm of which {:.1f} mm "
      "cutting\n",
      r.points, c.cut, c.in_air, c.plunges, c.rapids, r.path_length_m * 1e3, r.cutting_length_m * 1e3);
  if (r.removed_volume_m3 > 0.0) s += fmt::format("stock removed: {:.1f} mm^3\n", r.removed_volume_m3 * 1e9);
  if (c.rapids_through_stock > 0) {
    s += fmt::format("warning: {} positioning moves cut the stock (a collision), the first at line {}\n",
                     c.rapids_through_stock, c.first_rapid_through_stock_line);
  }
  s += fmt::format(
      "cutting force (average over a revolution): max {:.1f} N; per-revolution peak max {:.1f} N at {:.0f} Hz "
      "(tooth passing)\n",
      r.max_force_n, r.max_peak_force_n, r.tooth_passing_hz);
  s +=
      fmt::format("spindle angle: {:.1f}..{:.1f} deg, at most {:.3f} deg per mm along feed moves\n",
                  rad_to_deg(r.spin_min_rad), rad_to_deg(r.spin_max_rad), rad_to_deg(r.max_spin_rate_rad_per_m) * 1e-3);
  if (r.spin.margin_violations > 0) {
    s += fmt::format(
        "note: the fixed spindle angle comes within the joint-limit margin or the singularity floor at {} stages, "
        "the first at line {}\n",
        r.spin.margin_violations, r.spin.first_margin_violation_line);
  }
  s += fmt::format(
      "predicted deflection over the cutting points: mean {:.4f} mm, max {:.4f} mm; residual after compensation: "
      "max {:.2e} mm\n",
      r.mean_cutting_deflection_m * 1e3, r.max_cutting_deflection_m * 1e3, r.summary.max_residual_m * 1e3);
  s += fmt::format("largest correction: {:.4f} mm, {:.5f} deg of a joint\n", r.summary.max_correction_m * 1e3,
                   rad_to_deg(r.summary.max_joint_correction_rad));
  if (gcode) {
    s += fmt::format(
        "G-code carries positions only: the orientation part of the correction (max {:.4f} mrad) and the spindle "
        "angle are left to the controller; run so, the tip's residual is mean {:.2g} mm, max {:.2g} mm\n",
        r.max_orientation_correction_rad * 1e3, r.mean_gcode_residual_m * 1e3, r.max_gcode_residual_m * 1e3);
  }
  return s;
}

}  // namespace deflex
