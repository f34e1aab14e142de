// Reading small programs held in the tests for the toolpath tests.
#pragma once

#include <string>
#include <vector>

#include "deflex/toolpath/apt_reader.hpp"
#include "deflex/toolpath/gcode_reader.hpp"

namespace deflex::test {

inline std::vector<ToolpathPoint> gcode_points(const std::string& text, const ToolpathOptions& options = {},
                                               ToolpathSummary* summary = nullptr) {
  GcodeReader reader(text, "t.nc", options);
  std::vector<ToolpathPoint> points;
  ToolpathPoint p;
  while (reader.next(p)) points.push_back(p);
  if (summary != nullptr) *summary = reader.summary();
  return points;
}

inline std::vector<ToolpathPoint> apt_points(const std::string& text, const ToolpathOptions& options = {},
                                             ToolpathSummary* summary = nullptr) {
  AptReader reader(text, "t.apt", options);
  std::vector<ToolpathPoint> points;
  ToolpathPoint p;
  while (reader.next(p)) points.push_back(p);
  if (summary != nullptr) *summary = reader.summary();
  return points;
}

/// mm to m, for expected values written in the programs' unit.
inline Vector3 mm(double x, double y, double z) { return Vector3(x, y, z) * 1e-3; }

}  // namespace deflex::test
