// YAML field access with file, line and field in every error.
#include "deflex/text/yaml_fields.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string_view>
#include <utility>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "deflex/text/errors.hpp"
#include "deflex/text/input_file.hpp"
#include "deflex/text/nearest_name.hpp"
#include "deflex/text/parse_number.hpp"
#include "deflex/text/utf8_text.hpp"

namespace deflex::yaml {

Field::Field(const YAML::Node& node, std::string file, std::string path)
    : node_(std::make_shared<const YAML::Node>(node)), file_(std::move(file)), path_(std::move(path)) {}

bool Field::is_sequence() const { return node().IsSequence(); }
bool Field::is_map() const { return node().IsMap(); }

namespace {

std::string where_of(const std::string& file, const YAML::Mark& m) {
  return m.line >= 0 ? fmt::format("{}:{}:{}", file, m.line + 1, m.column + 1) : file;
}

// A tag ("!!str [1, 2]", "!pose {...}") would change what a value means in a YAML reader that honours
// it; yaml-cpp reads past it, so the value would mean something else here than the author meant.
// deflex's files have no use for tags: refused, naming it. "?" and "!" are yaml-cpp's marks of an
// untagged plain and quoted node.
void refuse_tag(const YAML::Node& node, const std::string& file, const std::string& path) {
  const std::string& tag = node.Tag();
  if (tag.empty() || tag == "?" || tag == "!") {
    return;
  }
  const std::string core = "tag:yaml.org,2002:";
  const std::string written = tag.rfind(core, 0) == 0 ? "!!" + tag.substr(core.size()) : tag;
  throw ModelError(fmt::format("{}: field '{}': a YAML tag ('{}'): deflex files take no tags; remove it",
                               where_of(file, node.Mark()), path.empty() ? "<document>" : path, written));
}

// yaml-cpp keeps both entries of a key given twice and answers lookups with the first, so a
// second value would be silently ignored: every map of the document is checked here.
void refuse_duplicate_keys(const YAML::Node& node, const std::string& file, const std::string& path, int depth,
                           std::size_t& visited) {
  // Aliases can make a small document a huge tree ("billion laughs"); no deflex file comes near this.
  if (++visited > 1000000) {
    throw ModelError(fmt::format("{}: more than a million YAML nodes (aliases expanding?)", file));
  }
  if (depth > 64) {
    throw ModelError(fmt::format("{}: field '{}': nested deeper than 64 levels", where_of(file, node.Mark()), path));
  }
  refuse_tag(node, file, path);
  if (node.IsScalar()) {
    // Names and notes go into JSON and YAML, which require UTF-8: a Latin-1 byte is named here.
    if (const auto bad = utf8_problem(node.Scalar())) {
      throw ModelError(
          fmt::format("{}: field '{}': {}", where_of(file, node.Mark()), path.empty() ? "<document>" : path, *bad));
    }
    return;
  }
  if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i) {
      refuse_duplicate_keys(node[i], file, fmt::format("{}[{}]", path, i + 1), depth + 1, visited);
    }
    return;
  }
  if (!node.IsMap()) {
    return;
  }
  std::vector<std::pair<std::string, YAML::Mark>> seen;
  for (const auto& kv : node) {
    if (!kv.first.IsScalar()) {
      throw ModelError(fmt::format("{}: field '{}': a key must be a plain name, not a list or a map ('? [a, b]')",
                                   where_of(file, kv.first.Mark()), path.empty() ? "<document>" : path));
    }
    refuse_tag(kv.first, file, path);
    const std::string key = kv.first.Scalar();
    if (const auto bad = utf8_problem(key)) {
      throw ModelError(fmt::format("{}: a key of field '{}': {}", where_of(file, kv.first.Mark()),
                                   path.empty() ? "<document>" : path, *bad));
    }
    const std::string child = path.empty() ? key : fmt::format("{}.{}", path, key);
    for (const auto& [k, mark] : seen) {
      if (k == key) {
        throw ModelError(fmt::format("{}: field '{}': key given twice (first at line {}); each key may appear once",
                                     where_of(file, kv.first.Mark()), child, mark.line + 1));
      }
    }
    seen.emplace_back(key, kv.first.Mark());
    refuse_duplicate_keys(kv.second, file, child, depth + 1, visited);
  }
}

}  // namespace

