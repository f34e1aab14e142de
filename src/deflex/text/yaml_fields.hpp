// Reading YAML configuration with errors that name the file, the line and the field. Every deflex
// YAML reader (robot, sensor, case files) goes through these, so messages look the same everywhere.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "deflex/text/input_file.hpp"
#include "deflex/text/input_ranges.hpp"

// yaml-cpp's node, declared only: a file that includes this header does not parse yaml-cpp's (those
// that call node() include <yaml-cpp/yaml.h> themselves).
namespace YAML {
class Node;
}  // namespace YAML

namespace deflex::yaml {

/// A YAML node with the file it came from and its dotted path, for error messages.
/// Thread safety: one thread at a time, counting every Field of one document as one: copies share
/// yaml-cpp's nodes, whose const reads are not safe from two threads at once.
class Field {
 public:
  Field(const YAML::Node& node, std::string file, std::string path);

  /// Parses a whole file (input_file.hpp: a regular file within the limit of `kind`); throws ModelError
  /// "FILE: cannot read" or "FILE:LINE: YAML syntax error", and "FILE:LINE:COL: field 'a.b': key given
  /// twice" for a key repeated in a map (yaml-cpp would silently keep the first). A UTF-8 BOM is dropped.
  static Field load_file(const std::string& path, InputKind kind = InputKind::kConfig);
  /// Parses text; `source` names it in messages.
  static Field load_string(const std::string& text, const std::string& source);

  [[nodiscard]] bool has(const std::string& key) const;
  /// Child that must exist. Throws ModelError "FILE:LINE: field 'a.b': missing".
  [[nodiscard]] Field at(const std::string& key) const;
  /// Child by index of a sequence.
  [[nodiscard]] Field at(std::size_t index) const;
  [[nodiscard]] std::size_t size() const;
  [[nodiscard]] bool is_sequence() const;
  [[nodiscard]] bool is_map() const;

  [[nodiscard]] double as_double() const;  ///< finite number within +-1e12, else ModelError
  /// The number times `scale` (the file's unit to the range's unit), checked against `r`:
  /// "FILE:LINE: field 'F': 1e+308 Nm/rad is outside 100..1e+10 Nm/rad (...)".
  [[nodiscard]] double as_in(const InputRange& r, double scale = 1.0) const;
  [[nodiscard]] std::vector<double> as_doubles_in(const InputRange& r, std::size_t expected_size = 0,
                                                  double scale = 1.0) const;
  /// as_in() of a key, or `fallback` when the key is absent.
  [[nodiscard]] double get_in(const std::string& key, double fallback, const InputRange& r) const;
  [[nodiscard]] int as_int() const;
  [[nodiscard]] bool as_bool() const;
  [[nodiscard]] std::string as_string() const;
  [[nodiscard]] std::vector<double> as_doubles(std::size_t expected_size = 0) const;  ///< 0: any size
  [[nodiscard]] Eigen::Vector3d as_vector3() const;

  double get(const std::string& key, double fallback) const;
  int get(const std::string& key, int fallback) const;
  bool get(const std::string& key, bool fallback) const;
  std::string get(const std::string& key, const std::string& fallback) const;

  /// Fails on any key of this map not in `allowed` (catches typos like 'stifness').
  void only_keys(const std::vector<std::string>& allowed) const;

  /// Throws ModelError "FILE:LINE: field 'PATH': MESSAGE".
  [[noreturn]] void fail(const std::string& message) const;

  [[nodiscard]] const std::string& file() const { return file_; }
  [[nodiscard]] const std::string& path() const { return path_; }
  [[nodiscard]] int line() const;  ///< 1-based, 0 if unknown
  [[nodiscard]] const YAML::Node& node() const { return *node_; }

 private:
  std::shared_ptr<const YAML::Node> node_;  // never null; copies of a Field share it as YAML::Node copies do
  std::string file_;
  std::string path_;
};

/// `text` as a double-quoted YAML scalar written by yaml-cpp's emitter (quotes, backslashes and
/// control characters escaped), so any name or note reads back as it was.
[[nodiscard]] std::string scalar_text(const std::string& text);

/// A pose written as {position: [x, y, z], quaternion_wxyz: [w, x, y, z]} or
/// {position: [...], rpy: [roll, pitch, yaw]} (fixed-axis X-Y-Z, i.e. R = Rz(yaw) Ry(pitch) Rx(roll)).
/// `length_scale` converts the file's length unit to m, `angle_scale` its angle unit to rad.
Eigen::Isometry3d parse_pose(const Field& f, double length_scale, double angle_scale);

}  // namespace deflex::yaml
