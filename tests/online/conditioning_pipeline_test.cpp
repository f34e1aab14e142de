// Each conditioning stage against hand-made expectations (the whole pipeline against the recorded
// example signal is in tests/sensors/replayed_signal_test.cpp, beside the replay that reads it).
#include <cmath>

#include <gtest/gtest.h>

#include "deflex/online/force_pipeline.hpp"
#include "deflex/text/errors.hpp"
#include "support/allocation_guard.hpp"

namespace deflex {
namespace {

Matrix3 rot(double ax, double ay, double az) {
  return (Eigen::AngleAxisd(az, Vector3::UnitZ()) * Eigen::AngleAxisd(ay, Vector3::UnitY()) *
          Eigen::AngleAxisd(ax, Vector3::UnitX()))
      .toRotationMatrix();
}

SensorConfig plain_sensor() {
  SensorConfig c;
  c.components = 6;
  c.sample_rate_hz = 1000.0;
  c.fault_threshold_N = 3000.0;
  c.fault_threshold_Nm = 1000.0;
  return c;
}

TEST(ConditioningStages, CrosstalkAndBiasWorkInTheSensorFrame) {
  CrosstalkDecoupling x;
  x.matrix.topLeftCorner<3, 3>() << 1.0, 0.1, 0.0, -0.05, 1.0, 0.02, 0.0, 0.0, 0.98;
  Vector6 raw;
  raw << 10, 20, 30, 1, 2, 3;
  const Vector6 w = x.step(raw);
  EXPECT_NEAR(w[0], 10 + 2, 1e-12);
  EXPECT_NEAR(w[1], -0.5 + 20 + 0.6, 1e-12);
  EXPECT_NEAR(w[2], 29.4, 1e-12);
  EXPECT_NEAR(w[4], 2.0, 1e-12);
  BiasRemoval b;
  b.bias_sensor << 1, 1, 1, 0.5, 0.5, 0.5;
  EXPECT_NEAR(b.step(raw)[2], 29.0, 1e-12);
  EXPECT_NEAR(b.step(raw)[5], 2.5, 1e-12);
}

TEST(ConditioningStages, RotationGravityAndTransport) {
  // Sensor turned 90 degrees about base z: sensor x is base y.
  const Matrix3 R = rot(0, 0, std::acos(-1.0) / 2);
  Vector6 ws;
  ws << 5, 0, 0, 0, 0, 2;
  const Vector6 wb = RotationToBase::step(ws, R);
  EXPECT_NEAR(wb[1], 5.0, 1e-12);
  EXPECT_NEAR(wb[0], 0.0, 1e-12);
  EXPECT_NEAR(wb[5], 2.0, 1e-12);

  // Gravity: 10 kg with its centre 0.1 m along sensor x, sensor x along base y: weight (0,0,-98.1) N
  // at lever (0,0.1,0) m -> moment (0.1*-98.1, 0, 0) about the sensor origin.
  GravityCompensation g;
  g.mass_kg = 10.0;
  g.cog_sensor_m = Vector3(0.1, 0, 0);
  Vector6 weight_reading;
  weight_reading << 0, 0, -98.1, -9.81, 0, 0;
  EXPECT_LT(g.step(weight_reading, R).norm(), 1e-12);

  // Transport: a force (0,0,100) N acting at a point 0.2 m along sensor z reads, about the sensor
  // origin, moment p x F = 0 when parallel; with F along x: (0,0.2,0)... done by hand: p=(0,0,0.2),
  // F=(100,0,0) -> M = p x F = (0, 20, 0).
  WrenchTransport t;
  t.wap_sensor_m = Vector3(0, 0, 0.2);
  Vector6 at_sensor;
  at_sensor << 100, 0, 0, 0, 20, 0;
  const Vector6 at_wap = t.step(at_sensor, Matrix3::Identity());
  EXPECT_NEAR(at_wap.tail<3>().norm(), 0.0, 1e-12);
  EXPECT_NEAR(at_wap[0], 100.0, 1e-12);
}

TEST(ConditioningStages, DeadBandAndFault) {
  DeadBand d{5.0, 0.5};
  Vector6 w;
  w << 3, 0, -3, 0.1, 0.1, 0.1;  // |F| = 4.24 < 5
  EXPECT_TRUE(d.step(w));
  EXPECT_TRUE(w.isZero(0.0));
  w << 3, 4, 1, 1, 0, 0;
  EXPECT_FALSE(d.step(w));
  EXPECT_EQ(w[1], 4.0);
  FaultThreshold f{100.0, 10.0};
  w << 60, 80, 1, 0, 0, 0;  // |F| = 100.005
  EXPECT_TRUE(f.is_fault(w));
  w << 60, 79, 0, 0, 0, 9.9;
  EXPECT_FALSE(f.is_fault(w));
  w[2] = std::nan("");
  EXPECT_TRUE(f.is_fault(w));
}

TEST(ForcePipeline, PayloadWeightAloneConditionsToZeroAtAnyOrientation) {
  SensorConfig c = plain_sensor();
  c.payload_mass_kg = 12.0;
  c.payload_cog_sensor_m = Vector3(0.02, -0.01, 0.15);
  c.bias_sensor << 3, -2, 1, 0.3, 0.2, -0.1;
  ForcePipeline p(c);
  for (int i = 0; i < 20; ++i) {
    const Matrix3 R = rot(0.3 * i, -0.2 * i, 0.17 * i);
    // The reading a real sensor gives: weight in the sensor frame, its moment, plus the bias.
    const Vector3 f_s = R.transpose() * (12.0 * Vector3(0, 0, -9.81));
    ForceSample s;
    s.wrench_sensor.head<3>() = f_s + c.bias_sensor.head<3>();
    s.wrench_sensor.tail<3>() = c.payload_cog_sensor_m.cross(f_s) + c.bias_sensor.tail<3>();
    p.reset();  // orientation jumps between samples: take each on its own
    const ConditionedWrench out = p.step(s, R);
    EXPECT_GE(static_cast<int>(out.status), 0);
    EXPECT_LT(out.wrench_base.norm(), 1e-9) << i;
  }
}

TEST(ForcePipeline, ProcessForceArrivesAtTheWapInTheBaseFrame) {
  SensorConfig c = plain_sensor();
  c.flange_T_sensor.translation() = Vector3(0, 0, 0.05);
  const Vector3 wap_sensor(0.01, 0.0, 0.25);
  Pose sensor_T_wap = Pose::Identity();
  sensor_T_wap.translation() = wap_sensor;
  ForcePipeline p(c, sensor_T_wap);
  const Matrix3 R = rot(0.4, -1.1, 2.0);
  const Vector3 f_base(100, -250, 400);  // the process force, applied at the WAP
  const Vector3 f_sensor = R.transpose() * f_base;
  ForceSample s;
  s.wrench_sensor.head<3>() = f_sensor;
  s.wrench_sensor.tail<3>() = wap_sensor.cross(f_sensor);  // its moment about the sensor origin
  const ConditionedWrench out = p.step(s, R);
  EXPECT_LT((out.wrench_base.head<3>() - f_base).norm(), 1e-9);
  EXPECT_LT(out.wrench_base.tail<3>().norm(), 1e-9);
}

TEST(ForcePipeline, FaultAndInvalidSamplesAreRejectedWithoutTouchingTheFilter) {
  ForcePipeline p(plain_sensor());
  ForceSample s;
  s.wrench_sensor << 0, 0, 100, 0, 0, 0;
  EXPECT_EQ(p.step(s, Matrix3::Identity()).status, PipelineStatus::kOk);
  ForceSample big = s;
  big.wrench_sensor[2] = 5000;
  const ConditionedWrench f = p.step(big, Matrix3::Identity());
  EXPECT_EQ(f.status, PipelineStatus::kFault);
  EXPECT_NEAR(f.wrench_base[2], 100.0, 1e-9);
  ForceSample nan = s;
  nan.wrench_sensor[0] = std::nan("");
  EXPECT_EQ(p.step(nan, Matrix3::Identity()).status, PipelineStatus::kInvalidSample);
  ForceSample flagged = s;
  flagged.valid = false;
  EXPECT_EQ(p.step(flagged, Matrix3::Identity()).status, PipelineStatus::kInvalidSample);
  // The filter saw only the 100 N samples: still exactly 100 N.
  EXPECT_NEAR(p.step(s, Matrix3::Identity()).wrench_base[2], 100.0, 1e-9);
}

TEST(ForcePipeline, StepDoesNotAllocate) {
  ForcePipeline p(plain_sensor());
  ForceSample s;
  s.wrench_sensor << 1, 2, 3, 0.1, 0.2, 0.3;
  (void)p.step(s, Matrix3::Identity());
  test::AllocationGuard guard;
  for (int i = 0; i < 100; ++i) {
    s.wrench_sensor[0] = i;
    (void)p.step(s, rot(0.01 * i, 0, 0));
  }
  EXPECT_EQ(guard.allocations(), 0u);
}

TEST(SensorConfig, ExampleLoadsAndBadFieldsNameTheLine) {
  const SensorConfig c = load_sensor_config(std::string(DEFLEX_SOURCE_DIR) + "/examples/online/sensor_3axis.yaml");
  EXPECT_EQ(c.components, 3);
  EXPECT_NEAR(c.payload_mass_kg, 8.5, 1e-12);
  EXPECT_NEAR(c.crosstalk(0, 1), -0.012, 1e-12);
  EXPECT_NEAR(c.flange_T_sensor.translation().z(), 0.06, 1e-12);
  const std::string dir = ::testing::TempDir();
  const auto expect_error = [&](const std::string& text, const std::string& needle) {
    const std::string path = dir + "/bad_sensor.yaml";
    FILE* f = std::fopen(path.c_str(), "w");
    std::fputs(text.c_str(), f);
    std::fclose(f);
    try {
      (void)load_sensor_config(path);
      ADD_FAILURE() << "no error for: " << text;
    } catch (const ModelError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  expect_error("deflex_sensor: 1\nlowpas: {cutoff_hz: 25}\n", "bad_sensor.yaml:2");
  expect_error("deflex_sensor: 1\nsample_rate_hz: 100\nlowpass: {cutoff_hz: 60}\n", "lowpass.cutoff_hz");
  expect_error("deflex_sensor: 1\ncrosstalk: [[1,0],[0,1]]\n", "crosstalk");
  expect_error("deflex_sensor: 1\npayload: {mass_kg: -1}\n", "mass_kg");
}

TEST(SensorConfig, WithoutAFileTheDefaultsSayWhereTheyCameFrom) {
  const SensorConfig d = load_sensor_config_or_defaults("");
  EXPECT_TRUE(d.crosstalk.isIdentity(0.0));
  EXPECT_EQ(d.payload_mass_kg, 0.0);
  EXPECT_TRUE(d.bias_sensor.isZero(0.0));
  EXPECT_TRUE(d.flange_T_sensor.matrix().isIdentity(0.0));
  EXPECT_NE(d.source.find("default sensor"), std::string::npos) << d.source;
  // With a path it is the file's, and a missing file is an error, never the defaults.
  const std::string example = std::string(DEFLEX_SOURCE_DIR) + "/examples/online/sensor_3axis.yaml";
  EXPECT_NEAR(load_sensor_config_or_defaults(example).payload_mass_kg, 8.5, 1e-12);
  EXPECT_THROW((void)load_sensor_config_or_defaults(::testing::TempDir() + "/no_such_sensor.yaml"), Error);
}

}  // namespace
}  // namespace deflex

namespace deflex {
namespace {

TEST(SensorConfig, WrittenYamlReadsBackTheSameConfiguration) {
  SensorConfig c;
  c.name = "round trip";
  c.components = 6;
  c.crosstalk(1, 4) = 0.02;
  c.flange_T_sensor.translation() = Vector3(0.01, -0.02, 0.07);
  c.flange_T_sensor.linear() = Eigen::AngleAxisd(0.4, Vector3(1, 1, 0).normalized()).toRotationMatrix();
  c.payload_mass_kg = 7.25;
  c.payload_cog_sensor_m = Vector3(0.001, 0.002, 0.11);
  c.bias_sensor << 1, -2, 3, 0.1, -0.2, 0.3;
  c.lowpass_order = 3;
  c.lowpass_cutoff_hz = 30;
  c.dead_band_N = 4;
  c.fault_threshold_N = 1500;
  const std::string path = ::testing::TempDir() + "/round_trip_sensor.yaml";
  FILE* f = std::fopen(path.c_str(), "w");
  std::fputs(sensor_config_to_yaml(c).c_str(), f);
  std::fclose(f);
  const SensorConfig r = load_sensor_config(path);
  EXPECT_EQ(r.name, c.name);
  EXPECT_TRUE(r.crosstalk.isApprox(c.crosstalk, 1e-12));
  EXPECT_TRUE(r.flange_T_sensor.isApprox(c.flange_T_sensor, 1e-9));
  EXPECT_NEAR(r.payload_mass_kg, 7.25, 1e-12);
  EXPECT_TRUE(r.payload_cog_sensor_m.isApprox(c.payload_cog_sensor_m, 1e-9));
  EXPECT_TRUE(r.bias_sensor.isApprox(c.bias_sensor, 1e-9));
  EXPECT_EQ(r.lowpass_order, 3);
  EXPECT_EQ(r.lowpass_cutoff_hz, 30.0);
  EXPECT_EQ(r.dead_band_N, 4.0);
  EXPECT_EQ(r.fault_threshold_N, 1500.0);
}

}  // namespace
}  // namespace deflex
