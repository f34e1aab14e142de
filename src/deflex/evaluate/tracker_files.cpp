// Tracker files: SA ASCII exports and plain CSV (see tracker_files.hpp).
#include "deflex/evaluate/tracker_files.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <optional>
#include <string_view>
#include <utility>

#include <fmt/format.h>

#include "deflex/text/csv_table.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/input_file.hpp"
#include "deflex/text/input_ranges.hpp"
#include "deflex/text/parse_number.hpp"
#include "deflex/text/utf8_text.hpp"

namespace deflex {
namespace {

std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

// Metres per unit of a length unit name, or nullopt.
std::optional<double> length_scale(const std::string& unit) {
  if (unit == "mm") return 1e-3;
  if (unit == "m") return 1.0;
  if (unit == "cm") return 1e-2;
  if (unit == "in") return 0.0254;
  if (unit == "ft") return 0.3048;
  return std::nullopt;
}

// The canonical name of a unit word from a header ("Millimeters" -> "mm"), or "".
std::string length_word(const std::string& w) {
  if (w == "mm" || w == "millimeter" || w == "millimeters" || w == "millimetre" || w == "millimetres") return "mm";
  if (w == "m" || w == "meter" || w == "meters" || w == "metre" || w == "metres") return "m";
  if (w == "cm" || w == "centimeter" || w == "centimeters" || w == "centimetre" || w == "centimetres") return "cm";
  if (w == "in" || w == "inch" || w == "inches") return "in";
  if (w == "ft" || w == "foot" || w == "feet") return "ft";
  return "";
}
std::string angle_word(const std::string& w) {
  if (w == "deg" || w == "degree" || w == "degrees") return "deg";
  if (w == "rad" || w == "radian" || w == "radians") return "rad";
  return "";
}

std::vector<std::string> words_of(std::string_view text) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : text) {
    if (std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_') {
      cur += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    } else if (!cur.empty()) {
      out.push_back(cur);
      cur.clear();
    }
  }
  if (!cur.empty()) out.push_back(cur);
  return out;
}

// --- Time stamps: seconds, or a calendar date and time of day. ---

bool all_digits(std::string_view s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// "2026/11/25" or "2026-11-25" -> days since 1970-01-01 (proleptic Gregorian), nullopt otherwise.
std::optional<long> date_days(std::string_view s) {
  if (s.size() < 8 || s.size() > 10) return std::nullopt;
  const char sep = s[4];
  if (sep != '/' && sep != '-') return std::nullopt;
  const auto second = s.find(sep, 5);
  if (second == std::string_view::npos) return std::nullopt;
  const std::string_view ys = s.substr(0, 4), ms = s.substr(5, second - 5), ds = s.substr(second + 1);
  if (!all_digits(ys) || !all_digits(ms) || !all_digits(ds) || ms.size() > 2 || ds.size() > 2) return std::nullopt;
  long y = std::stol(std::string(ys));
  const long m = std::stol(std::string(ms));
  const long d = std::stol(std::string(ds));
  if (m < 1 || m > 12 || d < 1 || d > 31) return std::nullopt;
  // Days from the civil date (H. Hinnant's well-known algorithm, written from its description).
  y -= m <= 2 ? 1 : 0;
  const long era = (y >= 0 ? y : y - 399) / 400;
  const long yoe = y - era * 400;
  const long doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const long doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + doe - 719468;
}

// "10:31:02.123" -> seconds into the day.
std::optional<double> time_of_day(std::string_view s) {
  const auto c1 = s.find(':');
  if (c1 == std::string_view::npos) return std::nullopt;
  const auto c2 = s.find(':', c1 + 1);
  if (c2 == std::string_view::npos) return std::nullopt;
  const std::string_view hs = s.substr(0, c1), ms = s.substr(c1 + 1, c2 - c1 - 1), ss = s.substr(c2 + 1);
  if (!all_digits(hs) || !all_digits(ms) || hs.size() > 2 || ms.size() != 2) return std::nullopt;
  const auto sec = parse_double(ss);
  if (!sec || ss.empty() || ss[0] < '0' || ss[0] > '9') return std::nullopt;
  const long h = std::stol(std::string(hs));
  const long mi = std::stol(std::string(ms));
  if (h > 23 || mi > 59 || *sec < 0.0 || *sec >= 61.0) return std::nullopt;
  return static_cast<double>(h * 3600 + mi * 60) + *sec;
}

// A date and time ("2026/11/25 10:31:02.5", "2026-11-25T10:31:02.5") -> seconds since 1970.
std::optional<double> date_time(std::string_view s) {
  auto split = s.find_first_of(" T");
  if (split == std::string_view::npos) return std::nullopt;
  const auto days = date_days(s.substr(0, split));
  const auto tod = time_of_day(trim_view(s.substr(split + 1)));
  if (!days || !tod) return std::nullopt;
  return static_cast<double>(*days) * 86400.0 + *tod;
}

// A line's fields: comma separated when it holds a comma, else blank separated; a date followed by a
// time of day is one field.
std::vector<std::string> fields_of(std::string_view line) {
  std::vector<std::string> raw;
  if (line.find(',') != std::string_view::npos) {
    for_each_csv_cell(line, [&raw](std::string_view cell) { raw.emplace_back(cell); });
    return raw;
  }
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    if (i >= line.size()) break;
    std::size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t') ++j;
    raw.emplace_back(line.substr(i, j - i));
    i = j;
  }
  std::vector<std::string> out;
  for (std::size_t k = 0; k < raw.size(); ++k) {
    if (k + 1 < raw.size() && date_days(raw[k]) && time_of_day(raw[k + 1])) {
      out.push_back(raw[k] + " " + raw[k + 1]);
      ++k;
    } else {
      out.push_back(raw[k]);
    }
  }
  return out;
}

