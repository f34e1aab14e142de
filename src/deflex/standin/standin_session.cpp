// deflex's runtime against an in-memory stand-in of the controller (see standin_session.hpp).
#include "deflex/standin/standin_session.hpp"

#include <algorithm>
#include <cmath>

#include "deflex/text/errors.hpp"
#include "deflex/wire/egm_codec.hpp"
#include "deflex/wire/fanuc_j519.hpp"
#include "deflex/wire/rsi_xml.hpp"

namespace deflex::standin {

namespace {
const DatagramAddress kDeflex{0x0a000001, 6510};      // 10.0.0.1:6510, the cell PC
const DatagramAddress kController{0x0a000002, 6511};  // 10.0.0.2:6511
}  // namespace

ArmForceSensor::ArmForceSensor(const RobotModel& robot, const SensorConfig& sensor)
    : robot_(robot), flange_T_sensor_(sensor.flange_T_sensor), ws_(robot_) {}

void ArmForceSensor::set(const JointVector& q_arm, const Vector3& force_base_n) {
  forward_kinematics(robot_, ws_, q_arm);
  const Pose base_T_sensor = ws_.base_T_flange * flange_T_sensor_;
  const Matrix3 R = base_T_sensor.linear();
  // The force acts at the TCP: in the sensor frame, with its moment about the sensor origin.
  const Vector3 f_s = R.transpose() * force_base_n;
  const Vector3 r_s = R.transpose() * (ws_.base_T_tcp.translation() - base_T_sensor.translation());
  pending_.wrench_sensor.head<3>() = f_s;
  pending_.wrench_sensor.tail<3>() = r_s.cross(f_s);
  pending_.valid = true;
}

void ArmForceSensor::sample(double t_s) noexcept {
  pending_.t_s = t_s;
  have_ = on;
}

bool ArmForceSensor::latest(ForceSample& out) noexcept {
  if (!have_) return false;
  have_ = false;
  out = pending_;
  return true;
}

// The controller's transport: what it reads from deflex is decoded on the way in.
class StandInSession::Tap final : public DatagramTransport {
 public:
  Tap(DatagramTransport& inner, StandInSession& owner) : inner_(inner), owner_(owner) {}
  bool wait_readable(double timeout_s) noexcept override { return inner_.wait_readable(timeout_s); }
  long receive(unsigned char* buffer, std::size_t capacity, DatagramAddress& from) noexcept override {
    const long n = inner_.receive(buffer, capacity, from);
    if (n > 0 && static_cast<std::size_t>(n) <= capacity && from == kDeflex) {
      owner_.decode(buffer, static_cast<std::size_t>(n));
    }
    return n;
  }
  bool send_to(const unsigned char* data, std::size_t size, const DatagramAddress& to) noexcept override {
    return inner_.send_to(data, size, to);
  }
  [[nodiscard]] DatagramAddress local_address() const noexcept override { return inner_.local_address(); }
  EgmCodec codec{6};

