// The milling force along a toolpath, point by point with the stock.
#include "deflex/machining/milling_force_model.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

// The peak is that of the engagement's one-arc summary (first entry to last exit over the whole band
// of heights: a patchwork engagement's peak costs a sampled integral over every patch, some 40 us),
// sampled again only when its entry or exit moves by more than a degree, its band or the feed per
// tooth by more than 2 %: a steady cut keeps its peak, and the peak stays off the per-point budget.
constexpr double kPeakAngleTolRad = 1.0 * kPi / 180.0;
constexpr double kPeakRelativeTol = 0.02;

bool close_relative(double a, double b) {
  return std::abs(a - b) <= kPeakRelativeTol * std::max(std::abs(a), std::abs(b));
}

[[noreturn]] void fail_tilted_axis(const MillingPointInput& in) {
  const double tilt = std::acos(std::clamp(in.tool_axis.z(), -1.0, 1.0));
  throw InputError(fmt::format(
      "line {}: the tool axis is tilted {:.2f} deg from the stock's +z: the stock models follow 3-axis cuts only; "
      "give ae_mm= and ap_mm= in --force milling:... and leave out --stock",
      in.line, rad_to_deg(tilt)));
}

}  // namespace

MillingForceModel::MillingForceModel(MillingSpec spec, const Cutter& cutter) : spec_(std::move(spec)), cutter_(cutter) {
  validate_cutter(cutter_, "cutter");
  check_overrides(spec_, cutter_);
}

Wrench MillingForceModel::wrench_at(std::size_t index, const Pose& /*base_T_tcp*/) const {
  throw InputError(
      fmt::format("path point {}: the milling force needs a toolpath (its feed, spindle and engagement): use it with "
                  "--toolpath",
                  index));
}

std::string MillingForceModel::describe() const {
  const CuttingCoefficients& k = spec_.coefficients.k;
  std::string s = fmt::format("milling, cutter {}, Ktc {:g} Krc {:g} Kac {:g} N/mm^2, Kte {:g} Kre {:g} Kae {:g} N/mm",
                              describe_cutter(cutter_), k.ktc_n_m2 * 1e-6, k.krc_n_m2 * 1e-6, k.kac_n_m2 * 1e-6,
                              k.kte_n_m * 1e-3, k.kre_n_m * 1e-3, k.kae_n_m * 1e-3);
  if (!spec_.coefficients.material.empty()) s += fmt::format(" ({})", spec_.coefficients.material);
  if (spec_.ae_m) {
    s += fmt::format(", ae {:g} mm ({})", *spec_.ae_m * 1e3,
                     spec_.cut == OverrideCut::kClimb ? "climb" : "conventional");
  }
  if (spec_.ap_m) s += fmt::format(", ap {:g} mm", *spec_.ap_m * 1e3);
  s += "; the average over a revolution, on the tool, moment about the tool tip";
  return s;
}

MillingProcess::MillingProcess(const MillingForceModel& model, Stock* stock) : model_(model), stock_(stock) {
  if (stock == nullptr && !model.has_full_override()) {
    throw InputError(
        "milling force: give a stock (--stock box:...) for the engagement, or both ae_mm= and ap_mm= in the force "
        "spec");
  }
}

void MillingProcess::remove(const MillingPointInput& in) {
  if (stock_ == nullptr || !previous_) return;
  const StockStatus s = stock_->remove_swept(model_.cutter(), *previous_, in.tip_m, in.tool_axis);
  if (s == StockStatus::kUnsupportedAxis) fail_tilted_axis(in);
  if (in.rapid && s == StockStatus::kCut) {
    if (counts_.rapids_through_stock++ == 0) counts_.first_rapid_through_stock_line = in.line;
  }
}

/// The engagement at the point: the stock's, with the overrides in place of its width or depth, or
/// the overrides alone. False when the cutter is in the air.
bool MillingProcess::engage(const MillingPointInput& in, Engagement& e) {
  const MillingSpec& spec = model_.spec();
  const Cutter& cutter = model_.cutter();
  if (stock_ == nullptr) {
    e = uniform_engagement(*spec.ae_m, *spec.ap_m, cutter.diameter_m,
                           spec.cut == OverrideCut::kClimb ? CutSide::kClimb : CutSide::kConventional);
    return true;
  }
  const StockStatus s = stock_->engagement(cutter, out_.frame, in.tip_m, *in.turn, e);
  if (s == StockStatus::kUnsupportedAxis) fail_tilted_axis(in);
  if (s != StockStatus::kCut) return false;
  if (spec.ae_m || spec.ap_m) {
    // The stock says that the tool cuts and on which side; the overrides say how much.
    const CutSide side =
        e.exit_rad > kPi - 1e-9 || e.entry_rad + e.exit_rad > kPi ? CutSide::kClimb : CutSide::kConventional;
    e = uniform_engagement(spec.ae_m.value_or(e.ae_m), spec.ap_m.value_or(e.ap_m), cutter.diameter_m, side);
  }
  return true;
}

