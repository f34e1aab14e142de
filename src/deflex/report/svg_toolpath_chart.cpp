// The chart of a toolpath job along its path: force, deflection with and without compensation, spin.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "deflex/report/detail/svg_canvas.hpp"
#include "deflex/report/detail/svg_chart_parts.hpp"
#include "deflex/report/svg_charts.hpp"

namespace deflex {
namespace {

using svg::Canvas;
using svg::Scale;

/// One panel: its series (values per sample, drawn as lines over s), its axis and legend.
struct ToolpathSeries {
  std::vector<double> values;
  std::string colour, label, extra;
};

void toolpath_panel(Canvas& c, const std::vector<double>& s_mm, const std::vector<ToolpathSeries>& series,
                    const Scale& x, double top, double bottom, const std::string& axis_label, bool from_zero) {
  std::vector<double> all;
  for (const ToolpathSeries& one : series) all.insert(all.end(), one.values.begin(), one.values.end());
  const svg::Range range = svg::fitted_range(all, from_zero);
  const Scale y{range.lo, range.hi, bottom, top};
  svg::value_axis(c, y, x.p0, x.p1, axis_label, 1.0, 56.0);
  // Steps: a point's value holds along the move into it (its force is that move's), so a long
  // positioning move is drawn at its end's value, not as a ramp from the cut before it.
  for (const ToolpathSeries& one : series) {
    std::vector<double> xy;
    for (std::size_t i = 0; i < s_mm.size(); ++i) {
      if (!std::isfinite(one.values[i])) continue;
      const double v = y(std::clamp(one.values[i], range.lo, range.hi));
      if (xy.size() >= 2 && std::abs(xy.back() - v) < 0.05) {
        xy[xy.size() - 2] = x(s_mm[i]);  // the same level goes on: one segment, not one a sample
        continue;
      }
      xy.insert(xy.end(), {x(s_mm[i == 0 ? 0 : i - 1]), v, x(s_mm[i]), v});
    }
    c.polyline(xy, one.colour, 1.4, one.extra);
  }
  double lx = x.p0 + 8.0;
  for (const ToolpathSeries& one : series) {
    lx = svg::legend_entry(c, lx, top - 8.0, one.extra.empty() ? "line" : "dash", one.colour, one.label) + 14.0;
  }
}

}  // namespace

std::string svg_toolpath_chart(const std::vector<ToolpathChartSample>& samples, const std::string& title, bool gcode) {
  const double width = svg::kMaxWidth, height = 900.0;
  Canvas c(width, height);
  c.title("Cutting force and predicted deflection along the toolpath");
  c.text(width / 2.0, 44.0, title, 13.0, "middle", R"(fill="#444")");
  if (samples.size() < 2) {
    c.text(width / 2.0, height / 2.0, "fewer than two points to plot", 14.0, "middle");
    return c.str();
  }
  std::vector<double> s_mm, force, peak, deflection, residual, gcode_residual, spin;
  for (const ToolpathChartSample& p : samples) {
    s_mm.push_back(p.s_m * 1e3);
    force.push_back(p.force_n);
    peak.push_back(p.peak_force_n);
    deflection.push_back(p.deflection_m * 1e3);
    residual.push_back(p.residual_m * 1e3);
    gcode_residual.push_back(p.gcode_residual_m * 1e3);
    spin.push_back(rad_to_deg(p.spin_rad));
  }
  const double left = 90.0, right = width - 30.0;
  const Scale x{s_mm.front(), std::max(s_mm.back(), s_mm.front() + 1e-9), left, right};
  toolpath_panel(c, s_mm,
                 {{force, svg::colour(0), "average over a revolution (what the compensation follows)", ""},
                  {peak, svg::colour(1), "per-revolution peak", R"(stroke-dasharray="5,3")"}},
                 x, 90.0, 300.0, "cutting force (N)", true);
  std::vector<ToolpathSeries> d{{deflection, svg::kUcColour, "without compensation", ""},
                                {residual, svg::kCColour, "compensated robot program", ""}};
  if (gcode)
    d.push_back({gcode_residual, svg::colour(4), "compensated G-code (positions only)", R"(stroke-dasharray="5,3")"});
  toolpath_panel(c, s_mm, d, x, 360.0, 600.0, "predicted tip deflection (mm)", true);
  toolpath_panel(c, s_mm, {{spin, svg::colour(2), "spindle angle", ""}}, x, 660.0, 820.0, "spindle angle (deg)", false);
  svg::position_axis(c, x, 820.0, "path length along the program (mm)");
  return c.str();
}

}  // namespace deflex
