// Parts the report's charts share: colours, axes, legend entries, whiskers and fitted ranges.
// Internal to the report module. Every text is at least kMinFont px, so a figure shown at its own
// width on the report's 1060 px page stays readable.
#pragma once

#include <string>
#include <vector>

#include "deflex/report/detail/svg_canvas.hpp"

namespace deflex::svg {

/// Smallest font size any chart uses (px), and the widest a chart may be (px): the report's page is
/// 1060 px wide, and a figure no wider than its content width is never scaled down.
constexpr double kMinFont = 11.0;
constexpr double kMaxWidth = 1020.0;

/// Series colours (Tableau-like, distinguishable in print and by most colour-blind readers).
std::string colour(std::size_t i);
/// A colour ("#RRGGBB") mixed with white (`amount` 0..1 of white): the pale "before" bars.
std::string pale(const std::string& hex, double amount = 0.7);
extern const char* const kUnloadedColour;
extern const char* const kUcColour;
extern const char* const kCColour;
extern const char* const kPaperColour;
/// Direction of travel in the per-lap figures.
extern const char* const kClockwiseColour;
extern const char* const kAnticlockwiseColour;

/// "offline (OFF)", "online (ON)" as the paper's Figure 5 names them; other names unchanged.
std::string short_setup_name(const std::string& setup);

/// Rough width of a text in Helvetica at `size` px (for layout: legends, label placement).
double text_width(const std::string& text, double size);

/// Horizontal grid, ticks and labels of a value axis at x_left, and its title rotated along it
/// `title_offset` px left of the axis. Tick labels show value * scale_to_label.
void value_axis(Canvas& c, const Scale& y, double x_left, double x_right, const std::string& label,
                double scale_to_label = 1.0, double title_offset = 48.0);
/// Ticks and labels below a horizontal axis at y_bottom, and its title under them (none if empty).
void position_axis(Canvas& c, const Scale& x, double y_bottom, const std::string& label);

/// A legend entry: a swatch and its text at (x, y) (y: the text's baseline). kind: "bar", "hollow"
/// (an outlined bar: the paper's), "line", "dash", "dot", "marker", "band". Returns the x after it.
double legend_entry(Canvas& c, double x, double y, const std::string& kind, const std::string& col,
                    const std::string& label);

/// A vertical whisker from y_lo_px to y_hi_px at x with caps `cap` px wide.
void whisker(Canvas& c, double x, double y_lo_px, double y_hi_px, const std::string& col, double cap = 7.0);

/// [lo, hi] covering `values` (NaN skipped) padded by `pad` of the span and widened to nice ticks;
/// from zero when `from_zero` (and every value >= 0). {0, 1} when there is no finite value.
struct Range {
  double lo = 0.0, hi = 1.0;
};
Range fitted_range(const std::vector<double>& values, bool from_zero, double pad = 0.08);

/// The largest nice value (1, 2 or 5 x 10^k) <= v; 1 for v <= 0 or not finite.
double nice_floor(double v);

}  // namespace deflex::svg