// --- SA column layouts. ---

enum class Col { kName, kX, kY, kZ, kR, kAzimuth, kZenith, kElevation, kTime, kIgnored };

struct Layout {
  std::vector<Col> cols;
  std::vector<std::string> names;  // as given, for messages
  std::string coordinates;         // "cartesian", "cylindrical", "spherical"
};

std::optional<Col> column_kind(const std::string& w) {
  if (w == "collection" || w == "group" || w == "target" || w == "name" || w == "point") return Col::kName;
  if (w == "x") return Col::kX;
  if (w == "y") return Col::kY;
  if (w == "z") return Col::kZ;
  if (w == "r" || w == "d" || w == "distance" || w == "radius") return Col::kR;
  if (w == "theta" || w == "az" || w == "azimuth") return Col::kAzimuth;
  if (w == "phi" || w == "zenith" || w == "zen") return Col::kZenith;
  if (w == "el" || w == "elevation") return Col::kElevation;
  if (w == "time" || w == "t" || w == "timestamp" || w == "time_stamp") return Col::kTime;
  if (w == "ux" || w == "uy" || w == "uz" || w == "u" || w == "tol" || w == "tolerance" || w == "uncertainty" ||
      w == "skip" || w == "comment") {
    return Col::kIgnored;
  }
  return std::nullopt;
}

[[noreturn]] void fail_at(const std::string& source, int line, const std::string& message) {
  if (line > 0) throw DataError(fmt::format("{}:{}: {}", source, line, message));
  throw DataError(fmt::format("{}: {}", source, message));
}

