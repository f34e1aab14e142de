// The slot-cut fit and the force logs it reads.
#include "deflex/machining/coefficient_fit.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "deflex/text/csv_table.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

struct LineFit {
  double slope = 0.0, intercept = 0.0;  // b1, b2 of F = b1 x1 + b2 x2
  double se_slope = kNaN, se_intercept = kNaN;
  double rms = 0.0;
};

/// F_i = b1 x1_i + b2 x2_i by least squares, standard errors from the residuals (n - 2 degrees of
/// freedom).
LineFit fit_line(const std::vector<double>& x1, const std::vector<double>& x2, const std::vector<double>& y) {
  Eigen::Matrix2d a = Eigen::Matrix2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  for (std::size_t i = 0; i < y.size(); ++i) {
    const Eigen::Vector2d x(x1[i], x2[i]);
    a += x * x.transpose();
    b += x * y[i];
  }
  const Eigen::Matrix2d inv = a.inverse();
  const Eigen::Vector2d beta = inv * b;
  double rss = 0.0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    const double r = y[i] - beta[0] * x1[i] - beta[1] * x2[i];
    rss += r * r;
  }
  LineFit f;
  f.slope = beta[0];
  f.intercept = beta[1];
  f.rms = std::sqrt(rss / static_cast<double>(y.size()));
  if (y.size() > 2) {
    const double s2 = rss / static_cast<double>(y.size() - 2);
    f.se_slope = std::sqrt(s2 * inv(0, 0));
    f.se_intercept = std::sqrt(s2 * inv(1, 1));
  }
  return f;
}

void check_cut(const SlotCut& c) {
  const std::string name = c.label.empty() ? std::string("a slot cut") : c.label;
  if (!std::isfinite(c.fz_m) || !(c.fz_m > 0.0)) {
    throw InputError(
        fmt::format("{}: feed per tooth {:g} mm: the cut needs a positive feed and spindle speed", name, c.fz_m * 1e3));
  }
  if (!std::isfinite(c.ap_m) || !(c.ap_m > 0.0)) {
    throw InputError(fmt::format("{}: ap_mm: {:g} mm is not a positive depth", name, c.ap_m * 1e3));
  }
  if (c.flutes < 1) throw InputError(fmt::format("{}: the cutter has no flutes", name));
  if (!c.mean_force_n.allFinite()) throw InputError(fmt::format("{}: the mean force is not finite", name));
}

/// A fitted coefficient below zero: zero with a warning when within three standard errors of it,
/// refused otherwise (the log's axes or its sign are the usual cause).
double non_negative(double value, double se, const char* key, double unit_scale, std::vector<std::string>& warnings) {
  if (value >= 0.0) return value;
  if (std::isfinite(se) && -value <= 3.0 * se) {
    warnings.push_back(
        fmt::format("{} fitted {:.4g} +- {:.2g}, negative but within three standard errors of 0: "
                    "written as 0 (a negative coefficient is not physical)",
                    key, value * unit_scale, se * unit_scale));
    return 0.0;
  }
  throw InputError(fmt::format(
      "the fit gives {} = {:.4g}{}: the logs do not follow the slot model; check that the cuts are full slots, the "
      "log's feed and tool axes and whether it measured the force on the tool or on the workpiece",
      key, value * unit_scale, std::isfinite(se) ? fmt::format(" +- {:.2g}", se * unit_scale) : std::string()));
}

}  // namespace

CoefficientFit fit_cutting_coefficients(const std::vector<SlotCut>& cuts) {
  if (cuts.size() < 2) {
    throw InputError(fmt::format("{} slot cut{} given: the fit needs at least two (three or more to check it)",
                                 cuts.size(), cuts.size() == 1 ? "" : "s"));
  }
  for (const SlotCut& c : cuts) check_cut(c);
  CoefficientFit out;
  out.cuts = static_cast<int>(cuts.size());
  std::vector<double> feeds;
  for (const SlotCut& c : cuts) {
    if (std::none_of(feeds.begin(), feeds.end(), [&](double f) { return std::abs(f - c.fz_m) <= 0.01 * f; })) {
      feeds.push_back(c.fz_m);
    }
  }
  out.distinct_feeds = static_cast<int>(feeds.size());
  out.fz_min_m = *std::min_element(feeds.begin(), feeds.end());
  out.fz_max_m = *std::max_element(feeds.begin(), feeds.end());
  if (out.distinct_feeds < 2) {
    throw InputError(
        fmt::format("every slot cut has the feed per tooth {:g} mm: the slope (cutting coefficients) and "
                    "the intercept (edge coefficients) need at least two different feeds",
                    out.fz_min_m * 1e3));
  }
  if (out.distinct_feeds < kMinDistinctFeeds) {
    out.warnings.push_back(
        fmt::format("only {} distinct feeds per tooth: {} or more let the fit check the model's "
                    "straight line (and give standard errors)",
                    out.distinct_feeds, kMinDistinctFeeds));
  }
  const double span = out.fz_max_m / out.fz_min_m;
  if (span < kMinFeedSpanRatio) {
    out.warnings.push_back(
        fmt::format("the feeds per tooth span {:g}..{:g} mm, a ratio of {:.2f}: below {:g} the edge "
                    "coefficients are extrapolated from a short line; cut at feeds further apart",
                    out.fz_min_m * 1e3, out.fz_max_m * 1e3, span, kMinFeedSpanRatio));
  }
  std::vector<double> x1, x2, y_feed, y_normal, y_axial;
  for (const SlotCut& c : cuts) {
    x1.push_back(c.flutes * c.ap_m * c.fz_m);
    x2.push_back(c.flutes * c.ap_m);
    y_feed.push_back(-c.mean_force_n[0]);
    y_normal.push_back(turn_sign(c.turn) * c.mean_force_n[1]);
    y_axial.push_back(-c.mean_force_n[2]);
  }
  const LineFit feed = fit_line(x1, x2, y_feed), normal = fit_line(x1, x2, y_normal), axial = fit_line(x1, x2, y_axial);
  // Slopes and intercepts to coefficients (the closed forms in the header); user units in messages.
  const double kc[3] = {4.0 * normal.slope, 4.0 * feed.slope, kPi * axial.slope};
  const double kc_se[3] = {4.0 * normal.se_slope, 4.0 * feed.se_slope, kPi * axial.se_slope};
  const double ke[3] = {kPi * normal.intercept, kPi * feed.intercept, 2.0 * axial.intercept};
  const double ke_se[3] = {kPi * normal.se_intercept, kPi * feed.se_intercept, 2.0 * axial.se_intercept};
  double values[6], errors[6];
  for (int i = 0; i < 3; ++i) {
    values[i] = non_negative(kc[i], kc_se[i], kCoefficientKeys[i], 1e-6, out.warnings);
    values[i + 3] = non_negative(ke[i], ke_se[i], kCoefficientKeys[i + 3], 1e-3, out.warnings);
    errors[i] = kc_se[i];
    errors[i + 3] = ke_se[i];
  }
  out.k = {values[0], values[1], values[2], values[3], values[4], values[5]};
  out.standard_error = {errors[0], errors[1], errors[2], errors[3], errors[4], errors[5]};
  out.residual_rms_n = Vector3(feed.rms, normal.rms, axial.rms);
  validate_coefficients(out.k, "the fitted coefficients");
  return out;
}