Field Field::load_file(const std::string& path, InputKind kind) {
  std::string text;
  try {
    text = read_input_file(path, kind);
  } catch (const DataError& e) {
    throw ModelError(e.what());
  }
  return load_string(text, path);
}

Field Field::load_string(const std::string& text, const std::string& source) {
  std::vector<YAML::Node> documents;
  try {
    documents = YAML::LoadAll(text.rfind("\xEF\xBB\xBF", 0) == 0 ? text.substr(3) : text);
  } catch (const YAML::ParserException& e) {
    throw ModelError(fmt::format("{}:{}: YAML syntax error: {}", source, e.mark.line + 1, e.msg));
  }
  // yaml-cpp's Load() would read the first document and drop any after a '---' silently.
  if (documents.size() > 1) {
    const YAML::Mark m = documents[1].Mark();
    throw ModelError(fmt::format("{}: a second YAML document (after '---'{}): a deflex file holds one document",
                                 m.line >= 0 ? fmt::format("{}:{}", source, m.line + 1) : source,
                                 m.line >= 0 ? "" : ", at the end"));
  }
  YAML::Node root = documents.empty() ? YAML::Node() : documents.front();
  std::size_t visited = 0;
  refuse_duplicate_keys(root, source, "", 0, visited);
  return Field(root, source, "");
}

std::string scalar_text(const std::string& text) {
  YAML::Emitter e;
  e << YAML::DoubleQuoted << text;
  return e.c_str();
}

int Field::line() const {
  const YAML::Mark m = node().Mark();
  return m.line >= 0 ? m.line + 1 : 0;
}

void Field::fail(const std::string& message) const {
  const int l = line();
  const std::string where = l > 0 ? fmt::format("{}:{}", file_, l) : file_;
  throw ModelError(fmt::format("{}: field '{}': {}", where, path_.empty() ? "<document>" : path_, message));
}

bool Field::has(const std::string& key) const {
  return node().IsMap() && node()[key].IsDefined() && !node()[key].IsNull();
}

Field Field::at(const std::string& key) const {
  const std::string child = path_.empty() ? key : path_ + "." + key;
  if (!node().IsMap()) {
    fail("expected a map with the key '" + key + "'");
  }
  YAML::Node n = node()[key];
  if (!n.IsDefined() || n.IsNull()) {
    const int l = line();
    const std::string where = l > 0 ? fmt::format("{}:{}", file_, l) : file_;
    throw ModelError(fmt::format("{}: field '{}': missing", where, child));
  }
  return Field(n, file_, child);
}

Field Field::at(std::size_t index) const {
  if (!node().IsSequence() || index >= node().size()) {
    fail(fmt::format("expected a list with at least {} entries", index + 1));
  }
  return Field(node()[index], file_, fmt::format("{}[{}]", path_, index + 1));
}

std::size_t Field::size() const { return node().IsSequence() || node().IsMap() ? node().size() : 0; }

double Field::as_double() const {
  if (!node().IsScalar()) {
    fail("expected a number");
  }
  const std::string& s = node().Scalar();
  const std::optional<double> v = parse_double(trim_view(s));
  if (!v) {
    fail(not_a_number(s));
  }
  // The key names its unit ("rate_Hz", "offset_um", "joint_stiffness_Nm_per_rad[2]"): its range applies.
  std::string_view key = path_;
  key = key.substr(key.rfind('.') == std::string_view::npos ? 0 : key.rfind('.') + 1);
  key = key.substr(0, key.find('['));
  if (const auto bad = range_violation(*v, range_for_name(key))) {
    fail(*bad);
  }
  return *v;
}

double Field::as_in(const InputRange& r, double scale) const {
  const double v = as_double();
  if (const auto bad = range_violation(v * scale, r)) {
    fail(scale == 1.0 ? *bad : fmt::format("{:g} in the file's unit: {}", v, *bad));
  }
  return v * scale;
}

