// The machining study's runs on the simulated cell (see detail/machining_run.hpp).
#include "deflex/study/detail/machining_run.hpp"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "deflex/cell/daq_stream.hpp"
#include "deflex/cell/egm_position_controller.hpp"
#include "deflex/cell/force_sensor.hpp"
#include "deflex/cell/milling_process.hpp"
#include "deflex/cell/path_drift.hpp"
#include "deflex/cell/robot_controller.hpp"
#include "deflex/machining/milling_force_model.hpp"
#include "deflex/model/kinematics.hpp"
#include "deflex/offline/compensate_path.hpp"
#include "deflex/online/online_strategy.hpp"
#include "deflex/runtime/session.hpp"
#include "deflex/sensors/datagram_force_source.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/transport/memory_network.hpp"

namespace deflex::study {
namespace {

// The machining cell's network: the controller, the cell PC running deflex, the DAQ.
const DatagramAddress kMillDeflexEgm{0x0a000001, 6510};
const DatagramAddress kMillDeflexForce{0x0a000001, 6600};
const DatagramAddress kMillController{0x0a000002, 6511};
const DatagramAddress kMillDaq{0x0a000003, 5000};

// The program holds the tool at its first point (spindle on, in the air) this long before it moves:
// EGM's start, the user's air reading for the slot logs.
constexpr double kHoldS = 0.3;
// A linked run lasts this much beyond the program, for the streamed motion to finish.
constexpr double kLinkTailS = 0.3;
// Program points along a pass (the controller interpolates between them).
constexpr double kProgramStepM = 0.5e-3;

enum class MillComponent : std::uint64_t { kSensor = 21, kDrift = 22 };
std::uint64_t mill_seed(std::uint64_t run, MillComponent c) {
  return splitmix(run ^ (static_cast<std::uint64_t>(c) * 0x2545f4914f6cdd1dULL));
}

bool strategy_linked(MachiningStrategy s) { return s == MachiningStrategy::kOnline || s == MachiningStrategy::kHybrid; }

// The cell's network for one pass, on a clock the pass advances.
struct MillNetwork {
  explicit MillNetwork(const cell::CellConfig& c)
      : network(clock),
        controller_port(network.add_endpoint(kMillController, c.controller.network_latency_s)),
        deflex_egm_port(network.add_endpoint(kMillDeflexEgm, c.controller.network_latency_s)),
        daq_port(network.add_endpoint(kMillDaq, c.sensor.daq_latency_s)),
        deflex_force_port(network.add_endpoint(kMillDeflexForce, 0.0)) {}
  ManualClock clock;
  MemoryNetwork network;
  MemoryTransport& controller_port;
  MemoryTransport& deflex_egm_port;
  MemoryTransport& daq_port;
  MemoryTransport& deflex_force_port;
};

// deflex's side of a linked pass, started as `deflex online` starts: EGM position guidance, the
// sensor's sheet and the user's tare, the identified model, and for hybrid the predicted force.
struct MillDeflex {
  std::unique_ptr<DatagramForceSource> force_source;
  std::unique_ptr<runtime::Session> session;
};

MillDeflex start_mill_session(const MillCell& mc, MachiningStrategy strategy,
                              const std::shared_ptr<const JointTrajectory>& program, const ForceModel* predicted,
                              MillNetwork& net, cell::ForceSensorDaq& sensor) {
  MillDeflex side;
  const CaseConfig& config = mc.config;
  const cell::CellConfig& c = config.cell;
  runtime::SessionConfig sc;
  sc.link = runtime::LinkKind::kEgmJoint;
  sc.online = online_config_from_case(config, c.controller.egm_period_s);
  sc.strategy = strategy == MachiningStrategy::kHybrid ? StrategyKind::kHybrid : StrategyKind::kOnline;
  sc.egm_joint.stream.ramp_in_s = config.online.ramp_in_s;
  sc.history_cycles = 16;
  side.force_source = std::make_unique<DatagramForceSource>(net.deflex_force_port);
  runtime::SessionEndpoints endpoints;
  endpoints.datagram = &net.deflex_egm_port;
  const cell::TrueRobot& robot = *mc.setup.robot;
  side.session =
      std::make_unique<runtime::Session>(sc, mc.setup.calibration.identified,
                                         tare_sensor(sensor_config_from_sheet(config, sensor.calibration()), sensor,
                                                     robot, program->points().front(), tare_limit_n(c.sensor)),
                                         program, strategy == MachiningStrategy::kHybrid ? predicted : nullptr,
                                         side.force_source.get(), net.clock, endpoints);
  return side;
}

// The distance of `p` (stock frame) from the polyline's nearest segment, in the plane of the cut.
double distance_from_pass(const MillPass& pass, const Vector3& p) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 1; i < pass.corners.size(); ++i) {
    const Eigen::Vector2d a = pass.corners[i - 1].head<2>(), b = pass.corners[i].head<2>();
    const Eigen::Vector2d ab = b - a;
    const double t = std::clamp((p.head<2>() - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (p.head<2>() - (a + t * ab)).norm());
  }
  return best;
}

// Where the user's touch-off put the stock: the true arm standing unloaded at the nominal joints of
// the first pass's first point is taken as that point, the stock's z along the true tool axis.
Pose touch_off(const MillCell& mc, const JointVector& q0, const Vector3& tip0_workpiece, cell::PathDrift& drift) {
  const cell::TrueRobot& robot = *mc.setup.robot;
  Workspace ws(robot.true_model());
  cell::TrueRobotState state = robot.initial_state(q0);
  cell::CoupledTickSolver solver;
  const Vector3 p = solver.at_rest(cell::CoupledArm{robot, ws, state, drift, nullptr}, q0);
  const Matrix3 tcp = ws.base_T_tcp.linear();
  Matrix3 r;
  r.col(2) = -tcp.col(2);
  r.col(0) = tcp.col(0);
  r.col(1) = r.col(2).cross(r.col(0));
  Pose base_T_stock = Pose::Identity();
  base_T_stock.linear() = r;
  base_T_stock.translation() = p - r * tip0_workpiece;
  return base_T_stock;
}

// One pass on the cell: the controller (its own program, or EGM fed by deflex) moves the arm, the
// coupled solve settles it against the cut each tick, the stock loses what the true tool swept.
struct PassRun {
  const MillCell& mc;
  const MillPass& pass;
  const PassProgram& program;
  const MillRunSpec& spec;
  const Pose& base_T_stock;
  DexelStock& stock;
  cell::PathDrift& drift;
  cell::ForceSensorDaq& sensor;
  bool log_sensor;
};

// The controller the pass's strategy talks to: the program itself, or EGM position guidance.
std::unique_ptr<cell::RobotController> make_pass_controller(const cell::CellConfig& c, bool linked,
                                                            const std::shared_ptr<const JointTrajectory>& program,
                                                            MillNetwork& net) {
  if (!linked) return std::make_unique<cell::ProgramController>(program);
  return std::make_unique<cell::EgmPositionGuidanceController>(c.controller, program->points().front(),
                                                               net.controller_port, kMillDeflexEgm);
}

cell::MillingProcessConfig pass_process_config(const PassRun& r) {
  cell::MillingProcessConfig pc;
  pc.cutter = study_cutter();
  pc.k = r.spec.true_k;
  pc.spindle_rpm = kStudySpindleRpm;
  pc.runout_m = r.spec.runout_m;
  pc.base_T_stock = r.base_T_stock;
  return pc;
}

// A sample of the pass for the report: the true tip (base frame) and the wrench it was solved under.
void record_pass_sample(const PassRun& r, const Vector3& p_base, const Wrench& w, PassTrace& trace) {
  const Pose stock_T_base = r.base_T_stock.inverse();
  const Vector3 tip = stock_T_base * p_base;
  trace.x_m.push_back(tip.x());
  trace.true_force_n.push_back((stock_T_base.linear() * w.head<3>()).head<2>().norm());
  trace.deflection_m.push_back(distance_from_pass(r.pass, tip));
  // The model's wrench where the program put this point: the true tip taken back to the nominal frame.
  Wrench predicted = Wrench::Zero();
  const Pose programmed(Eigen::Translation3d(r.mc.base_T_workpiece * tip));
  if (r.program.predicted) (void)r.program.predicted->wrench_at_pose(programmed, predicted);
  trace.predicted_force_n.push_back(
      (r.mc.base_T_workpiece.linear().transpose() * predicted.head<3>()).head<2>().norm());
}

void run_one_pass(const PassRun& r, MillRunResult& out) {
  const cell::CellConfig& c = r.mc.config.cell;
  const cell::TrueRobot& robot = *r.mc.setup.robot;
  const bool linked = strategy_linked(r.spec.strategy);
  auto program = std::make_shared<const JointTrajectory>(trajectory_at_tcp_speed(
      r.program.poses, r.program.q, r.spec.feed_mm_min / 60.0 * 1e-3, r.mc.setup.calibration.identified, kHoldS));
  MillNetwork net(c);
  const std::unique_ptr<cell::RobotController> controller = make_pass_controller(c, linked, program, net);
  cell::DaqStream daq(net.daq_port, kMillDeflexForce);
  MillDeflex side;
  if (linked) side = start_mill_session(r.mc, r.spec.strategy, program, r.program.predicted.get(), net, r.sensor);
  cell::MillingProcess process(pass_process_config(r), r.stock);
  const Matrix3 decoupling = r.sensor.calibration().decoupling;
  Workspace ws(robot.true_model());
  JointVector q = program->points().front();
  cell::TrueRobotState state = robot.initial_state(q);
  cell::CoupledTickSolver solver;
  (void)solver.at_rest(cell::CoupledArm{robot, ws, state, r.drift, nullptr}, q);
  const double end_s = program->end_time_s() + (linked ? kLinkTailS : 0.0);
  const double dt = c.controller.servo_period_s;
  const double daq_period = 1.0 / c.sensor.rate_hz;
  double next_daq = daq_period;
  PassTrace trace;
  trace.name = r.pass.name;
  std::vector<std::pair<double, Vector3>> log;
  for (long k = 1; k <= static_cast<long>(std::ceil(end_s / dt)); ++k) {
    const double t = static_cast<double>(k) * dt;
    net.clock.set(t);
    q = controller->tick(t);
    r.drift.advance(dt);
    process.advance(dt);
    Wrench w;
    const Vector3 p = solver.tick(cell::CoupledArm{robot, ws, state, r.drift, &process}, q, dt, w);
    controller->encoders(state.q_motor);
    for (; next_daq <= t + 1e-12; next_daq += daq_period) {
      const Vector3 reading = r.sensor.sample(w.head<3>(), ws.base_T_flange.linear(), next_daq);
      if (linked) daq.send(next_daq, reading);
      if (r.log_sensor) log.emplace_back(next_daq, decoupling * reading);
    }
    if (linked) {
      net.clock.set(t + c.controller.network_latency_s);
      poll_deflex_session(*side.session, out.link_cycles, "machining run");
    }
    if (r.spec.trace && k % 10 == 0) record_pass_sample(r, p, w, trace);
  }
  if (linked) {
    (void)side.session->finish();
    const auto* egm = dynamic_cast<const cell::EgmPositionGuidanceController*>(controller.get());
    if (egm != nullptr && egm->counters().timed_out) {
      throw Error("machining run: the simulated controller stopped EGM for lack of answers (a broken setup)");
    }
  }
  out.coupled.add(solver.counters());
  out.simulated_s += end_s;
  if (r.spec.trace) out.passes.push_back(std::move(trace));
  if (r.log_sensor) out.sensor_logs.push_back(std::move(log));
}

}  // namespace

