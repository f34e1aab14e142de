// The cell's milling cut as a process force (see milling_process.hpp).
#include "deflex/cell/milling_process.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include <fmt/format.h>
#include <boost/random/normal_distribution.hpp>

#include "deflex/machining/milling_force.hpp"
#include "deflex/machining/zmap_stock.hpp"
#include "deflex/text/errors.hpp"

namespace deflex::cell {
namespace {

// A runout beyond this is a bent tool or a dirty collet, not a runout a cut is planned with.
constexpr double kMaxRunoutM = 1e-3;

}  // namespace

CuttingCoefficients draw_true_coefficients(const CuttingCoefficients& published, double relative_sigma,
                                           std::uint64_t seed) {
  if (!std::isfinite(relative_sigma) || relative_sigma < 0.0 || relative_sigma > 1.0) {
    throw InputError(fmt::format("coefficient spread: {} is outside 0..1 (a relative 1-sigma)", relative_sigma));
  }
  std::mt19937_64 rng(seed);
  boost::random::normal_distribution<double> normal(0.0, 1.0);
  CuttingCoefficients k = published;
  for (double* c : {&k.ktc_n_m2, &k.krc_n_m2, &k.kac_n_m2, &k.kte_n_m, &k.kre_n_m, &k.kae_n_m}) {
    *c *= std::exp(relative_sigma * normal(rng));
  }
  return k;
}

MillingProcess::MillingProcess(const MillingProcessConfig& config, Stock& stock)
    : config_(config), envelope_(config.cutter), stock_(stock) {
  validate_cutter(config.cutter, "milling process: cutter");
  validate_coefficients(config.k, "milling process: true coefficients");
  if (!std::isfinite(config.spindle_rpm) || !(config.spindle_rpm > 0.0)) {
    throw InputError(fmt::format("milling process: spindle_rpm: {} is not a positive speed", config.spindle_rpm));
  }
  if (!std::isfinite(config.runout_m) || config.runout_m < 0.0 || config.runout_m > kMaxRunoutM) {
    throw InputError(fmt::format("milling process: runout: {} mm is outside 0..1 mm", config.runout_m * 1e3));
  }
  if (!config.tool_axis_tcp.allFinite() || !(config.tool_axis_tcp.norm() > 0.5)) {
    throw InputError("milling process: tool_axis_tcp: not a unit vector");
  }
  config_.tool_axis_tcp.normalize();
  envelope_.diameter_m += 2.0 * config.runout_m;
  stock_T_base_ = config.base_T_stock.inverse();
  stock_R_base_ = stock_T_base_.linear();
}

void MillingProcess::advance(double dt_s) { dt_s_ = dt_s; }

Vector3 MillingProcess::feed_velocity(const Vector3& tip, const TcpMotion& motion) const {
  // The chips of a revolution are what the tool's motion over that revolution leaves for its teeth,
  // so the feed (its direction, and the feed per tooth) is the tool's mean velocity over the last
  // revolution: 5 ticks at 12 000 rpm and 1 kHz; one tick when a revolution is shorter, 64 at most.
  // The tick's own velocity would turn the cut frame with each trial of the coupled solve and with
  // each micrometre the tool yields, a force a revolution does not see.
  if (history_count_ == 0 || !(dt_s_ > 0.0)) return stock_R_base_ * motion.velocity_m_s;
  const double revolution_ticks = 60.0 / (config_.spindle_rpm * dt_s_);
  const int back = revolution_ticks >= history_count_ ? history_count_
                                                      : std::max(1, static_cast<int>(std::lround(revolution_ticks)));
  const std::size_t i = static_cast<std::size_t>((history_next_ + kHistory - back) % kHistory);
  return (tip - history_[i]) / (back * dt_s_);
}

Vector3 MillingProcess::tip_in_stock(const TcpMotion& motion, bool& tilted) const {
  const Vector3 axis = stock_R_base_ * (motion.orientation * config_.tool_axis_tcp);
  tilted = axis.z() < std::cos(ZMapStock::kMaxTiltRad);
  return stock_T_base_ * motion.position_m;
}

Wrench MillingProcess::cut_at(const TcpMotion& motion, MillingTickRecord& record) const {
  record = MillingTickRecord{};
  bool tilted = false;
  const Vector3 tip = tip_in_stock(motion, tilted);
  // The 3-axis stock's z is the axis of the cut (a deflected arm tilts the tool by hundredths of a
  // degree, which moves the edge by the depth times the tilt: under a micrometre at 5 mm).
  const Vector3 velocity = feed_velocity(tip, motion);
  CutFrame frame;
  if (!make_cut_frame(Vector3::UnitZ(), velocity, frame)) return Wrench::Zero();
  Engagement engagement;
  if (stock_.engagement(envelope_, frame, tip, config_.turn, engagement) != StockStatus::kCut) return Wrench::Zero();
  MillingCut cut;
  cut.cutter = envelope_;
  cut.k = config_.k;
  cut.turn = config_.turn;
  // The true feed per tooth: the tool's true speed in the plane of the cut, the arm's yield included.
  const double in_plane_speed = velocity.head<2>().norm();
  cut.fz_m = in_plane_speed * 60.0 / (config_.spindle_rpm * config_.cutter.flutes);
  const Wrench w_stock = milling_wrench(average_milling_force(cut, engagement), frame, 0.0);
  const Matrix3 base_R_stock = config_.base_T_stock.linear();
  Wrench w;
  w.head<3>() = base_R_stock * w_stock.head<3>();
  w.tail<3>() = base_R_stock * w_stock.tail<3>();
  record.engaged = true;
  record.wrench_base = w;
  record.ae_m = engagement.ae_m;
  record.ap_m = engagement.ap_m;
  record.fz_m = cut.fz_m;
  return w;
}

Wrench MillingProcess::wrench_at(const TcpMotion& motion) const {
  MillingTickRecord scratch;
  return cut_at(motion, scratch);
}

void MillingProcess::commit(const TcpMotion& motion) {
  (void)cut_at(motion, last_);
  bool tilted = false;
  const Vector3 tip = tip_in_stock(motion, tilted);
  if (tilted) ++tilted_ticks_;
  // The engagement above was the tick's end position's, before the move that led there is removed
  // (stock.hpp: the teeth cut on the front half, which the move has not swept yet).
  if (history_count_ > 0) {
    const std::size_t last = static_cast<std::size_t>((history_next_ + kHistory - 1) % kHistory);
    (void)stock_.remove_swept(envelope_, history_[last], tip, Vector3::UnitZ());
  }
  history_[static_cast<std::size_t>(history_next_)] = tip;
  history_next_ = (history_next_ + 1) % kHistory;
  history_count_ = std::min(history_count_ + 1, kHistory);
}

}  // namespace deflex::cell