Layout parse_layout(const std::string& text, const std::string& source, int line, const char* where) {
  Layout l;
  for (const auto& w : words_of(text)) {
    const auto kind = column_kind(w);
    if (!kind) {
      fail_at(source, line,
              fmt::format("{}: unknown column '{}' (names: collection group target, x y z, r theta z, r theta phi "
                          "or r az el, time, and ux uy uz tol skip for columns to leave out)",
                          where, w));
    }
    l.cols.push_back(*kind);
    l.names.push_back(w);
  }
  auto count = [&](Col c) { return std::count(l.cols.begin(), l.cols.end(), c); };
  const auto nx = count(Col::kX), ny = count(Col::kY), nz = count(Col::kZ), nr = count(Col::kR);
  const auto na = count(Col::kAzimuth), nzen = count(Col::kZenith), nel = count(Col::kElevation);
  if (nx == 1 && ny == 1 && nz == 1 && nr + na + nzen + nel == 0) {
    l.coordinates = "cartesian";
  } else if (nr == 1 && na == 1 && nz == 1 && nx + ny + nzen + nel == 0) {
    l.coordinates = "cylindrical";
  } else if (nr == 1 && na == 1 && nzen + nel == 1 && nx + ny + nz == 0) {
    l.coordinates = "spherical";
  } else {
    fail_at(source, line,
            fmt::format("{} '{}' name no single coordinate system: give x y z (Cartesian), r theta z (cylindrical) "
                        "or r theta phi / r az el (spherical), once each",
                        where, text));
  }
  if (count(Col::kTime) > 1 || count(Col::kName) > 3) {
    fail_at(source, line, fmt::format("{} '{}': at most three name columns and one time column", where, text));
  }
  return l;
}

struct Header {
  std::string version, frame, coordinates, length_unit, angle_unit, columns;
  int coordinates_line = 0, columns_line = 0, frame_line = 0, unit_line = 0;
};

bool any_word(const std::vector<std::string>& words, std::initializer_list<const char*> wanted) {
  return std::any_of(words.begin(), words.end(), [&](const std::string& w) {
    return std::any_of(wanted.begin(), wanted.end(), [&](const char* k) { return w == k; });
  });
}

void read_coordinates(const std::vector<std::string>& words, int line, const std::string& source, Header& h) {
  for (const char* system : {"cartesian", "cylindrical", "spherical"}) {
    if (!any_word(words, {system})) continue;
    if (!h.coordinates.empty() && h.coordinates != system) {
      fail_at(source, line,
              fmt::format("mixed coordinate types: this comment names {} coordinates, line {} named {}", system,
                          h.coordinates_line, h.coordinates));
    }
    h.coordinates = system;
    h.coordinates_line = line;
  }
}

void read_units(const std::string& value, int line, const std::string& source, Header& h) {
  for (const auto& w : words_of(value)) {
    if (const auto lw = length_word(w); !lw.empty()) {
      if (!h.length_unit.empty() && h.length_unit != lw) {
        fail_at(source, line, fmt::format("two length units in the header ({} and {})", h.length_unit, lw));
      }
      h.length_unit = lw;
      h.unit_line = line;
    } else if (const auto aw = angle_word(w); !aw.empty()) {
      h.angle_unit = aw;
    }
  }
}

// A header comment as SA writes it, "LABEL: VALUE": the label alone says what the line is ("Working
// Frame", "Units", "Coordinate System", "Columns", "SA Version"), so the value - a frame named
// "Column C3" or "Test Unit in Bay 4" - may hold any word. A comment without a colon counts only when
// it is nothing but a coordinate system's name ("// Cartesian"); any other comment is a note.
void read_comment(std::string_view body, int line, const std::string& source, Header& h) {
  const auto colon = body.find(':');
  if (colon == std::string_view::npos) {
    const auto words = words_of(body);
    const bool only_system = !words.empty() && std::all_of(words.begin(), words.end(), [](const std::string& w) {
      return w == "cartesian" || w == "cylindrical" || w == "spherical" || w == "coordinate" || w == "coordinates" ||
             w == "system";
    });
    if (only_system) read_coordinates(words, line, source, h);
    return;
  }
  const auto label = words_of(body.substr(0, colon));
  const std::string value(trim_view(body.substr(colon + 1)));
  if (any_word(label, {"column", "columns"})) {
    h.columns = value;
    h.columns_line = line;
  } else if (any_word(label, {"version"})) {
    h.version = value;
  } else if (any_word(label, {"frame"})) {
    if (h.frame_line == 0) {
      h.frame = value;
      h.frame_line = line;
    }
  } else if (any_word(label, {"unit", "units"})) {
    read_units(value, line, source, h);
  } else if (any_word(label, {"coordinate", "coordinates"})) {
    read_coordinates(words_of(value), line, source, h);
  }
}

bool is_sa_number(const std::string& s) { return parse_double(s).has_value(); }