double Field::get_in(const std::string& key, double fallback, const InputRange& r) const {
  return has(key) ? at(key).as_in(r) : fallback;
}

std::vector<double> Field::as_doubles_in(const InputRange& r, std::size_t expected_size, double scale) const {
  std::vector<double> out = as_doubles(expected_size);
  for (std::size_t i = 0; i < out.size(); ++i) {
    out[i] = at(i).as_in(r, scale);
  }
  return out;
}

int Field::as_int() const {
  const double v = as_double();
  if (v != std::floor(v) || std::abs(v) > 1e9) {
    fail(fmt::format("expected a whole number, got {:g}", v));
  }
  return static_cast<int>(v);
}

bool Field::as_bool() const {
  try {
    return node().as<bool>();
  } catch (const YAML::Exception&) {
    fail("expected true or false");
  }
}

std::string Field::as_string() const {
  if (!node().IsScalar()) {
    fail("expected a text value");
  }
  return node().Scalar();
}

std::vector<double> Field::as_doubles(std::size_t expected_size) const {
  if (!node().IsSequence()) {
    fail("expected a list of numbers");
  }
  if (expected_size != 0 && node().size() != expected_size) {
    fail(fmt::format("expected {} numbers, got {}", expected_size, node().size()));
  }
  std::vector<double> out;
  for (std::size_t i = 0; i < node().size(); ++i) {
    out.push_back(at(i).as_double());
  }
  return out;
}

Eigen::Vector3d Field::as_vector3() const {
  const auto v = as_doubles(3);
  return {v[0], v[1], v[2]};
}

double Field::get(const std::string& key, double fallback) const { return has(key) ? at(key).as_double() : fallback; }
int Field::get(const std::string& key, int fallback) const { return has(key) ? at(key).as_int() : fallback; }
bool Field::get(const std::string& key, bool fallback) const { return has(key) ? at(key).as_bool() : fallback; }
std::string Field::get(const std::string& key, const std::string& fallback) const {
  return has(key) ? at(key).as_string() : fallback;
}

void Field::only_keys(const std::vector<std::string>& allowed) const {
  if (!node().IsMap()) {
    fail("expected a map");
  }
  for (const auto& kv : node()) {
    const std::string key = kv.first.as<std::string>();
    if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
      Field(kv.first, file_, path_.empty() ? key : path_ + "." + key)
          .fail(
              fmt::format("unknown field{} (allowed here: {})", did_you_mean(key, allowed), fmt::join(allowed, ", ")));
    }
  }
}

Eigen::Isometry3d parse_pose(const Field& f, double length_scale, double angle_scale) {
  f.only_keys({"position", "quaternion_wxyz", "rpy"});
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  if (f.has("position")) {
    const auto p = f.at("position").as_doubles_in(range::kLengthM, 3, length_scale);
    pose.translation() = Eigen::Vector3d(p[0], p[1], p[2]);
  }
  if (f.has("quaternion_wxyz") && f.has("rpy")) {
    f.fail("give either quaternion_wxyz or rpy, not both");
  }
  if (f.has("quaternion_wxyz")) {
    const Field qf = f.at("quaternion_wxyz");
    const auto q = qf.as_doubles(4);
    Eigen::Quaterniond quat(q[0], q[1], q[2], q[3]);
    const double norm = quat.norm();
    if (std::abs(norm - 1.0) > 1e-3) {
      qf.fail(fmt::format("quaternion must have unit length, its norm is {:.6f}", norm));
    }
    pose.linear() = quat.normalized().toRotationMatrix();
  } else if (f.has("rpy")) {
    const auto r = f.at("rpy").as_doubles(3);
    pose.linear() = (Eigen::AngleAxisd(r[2] * angle_scale, Eigen::Vector3d::UnitZ()) *
                     Eigen::AngleAxisd(r[1] * angle_scale, Eigen::Vector3d::UnitY()) *
                     Eigen::AngleAxisd(r[0] * angle_scale, Eigen::Vector3d::UnitX()))
                        .toRotationMatrix();
  }
  return pose;
}

}  // namespace deflex::yaml
