// The error budget drawn as what it is: a one-effect-at-a-time sensitivity. One bar per effect, C
// with that effect alone off, against C with every effect on and C with every effect off at once.
#include <algorithm>
#include <cmath>
#include <numeric>

#include <fmt/format.h>

#include "deflex/report/detail/svg_canvas.hpp"
#include "deflex/report/detail/svg_chart_parts.hpp"
#include "deflex/report/svg_charts.hpp"

namespace deflex {
namespace {

using svg::Canvas;
using svg::kMinFont;
using svg::Scale;

constexpr const char* kFallsColour = "#4C78A8";  // C falls with the effect off: the effect adds to C
constexpr const char* kRisesColour = "#F58518";  // C rises with the effect off: the effect offsets another
constexpr const char* kAllOnColour = "#C62828";
constexpr const char* kAllOffColour = "#2E7D32";

std::string mm_text(double v) { return std::isfinite(v) ? fmt::format("{:.3f} mm", v) : "n/a"; }

// A vertical reference line over the rows, its label above it.
void reference_line(Canvas& c, const Scale& x, double value, double top, double bottom, const std::string& colour,
                    const std::string& dash, const std::string& cls, const std::string& label, double label_y,
                    const std::string& anchor) {
  if (!std::isfinite(value)) return;
  c.line(x(value), top, x(value), bottom, colour, 2.0,
         fmt::format(R"({} class="{}" data-value="{:.6g}")", dash, cls, value));
  c.text(x(value) + (anchor == "end" ? -4.0 : 4.0), label_y, label, kMinFont, anchor,
         fmt::format(R"(fill="{}")", colour));
}

}  // namespace

std::string svg_error_budget(const ErrorBudget& b) {
  const double row_h = 22.0;
  const double top = 134.0;
  const double n_rows = static_cast<double>(std::max<std::size_t>(1, b.entries.size()));
  const double bottom = top + row_h * n_rows;
  const double width = svg::kMaxWidth, height = bottom + 64.0;
  Canvas c(width, height);
  c.title(fmt::format("Error budget, one effect at a time: {} {:g} N at {:g} mm/s", b.setup, b.load_N, b.speed_mm_s));
  c.text(width / 2.0, 44.0,
         fmt::format("C with every effect on {}; with every effect off at once {}{}", mm_text(b.residual_mm_all),
                     std::isfinite(b.residual_mm_all_off) ? mm_text(b.residual_mm_all_off) : "(not run)",
                     b.uc_mm > 0.0 ? fmt::format("; UC {}", mm_text(b.uc_mm)) : std::string()),
         13.0, "middle", R"(fill="#444")");
  if (b.entries.empty()) {
    c.text(width / 2.0, (top + bottom) / 2.0, "no effect in this budget", 14.0, "middle");
    return c.str();
  }
  // Legend.
  double lx = 40.0;
  lx =
      svg::legend_entry(c, lx, 70.0, "bar", kFallsColour, "C with this effect alone off: lower than with every effect");
  svg::legend_entry(c, lx, 70.0, "bar", kRisesColour, "higher (the effect offsets another)");
  lx = svg::legend_entry(c, 40.0, 90.0, "line", kAllOnColour, "C with every effect on");
  svg::legend_entry(c, lx, 90.0, "dash", kAllOffColour, "C with every effect off at once (own calibration)");

  // Rows from the largest drop of C to the largest rise: the effects that matter most on top.
  std::vector<std::size_t> order(b.entries.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t i, std::size_t j) {
    const double a = b.entries[i].residual_mm_without_it, d = b.entries[j].residual_mm_without_it;
    return std::isfinite(a) && (!std::isfinite(d) || a < d);
  });
  double label_w = 0.0, max_mm = 0.0;
  for (const auto& e : b.entries) {
    label_w = std::max(label_w, svg::text_width(e.effect, 12.0));
    if (std::isfinite(e.residual_mm_without_it)) max_mm = std::max(max_mm, e.residual_mm_without_it);
  }
  for (const double v : {b.residual_mm_all, b.residual_mm_all_off}) {
    if (std::isfinite(v)) max_mm = std::max(max_mm, v);
  }
  const double left = std::min(380.0, 24.0 + label_w), right = width - 150.0;
  const Scale x{0.0, svg::nice_ceiling(std::max(max_mm, 1e-6) * 1.05), left, right};
  for (const double t : svg::nice_ticks(x.d0, x.d1)) {
    c.line(x(t), top - 4.0, x(t), bottom, "#e6e6e6", 1.0);
  }
  for (std::size_t r = 0; r < order.size(); ++r) {
    const ErrorBudgetEntry& e = b.entries[order[r]];
    const double y = top + row_h * static_cast<double>(r);
    const double s = printed_sensitivity(b, e);
    c.group_begin(fmt::format("{} ({}): C {} with it alone off; sensitivity {}", e.effect, e.size,
                              mm_text(e.residual_mm_without_it), percent_text(s)));
    c.text(left - 8.0, y + 15.0, e.effect, 12.0, "end");
    if (std::isfinite(e.residual_mm_without_it)) {
      const double v = std::clamp(e.residual_mm_without_it, x.d0, x.d1);
      // By the sensitivity as printed beside it, so no bar labelled 0% stands out as a rise.
      const bool rises = std::isfinite(s) && whole_percent(s) < 0.0;
      c.rect(x(0.0), y + 4.0, x(v) - x(0.0), row_h - 8.0, rises ? kRisesColour : kFallsColour,
             fmt::format(R"(class="budget-bar" data-value="{:.6g}")", e.residual_mm_without_it));
    }
    c.text(right + 8.0, y + 15.0, fmt::format("{} ({})", mm_text(e.residual_mm_without_it), percent_text(s)), kMinFont,
           "start", R"(class="budget-value" fill="#333")");
    c.group_end();
  }
  c.line(x(0.0), top - 4.0, x(0.0), bottom, "#444", 1.0);
  // The two references over every row; their labels above the rows, one row each, on the side of
  // its line towards the middle of the axis, so neither runs into the value column.
  const double mid = (left + right) / 2.0;
  const auto side = [&](double v) {
    return std::isfinite(v) && x(v) > mid ? std::string("end") : std::string("start");
  };
  reference_line(c, x, b.residual_mm_all, top - 8.0, bottom, kAllOnColour, "", "ref-all-on",
                 fmt::format("every effect on: {}", mm_text(b.residual_mm_all)), top - 10.0, side(b.residual_mm_all));
  reference_line(c, x, b.residual_mm_all_off, top - 22.0, bottom, kAllOffColour, R"(stroke-dasharray="6 4")",
                 "ref-all-off", fmt::format("every effect off: {}", mm_text(b.residual_mm_all_off)), top - 24.0,
                 side(b.residual_mm_all_off));
  svg::position_axis(c, x, bottom, "C, mean distance of the compensated run from the unloaded path (mm)");
  c.text(right + 8.0, top - 24.0, "C without it", kMinFont, "start", R"(fill="#444")");
  c.text(right + 8.0, top - 10.0, "(sensitivity)", kMinFont, "start", R"(fill="#444")");
  return c.str();
}

}  // namespace deflex