// The layout of a file that declares none: up to three text names, then x y z and, optionally, a
// calendar time stamp. Anything else could be read two ways and is refused.
Layout inferred_layout(const std::vector<std::string>& f, const std::string& source, int line) {
  Layout l;
  l.coordinates = "cartesian";
  std::size_t k = 0;
  while (k < f.size() && !is_sa_number(f[k]) && !date_time(f[k])) {
    l.cols.push_back(Col::kName);
    ++k;
  }
  const std::size_t numbers = f.size() - k;
  const bool dated = numbers >= 1 && date_time(f.back()).has_value();
  if (l.cols.size() <= 3 && numbers == (dated ? 4U : 3U)) {
    for (Col c : {Col::kX, Col::kY, Col::kZ}) l.cols.push_back(c);
    if (dated) l.cols.push_back(Col::kTime);
    return l;
  }
  fail_at(source, line,
          fmt::format("{} field(s) after {} name(s) and no '// Columns:' comment saying what they are: give the "
                      "columns with --sa-columns (e.g. \"target x y z time\"); only 'names, x y z' is read without",
                      numbers, l.cols.size()));
}

Vector3 to_cartesian(const Layout& l, const std::array<double, 4>& v, double length, double angle) {
  // v: [x or r, y or azimuth, z or zenith/elevation, unused]
  if (l.coordinates == "cartesian") return Vector3(v[0], v[1], v[2]) * length;
  if (l.coordinates == "cylindrical") {
    const double r = v[0] * length, a = v[1] * angle;
    return {r * std::cos(a), r * std::sin(a), v[2] * length};
  }
  const bool elevation = std::find(l.cols.begin(), l.cols.end(), Col::kElevation) != l.cols.end();
  const double r = v[0] * length, a = v[1] * angle;
  const double polar = elevation ? kPi / 2 - v[2] * angle : v[2] * angle;
  return {r * std::sin(polar) * std::cos(a), r * std::sin(polar) * std::sin(a), r * std::cos(polar)};
}

// Every coordinate within the length range deflex accepts (+-100 m), named by the field it came from:
// a file in millimetres read as metres puts a point 1.5 m away 1.5 km away instead.
void check_position(const TrackerPoint& p, const Layout& l, const std::array<std::size_t, 3>& field_of,
                    const TrackerFile& file, int unit_line, const std::string& source) {
  for (int axis = 0; axis < 3; ++axis) {
    const double c = p.p_m[axis];
    if (std::isfinite(c) && std::abs(c) <= range::kLengthM.max) continue;
    // The field that put the point there: x/y/z itself, the radius for the other axes of a polar form.
    const bool own = l.coordinates == "cartesian" || (l.coordinates == "cylindrical" && axis == 2);
    const std::size_t k = field_of[static_cast<std::size_t>(own ? axis : 0)];
    const std::string name = k < l.names.size() ? l.names[k] : std::string(1, own ? "xyz"[axis] : 'r');
    const std::string from =
        file.unit_from == "header" ? fmt::format("the header, line {}", unit_line) : "--tracker-units";
    fail_at(source, p.line,
            fmt::format("field {} ({}): the point lies {:g} m from the frame's origin along {}, outside {:g}..{:g} m "
                        "(the length range deflex accepts): is the file in another unit than {} ({})?",
                        k + 1, name, c, "xyz"[axis], range::kLengthM.min, range::kLengthM.max, file.length_unit, from));
  }
}

