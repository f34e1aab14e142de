// Reading back what the report's SVG draws: tags and their attributes, texts with their position
// and size, path data. Plain scanning, not std::regex: libstdc++'s regex recurses per character and
// overflows the stack on a long SVG under AddressSanitizer.
#pragma once

#include <cmath>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace deflex::test {

/// The text of every <name ...> tag (from '<' up to its '>'), in document order.
inline std::vector<std::string> tags(const std::string& svg, const std::string& name) {
  std::vector<std::string> out;
  const std::string open = "<" + name + " ";
  for (auto p = svg.find(open); p != std::string::npos; p = svg.find(open, p + 1)) {
    out.push_back(svg.substr(p, svg.find('>', p) - p + 1));
  }
  return out;
}

/// Value of the attribute `name` inside one tag's text, or "" when absent.
inline std::string attribute(const std::string& tag, const std::string& name) {
  const std::string key = " " + name + "=\"";
  const auto b = tag.find(key);
  if (b == std::string::npos) {
    return "";
  }
  const auto start = b + key.size();
  return tag.substr(start, tag.find('"', start) - start);
}

/// A numeric attribute, NaN when absent.
inline double number(const std::string& tag, const std::string& name) {
  const std::string v = attribute(tag, name);
  return v.empty() ? std::nan("") : std::stod(v);
}

struct SvgText {
  double x = 0.0, y = 0.0, size = 0.0;
  std::string anchor, content, tag;
};

/// Every <text> element with its position, size, anchor and (still escaped) content.
inline std::vector<SvgText> texts(const std::string& svg) {
  std::vector<SvgText> out;
  for (auto p = svg.find("<text "); p != std::string::npos; p = svg.find("<text ", p + 1)) {
    const auto close = svg.find('>', p);
    SvgText t;
    t.tag = svg.substr(p, close - p + 1);
    t.x = number(t.tag, "x");
    t.y = number(t.tag, "y");
    t.size = number(t.tag, "font-size");
    t.anchor = attribute(t.tag, "text-anchor");
    t.content = svg.substr(close + 1, svg.find("</text>", close) - close - 1);
    out.push_back(t);
  }
  return out;
}

/// The first text whose content is exactly `content`, or nullptr.
inline const SvgText* find_text(const std::vector<SvgText>& ts, const std::string& content) {
  for (const auto& t : ts) {
    if (t.content == content) {
      return &t;
    }
  }
  return nullptr;
}

/// Every font-size="..." in the document.
inline std::vector<double> font_sizes(const std::string& svg) {
  std::vector<double> out;
  const std::string key = "font-size=\"";
  for (auto p = svg.find(key); p != std::string::npos; p = svg.find(key, p + 1)) {
    out.push_back(std::stod(svg.substr(p + key.size())));
  }
  return out;
}

/// The root <svg>'s width attribute.
inline double svg_width(const std::string& svg) { return number(svg.substr(svg.find("<svg "), 200), "width"); }

/// The pieces of a path's d attribute ("M x,y L x,y ... M x,y ..."), each a list of (x, y).
inline std::vector<std::vector<std::pair<double, double>>> path_pieces(const std::string& d) {
  std::vector<std::vector<std::pair<double, double>>> out;
  std::stringstream ss(d);
  std::string token;
  while (ss >> token) {
    const char cmd = token[0];
    if (cmd == 'M') {
      out.emplace_back();
    }
    const std::string xy = token.substr(1);
    const auto comma = xy.find(',');
    if (out.empty() || comma == std::string::npos) {
      continue;
    }
    out.back().emplace_back(std::stod(xy.substr(0, comma)), std::stod(xy.substr(comma + 1)));
  }
  return out;
}

/// Points of a points="x,y x,y ..." attribute.
inline std::vector<std::pair<double, double>> point_list(const std::string& points) {
  std::vector<std::pair<double, double>> pts;
  std::stringstream ss(points);
  std::string pair;
  while (ss >> pair) {
    const auto comma = pair.find(',');
    pts.emplace_back(std::stod(pair.substr(0, comma)), std::stod(pair.substr(comma + 1)));
  }
  return pts;
}

}  // namespace deflex::test
