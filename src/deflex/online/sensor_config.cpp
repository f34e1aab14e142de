// Reading and writing the force sensor's YAML configuration.
#include "deflex/online/sensor_config.hpp"

#include <cmath>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"
#include "deflex/text/input_ranges.hpp"
#include "deflex/text/yaml_fields.hpp"

namespace deflex {

void SensorConfig::validate() const {
  const auto fail = [this](const std::string& what) {
    throw InputError(fmt::format("{}: sensor configuration: {}", source, what));
  };
  if (components != 3 && components != 6) {
    fail("components must be 3 or 6");
  }
  if (!crosstalk.allFinite() || std::abs(crosstalk.determinant()) < 1e-12) {
    fail("crosstalk matrix must be finite and invertible");
  }
  if (!flange_T_sensor.matrix().allFinite() || !bias_sensor.allFinite() || !payload_cog_sensor_m.allFinite() ||
      !gravity_base_m_s2.allFinite()) {
    fail("non-finite pose, bias, centre of gravity or gravity");
  }
  if (const auto bad = range_violation(payload_mass_kg, range::kMassKg)) {
    fail("payload mass: " + *bad);
  }
  for (int i = 0; i < 3; ++i) {
    if (const auto bad = range_violation(payload_cog_sensor_m[i], {"centre of gravity", "m", -10.0, 10.0})) {
      fail("payload centre of gravity: " + *bad);
    }
    if (const auto bad = range_violation(bias_sensor[i], range::kForceN)) {
      fail("force bias: " + *bad);
    }
  }
  if (!(sample_rate_hz > 0.0) || !std::isfinite(sample_rate_hz)) {
    fail("sample_rate_hz must be > 0");
  }
  if (!(lowpass_cutoff_hz > 0.0) || lowpass_cutoff_hz >= 0.5 * sample_rate_hz) {
    fail(fmt::format("low-pass cut-off {} Hz must be > 0 and below half the sample rate ({} Hz)", lowpass_cutoff_hz,
                     0.5 * sample_rate_hz));
  }
  if (lowpass_order < 1 || lowpass_order > 8) {
    fail("low-pass order must be 1..8");
  }
  if (!(dead_band_N >= 0.0) || !(dead_band_Nm >= 0.0) || !std::isfinite(dead_band_N) || !std::isfinite(dead_band_Nm)) {
    fail("dead band must be finite and >= 0");
  }
  if (!(fault_threshold_N > dead_band_N) || !(fault_threshold_Nm > dead_band_Nm)) {
    fail("fault threshold must be above the dead band");
  }
}

namespace {

Vector3 read_vector3(const yaml::Field& f) { return f.as_vector3(); }

}  // namespace

SensorConfig load_sensor_config_or_defaults(const std::string& yaml_path) {
  if (yaml_path.empty()) {
    SensorConfig c;
    c.source = "<default sensor: identity crosstalk, no payload, no bias>";
    return c;
  }
  return load_sensor_config(yaml_path);
}

namespace {

// The crosstalk matrix: a 3x3 or 6x6 list of rows, not singular.
void read_crosstalk(const yaml::Field& m, SensorConfig& c) {
  const std::size_t n = m.size();
  if (!m.is_sequence() || (n != 3 && n != 6)) {
    m.fail("must be a 3x3 or 6x6 matrix written as a list of rows");
  }
  c.crosstalk.setIdentity();
  for (std::size_t r = 0; r < n; ++r) {
    const std::vector<double> row = m.at(r).as_doubles(n);
    for (std::size_t k = 0; k < n; ++k) {
      c.crosstalk(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(k)) = row[k];
    }
  }
  if (std::abs(c.crosstalk.determinant()) < 1e-12) {
    m.fail("matrix is singular");
  }
}

// The conditioning the online cycle applies: the low-pass filter, the dead band, the fault threshold.
void read_conditioning(const yaml::Field& root, SensorConfig& c) {
  if (root.has("lowpass")) {
    const yaml::Field l = root.at("lowpass");
    l.only_keys({"cutoff_hz", "order"});
    c.lowpass_cutoff_hz = l.get("cutoff_hz", c.lowpass_cutoff_hz);
    c.lowpass_order = l.get("order", c.lowpass_order);
    if (c.lowpass_order < 1 || c.lowpass_order > 8) {
      l.at("order").fail("must be 1..8");
    }
    if (!(c.lowpass_cutoff_hz > 0.0) || c.lowpass_cutoff_hz >= 0.5 * c.sample_rate_hz) {
      l.at("cutoff_hz").fail(fmt::format("must be > 0 and below half the sample rate ({} Hz)", 0.5 * c.sample_rate_hz));
    }
  }
  if (root.has("dead_band")) {
    const yaml::Field d = root.at("dead_band");
    d.only_keys({"force_N", "moment_Nm"});
    c.dead_band_N = d.get("force_N", c.dead_band_N);
    c.dead_band_Nm = d.get("moment_Nm", c.dead_band_Nm);
    if (c.dead_band_N < 0.0 || c.dead_band_Nm < 0.0) {
      d.fail("must be >= 0");
    }
  }
  if (root.has("fault_threshold")) {
    const yaml::Field t = root.at("fault_threshold");
    t.only_keys({"force_N", "moment_Nm"});
    c.fault_threshold_N = t.get("force_N", c.fault_threshold_N);
    c.fault_threshold_Nm = t.get("moment_Nm", c.fault_threshold_Nm);
    if (!(c.fault_threshold_N > c.dead_band_N) || !(c.fault_threshold_Nm > c.dead_band_Nm)) {
      t.fail("must be above the dead band");
    }
  }
}

}  // namespace

SensorConfig load_sensor_config(const std::string& yaml_path) {
  const yaml::Field root = yaml::Field::load_file(yaml_path);
  root.only_keys({"deflex_sensor", "name", "components", "sample_rate_hz", "crosstalk", "flange_T_sensor_m_deg", "bias",
                  "payload", "gravity_base_m_s2", "lowpass", "dead_band", "fault_threshold"});
  SensorConfig c;
  c.source = yaml_path;
  c.name = root.get("name", c.name);
  c.components = root.get("components", c.components);
  if (c.components != 3 && c.components != 6) {
    root.at("components").fail("must be 3 or 6");
  }
  c.sample_rate_hz = root.get("sample_rate_hz", c.sample_rate_hz);
  if (root.has("crosstalk")) read_crosstalk(root.at("crosstalk"), c);
  if (root.has("flange_T_sensor_m_deg")) {
    c.flange_T_sensor = yaml::parse_pose(root.at("flange_T_sensor_m_deg"), 1.0, deg_to_rad(1.0));
  }
  if (root.has("bias")) {
    const yaml::Field b = root.at("bias");
    b.only_keys({"force_N", "moment_Nm"});
    if (b.has("force_N")) {
      c.bias_sensor.head<3>() = read_vector3(b.at("force_N"));
    }
    if (b.has("moment_Nm")) {
      c.bias_sensor.tail<3>() = read_vector3(b.at("moment_Nm"));
    }
  }
  if (root.has("payload")) {
    const yaml::Field p = root.at("payload");
    p.only_keys({"mass_kg", "cog_sensor_m"});
    c.payload_mass_kg = p.get("mass_kg", 0.0);
    if (c.payload_mass_kg < 0.0) {
      p.at("mass_kg").fail("must be >= 0");
    }
    if (p.has("cog_sensor_m")) {
      c.payload_cog_sensor_m = read_vector3(p.at("cog_sensor_m"));
    }
  }
  if (root.has("gravity_base_m_s2")) {
    c.gravity_base_m_s2 = read_vector3(root.at("gravity_base_m_s2"));
  }
  read_conditioning(root, c);
  if (c.components == 3) {
    // A 3-component sensor measures no moments: its bias moments are meaningless.
    c.bias_sensor.tail<3>().setZero();
  }
  c.validate();
  return c;
}

std::string sensor_config_to_yaml(const SensorConfig& c) {
  const auto v3 = [](const Vector3& v) { return fmt::format("[{:.9g}, {:.9g}, {:.9g}]", v.x(), v.y(), v.z()); };
  std::string out = "# deflex force-sensor configuration (docs/online.md). SI units; angles in degrees.\n";
  out += "deflex_sensor: 1\n";
  out += fmt::format("name: {}\ncomponents: {}\nsample_rate_hz: {:.9g}\n", yaml::scalar_text(c.name), c.components,
                     c.sample_rate_hz);
  const int n = c.components == 3 && c.crosstalk.block<3, 3>(0, 3).isZero() && c.crosstalk.block<3, 3>(3, 0).isZero() &&
                        c.crosstalk.block<3, 3>(3, 3).isIdentity()
                    ? 3
                    : 6;
  out += "crosstalk:\n";
  for (int r = 0; r < n; ++r) {
    out += "  - [";
    for (int k = 0; k < n; ++k) {
      out += fmt::format("{}{:.9g}", k == 0 ? "" : ", ", c.crosstalk(r, k));
    }
    out += "]\n";
  }
  const Eigen::Quaterniond q(c.flange_T_sensor.linear());
  out += fmt::format("flange_T_sensor_m_deg: {{position: {}, quaternion_wxyz: [{:.12g}, {:.12g}, {:.12g}, {:.12g}]}}\n",
                     v3(c.flange_T_sensor.translation()), q.w(), q.x(), q.y(), q.z());
  out +=
      fmt::format("bias: {{force_N: {}, moment_Nm: {}}}\n", v3(c.bias_sensor.head<3>()), v3(c.bias_sensor.tail<3>()));
  out += fmt::format("payload: {{mass_kg: {:.9g}, cog_sensor_m: {}}}\n", c.payload_mass_kg, v3(c.payload_cog_sensor_m));
  out += fmt::format("gravity_base_m_s2: {}\n", v3(c.gravity_base_m_s2));
  out += fmt::format("lowpass: {{cutoff_hz: {:.9g}, order: {}}}\n", c.lowpass_cutoff_hz, c.lowpass_order);
  out += fmt::format("dead_band: {{force_N: {:.9g}, moment_Nm: {:.9g}}}\n", c.dead_band_N, c.dead_band_Nm);
  out += fmt::format("fault_threshold: {{force_N: {:.9g}, moment_Nm: {:.9g}}}\n", c.fault_threshold_N,
                     c.fault_threshold_Nm);
  return out;
}

}  // namespace deflex