// One point of an SA export from its fields in the file's layout: names joined with "::", the time
// (seconds or a date and time), the position in m, checked against the length range.
TrackerPoint read_point(const std::vector<std::string>& f, int line, const Layout& l, double length, double angle,
                        const TrackerFile& file, int unit_line, const std::string& source) {
  TrackerPoint p;
  p.line = line;
  std::array<double, 4> v{kNaN, kNaN, kNaN, 0.0};
  std::array<std::size_t, 3> field_of{};  // the field each of v[0..2] came from
  for (std::size_t k = 0; k < f.size(); ++k) {
    const Col c = l.cols[k];
    const std::string col_name = k < l.names.size() ? l.names[k] : fmt::format("field {}", k + 1);
    if (c == Col::kName) {
      if (f[k].empty()) fail_at(source, line, fmt::format("field {} (a name) is empty", k + 1));
      p.name += (p.name.empty() ? "" : "::") + f[k];
      continue;
    }
    if (c == Col::kIgnored) continue;
    if (c == Col::kTime) {
      if (const auto dt = date_time(f[k])) {
        p.t_s = *dt;
        continue;
      }
    }
    const auto value = parse_double(f[k]);
    if (!value) {
      fail_at(source, line,
              fmt::format("field {} ({}): {}", k + 1, col_name,
                          c == Col::kTime ? fmt::format("'{}' is neither seconds nor a date and time", f[k])
                                          : not_a_number(f[k])));
    }
    switch (c) {
      case Col::kX:
      case Col::kR:
        v[0] = *value;
        field_of[0] = k;
        break;
      case Col::kY:
      case Col::kAzimuth:
        v[1] = *value;
        field_of[1] = k;
        break;
      case Col::kZ:
        if (l.coordinates == "cartesian" || l.coordinates == "cylindrical") {
          v[2] = *value;
          field_of[2] = k;
        }
        break;
      case Col::kZenith:
      case Col::kElevation:
        v[2] = *value;
        field_of[2] = k;
        break;
      case Col::kTime:
        p.t_s = *value;
        break;
      default:
        break;
    }
  }
  p.p_m = to_cartesian(l, v, length, angle);
  check_position(p, l, field_of, file, unit_line, source);
  return p;
}

// NOLINTNEXTLINE(readability-function-size): listed in docs/architecture.md, "Functions over 80 lines"
TrackerFile parse_sa(const std::string& text, const std::string& source, const TrackerReadOptions& options) {
  TrackerFile out;
  out.source = source;
  out.format = "sa";
  Header h;
  std::optional<Layout> layout;
  std::size_t expected_fields = 0;
  int first_data_line = 0;
  double length = 0.0, angle = 0.0;
  int line_no = 0;
  std::size_t pos = 0;
  auto settle_layout = [&](const std::vector<std::string>& f, int line) {
    if (!options.columns.empty()) {
      layout = parse_layout(options.columns, source, 0, "option --sa-columns");
    } else if (!h.columns.empty()) {
      layout = parse_layout(h.columns, source, h.columns_line, "the '// Columns:' comment");
    } else {
      layout = inferred_layout(f, source, line);
    }
    if (!h.coordinates.empty() && h.coordinates != layout->coordinates) {
      fail_at(source, line,
              fmt::format("mixed coordinate types: the header (line {}) says {} coordinates, the columns are {}",
                          h.coordinates_line, h.coordinates, layout->coordinates));
    }
    // The length unit: from the header or the option, never guessed; both must agree.
    if (!options.length_unit.empty() && !length_scale(options.length_unit)) {
      throw InputError(
          fmt::format("option --tracker-units: '{}' is not one of mm, m, cm, in, ft", options.length_unit));
    }
    if (!h.length_unit.empty() && !options.length_unit.empty() && h.length_unit != options.length_unit) {
      fail_at(source, h.unit_line,
              fmt::format("the header says {} and --tracker-units says {}: which is it?", h.length_unit,
                          options.length_unit));
    }
    out.length_unit = !h.length_unit.empty() ? h.length_unit : options.length_unit;
    out.unit_from = !h.length_unit.empty() ? "header" : "option";
    if (out.length_unit.empty()) {
      fail_at(source, 0,
              "the header names no length unit (no '// Units: Millimeters' comment): give the file's unit with "
              "--tracker-units mm|m|cm|in|ft");
    }
    length = *length_scale(out.length_unit);
    if (layout->coordinates != "cartesian") {
      std::string au = !h.angle_unit.empty() ? h.angle_unit : options.angle_unit;
      if (!h.angle_unit.empty() && !options.angle_unit.empty() && h.angle_unit != options.angle_unit) {
        fail_at(source, h.unit_line,
                fmt::format("the header says {} and --tracker-angle-units says {}", h.angle_unit, options.angle_unit));
      }
      if (au.empty()) {
        fail_at(source, 0,
                fmt::format("{} coordinates and no angle unit in the header: give --tracker-angle-units deg|rad",
                            layout->coordinates));
      }
      if (au != "deg" && au != "rad") {
        throw InputError(fmt::format("option --tracker-angle-units: '{}' is not deg or rad", au));
      }
      angle = au == "deg" ? kPi / 180.0 : 1.0;
    }
    out.coordinates = layout->coordinates;
    out.has_time = std::find(layout->cols.begin(), layout->cols.end(), Col::kTime) != layout->cols.end();
    out.has_names = std::find(layout->cols.begin(), layout->cols.end(), Col::kName) != layout->cols.end();
    expected_fields = layout->cols.size();
    first_data_line = line;
    if (!options.expect_frame.empty() && !h.frame.empty() && h.frame != options.expect_frame) {
      fail_at(source, h.frame_line,
              fmt::format("the working frame is '{}', not the expected '{}' (the points would be in another frame)",
                          h.frame, options.expect_frame));
    }
  };

  while (pos <= text.size()) {
    auto end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    std::string_view raw(text.data() + pos, end - pos);
    pos = end + 1;
    ++line_no;
    if (!raw.empty() && raw.back() == '\r') raw.remove_suffix(1);
    const std::string_view line = trim_view(raw);
    if (line.empty()) {
      if (end == text.size()) break;
      continue;
    }
    if (line.rfind("//", 0) == 0) {
      if (layout) fail_at(source, line_no, "a '//' comment after the first point (two exports run together?)");
      read_comment(line.substr(2), line_no, source, h);
      continue;
    }
    const std::vector<std::string> f = fields_of(line);
    if (!layout) settle_layout(f, line_no);
    if (f.size() != expected_fields) {
      fail_at(source, line_no,
              fmt::format("{} field(s) where the layout ({}) has {} (line {} had {})", f.size(),
                          options.columns.empty() && h.columns.empty() ? "inferred from the first point" : "declared",
                          expected_fields, first_data_line, expected_fields));
    }
    out.points.push_back(read_point(f, line_no, *layout, length, angle, out, h.unit_line, source));
    if (end == text.size()) break;
  }
  if (out.points.empty()) fail_at(source, 0, "no points (only comments or blank lines)");
  out.frame = h.frame;
  out.version = h.version;
  return out;
}

