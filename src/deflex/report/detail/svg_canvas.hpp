// A minimal SVG builder for the report's charts: shapes and text in pixel coordinates, axes with
// "nice" ticks. Internal to the report module.
#pragma once

#include <string>
#include <vector>

namespace deflex::svg {

/// Linear map from data to pixels.
struct Scale {
  double d0 = 0.0, d1 = 1.0;  ///< data range
  double p0 = 0.0, p1 = 1.0;  ///< pixel range
  [[nodiscard]] double operator()(double d) const { return p0 + (d - d0) / (d1 - d0) * (p1 - p0); }
};

/// Logarithmic map from data (> 0) to pixels, for figures that span decades (0.04 to 1.1 mm).
struct LogScale {
  double d0 = 0.1, d1 = 1.0;  ///< data range, both > 0
  double p0 = 0.0, p1 = 1.0;  ///< pixel range
  [[nodiscard]] double operator()(double d) const;
};
/// Ticks 1, 2, 5 x 10^k inside [lo, hi] (both > 0).
std::vector<double> log_ticks(double lo, double hi);

/// Tick values for [lo, hi]: steps of 1, 2 or 5 x 10^k, about `target` of them.
std::vector<double> nice_ticks(double lo, double hi, int target = 6);
/// The smallest nice tick value >= v (for an axis maximum).
double nice_ceiling(double v);
/// Shortest fixed-point text of a tick value given the tick step.
std::string tick_label(double value, double step);

class Canvas {
 public:
  Canvas(double width, double height);
  void rect(double x, double y, double w, double h, const std::string& fill, const std::string& extra = "");
  void line(double x1, double y1, double x2, double y2, const std::string& stroke, double width = 1.0,
            const std::string& extra = "");
  void polyline(const std::vector<double>& xy, const std::string& stroke, double width = 1.0,
                const std::string& extra = "");
  void circle(double cx, double cy, double r, const std::string& fill, const std::string& extra = "");
  /// anchor: "start", "middle" or "end". Text is escaped.
  void text(double x, double y, const std::string& text, double size = 12.0, const std::string& anchor = "start",
            const std::string& extra = "");
  /// SVG path data (M/L/Z commands in pixels): several pieces in one element.
  void path(const std::string& d, const std::string& stroke, double width = 1.0, const std::string& extra = "");
  /// A closed, filled shape through xy pairs.
  void polygon(const std::vector<double>& xy, const std::string& fill, const std::string& extra = "");
  /// A group; a non-empty tooltip becomes its <title> (a browser shows it on hover, no script).
  void group_begin(const std::string& tooltip = "", const std::string& extra = "");
  void group_end();
  /// A title line across the top.
  void title(const std::string& text);
  /// Raw SVG markup (already well-formed).
  void raw(const std::string& markup);
  [[nodiscard]] std::string str() const;
  [[nodiscard]] double width() const { return width_; }
  [[nodiscard]] double height() const { return height_; }

 private:
  double width_, height_;
  std::string body_;
};

}  // namespace deflex::svg
