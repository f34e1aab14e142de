// YAML field access with file, line and field in every error.
#include "deflex/model/yaml_fields.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "deflex/model/errors.hpp"

namespace deflex::yaml {

Field::Field(YAML::Node node, std::string file, std::string path)
    : node_(std::move(node)), file_(std::move(file)), path_(std::move(path)) {}

Field Field::load_file(const std::string& path) {
  try {
    return Field(YAML::LoadFile(path), path, "");
  } catch (const YAML::BadFile&) {
    throw ModelError(fmt::format("{}: cannot read the file", path));
  } catch (const YAML::ParserException& e) {
    throw ModelError(fmt::format("{}:{}: YAML syntax error: {}", path, e.mark.line + 1, e.msg));
  }
}

Field Field::load_string(const std::string& text, const std::string& source) {
  try {
    return Field(YAML::Load(text), source, "");
  } catch (const YAML::ParserException& e) {
    throw ModelError(fmt::format("{}:{}: YAML syntax error: {}", source, e.mark.line + 1, e.msg));
  }
}

int Field::line() const {
  const YAML::Mark m = node_.Mark();
  return m.line >= 0 ? m.line + 1 : 0;
}

void Field::fail(const std::string& message) const {
  const int l = line();
  const std::string where = l > 0 ? fmt::format("{}:{}", file_, l) : file_;
  throw ModelError(fmt::format("{}: field '{}': {}", where, path_.empty() ? "<document>" : path_, message));
}

bool Field::has(const std::string& key) const { return node_.IsMap() && node_[key].IsDefined() && !node_[key].IsNull(); }

Field Field::at(const std::string& key) const {
  const std::string child = path_.empty() ? key : path_ + "." + key;
  if (!node_.IsMap()) {
    fail("expected a map with the key '" + key + "'");
  }
  YAML::Node n = node_[key];
  if (!n.IsDefined() || n.IsNull()) {
    const int l = line();
    const std::string where = l > 0 ? fmt::format("{}:{}", file_, l) : file_;
    throw ModelError(fmt::format("{}: field '{}': missing", where, child));
  }
  return Field(n, file_, child);
}

Field Field::at(std::size_t index) const {
  if (!node_.IsSequence() || index >= node_.size()) {
    fail(fmt::format("expected a list with at least {} entries", index + 1));
  }
  return Field(node_[index], file_, fmt::format("{}[{}]", path_, index + 1));
}

std::size_t Field::size() const { return node_.IsSequence() || node_.IsMap() ? node_.size() : 0; }

double Field::as_double() const {
  if (!node_.IsScalar()) {
    fail("expected a number");
  }
  const std::string s = node_.Scalar();
  double v = 0.0;
  try {
    std::size_t used = 0;
    v = std::stod(s, &used);
    if (used != s.size()) {
      fail(fmt::format("'{}' is not a number", s));
    }
  } catch (const std::logic_error&) {
    fail(fmt::format("'{}' is not a number", s));
  }
  if (!std::isfinite(v)) {
    fail(fmt::format("'{}' is not a finite number", s));
  }
  return v;
}

int Field::as_int() const {
  const double v = as_double();
  if (v != std::floor(v) || std::abs(v) > 1e9) {
    fail(fmt::format("expected a whole number, got {}", v));
  }
  return static_cast<int>(v);
}

bool Field::as_bool() const {
  try {
    return node_.as<bool>();
  } catch (const YAML::Exception&) {
    fail("expected true or false");
  }
}

std::string Field::as_string() const {
  if (!node_.IsScalar()) {
    fail("expected a text value");
  }
  return node_.Scalar();
}

std::vector<double> Field::as_doubles(std::size_t expected_size) const {
  if (!node_.IsSequence()) {
    fail("expected a list of numbers");
  }
  if (expected_size != 0 && node_.size() != expected_size) {
    fail(fmt::format("expected {} numbers, got {}", expected_size, node_.size()));
  }
  std::vector<double> out;
  for (std::size_t i = 0; i < node_.size(); ++i) {
    out.push_back(at(i).as_double());
  }
  return out;
}

Vector3 Field::as_vector3() const {
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
  if (!node_.IsMap()) {
    fail("expected a map");
  }
  for (const auto& kv : node_) {
    const std::string key = kv.first.as<std::string>();
    if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
      Field(kv.first, file_, path_.empty() ? key : path_ + "." + key)
          .fail(fmt::format("unknown field (allowed here: {})", fmt::join(allowed, ", ")));
    }
  }
}

Pose parse_pose(const Field& f, double length_scale, double angle_scale) {
  f.only_keys({"position", "quaternion_wxyz", "rpy"});
  Pose pose = Pose::Identity();
  if (f.has("position")) {
    pose.translation() = f.at("position").as_vector3() * length_scale;
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
    pose.linear() = (Eigen::AngleAxisd(r[2] * angle_scale, Vector3::UnitZ()) *
                     Eigen::AngleAxisd(r[1] * angle_scale, Vector3::UnitY()) *
                     Eigen::AngleAxisd(r[0] * angle_scale, Vector3::UnitX()))
                        .toRotationMatrix();
  }
  return pose;
}

}  // namespace deflex::yaml
