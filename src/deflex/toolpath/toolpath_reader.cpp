// Choosing a toolpath reader by extension, reading a whole toolpath, checking the options.
#include "deflex/toolpath/toolpath_reader.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"
#include "deflex/text/key_value_spec.hpp"
#include "deflex/text/parse_number.hpp"
#include "deflex/toolpath/apt_reader.hpp"
#include "deflex/toolpath/gcode_reader.hpp"

namespace deflex {

void check_toolpath_options(const ToolpathOptions& o) {
  const auto within = [](double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; };
  if (!within(o.chord_tolerance_m, 1e-7, 1e-3)) {
    throw InputError(fmt::format("toolpath option chord_tolerance_m: {} m is outside 1e-7..1e-3 m (0.0001..1 mm)",
                                 number_text(o.chord_tolerance_m)));
  }
  if (!within(o.arc_radius_tolerance_m, 1e-7, 1e-3)) {
    throw InputError(fmt::format("toolpath option arc_radius_tolerance_m: {} m is outside 1e-7..1e-3 m",
                                 number_text(o.arc_radius_tolerance_m)));
  }
  if (!(o.max_linear_step_m == 0.0 || within(o.max_linear_step_m, 1e-5, 1.0))) {
    throw InputError(fmt::format("toolpath option max_linear_step_m: {} m is neither 0 nor inside 1e-5..1 m",
                                 number_text(o.max_linear_step_m)));
  }
}

ToolpathOptions parse_toolpath_options_spec(const std::string& spec) {
  const KeyValueSpec keys(spec, spec, {"chord_mm", "arc_tolerance_mm", "step_mm", "rotary", "dialect", "apt_units"});
  ToolpathOptions o;
  o.chord_tolerance_m = keys.number("chord_mm", o.chord_tolerance_m * 1e3) * 1e-3;
  o.arc_radius_tolerance_m = keys.number("arc_tolerance_mm", o.arc_radius_tolerance_m * 1e3) * 1e-3;
  o.max_linear_step_m = keys.number("step_mm", 0.0) * 1e-3;
  const auto choice = [&](const char* key, const char* a, const char* b) {
    if (!keys.has(key)) return true;
    const std::string& v = keys.text(key);
    if (v != a && v != b) keys.fail(fmt::format("key '{}': '{}' is neither {} nor {}", key, v, a, b));
    return v == a;
  };
  o.rotary = choice("rotary", "head-head", "table-table") ? RotaryConvention::kHeadHead : RotaryConvention::kTableTable;
  o.dialect = choice("dialect", "iso", "siemens") ? GcodeDialect::kIso : GcodeDialect::kSiemens;
  o.apt_default_units = choice("apt_units", "mm", "inch") ? LengthUnit::kMillimetre : LengthUnit::kInch;
  try {
    check_toolpath_options(o);
  } catch (const InputError& e) {
    keys.fail(e.what());
  }
  return o;
}

ToolpathFormat toolpath_format_for(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".nc" || ext == ".gcode" || ext == ".tap") {
    return ToolpathFormat::kGcode;
  }
  if (ext == ".apt" || ext == ".cls") {
    return ToolpathFormat::kApt;
  }
  throw InputError(
      fmt::format("{}: the toolpath's extension '{}' names no format deflex reads: .nc, .gcode, .tap "
                  "(G-code) or .apt, .cls (APT/CL data)",
                  path, ext));
}

std::unique_ptr<ToolpathReader> open_toolpath(const std::string& path, const ToolpathOptions& options) {
  if (toolpath_format_for(path) == ToolpathFormat::kGcode) {
    return std::make_unique<GcodeReader>(path, options);
  }
  return std::make_unique<AptReader>(path, options);
}

Toolpath read_toolpath(ToolpathReader& reader) {
  Toolpath t;
  ToolpathPoint p;
  while (reader.next(p)) {
    if (t.points.size() >= kMaxHeldToolpathPoints) {
      throw DataError(
          fmt::format("{}: more than {} toolpath points to hold in memory: read it a point at a time "
                      "(open_toolpath)",
                      reader.summary().source, kMaxHeldToolpathPoints));
    }
    t.points.push_back(p);
  }
  t.summary = reader.summary();
  return t;
}

Toolpath read_toolpath(const std::string& path, const ToolpathOptions& options) {
  const std::unique_ptr<ToolpathReader> reader = open_toolpath(path, options);
  return read_toolpath(*reader);
}

}  // namespace deflex