MillCell build_mill_cell(std::uint64_t seed) {
  CaseConfig config = paper_case();
  config.seed = seed;
  SetupCell setup = build_setup_cell(config, true);
  MillCell mc{std::move(config), std::move(setup), Pose::Identity(), Matrix3::Identity()};
  mc.tcp_orientation = mc.config.circle.tcp_orientation.linear();
  // The workpiece at the circle's centre, its z along the tool axis (from the tip into the
  // spindle: the TCP's -z), its x along the TCP's x.
  Matrix3 r;
  r.col(2) = -mc.tcp_orientation.col(2);
  r.col(0) = mc.tcp_orientation.col(0);
  r.col(1) = r.col(2).cross(r.col(0));
  mc.base_T_workpiece.linear() = r;
  mc.base_T_workpiece.translation() = mc.config.circle.center_m;
  return mc;
}

PathWrenchModel::PathWrenchModel(std::vector<Vector3> positions_base_m, std::vector<Wrench> wrenches)
    : positions_(std::move(positions_base_m)), wrenches_(std::move(wrenches)) {
  if (positions_.size() != wrenches_.size() || positions_.empty()) {
    throw InputError("path wrench model: one wrench a point, and at least one point");
  }
}

Wrench PathWrenchModel::wrench_at(std::size_t index, const Pose& /*base_T_tcp*/) const {
  if (index >= wrenches_.size()) {
    throw InputError(fmt::format("path wrench model: point {} of {}", index, wrenches_.size()));
  }
  return wrenches_[index];
}