SlotLogMean read_slot_log(const std::string& path, const SlotLogOptions& o) {
  if (o.feed_axis < 0 || o.feed_axis > 2 || o.tool_axis < 0 || o.tool_axis > 2 || o.feed_axis == o.tool_axis) {
    throw InputError(fmt::format("{}: the feed and tool axes must be two different axes of x, y, z", path));
  }
  const CsvTable t = CsvTable::read_file(path);
  t.require({"t_s", "fx_N", "fy_N", "fz_N"});
  t.allow_only({"t_s", "fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm"});
  const std::size_t ct = t.column("t_s"), cf[3] = {t.column("fx_N"), t.column("fy_N"), t.column("fz_N")};
  auto mean_over = [&](std::optional<double> from, std::optional<double> to, const char* what, int& count,
                       double& duration) {
    Vector3 sum = Vector3::Zero();
    double first = kNaN, last = kNaN;
    count = 0;
    for (std::size_t r = 0; r < t.rows(); ++r) {
      const double ts = t.at(r, ct);
      if (r > 0 && !(ts > t.at(r - 1, ct))) {
        t.fail(r, "t_s", fmt::format("time {:g} s does not increase (previous {:g} s)", ts, t.at(r - 1, ct)));
      }
      if ((from && ts < *from) || (to && ts > *to)) continue;
      sum += Vector3(t.at(r, cf[0]), t.at(r, cf[1]), t.at(r, cf[2]));
      if (count++ == 0) first = ts;
      last = ts;
    }
    if (count < 2) {
      throw DataError(fmt::format("{}: the {} {}..{} s holds {} sample{} (at least 2)", path, what,
                                  from ? fmt::format("{:g}", *from) : "start", to ? fmt::format("{:g}", *to) : "end",
                                  count, count == 1 ? "" : "s"));
    }
    duration = last - first;
    return Vector3(sum / count);
  };
  SlotLogMean out;
  std::optional<double> to = o.window_to_s;
  if (o.spindle_rpm && *o.spindle_rpm > 0.0) {
    // The window's first and last samples, then its end moved back to the last whole revolution.
    std::optional<double> first, last;
    for (std::size_t r = 0; r < t.rows(); ++r) {
      const double ts = t.at(r, ct);
      if ((o.window_from_s && ts < *o.window_from_s) || (o.window_to_s && ts > *o.window_to_s)) continue;
      if (!first) first = ts;
      last = ts;
    }
    if (first && last) {
      const double period = 60.0 / *o.spindle_rpm;
      out.revolutions = std::floor((*last - *first) / period + 1e-9);
      if (out.revolutions >= 1.0) to = *first + out.revolutions * period - 1e-9 * period;
    }
  }
  Vector3 mean = mean_over(o.window_from_s, to, "cut window", out.samples, out.duration_s);
  if (o.air_from_s || o.air_to_s) {
    double air_duration = 0.0;
    mean -= mean_over(o.air_from_s, o.air_to_s, "air window", out.air_samples, air_duration);
  }
  const Vector3 feed = o.feed_sign * Vector3::Unit(o.feed_axis), axis = o.tool_sign * Vector3::Unit(o.tool_axis);
  const Vector3 normal = axis.cross(feed);
  out.mean_force_n = Vector3(feed.dot(mean), normal.dot(mean), axis.dot(mean));
  if (o.force_on_workpiece) out.mean_force_n = -out.mean_force_n;
  return out;
}

}  // namespace deflex
