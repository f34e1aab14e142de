// The whole conditioning pipeline on the recorded example signal (examples/online/force_replay.csv),
// read by the CSV replay, against values computed here from the formula that generated it.
#include <cmath>

#include <gtest/gtest.h>

#include "deflex/online/force_pipeline.hpp"
#include "deflex/sensors/detail/csv_force_replay.hpp"

namespace deflex {
namespace {

Matrix3 rot(double ax, double ay, double az) {
  return (Eigen::AngleAxisd(az, Vector3::UnitZ()) * Eigen::AngleAxisd(ay, Vector3::UnitY()) *
          Eigen::AngleAxisd(ax, Vector3::UnitX()))
      .toRotationMatrix();
}

TEST(ForcePipeline, RecordedSignalMatchesItsGeneratingFormula) {
  // examples/online/force_replay.csv: sensor pointing down (sensor z = -base z), raw =
  // bias (1.5,-0.8,2.2) + weight (0,0,8.5*9.81) + push ramp (0.6,0,0.8)*400 N + 3 N at 150 Hz on x.
  const SensorConfig c = load_sensor_config(std::string(DEFLEX_SOURCE_DIR) + "/examples/online/sensor_3axis.yaml");
  CsvForceReplay replay(std::string(DEFLEX_SOURCE_DIR) + "/examples/online/force_replay.csv");
  ASSERT_EQ(replay.size(), 500u);
  ForcePipeline p(c);
  const Matrix3 R = rot(std::acos(-1.0), 0, 0);  // 180 degrees about x: z down
  replay.advance_to(1e9);
  ForceSample s;
  Matrix3 C = c.crosstalk.topLeftCorner<3, 3>();
  const Vector3 raw_mean(1.5 + 240.0, -0.8, 2.2 + 8.5 * 9.81 + 320.0);
  const Vector3 expected = R * (C * raw_mean - Vector3(1.5, -0.8, 2.2)) - 8.5 * Vector3(0, 0, -9.81);
  // Ripple left after the filter: the 150 Hz component times the closed-form gain.
  const double pi = std::acos(-1.0);
  const double r = std::tan(pi * 150.0 / 1000.0) / std::tan(pi * 25.0 / 1000.0);
  const double ripple = (R * C * Vector3(3.0, 0, 0)).norm() / std::sqrt(1.0 + std::pow(r, 4.0));
  int checked = 0;
  while (replay.latest(s)) {
    const ConditionedWrench out = p.step(s, R);
    if (s.t_s < 0.02) {
      // Before the push only the crosstalk residue of the weight remains: inside the 5 N dead band.
      EXPECT_TRUE(out.wrench_base.isZero(0.0)) << s.t_s;
    }
    if (s.t_s > 0.35) {
      EXPECT_LT((out.wrench_base.head<3>() - expected).norm(), ripple * 1.05 + 1e-6) << s.t_s;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 149);
  EXPECT_GT(ripple, 0.05);  // the check is not trivially loose ...
  EXPECT_LT(ripple, 0.5);   // ... nor trivially tight
}

}  // namespace
}  // namespace deflex
