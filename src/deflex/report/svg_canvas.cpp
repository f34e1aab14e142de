// A minimal SVG builder for the report's charts.
#include "deflex/report/detail/svg_canvas.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "deflex/text/parse_number.hpp"

#include "deflex/report/svg_charts.hpp"

namespace deflex::svg {

std::vector<double> nice_ticks(double lo, double hi, int target) {
  std::vector<double> ticks;
  if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi)) {
    return {lo};
  }
  const double raw = (hi - lo) / std::max(1, target);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (const double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * mag >= raw) {
      step = m * mag;
      break;
    }
  }
  // Each tick as (k * step), not by adding step up: no drift (0.30000000000000004), and a range
  // narrower than the doubles' resolution at its magnitude (lo = 1000, hi = the next double) ends
  // instead of adding a step that rounds away, forever.
  const double first = std::ceil(lo / step - 1e-9);
  for (int i = 0; i <= 1000; ++i) {
    const double t = (first + i) * step;
    if (t > hi + step * 1e-9) {
      break;
    }
    const double tick = std::abs(t) < step * 1e-9 ? 0.0 : t;
    if (!ticks.empty() && !(tick > ticks.back())) {
      break;
    }
    ticks.push_back(tick);
  }
  return ticks;
}

double nice_ceiling(double v) {
  if (!(v > 0.0) || !std::isfinite(v)) {
    return 1.0;
  }
  const double mag = std::pow(10.0, std::floor(std::log10(v)));
  for (const double m : {1.0, 1.2, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0}) {
    if (m * mag >= v * (1.0 - 1e-12)) {
      return m * mag;
    }
  }
  return 10.0 * mag;
}

double LogScale::operator()(double d) const {
  return p0 + (std::log10(d) - std::log10(d0)) / (std::log10(d1) - std::log10(d0)) * (p1 - p0);
}

std::vector<double> log_ticks(double lo, double hi) {
  std::vector<double> ticks;
  if (!(lo > 0.0) || !(hi > lo) || !std::isfinite(hi)) {
    return ticks;
  }
  for (int k = static_cast<int>(std::floor(std::log10(lo))); k <= static_cast<int>(std::ceil(std::log10(hi))); ++k) {
    for (const double m : {1.0, 2.0, 5.0}) {
      // m * 10^k written from the decimal text, so 0.2 is the double nearest 0.2, not 2 * 0.1.
      const double t = parse_double(fmt::format("{:g}e{}", m, k)).value_or(m * std::pow(10.0, k));
      if (t >= lo * (1.0 - 1e-9) && t <= hi * (1.0 + 1e-9)) {
        ticks.push_back(t);
      }
    }
  }
  return ticks;
}

std::string tick_label(double value, double step) {
  const int decimals = std::max(0, static_cast<int>(std::ceil(-std::log10(step) - 1e-9)));
  return fmt::format("{:.{}f}", value, decimals);
}

Canvas::Canvas(double width, double height) : width_(width), height_(height) {}

void Canvas::rect(double x, double y, double w, double h, const std::string& fill, const std::string& extra) {
  body_ += fmt::format(R"(<rect x="{:.2f}" y="{:.2f}" width="{:.2f}" height="{:.2f}" fill="{}"{}/>)", x, y,
                       std::max(0.0, w), std::max(0.0, h), fill, extra.empty() ? "" : " " + extra);
  body_ += "\n";
}

void Canvas::line(double x1, double y1, double x2, double y2, const std::string& stroke, double width,
                  const std::string& extra) {
  body_ += fmt::format(R"(<line x1="{:.2f}" y1="{:.2f}" x2="{:.2f}" y2="{:.2f}" stroke="{}" stroke-width="{:.2f}"{}/>)",
                       x1, y1, x2, y2, stroke, width, extra.empty() ? "" : " " + extra);
  body_ += "\n";
}

void Canvas::polyline(const std::vector<double>& xy, const std::string& stroke, double width,
                      const std::string& extra) {
  std::string pts;
  pts.reserve(xy.size() * 8);
  for (std::size_t i = 0; i + 1 < xy.size(); i += 2) {
    pts += fmt::format("{}{:.1f},{:.1f}", i == 0 ? "" : " ", xy[i], xy[i + 1]);
  }
  body_ +=
      fmt::format(R"(<polyline points="{}" fill="none" stroke="{}" stroke-width="{:.2f}" stroke-linejoin="round"{}/>)",
                  pts, stroke, width, extra.empty() ? "" : " " + extra);
  body_ += "\n";
}

void Canvas::circle(double cx, double cy, double r, const std::string& fill, const std::string& extra) {
  body_ += fmt::format(R"(<circle cx="{:.2f}" cy="{:.2f}" r="{:.2f}" fill="{}"{}/>)", cx, cy, r, fill,
                       extra.empty() ? "" : " " + extra);
  body_ += "\n";
}

void Canvas::text(double x, double y, const std::string& t, double size, const std::string& anchor,
                  const std::string& extra) {
  body_ += fmt::format(R"(<text x="{:.2f}" y="{:.2f}" font-size="{:.1f}" text-anchor="{}"{}>{}</text>)", x, y, size,
                       anchor, extra.empty() ? "" : " " + extra, xml_escape(t));
  body_ += "\n";
}

void Canvas::path(const std::string& d, const std::string& stroke, double width, const std::string& extra) {
  body_ += fmt::format(R"(<path d="{}" fill="none" stroke="{}" stroke-width="{:.2f}" stroke-linejoin="round"{}/>)", d,
                       stroke, width, extra.empty() ? "" : " " + extra);
  body_ += "\n";
}

void Canvas::polygon(const std::vector<double>& xy, const std::string& fill, const std::string& extra) {
  std::string pts;
  for (std::size_t i = 0; i + 1 < xy.size(); i += 2) {
    pts += fmt::format("{}{:.1f},{:.1f}", i == 0 ? "" : " ", xy[i], xy[i + 1]);
  }
  body_ += fmt::format(R"(<polygon points="{}" fill="{}"{}/>)", pts, fill, extra.empty() ? "" : " " + extra);
  body_ += "\n";
}

void Canvas::group_begin(const std::string& tooltip, const std::string& extra) {
  body_ += extra.empty() ? "<g>" : "<g " + extra + ">";
  if (!tooltip.empty()) {
    body_ += "<title>" + xml_escape(tooltip) + "</title>";
  }
  body_ += "\n";
}

void Canvas::group_end() { body_ += "</g>\n"; }

void Canvas::title(const std::string& t) { text(width_ / 2.0, 24.0, t, 16.0, "middle", R"(font-weight="bold")"); }

void Canvas::raw(const std::string& markup) { body_ += markup; }

std::string Canvas::str() const {
  return fmt::format(
      R"(<svg xmlns="http://www.w3.org/2000/svg" width="{0:.0f}" height="{1:.0f}" viewBox="0 0 {0:.0f} {1:.0f}" )"
      R"(font-family="Helvetica, Arial, sans-serif" fill="#222">)"
      "\n<rect x=\"0\" y=\"0\" width=\"{0:.0f}\" height=\"{1:.0f}\" fill=\"white\"/>\n{2}</svg>\n",
      width_, height_, body_);
}

}  // namespace deflex::svg

namespace deflex {

std::string xml_escape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char ch : text) {
    switch (ch) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += ch;
    }
  }
  return out;
}

}  // namespace deflex