// The first of `names` the table has, or "".
std::string first_of(const CsvTable& table, std::initializer_list<const char*> names) {
  for (const char* n : names) {
    if (table.has(n)) return n;
  }
  return "";
}

TrackerFile parse_csv(const std::string& text, const std::string& source, const TrackerReadOptions& options) {
  // Only these columns are read; any other - a point's name, a note, a tracker's status - is left
  // out, text or number (docs/evaluation.md).
  const CsvTable table = CsvTable::parse(text, source, {"t_s", "x_mm", "y_mm", "z_mm", "x_m", "y_m", "z_m"});
  TrackerFile out;
  out.source = source;
  out.format = "csv";
  out.coordinates = "cartesian";
  out.unit_from = "column names";
  const std::string mm = first_of(table, {"x_mm", "y_mm", "z_mm"});
  const std::string m = first_of(table, {"x_m", "y_m", "z_m"});
  if (!mm.empty() && !m.empty()) {
    throw DataError(fmt::format("{}: columns '{}' and '{}': positions in two units; keep one", source, mm, m));
  }
  if (mm.empty() && m.empty()) {
    std::string have;
    for (const auto& c : table.columns()) have += (have.empty() ? "" : ", ") + c;
    throw DataError(
        fmt::format("{}: no position columns with a unit in their name: give x_mm,y_mm,z_mm or "
                    "x_m,y_m,z_m (have: {})",
                    source, have));
  }
  const std::string suffix = !mm.empty() ? "_mm" : "_m";
  table.require({"x" + suffix, "y" + suffix, "z" + suffix});
  out.length_unit = !mm.empty() ? "mm" : "m";
  if (!options.length_unit.empty() && options.length_unit != out.length_unit) {
    throw DataError(fmt::format("{}: the columns are in {} and --tracker-units says {}", source, out.length_unit,
                                options.length_unit));
  }
  const double scale = !mm.empty() ? 1e-3 : 1.0;
  const std::size_t cx = table.column("x" + suffix), cy = table.column("y" + suffix), cz = table.column("z" + suffix);
  out.has_time = table.has("t_s");
  const std::size_t ct = out.has_time ? table.column("t_s") : 0;
  if (table.rows() == 0) throw DataError(fmt::format("{}: no samples (only a header row)", source));
  out.points.reserve(table.rows());
  for (std::size_t r = 0; r < table.rows(); ++r) {
    TrackerPoint p;
    p.line = table.line_of(r);
    p.t_s = out.has_time ? table.at(r, ct) : kNaN;
    // A tracker stamps its samples in order: a stamp before the previous one means rows out of order
    // or two runs in one file (a repeated stamp is allowed: a tracker may stamp two samples alike).
    if (r > 0 && out.has_time && p.t_s < out.points.back().t_s) {
      table.fail(r, "t_s",
                 fmt::format("time goes backwards ({} s after {} s on line {})", number_text(p.t_s),
                             number_text(out.points.back().t_s), out.points.back().line));
    }
    p.p_m = Vector3(table.at(r, cx), table.at(r, cy), table.at(r, cz)) * scale;
    out.points.push_back(std::move(p));
  }
  return out;
}