 private:
  DatagramTransport& inner_;
  StandInSession& owner_;
};

// NOLINTNEXTLINE(readability-function-size): listed in docs/architecture.md, "Functions over 80 lines"
StandInSession::StandInSession(const runtime::SessionConfig& config, const RobotModel& robot,
                               const SensorConfig& sensor, std::shared_ptr<const JointTrajectory> program,
                               const ForceModel* force_model, const StandInConfig& standin)
    : kind_(config.link),
      config_(config),
      standin_(standin),
      robot_(robot),
      program_(std::move(program)),
      // MotoROS2's reply is 2053 bytes.
      network_(clock_, config.link == runtime::LinkKind::kMotoros2Rt ? 4096 : 2048),
      deflex_port_(network_.add_endpoint(kDeflex, standin.network_latency_s)),
      controller_port_(network_.add_endpoint(kController, standin.network_latency_s)),
      motion_(clock_, standin.network_latency_s),
      state_(clock_, standin.network_latency_s),
      sensor_(robot, sensor) {
  if (!program_) throw InputError("stand-in: a program is needed (the nominal deflex streams, or the controller's)");
  if (robot.dof() != 6) throw InputError("stand-in: the controller stand-ins drive 6-axis arms");
  tap_ = std::make_unique<Tap>(controller_port_, *this);
  if (kind_ == runtime::LinkKind::kFanucJ519) {
    config_.fanuc_j519.controller = kController;
    config_.network.robot_host.clear();
  }
  if (kind_ == runtime::LinkKind::kMotoros2Rt) {
    config_.motoros2_rt.controller = kController;
    config_.network.robot_host.clear();
  }
  const bool streams = runtime::link_kind(kind_).streams_program;
  runtime::SessionEndpoints ends{&deflex_port_, &motion_.client(), &state_.client()};
  if (kind_ == runtime::LinkKind::kMotoros2Rt && config_.motoros2_rt.status_port >= 0) {
    // The controller's RobotState comes to the PC's address at the status port.
    ends.status = &network_.add_endpoint(
        DatagramAddress{kDeflex.ipv4, static_cast<std::uint16_t>(config_.motoros2_rt.status_port)},
        standin.network_latency_s);
  }
  session_ = std::make_unique<runtime::Session>(config_, robot, sensor, streams ? program_ : nullptr, force_model,
                                                &sensor_, clock_, ends);
  cell::ControllerConfig cc = standin.controller;
  cc.network_latency_s = standin.network_latency_s;
  switch (kind_) {
    case runtime::LinkKind::kEgmJoint: {
      auto c = std::make_unique<cell::EgmPositionGuidanceController>(cc, program_->points().front(), *tap_, kDeflex);
      egm_ = c.get();
      controller_ = std::move(c);
      break;
    }
    case runtime::LinkKind::kEgmPath: {
      cc.path_corr_period_s = config_.online.period_s;
      cc.path_corr_frame = to_string(config_.egm_path.frame);
      auto c = std::make_unique<cell::EgmPathCorrectionController>(cc, robot, program_, *tap_, kDeflex);
      path_ = c.get();
      controller_ = std::move(c);
      break;
    }
    case runtime::LinkKind::kRsi: {
      cell::RsiControllerConfig rc = standin.rsi;
      // AXISCORR's limits as deflex controller-setup writes them: deflex's bound, AXISCORRMON 1.2 x.
      const double bound_deg = rad_to_deg(config_.online.max_joint_correction_rad);
      rc.upper_limit_deg = bound_deg;
      rc.lower_limit_deg = -bound_deg;
      rc.max_correction_deg = 1.2 * bound_deg;
      rc.cycle_s = config_.online.period_s;
      rc.timeout = config_.rsi.controller_timeout;
      rc.sentype = config_.rsi.sentype;
      auto c = std::make_unique<cell::RsiController>(rc, robot, program_, *tap_, kDeflex);
      rsi_ = c.get();
      controller_ = std::move(c);
      break;
    }
    case runtime::LinkKind::kSimpleMessage: {
      cell::SimpleMessageServerConfig sc = standin.server;
      sc.byte_order = config_.simple_message.byte_order;
      sc.record_points = true;
      auto c = std::make_unique<cell::SimpleMessageServer>(sc, robot, program_->points().front(), motion_.server(),
                                                           state_.server());
      server_ = c.get();
      controller_ = std::move(c);
      break;
    }
    case runtime::LinkKind::kFanucJ519: {
      cell::FanucJ519ControllerConfig fc = standin.fanuc;
      fc.interval_s = config_.online.period_s;
      fc.version = config_.fanuc_j519.version;
      auto c = std::make_unique<cell::FanucJ519Controller>(fc, program_->points().front(), *tap_);
      fanuc_ = c.get();
      controller_ = std::move(c);
      break;
    }
    case runtime::LinkKind::kUrRtde: {
      cell::UrRtdeControllerConfig uc = standin.ur;
      uc.e_series = config_.online.period_s < 0.005;
      uc.register_offset = config_.ur_rtde.register_offset;
      auto c = std::make_unique<cell::UrRtdeController>(uc, program_->points().front(), motion_.server());
      ur_ = c.get();
      controller_ = std::move(c);
      break;
    }
    case runtime::LinkKind::kMotoros2Rt: {
      cell::Motoros2RtControllerConfig mc = standin.motoros2;
      mc.period_s = config_.online.period_s;
      mc.group = config_.motoros2_rt.group;
      mc.status_port = config_.motoros2_rt.status_port;
      auto c = std::make_unique<cell::Motoros2RtController>(mc, program_->points().front(), *tap_);
      motoros2_ = c.get();
      controller_ = std::move(c);
      break;
    }
  }
  arm_ = program_->points().front();
}

StandInSession::~StandInSession() = default;

void StandInSession::decode(const unsigned char* data, std::size_t size) {
  WireCommand c;
  c.t_s = clock_.now_s();
  if (kind_ == runtime::LinkKind::kEgmJoint) {
    EgmSensorMessage m;
    if (!tap_->codec.decode_sensor(data, size, m)) return;
    c.joints = m.planned_joints_deg * (kPi / 180.0);
  } else if (kind_ == runtime::LinkKind::kEgmPath) {
    EgmPathCorrMessage m;
    if (!tap_->codec.decode_path_corr(data, size, m)) return;
    c.offset_m = m.pos_mm * 1e-3;
  } else if (kind_ == runtime::LinkKind::kRsi) {
    RsiSensorMessage m;
    if (decode_rsi_sensor(data, size, config_.rsi.sentype, 6, m) != RsiDecodeStatus::kOk) return;
    c.joints = m.correction_deg * (kPi / 180.0);
  } else if (kind_ == runtime::LinkKind::kFanucJ519) {
    fanuc_j519::Command m;
    std::uint32_t version = 0;
    if (fanuc_j519::decode(data, size, m, version) != fanuc_j519::DecodeStatus::kOk) return;
    c.joints = JointVector(6);
    for (int i = 0; i < 6; ++i) c.joints[i] = deg_to_rad(m.target[static_cast<std::size_t>(i)]);
  } else {
    return;
  }
  wire_.push_back(c);
}

void StandInSession::tick() {
  // FANUC's 1 ms interval needs a tick of 1 ms, UR's 2 ms loop one of 2 ms.
  const double tick_s = fanuc_ != nullptr || ur_ != nullptr
                            ? std::min(standin_.controller.servo_period_s, config_.online.period_s)
                            : standin_.controller.servo_period_s;
  t_s_ += tick_s;
  clock_.set(t_s_);
  arm_ = controller_->tick(t_s_);
  if (motoros2_ != nullptr) {
    // Every increment the controller took, as the command position it moved to (the session's first
    // command, with no increment, left out).
    const auto& taken = motoros2_->taken();
    for (std::size_t i = std::max<std::size_t>(motoros2_seen_, 1); i < taken.size(); ++i) {
      WireCommand c;
      c.t_s = t_s_;
      c.joints = taken[i];
      wire_.push_back(c);
    }
    motoros2_seen_ = taken.size();
  }
  if (ur_ != nullptr) {
    for (std::size_t i = ur_seen_; i < ur_->targets().size(); ++i) {
      WireCommand c;
      c.t_s = t_s_;
      c.joints = ur_->targets()[i];
      wire_.push_back(c);
    }
    ur_seen_ = ur_->targets().size();
  }
  if (server_ != nullptr) {
    // Every point the server took, as the wire carried it (float32 radians).
    for (std::size_t i = wire_.size(); i < server_->accepted_points().size(); ++i) {
      WireCommand c;
      c.t_s = server_->accepted_points()[i].t_s;
      c.joints = server_->accepted_points()[i].q;
      wire_.push_back(c);
    }
  }
  sensor_.set(arm_, standin_.force_base_n);
  if (t_s_ + 1e-12 >= next_sample_s_) {
    sensor_.sample(t_s_);
    next_sample_s_ += 1.0 / standin_.sensor_rate_hz;
  }
  clock_.set(t_s_ + standin_.network_latency_s);
  if (stalled_) return;
  while (!session_->ended() && session_->poll(0.0) != LinkPollResult::kIdle) {
  }
  session_->service();
}

void StandInSession::run_for(double seconds) {
  const double until = t_s_ + seconds;
  while (t_s_ < until - 1e-9 && !session_->ended()) tick();
}

void StandInSession::outage(double seconds) {
  if (ur_ != nullptr) {
    ur_->stall_network(t_s_ + seconds);  // TCP loses nothing: an outage is a stall both ways
    return;
  }
  network_.add_outage(t_s_, t_s_ + seconds);
}

void StandInSession::reorder(int count) { network_.add_reordering(t_s_, count, kController); }

void StandInSession::restart(bool reset_reference, double off_s) {
  if (egm_ != nullptr) egm_->restart(t_s_, reset_reference);
  if (path_ != nullptr) path_->restart();
  if (rsi_ != nullptr) {
    if (off_s > 0.0) {
      // Off through the last tick of the wait too: RSI_ON comes before the next document.
      rsi_->pause(t_s_, t_s_ + off_s + standin_.controller.servo_period_s);
      run_for(off_s);
    }
    rsi_->restart();
  }
  if (fanuc_ != nullptr) fanuc_->restart(t_s_);
  if (motoros2_ != nullptr) motoros2_->restart(t_s_);
  if (server_ != nullptr) throw InputError("stand-in: the simple message server has no session to restart");
  if (ur_ != nullptr) throw InputError("stand-in: a UR program stopped and played again is a new session");
}

void StandInSession::end_session(int mci_state) {
  if (egm_ == nullptr) throw InputError("stand-in: only EGM ends its session with a state (mciState)");
  egm_->end_session(mci_state);
}

void StandInSession::motors_off() {
  if (egm_ != nullptr) {
    egm_->motors_off();
  } else if (server_ != nullptr) {
    server_->emergency_stop(t_s_);
  } else if (fanuc_ != nullptr) {
    fanuc_->raise_alarm("SRVO-001 Operator panel E-stop");
  } else if (motoros2_ != nullptr) {
    motoros2_->stop("e-stop");
  } else if (ur_ != nullptr) {
    ur_->emergency_stop();
  } else {
    throw InputError("stand-in: this controller reports no motor state");
  }
}

}  // namespace deflex::standin
