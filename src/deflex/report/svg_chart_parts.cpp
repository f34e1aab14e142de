// Parts the report's charts share.
#include "deflex/report/detail/svg_chart_parts.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <fmt/format.h>

namespace deflex::svg {
namespace {

const char* const kPalette[] = {"#4C78A8", "#F58518", "#54A24B", "#B279A2", "#E45756", "#72B7B2", "#9D755D"};
constexpr std::size_t kPaletteSize = sizeof(kPalette) / sizeof(kPalette[0]);

}  // namespace

const char* const kUnloadedColour = "#888888";
const char* const kUcColour = "#D62728";
const char* const kCColour = "#1F77B4";
const char* const kPaperColour = "#111111";
const char* const kClockwiseColour = "#E66101";
const char* const kAnticlockwiseColour = "#5E3C99";

std::string colour(std::size_t i) { return kPalette[i % kPaletteSize]; }

std::string pale(const std::string& hex, double amount) {
  unsigned r = 0, g = 0, b = 0;
  if (std::sscanf(hex.c_str(), "#%02x%02x%02x", &r, &g, &b) != 3) {
    return hex;
  }
  auto mix = [&](unsigned ch) { return static_cast<unsigned>(std::lround(ch + (255.0 - ch) * amount)); };
  return fmt::format("#{:02X}{:02X}{:02X}", mix(r), mix(g), mix(b));
}

std::string short_setup_name(const std::string& setup) {
  if (setup == "offline") {
    return "offline (OFF)";
  }
  if (setup == "online") {
    return "online (ON)";
  }
  return setup;
}

double text_width(const std::string& text, double size) {
  // Helvetica averages about 0.55 em a character in mixed text; UTF-8 continuation bytes add none.
  double n = 0.0;
  for (const char ch : text) {
    if ((static_cast<unsigned char>(ch) & 0xC0U) != 0x80U) {
      n += 1.0;
    }
  }
  return 0.56 * size * n;
}

void value_axis(Canvas& c, const Scale& y, double x_left, double x_right, const std::string& label,
                double scale_to_label, double title_offset) {
  const auto ticks = nice_ticks(std::min(y.d0, y.d1), std::max(y.d0, y.d1), 6);
  const double step = ticks.size() > 1 ? ticks[1] - ticks[0] : 1.0;
  for (const double t : ticks) {
    c.line(x_left, y(t), x_right, y(t), "#e3e3e3", 1.0);
    c.text(x_left - 6.0, y(t) + 4.0, tick_label(t * scale_to_label, step * scale_to_label), kMinFont, "end");
  }
  c.line(x_left, y.p0, x_left, y.p1, "#444", 1.0);
  const double mid = (y.p0 + y.p1) / 2.0;
  c.text(x_left - title_offset, mid, label, 12.0, "middle",
         fmt::format(R"svg(transform="rotate(-90 {:.2f} {:.2f})")svg", x_left - title_offset, mid));
}

void position_axis(Canvas& c, const Scale& x, double y_bottom, const std::string& label) {
  const auto ticks = nice_ticks(std::min(x.d0, x.d1), std::max(x.d0, x.d1), 6);
  const double step = ticks.size() > 1 ? ticks[1] - ticks[0] : 1.0;
  c.line(x.p0, y_bottom, x.p1, y_bottom, "#444", 1.0);
  for (const double t : ticks) {
    c.line(x(t), y_bottom, x(t), y_bottom + 5.0, "#444", 1.0);
    c.text(x(t), y_bottom + 18.0, tick_label(t, step), kMinFont, "middle");
  }
  if (!label.empty()) {
    c.text((x.p0 + x.p1) / 2.0, y_bottom + 36.0, label, 12.0, "middle");
  }
}

double legend_entry(Canvas& c, double x, double y, const std::string& kind, const std::string& col,
                    const std::string& label) {
  if (kind == "bar") {
    c.rect(x, y - 10.0, 14.0, 12.0, col);
  } else if (kind == "hollow") {
    c.rect(x + 3.0, y - 11.0, 8.0, 13.0, "white", fmt::format(R"(stroke="{}" stroke-width="1.5")", col));
  } else if (kind == "band") {
    c.rect(x, y - 11.0, 18.0, 13.0, col);
  } else if (kind == "marker") {
    c.line(x - 2.0, y - 4.0, x + 16.0, y - 4.0, col, 2.5);
    c.circle(x + 7.0, y - 4.0, 3.0, "white", fmt::format(R"(stroke="{}" stroke-width="1.5")", col));
  } else if (kind == "dash") {
    c.line(x, y - 4.0, x + 18.0, y - 4.0, col, 2.0, R"(stroke-dasharray="5 3")");
  } else if (kind == "dot") {
    c.circle(x + 8.0, y - 4.0, 4.0, col);
  } else {
    c.line(x, y - 4.0, x + 18.0, y - 4.0, col, 2.0);
  }
  c.text(x + 24.0, y, label, 12.0);
  return x + 24.0 + text_width(label, 12.0) + 18.0;
}

void whisker(Canvas& c, double x, double y_lo_px, double y_hi_px, const std::string& col, double cap) {
  if (!std::isfinite(y_lo_px) || !std::isfinite(y_hi_px)) {
    return;
  }
  c.line(x, y_lo_px, x, y_hi_px, col, 1.3, R"(class="whisker")");
  c.line(x - cap / 2.0, y_lo_px, x + cap / 2.0, y_lo_px, col, 1.3);
  c.line(x - cap / 2.0, y_hi_px, x + cap / 2.0, y_hi_px, col, 1.3);
}

Range fitted_range(const std::vector<double>& values, bool from_zero, double pad) {
  double lo = HUGE_VAL, hi = -HUGE_VAL;
  for (const double v : values) {
    if (std::isfinite(v)) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  }
  if (!std::isfinite(lo)) {
    return {};
  }
  if (from_zero && lo >= 0.0) {
    lo = 0.0;
  }
  double span = hi - lo;
  if (!(span > 0.0)) {
    span = std::abs(hi) > 0.0 ? std::abs(hi) * 0.2 : 1.0;
  }
  const double plo = lo == 0.0 && from_zero ? 0.0 : lo - pad * span;
  const double phi = hi + pad * span;
  // Widen to the ticks nice_ticks puts inside, plus one step each side where they fall short.
  const auto ticks = nice_ticks(plo, phi, 5);
  const double step = ticks.size() > 1 ? ticks[1] - ticks[0] : span;
  Range r{plo, phi};
  if (!ticks.empty()) {
    r.lo = ticks.front() <= plo + 1e-12 * step ? ticks.front() : ticks.front() - step;
    r.hi = ticks.back() >= phi - 1e-12 * step ? ticks.back() : ticks.back() + step;
  }
  if (from_zero && lo >= 0.0) {
    r.lo = std::max(r.lo, 0.0);
  }
  return r;
}

double nice_floor(double v) {
  if (!(v > 0.0) || !std::isfinite(v)) {
    return 1.0;
  }
  const double mag = std::pow(10.0, std::floor(std::log10(v)));
  for (const double m : {5.0, 2.0, 1.0}) {
    if (m * mag <= v) {
      return m * mag;
    }
  }
  return mag;
}

}  // namespace deflex::svg