bool PathWrenchModel::wrench_at_pose(const Pose& base_T_tcp, Wrench& out) const noexcept {
  const Vector3 p = base_T_tcp.translation();
  std::size_t best = 0;
  double best_d = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < positions_.size(); ++i) {
    const double d = (positions_[i] - p).squaredNorm();
    if (d < best_d) {
      best_d = d;
      best = i;
    }
  }
  out = wrenches_[best];
  return true;
}

namespace {

// The user's prediction of one pass (base frame, at each program point) from the force model on the
// nominal stock, which `predictor` carries from pass to pass. From the second pass on, the tool
// leaves the part as a CAM program would: up clear of the stock, across and down outside it, all
// rapid (else the model would cut the straight line between the passes).
std::shared_ptr<const PathWrenchModel> predict_pass(const MillCell& mc, const MillPass* previous, const MillPass& pass,
                                                    const PassProgram& pp, double clear_z, double feed_mm_min,
                                                    MillingProcess& predictor) {
  if (previous != nullptr) {
    const Vector3 from = previous->corners.back(), to = pass.corners.front();
    for (const Vector3& v : {Vector3(from.x(), from.y(), clear_z), Vector3(to.x(), to.y(), clear_z)}) {
      MillingPointInput in;
      in.tip_m = v;
      in.rapid = true;
      in.spindle_rpm = kStudySpindleRpm;
      in.turn = SpindleTurn::kClockwise;
      (void)predictor.next(in);
    }
  }
  const Matrix3 base_R_wp = mc.base_T_workpiece.linear();
  std::vector<Vector3> positions;
  std::vector<Wrench> wrenches;
  for (std::size_t i = 0; i < pp.tips_workpiece_m.size(); ++i) {
    MillingPointInput in;
    in.tip_m = pp.tips_workpiece_m[i];
    in.feed_mm_min = feed_mm_min;
    in.spindle_rpm = kStudySpindleRpm;
    in.turn = SpindleTurn::kClockwise;
    in.line = i + 1;
    in.rapid = i == 0;
    const Wrench w_wp = predictor.next(in).wrench;
    Wrench w;
    w << base_R_wp * w_wp.head<3>(), base_R_wp * w_wp.tail<3>();
    positions.push_back(pp.poses[i].translation());
    wrenches.push_back(w);
  }
  return std::make_shared<const PathWrenchModel>(std::move(positions), std::move(wrenches));
}

}  // namespace