void MillingProcess::update_peak(const MillingCut& cut, const Engagement& e) {
  EngagementPatch band{e.entry_rad, e.exit_rad, HUGE_VAL, -HUGE_VAL};
  for (int k = 0; k < e.count; ++k) {
    band.z_lo_m = std::min(band.z_lo_m, e.patches[static_cast<std::size_t>(k)].z_lo_m);
    band.z_hi_m = std::max(band.z_hi_m, e.patches[static_cast<std::size_t>(k)].z_hi_m);
  }
  const EngagementPatch& p = peak_band_;
  const bool same = peak_fz_m_ > 0.0 && std::abs(p.entry_rad - band.entry_rad) <= kPeakAngleTolRad &&
                    std::abs(p.exit_rad - band.exit_rad) <= kPeakAngleTolRad && close_relative(p.z_lo_m, band.z_lo_m) &&
                    close_relative(p.z_hi_m, band.z_hi_m) && close_relative(peak_fz_m_, cut.fz_m);
  if (!same) {
    Engagement one;
    one.add(band);
    one.summarise(cut.cutter.radius_m());
    peak_n_ = peak_milling_force(cut, one).peak_force_n;
    peak_band_ = band;
    peak_fz_m_ = cut.fz_m;
  }
  out_.peak_force_n = peak_n_;
}

const MillingPointForce& MillingProcess::next(const MillingPointInput& in) {
  const Cutter& cutter = model_.cutter();
  out_ = MillingPointForce{};
  if (!previous_) {
    previous_ = in.tip_m;
    return out_;
  }
  if (in.rapid) {
    out_.state = MillingPointState::kRapid;
    ++counts_.rapids;
    remove(in);
    previous_ = in.tip_m;
    return out_;
  }
  const Vector3 move = in.tip_m - *previous_;
  if (!make_cut_frame(in.tool_axis, move, out_.frame) || out_.frame.in_plane_fraction < kMinInPlaneFraction) {
    out_.state = MillingPointState::kPlunge;
    ++counts_.plunges;
    remove(in);
    previous_ = in.tip_m;
    return out_;
  }
  if (!in.turn) {
    throw InputError(fmt::format("line {}: a feed move with the spindle off", in.line));
  }
  if (!engage(in, engagement_)) {
    out_.state = MillingPointState::kInAir;
    ++counts_.in_air;
    remove(in);
    previous_ = in.tip_m;
    return out_;
  }
  if (tool_ && *tool_ != in.tool) {
    throw InputError(fmt::format(
        "line {}: tool {} cuts, after tool {}: one --cutter describes one tool; compensate each tool's part of the "
        "program on its own",
        in.line, in.tool, *tool_));
  }
  tool_ = in.tool;
  MillingCut cut;
  cut.cutter = cutter;
  cut.k = model_.spec().coefficients.k;
  cut.turn = *in.turn;
  try {
    cut.fz_m = feed_per_tooth_m(in.feed_mm_min, in.spindle_rpm, cutter.flutes) * out_.frame.in_plane_fraction;
  } catch (const InputError& e) {
    throw InputError(fmt::format("line {}: {}", in.line, e.what()));
  }
  const MillingForce f = average_milling_force(cut, engagement_);
  out_.state = MillingPointState::kCut;
  ++counts_.cut;
  out_.wrench = milling_wrench(f, out_.frame, 0.0);
  out_.ae_m = engagement_.ae_m;
  out_.ap_m = engagement_.ap_m;
  out_.fz_m = cut.fz_m;
  out_.tooth_passing_hz = tooth_passing_frequency_hz(in.spindle_rpm, cutter.flutes);
  update_peak(cut, engagement_);
  remove(in);
  previous_ = in.tip_m;
  return out_;
}

ProcessForceSpecs milling_force_specs(const Cutter& cutter) {
  return [cutter](const std::string& spec) {
    std::vector<std::unique_ptr<ForceModel>> models;
    MillingSpec milling = parse_milling_spec(spec);
    try {
      models.push_back(std::make_unique<MillingForceModel>(std::move(milling), cutter));
    } catch (const InputError& e) {
      throw InputError(fmt::format("force spec '{}': {}", spec, e.what()));
    }
    return models;
  };
}

}  // namespace deflex
