// The controller side of a UR arm over RTDE (see ur_rtde_controller.hpp).
#include "deflex/cell/ur_rtde_controller.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <string>
#include <string_view>

namespace deflex::cell {
namespace {

// The type of an output or input field the stand-in serves, false for one it has not.
bool field_type(std::string_view name, bool output, rtde::FieldType& type) {
  const auto reg = [&](std::string_view prefix) {
    if (name.substr(0, prefix.size()) != prefix) return false;
    const std::string_view n = name.substr(prefix.size());
    if (n.empty() || n.size() > 2) return false;
    int v = 0;
    for (const char c : n) {
      if (c < '0' || c > '9') return false;
      v = 10 * v + (c - '0');
    }
    return v <= 47;
  };
  using F = rtde::FieldType;
  if (output) {
    if (name == "timestamp") return type = F::kDouble, true;
    if (name == "actual_q" || name == "target_q" || name == "actual_qd") return type = F::kVector6d, true;
    if (name == "robot_mode" || name == "safety_mode") return type = F::kInt32, true;
    if (name == "runtime_state") return type = F::kUint32, true;
    if (reg("output_int_register_")) return type = F::kInt32, true;
    if (reg("output_double_register_")) return type = F::kDouble, true;
    return false;
  }
  if (reg("input_int_register_")) return type = F::kInt32, true;
  if (reg("input_double_register_")) return type = F::kDouble, true;
  return false;
}

std::size_t index_of(const std::vector<std::string>& fields, const std::string& name) {
  return static_cast<std::size_t>(std::find(fields.begin(), fields.end(), name) - fields.begin());
}

}  // namespace

UrRtdeController::UrRtdeController(const UrRtdeControllerConfig& config, const JointVector& q_start,
                                   StreamTransport& stream)
    : config_(config), stream_(stream), target_(q_start), position_(q_start), previous_(q_start), encoders_(q_start) {
  rx_.assign(1 << 16, 0);
  tx_.assign(1 << 16, 0);
}

void UrRtdeController::send(std::size_t n, double t_s) {
  if (n == 0 || closed_) return;
  if (t_s < stall_until_s_) {
    held_.insert(held_.end(), tx_.begin(), tx_.begin() + static_cast<long>(n));
    return;
  }
  if (!held_.empty()) {  // the stall's end: TCP delivers what it held, in order
    for (std::size_t at = 0; at < held_.size();) {
      const long w = stream_.write(held_.data() + at, held_.size() - at);
      if (w <= 0) break;
      at += static_cast<std::size_t>(w);
    }
    held_.clear();
  }
  std::size_t at = 0;
  while (at < n) {  // the simulation's window is large; a full one loses the package, as a stalled reader would
    const long w = stream_.write(tx_.data() + at, n - at);
    if (w <= 0) return;
    at += static_cast<std::size_t>(w);
  }
}

void UrRtdeController::halt(const std::string& why, std::uint32_t runtime_state) {
  if (stopped_.empty()) stopped_ = why;
  runtime_state_ = runtime_state;
  target_ = position_;  // the arm halts where it is
  delay_.clear();
}

void UrRtdeController::protective_stop(const std::string& why) {
  safety_mode_ = 3;
  halt("protective stop: " + why, 4);
}
void UrRtdeController::emergency_stop() {
  safety_mode_ = 7;
  halt("robot emergency stop", 1);
}
void UrRtdeController::stop_program() { halt("the program was stopped", 1); }

void UrRtdeController::error_message(const std::string& text) {
  rtde::TextMessage m;
  m.message = text;
  m.source = "URControl";
  m.level = 1;
  send(rtde::encode(m, tx_.data(), tx_.size()));
}

// A setup request: the reply names each field's type, or NOT_FOUND / IN_USE.
void UrRtdeController::setup(const unsigned char* p, std::size_t size, rtde::PackageType type) {
  double hz = 0.0;
  std::string_view names;
  const bool outputs = type == rtde::PackageType::kSetupOutputs;
  if (rtde::decode_setup_request(p, size, type, hz, names) != rtde::DecodeStatus::kOk) {
    ++counters_.rejected;
    return;
  }
  std::vector<std::string>& fields = outputs ? out_fields_ : in_fields_;
  fields.clear();
  std::string reply;
  std::vector<rtde::FieldType> types;
  bool ok = true;
  for (std::size_t start = 0; start <= names.size();) {
    const std::size_t comma = std::min(names.find(',', start), names.size());
    const std::string name(names.substr(start, comma - start));
    rtde::FieldType t{};
    std::string word;
    if (!field_type(name, outputs, t)) {
      word = "NOT_FOUND";
      ok = false;
    } else if (!outputs && std::any_of(config_.in_use_registers.begin(), config_.in_use_registers.end(), [&](int r) {
                 return name == "input_int_register_" + std::to_string(r) ||
                        name == "input_double_register_" + std::to_string(r);
               })) {
      word = "IN_USE";
      ok = false;
    } else {
      word = rtde::to_string(t);
    }
    fields.push_back(name);
    types.push_back(t);
    reply += (reply.empty() ? "" : ",") + word;
    start = comma + 1;
  }
  // A frequency above the loop: the controller answers the recipe but refuses the start (strict: the
  // sources do not say which step refuses).
  const bool rate_ok = !outputs || hz <= 1.0 / config_.period_s() * (1 + 1e-9);
  rtde::Recipe& r = outputs ? out_recipe_ : in_recipe_;
  r = rtde::Recipe{};
  if (ok) (void)rtde::make_recipe(outputs ? 1 : 2, types.data(), types.size(), r);
  const std::uint8_t id = r.id;
  if (!rate_ok) r.count = 0;
  send(rtde::encode_setup_reply(type, id, reply, tx_.data(), tx_.size()));
}

void UrRtdeController::handle(const unsigned char* p, std::size_t size, std::uint8_t type) {
  using T = rtde::PackageType;
  const auto t = static_cast<T>(type);
  switch (t) {
    case T::kRequestProtocolVersion: {
      std::uint16_t v = 0;
      const bool ok = rtde::decode_protocol_request(p, size, v) == rtde::DecodeStatus::kOk && v == 2;
      send(rtde::encode_accepted(t, ok, tx_.data(), tx_.size()));
      return;
    }
    case T::kGetUrControlVersion: {
      rtde::UrControlVersion v;
      v.major = config_.e_series ? 5 : 3;
      v.minor = config_.e_series ? 11 : 15;
      send(rtde::encode(v, tx_.data(), tx_.size()));
      return;
    }
    case T::kSetupOutputs:
    case T::kSetupInputs:
      setup(p, size, t);
      return;
    case T::kStart: {
      started_ = out_recipe_.count > 0 && in_recipe_.count > 0;
      send(rtde::encode_accepted(t, started_, tx_.data(), tx_.size()));
      return;
    }
    case T::kPause:
      started_ = false;
      send(rtde::encode_accepted(t, true, tx_.data(), tx_.size()));
      return;
    case T::kDataPackage: {
      rtde::DataView v;
      if (in_recipe_.count == 0 || v.reset(in_recipe_, p, size) != rtde::DecodeStatus::kOk) {
        ++counters_.rejected;
        return;
      }
      inputs_.assign(p, p + size);  // registers keep their last value
      have_inputs_ = true;
      ++counters_.inputs;
      return;
    }
    default:
      ++counters_.rejected;
      return;
  }
}

void UrRtdeController::read_client() {
  if (closed_) return;
  for (;;) {
    const long n = stream_.read(rx_.data() + rx_size_, rx_.size() - rx_size_);
    if (n == StreamTransport::kClosed) {
      closed_ = true;
      started_ = false;
      return;
    }
    if (n == 0) return;
    rx_size_ += static_cast<std::size_t>(n);
    std::size_t at = 0;
    for (;;) {
      std::size_t bytes = 0;
      std::uint8_t type = 0;
      const rtde::FrameStatus f = rtde::peek_package(rx_.data() + at, rx_size_ - at, rx_.size(), bytes, type);
      if (f == rtde::FrameStatus::kIncomplete) break;
      if (f != rtde::FrameStatus::kComplete) {  // out of step: the controller drops the client
        stream_.close();
        closed_ = true;
        started_ = false;
        return;
      }
      handle(rx_.data() + at, bytes, type);
      at += bytes;
    }
    std::memmove(rx_.data(), rx_.data() + at, rx_size_ - at);
    rx_size_ -= at;
  }
}

// The script's cycle: the newest registers to servoj, the watchdog, the safety limit.
void UrRtdeController::servo_cycle(double t_s) {
  if (runtime_state_ != 2) return;
  if (end_at_s_ >= 0.0 && t_s >= end_at_s_ - 1e-12) {
    halt("the program ended (the stream's end)", 1);
    return;
  }
  if (!have_inputs_) {
    last_counter_change_s_ = t_s;  // the watchdog is armed by the first input
    return;
  }
  const int o = config_.register_offset;
  rtde::DataView v;
  (void)v.reset(in_recipe_, inputs_.data(), inputs_.size());
  const std::size_t ic = index_of(in_fields_, "input_int_register_" + std::to_string(o));
  const std::size_t im = index_of(in_fields_, "input_int_register_" + std::to_string(o + 1));
  const std::int32_t counter = ic < in_fields_.size() ? v.get_int32(ic) : 0;
  const std::int32_t mode = im < in_fields_.size() ? v.get_int32(im) : 0;
  if (counter != counter_) {
    counter_ = counter;
    last_counter_change_s_ = t_s;
  } else if (t_s - last_counter_change_s_ > config_.watchdog_s + 1e-12) {
    halt("the RTDE watchdog: input_int_register_" + std::to_string(o) + " did not change", 1);
    return;
  }
  if (mode != 1 && mode != 2) return;
  JointVector q(position_.size());
  for (int j = 0; j < q.size(); ++j) {
    q[j] = v.get_double(index_of(in_fields_, "input_double_register_" + std::to_string(o + j)));
  }
  const double la = v.get_double(index_of(in_fields_, "input_double_register_" + std::to_string(o + 6)));
  const double g = v.get_double(index_of(in_fields_, "input_double_register_" + std::to_string(o + 7)));
  if (!(la >= 0.03 - 1e-12 && la <= 0.2 + 1e-12 && g >= 100.0 && g <= 2000.0)) {
    halt("servoj: lookahead_time or gain out of range", 1);
    return;
  }
  lookahead_s_ = la;
  gain_ = g;
  echo_ = counter;
  if (mode == 2 && end_at_s_ < 0.0) end_at_s_ = t_s + std::min(2.0 * la, 0.5 * config_.watchdog_s);
  targets_.push_back(q);
  ++counters_.servo_cycles;
  delay_.emplace_back(t_s + la, q);
}

void UrRtdeController::send_outputs(double t_s) {
  if (!started_ || closed_) return;
  rtde::DataBuilder b(out_recipe_, tx_.data(), tx_.size());
  const JointVector& actual = have_encoders_ ? encoders_ : position_;
  const auto vec = [](const JointVector& q) {
    std::array<double, 6> a{};
    for (int j = 0; j < q.size() && j < 6; ++j) a[static_cast<std::size_t>(j)] = q[j];
    return a;
  };
  const std::string echo = "output_int_register_" + std::to_string(config_.register_offset);
  for (std::size_t k = 0; k < out_fields_.size(); ++k) {
    const std::string& f = out_fields_[k];
    if (f == "timestamp") b.set(k, t_s);
    if (f == "actual_q") b.set(k, vec(actual));
    if (f == "target_q") b.set(k, vec(position_));
    if (f == "actual_qd") b.set(k, vec((position_ - previous_) / config_.period_s()));
    if (f == "robot_mode") b.set(k, std::int32_t{safety_mode_ == 7 ? 3 : 7});
    if (f == "safety_mode") b.set(k, safety_mode_);
    if (f == "runtime_state") b.set(k, runtime_state_);
    if (f == echo) b.set(k, echo_);
  }
  send(b.finish(), t_s);
  ++counters_.outputs;
}

const JointVector& UrRtdeController::tick(double t_s) {
  if (t_s >= stall_until_s_) read_client();
  while (t_s + 1e-12 >= next_cycle_s_) {
    const double tc = next_cycle_s_;
    next_cycle_s_ += config_.period_s();
    servo_cycle(tc);
    // servoj: the target after the lookahead's dead time, followed with the gain's lag.
    while (!delay_.empty() && delay_.front().first <= tc + 1e-12) {
      target_ = delay_.front().second;
      delay_.pop_front();
    }
    previous_ = position_;
    position_ += (1.0 - std::exp(-config_.period_s() * gain_)) * (target_ - position_);
    const double step = (position_ - previous_).cwiseAbs().maxCoeff();
    if (runtime_state_ == 2 && step > config_.max_speed_rad_s * config_.period_s()) {
      position_ = previous_;
      protective_stop("a joint's speed limit was exceeded");
    }
    send_outputs(tc);
  }
  return position_;
}

void UrRtdeController::encoders(const JointVector& q_motor_rad) {
  encoders_ = q_motor_rad;
  have_encoders_ = true;
}

}  // namespace deflex::cell