std::vector<PassProgram> plan_passes(const MillCell& mc, const std::vector<MillPass>& passes, const StockBox& stock,
                                     MachiningStrategy strategy, double feed_mm_min, const CuttingCoefficients* k) {
  const RobotModel& model = mc.setup.calibration.identified;
  const bool offline_model = strategy == MachiningStrategy::kOffline || strategy == MachiningStrategy::kHybrid;
  if (offline_model && k == nullptr) throw InputError("machining plan: the offline strategies need coefficients");
  // The user's model of the cut: the fitted coefficients on the nominal stock, the passes in order.
  std::unique_ptr<MillingForceModel> force;
  std::unique_ptr<DexelStock> nominal_stock;
  std::unique_ptr<MillingProcess> predictor;
  if (offline_model) {
    MillingSpec spec;
    spec.coefficients.k = *k;
    force = std::make_unique<MillingForceModel>(spec, study_cutter());
    nominal_stock = std::make_unique<DexelStock>(make_stock(stock));
    predictor = std::make_unique<MillingProcess>(*force, nominal_stock.get());
  }
  std::vector<PassProgram> out;
  IkRequest first;
  first.seed = standing_pose(model);
  for (std::size_t n = 0; n < passes.size(); ++n) {
    PassProgram pp;
    pp.tips_workpiece_m = sample_pass(passes[n], kProgramStepM);
    for (const Vector3& tip : pp.tips_workpiece_m) {
      Pose pose = Pose::Identity();
      pose.linear() = mc.tcp_orientation;
      pose.translation() = mc.base_T_workpiece * tip;
      pp.poses.push_back(pose);
    }
    JointPath path = solve_path_ik(model, pp.poses, first);
    first.seed = path.q.front();
    if (!offline_model) {
      pp.q = std::move(path.q);
      out.push_back(std::move(pp));
      continue;
    }
    pp.predicted = predict_pass(mc, n > 0 ? &passes[n - 1] : nullptr, passes[n], pp, stock.max_m.z() + 5e-3,
                                feed_mm_min, *predictor);
    OfflineOptions options;
    options.predict = false;
    for (const auto& p : compensate_path(model, path, pp.poses, *pp.predicted, options).points) {
      pp.q.push_back(p.q_command);
    }
    out.push_back(std::move(pp));
  }
  return out;
}

