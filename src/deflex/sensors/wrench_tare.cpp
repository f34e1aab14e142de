// The software tare of a force source (see wrench_tare.hpp).
#include "deflex/sensors/wrench_tare.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "deflex/text/errors.hpp"
#include "deflex/text/parse_number.hpp"

namespace deflex {
namespace {

std::string axes(const Vector6& v) {
  return fmt::format("[{:.3f} {:.3f} {:.3f}] N [{:.4f} {:.4f} {:.4f}] Nm", v(0), v(1), v(2), v(3), v(4), v(5));
}

}  // namespace

void TareSettings::validate() const {
  auto positive = [](double v, const char* field) {
    if (!(v > 0.0) || !std::isfinite(v)) {
      throw InputError(fmt::format("tare: {} must be a positive number, not {}", field, number_text(v)));
    }
  };
  positive(window_s, "the window (s)");
  positive(max_std_force_n, "the largest force standard deviation (N)");
  positive(max_std_torque_nm, "the largest torque standard deviation (Nm)");
  if (!expected_wrench_sensor.allFinite()) {
    throw InputError("tare: the expected wrench at the tare pose must be finite");
  }
}

const char* to_string(TareState s) {
  switch (s) {
    case TareState::kOff:
      return "off";
    case TareState::kCollecting:
      return "collecting";
    case TareState::kDone:
      return "done";
    case TareState::kRejected:
      return "rejected";
  }
  return "?";
}

std::string describe(const TareResult& r, const TareSettings& s) {
  const double std_f = r.std_sensor.head<3>().maxCoeff();
  const double std_t = r.std_sensor.tail<3>().maxCoeff();
  switch (r.state) {
    case TareState::kOff:
      return "tare: off";
    case TareState::kCollecting:
      return fmt::format("tare: collecting, {} of {} samples", r.samples, r.samples_wanted);
    case TareState::kDone:
      return fmt::format("tare done: {} samples over {} s, offset {}, standard deviation at most {:.3f} N, {:.4f} Nm",
                         r.samples, number_text(s.window_s), axes(r.offset_sensor), std_f, std_t);
    case TareState::kRejected:
      if (r.faulty > 0) {
        return fmt::format(
            "tare refused: {} of the {} samples in the window were faulty (sensor status or "
            "saturation); check the sensor before taring",
            r.faulty, r.samples + r.faulty);
      }
      return fmt::format(
          "tare refused: the reading moved during the {} s window (standard deviation {} against "
          "the limits {} N, {} Nm): hold the arm still, stop the tool, and tare again",
          number_text(s.window_s), axes(r.std_sensor), number_text(s.max_std_force_n),
          number_text(s.max_std_torque_nm));
  }
  return "tare: ?";
}

Vector6 payload_wrench_sensor(double mass_kg, const Vector3& cog_sensor_m, const Vector3& gravity_base_m_s2,
                              const Matrix3& base_R_sensor) {
  Vector6 w;
  w.head<3>() = mass_kg * (base_R_sensor.transpose() * gravity_base_m_s2);
  w.tail<3>() = cog_sensor_m.cross(Vector3(w.head<3>()));
  return w;
}

void WrenchTare::start(const TareSettings& settings, double rate_hz) {
  settings.validate();
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz)) {
    throw InputError(
        fmt::format("tare: the sample rate must be a positive number of Hz, not {}", number_text(rate_hz)));
  }
  settings_ = settings;
  result_ = TareResult{};
  result_.state = TareState::kCollecting;
  result_.samples_wanted = std::max(2, static_cast<int>(std::ceil(settings.window_s * rate_hz - 1e-9)));
  m2_.setZero();
}

TareState WrenchTare::add(const ForceSample& sample) noexcept {
  if (result_.state != TareState::kCollecting) {
    return result_.state;
  }
  if (!sample.valid || !sample.wrench_sensor.allFinite()) {
    ++result_.faulty;
  } else {
    ++result_.samples;
    const Vector6 delta = sample.wrench_sensor - result_.mean_sensor;
    result_.mean_sensor += delta / static_cast<double>(result_.samples);
    m2_ += delta.cwiseProduct(sample.wrench_sensor - result_.mean_sensor);
  }
  if (result_.samples + result_.faulty >= result_.samples_wanted) {
    finish();
  }
  return result_.state;
}

void WrenchTare::finish() noexcept {
  const int n = result_.samples;
  result_.std_sensor = n > 1 ? Vector6((m2_ / static_cast<double>(n - 1)).cwiseSqrt()) : Vector6::Zero();
  const bool still = result_.std_sensor.head<3>().maxCoeff() <= settings_.max_std_force_n &&
                     result_.std_sensor.tail<3>().maxCoeff() <= settings_.max_std_torque_nm;
  if (result_.faulty > 0 || n < 2 || !still) {
    result_.state = TareState::kRejected;
    return;
  }
  result_.offset_sensor = result_.mean_sensor - settings_.expected_wrench_sensor;
  result_.state = TareState::kDone;
}

}  // namespace deflex