// CSV when the first line (after '#' comments) names a unit-named column (split at commas, semicolons,
// tabs or blanks, so a CSV with the wrong separator still reaches the CSV reader and its message);
// an SA export when it is a '//' comment; otherwise by the file's extension (.csv: CSV).
bool looks_like_csv(const std::string& text, const std::string& source) {
  std::size_t pos = 0;
  while (pos < text.size()) {
    auto end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    const std::string_view line = trim_view(std::string_view(text).substr(pos, end - pos));
    pos = end + 1;
    if (line.empty() || line[0] == '#') continue;
    if (line.rfind("//", 0) == 0) return false;
    std::string cell;
    for (std::size_t i = 0; i <= line.size(); ++i) {
      const char ch = i < line.size() ? line[i] : ',';
      if (ch == ',' || ch == ';' || ch == '\t' || ch == ' ') {
        if (cell == "t_s" || cell == "x_mm" || cell == "x_m" || cell == "y_mm" || cell == "y_m") return true;
        cell.clear();
      } else {
        cell += ch;
      }
    }
    break;
  }
  const std::string ext = ".csv";
  return source.size() >= ext.size() && lower(source.substr(source.size() - ext.size())) == ext;
}

bool has_control(const std::string& s) {
  return std::any_of(s.begin(), s.end(), [](char c) { return static_cast<unsigned char>(c) < 0x20 || c == 0x7F; });
}

// Names written as they will be read back: a frame on its comment line, trimmed; a collection and a
// group each one field of a line split at blanks or commas.
void check_export_names(const SaExportOptions& o) {
  if (has_control(o.frame) || trim_view(o.frame).size() != o.frame.size() || invalid_utf8_at(o.frame)) {
    throw InputError(fmt::format(
        "SA export: working frame '{}': a line break, a control character, blanks at its ends or bytes that are "
        "not UTF-8 would not read back as the same name",
        o.frame));
  }
  for (const auto& [what, name] : {std::pair{"collection", &o.collection}, std::pair{"group", &o.group}}) {
    if (name->empty() || has_control(*name) || name->find_first_of(" \t,") != std::string::npos ||
        invalid_utf8_at(*name) || name->rfind("//", 0) == 0) {
      throw InputError(fmt::format(
          "SA export: {} name '{}': must be one word (no blank, comma or control character, not empty) to read "
          "back as one field",
          what, *name));
    }
  }
}

}  // namespace