MillRunResult run_mill_passes(const MillCell& mc, const std::vector<MillPass>& passes,
                              const std::vector<PassProgram>& programs, DexelStock& stock, const MillRunSpec& spec,
                              bool log_sensor) {
  const cell::CellConfig& c = mc.config.cell;
  // One physical sensor for the seed's cell (its crosstalk and sensitivities), its noise the run's.
  cell::ForceSensorDaq sensor(c.sensor, c.tool, mill_seed(spec.seed, MillComponent::kSensor),
                              splitmix(mc.config.seed ^ 0x5e5503ULL));
  cell::PathDrift drift(c.drift, mill_seed(spec.seed, MillComponent::kDrift));
  // The touch-off uses the nominal joints, whatever the strategy's program (the same stock placement).
  IkRequest first;
  first.seed = standing_pose(mc.setup.calibration.identified);
  Pose pose0 = Pose::Identity();
  pose0.linear() = mc.tcp_orientation;
  pose0.translation() = mc.base_T_workpiece * passes.front().corners.front();
  const JointPath q0 = solve_path_ik(mc.setup.calibration.identified, {pose0}, first);
  const Pose base_T_stock = touch_off(mc, q0.q.front(), passes.front().corners.front(), drift);
  MillRunResult out;
  for (std::size_t i = 0; i < passes.size(); ++i) {
    run_one_pass(PassRun{mc, passes[i], programs[i], spec, base_T_stock, stock, drift, sensor, log_sensor}, out);
  }
  return out;
}

std::vector<SlotCut> run_slot_cuts(const MillCell& mc, const SlotCutPlan& plan, const MillRunSpec& spec,
                                   const std::string& log_dir) {
  const Cutter cutter = study_cutter();
  DexelStock stock = make_stock(plan.stock);
  std::vector<SlotCut> cuts;
  // The mounting's nominal axes: which of the sensor's axes lies along the feed (the workpiece's x)
  // and which along the tool axis (its z), from the nominal kinematics at the first point.
  const RobotModel& nominal = mc.setup.robot->nominal_model();
  for (std::size_t i = 0; i < plan.passes.size(); ++i) {
    const std::vector<MillPass> one{plan.passes[i]};
    const double feed_mm_min = plan.fz_m[i] * kStudySpindleRpm * cutter.flutes * 1e3;
    const std::vector<PassProgram> programs =
        plan_passes(mc, one, plan.stock, MachiningStrategy::kUncompensated, feed_mm_min, nullptr);
    MillRunSpec s = spec;
    s.strategy = MachiningStrategy::kUncompensated;
    s.feed_mm_min = feed_mm_min;
    s.seed = splitmix(spec.seed ^ (i + 101));
    s.trace = false;
    const MillRunResult r = run_mill_passes(mc, one, programs, stock, s, true);
    const std::string path = fmt::format("{}/slot_{}.csv", log_dir, i + 1);
    {
      std::ofstream f(path);
      f << "t_s,fx_N,fy_N,fz_N\n";
      for (const auto& [t, v] : r.sensor_logs.front()) {
        f << fmt::format("{:.6f},{:.4f},{:.4f},{:.4f}\n", t, v.x(), v.y(), v.z());
      }
      if (!f) throw Error(fmt::format("slot cuts: cannot write {}", path));
    }
    Workspace ws(nominal);
    forward_kinematics(nominal, ws, programs.front().q.front());
    const Matrix3 sensor_R_wp = ws.base_T_flange.linear().transpose() * mc.base_T_workpiece.linear();
    SlotLogOptions o;
    Eigen::Index axis = 0;
    o.feed_sign = sensor_R_wp.col(0).cwiseAbs().maxCoeff(&axis) > 0.0 && sensor_R_wp(axis, 0) < 0.0 ? -1.0 : 1.0;
    o.feed_axis = static_cast<int>(axis);
    o.tool_sign = sensor_R_wp.col(2).cwiseAbs().maxCoeff(&axis) > 0.0 && sensor_R_wp(axis, 2) < 0.0 ? -1.0 : 1.0;
    o.tool_axis = static_cast<int>(axis);
    const double speed = feed_mm_min / 60.0 * 1e-3;
    const double x0 = plan.passes[i].corners.front().x();
    o.air_from_s = 0.05;
    o.air_to_s = kHoldS - 0.02;
    o.window_from_s = kHoldS + (plan.window_from_x_m - x0) / speed;
    o.window_to_s = kHoldS + (plan.window_to_x_m - x0) / speed;
    o.spindle_rpm = kStudySpindleRpm;
    const SlotLogMean mean = read_slot_log(path, o);
    SlotCut cut;
    cut.fz_m = plan.fz_m[i];
    cut.ap_m = plan.ap_m;
    cut.flutes = cutter.flutes;
    cut.turn = SpindleTurn::kClockwise;
    cut.mean_force_n = mean.mean_force_n;
    cut.label = path;
    cuts.push_back(cut);
  }
  return cuts;
}

}  // namespace deflex::study