TrackerFile parse_tracker_file(const std::string& text, const std::string& source, const TrackerReadOptions& options) {
  std::string body = text;
  if (body.rfind("\xEF\xBB\xBF", 0) == 0) body.erase(0, 3);
  // SA on Windows exports in the ANSI code page: a frame "Caf\xE9" would reach the frame file as U+FFFD
  // and no longer match the tracker's own files. One decoding for every reader of tracker files.
  const bool windows1252 = invalid_utf8_at(body).has_value();
  if (windows1252) body = windows1252_to_utf8(body);
  TrackerFile f = looks_like_csv(body, source) ? parse_csv(body, source, options) : parse_sa(body, source, options);
  if (windows1252) f.encoding = "windows-1252";
  if (!options.expect_frame.empty() && f.frame.empty() && f.format == "sa") {
    // A file that names no frame cannot be checked against the expected one; say so rather than pass.
    throw DataError(
        fmt::format("{}: the header names no working frame, and '{}' was expected (export with the SA "
                    "version and frame comments, or leave out --expect-frame)",
                    source, options.expect_frame));
  }
  return f;
}

TrackerFile read_tracker_file(const std::string& path, const TrackerReadOptions& options) {
  return parse_tracker_file(read_input_file(path, InputKind::kCsvTable), path, options);
}

TrackerTrace timed_trace(const TrackerFile& file, const std::string& what) {
  if (!file.has_time) {
    throw DataError(
        fmt::format("{}: {} needs time stamps and the points have none{}", file.source, what,
                    file.format == "sa" ? " (export with time stamps, or name a time column)" : " (no t_s column)"));
  }
  TrackerTrace trace;
  trace.reserve(file.points.size());
  for (std::size_t i = 0; i < file.points.size(); ++i) {
    const TrackerPoint& p = file.points[i];
    if (!std::isfinite(p.t_s)) {
      throw DataError(fmt::format("{}:{}: {} needs a time stamp on every point", file.source, p.line, what));
    }
    if (i > 0 && !(p.t_s > file.points[i - 1].t_s)) {
      throw DataError(fmt::format("{}:{}: time stamp {} s {} line {}'s ({} s): {} needs increasing stamps", file.source,
                                  p.line, number_text(p.t_s),
                                  p.t_s == file.points[i - 1].t_s ? "repeats" : "goes back from",
                                  file.points[i - 1].line, number_text(file.points[i - 1].t_s), what));
    }
    trace.push_back({p.t_s, p.p_m});
  }
  return trace;
}

TrackerTrace untimed_trace(const TrackerFile& file) {
  TrackerTrace trace;
  trace.reserve(file.points.size());
  for (const auto& p : file.points) trace.push_back({std::isfinite(p.t_s) ? p.t_s : 0.0, p.p_m});
  return trace;
}

void write_sa_export(const TrackerTrace& trace, OutputFile& out, const SaExportOptions& o) {
  check_export_names(o);
  const char* sep = o.comma ? "," : " ";
  std::string text;
  text += "// SA Version: written by deflex (Spatial Analyzer ASCII point export layout)\n";
  text += fmt::format("// Working Frame: {}\n", o.frame);
  text += "// Units: Millimeters\n";
  text += "// Coordinate System: Cartesian\n";
  text += fmt::format("// Columns: Collection{0}Group{0}Target{0}X{0}Y{0}Z{1}\n", sep,
                      o.time ? fmt::format("{}Time", sep) : "");
  out.write(text);
  std::string line;
  for (std::size_t i = 0; i < trace.size(); ++i) {
    line.clear();
    const Vector3 mm = trace[i].p_m * 1e3;
    fmt::format_to(std::back_inserter(line), "{1}{0}{2}{0}P{3:06d}", sep, o.collection, o.group, i + 1);
    for (int k = 0; k < 3; ++k) {
      if (o.scientific) {
        fmt::format_to(std::back_inserter(line), "{}{:.16e}", sep, mm[k]);
      } else {
        fmt::format_to(std::back_inserter(line), "{}{:.6f}", sep, mm[k]);
      }
    }
    if (o.time) fmt::format_to(std::back_inserter(line), "{}{:.6f}", sep, trace[i].t_s);
    line += '\n';
    out.write(line);
  }
}

void write_sa_export(const TrackerTrace& trace, const std::string& path, const SaExportOptions& options) {
  OutputFile out(path, "tracker export");
  write_sa_export(trace, out, options);
  out.commit();
}

}  // namespace deflex
