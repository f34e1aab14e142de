// The cell's cut: the true arm mills a wall in a dexel stock through the tick's coupled solve, and
// the part probe measures what it left. A rigid arm leaves the wall where it was programmed; a
// compliant one, uncompensated, leaves it where the closed form puts it: the arm's first-order
// compliance (the core's tcp_deflection, not the cell's solve) times the revolution-average force of
// an independent per-tooth sum (textbook_milling.hpp), with the chip's feedback (the true radial
// width and depth are the programmed ones less the tool's deflection) solved by a fixed point here.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>

#include "deflex/cell/cell_config.hpp"
#include "deflex/cell/coupled_tick.hpp"
#include "deflex/cell/milling_process.hpp"
#include "deflex/cell/part_probe.hpp"
#include "deflex/cell/path_drift.hpp"
#include "deflex/cell/true_robot.hpp"
#include "deflex/machining/dexel_stock.hpp"
#include "deflex/model/compliance.hpp"
#include "deflex/model/inverse_kinematics.hpp"
#include "deflex/text/errors.hpp"
#include "machining/textbook_milling.hpp"

namespace deflex::cell {
namespace {

// The cut: a 10 mm, three-flute end mill at 12 000 rpm and 1500 mm/min (fz 0.042 mm) takes a 2 mm
// wide, 5 mm deep side cut off a 24 mm long block of Al7075-T6 (reference/machining.md's set).
constexpr double kDiameter = 10e-3, kAe = 2e-3, kAp = 5e-3, kRpm = 12000.0, kFeed = 1500.0 / 60.0 * 1e-3;
constexpr double kLength = 24e-3, kDt = 1e-3;
constexpr int kFlutes = 3;

CuttingCoefficients al7075() {
  CuttingCoefficients k;
  k.ktc_n_m2 = 767e6;
  k.krc_n_m2 = 168.8e6;
  k.kac_n_m2 = 222e6;
  k.kte_n_m = 27.7e3;
  k.kre_n_m = 26.6e3;
  k.kae_n_m = 0.7e3;
  return k;
}

JointVector start_pose() {
  JointVector q(6);
  q << 0.1, deg_to_rad(25.0), deg_to_rad(5.0), 0.2, deg_to_rad(55.0), -0.3;
  return q;
}

// The stock frame: z along the tool axis (from the tip into the spindle), x the feed. Down milling
// (`climb`): the block from (0, -15, -10) mm to (24, 0, 0) mm, the wall to be cut the plane y = -ae
// with the material below it, the tool's tip along y = R - ae; up milling: the mirror image in y (the
// teeth, turning M3, enter the material where the chip is thinnest). The tip runs at z = -ap from
// x = -R - 1 mm to the far side.
struct CutRig {
  CutRig(double stiffness_scale, double runout_m, bool climb = true)
      : side(climb ? 1.0 : -1.0),
        config(make_config(stiffness_scale)),
        robot(config, false, 7),
        ws(robot.true_model()),
        state(robot.initial_state(start_pose())),
        drift({}, 1),
        stock(climb ? DexelStock::box(Vector3(0.0, -15e-3, -10e-3), Vector3(kLength, 0.0, 0.0), 0.1e-3, 0.5e-3)
                    : DexelStock::box(Vector3(0.0, 0.0, -10e-3), Vector3(kLength, 15e-3, 0.0), 0.1e-3, 0.5e-3)) {
    Workspace fk(robot.true_model());
    forward_kinematics(robot.true_model(), fk, start_pose());
    tcp_r = fk.base_T_tcp.linear();
    Matrix3 r;
    r.col(2) = -tcp_r.col(2);
    r.col(0) = tcp_r.col(0);
    r.col(1) = r.col(2).cross(r.col(0));
    base_T_stock.linear() = r;
    base_T_stock.translation() = fk.base_T_tcp.translation() - r * tip_at(0.0);
    process_config.cutter.diameter_m = kDiameter;
    process_config.cutter.flutes = kFlutes;
    process_config.cutter.helix_rad = deg_to_rad(30.0);
    process_config.k = al7075();
    process_config.spindle_rpm = kRpm;
    process_config.runout_m = runout_m;
    process_config.base_T_stock = base_T_stock;
  }
  static CellConfig make_config(double stiffness_scale) {
    CellConfig c;  // the built-in robot, lumped joints, no gravity, no drift
    c.robot.stiffness_scale = stiffness_scale;
    return c;
  }
  // The programmed tip (stock frame) a time t after the start.
  [[nodiscard]] Vector3 tip_at(double t) const {
    return {-0.5 * kDiameter - 1e-3 + kFeed * t, side * (0.5 * kDiameter - kAe), -kAp};
  }
  // The joints that put the programmed tip at `tip` with the start's orientation.
  JointVector joints_at(const Vector3& tip, const JointVector& seed) {
    Pose target = Pose::Identity();
    target.linear() = tcp_r;
    target.translation() = base_T_stock * tip;
    IkRequest request;
    request.seed = seed;
    Workspace ik(robot.true_model());
    const IkResult r = inverse_kinematics(robot.true_model(), ik, target, request);
    EXPECT_TRUE(r.ok()) << r.message;
    return r.q;
  }
  // Runs the whole pass; returns the coupled solves' counters, and in `steady_unconverged` the ticks
  // left unconverged while the tool's centre was between 1 mm and 17 mm (where the walls are probed).
  CoupledTickCounters cut(MillingProcess& process, std::uint64_t* steady_unconverged = nullptr) {
    CoupledTickSolver solver;
    std::uint64_t before = 0, after = 0;
    (void)solver.at_rest(CoupledArm{robot, ws, state, drift, nullptr}, start_pose());
    JointVector q = start_pose();
    const int ticks = static_cast<int>((kLength + kDiameter + 2e-3) / kFeed / kDt);
    for (int i = 1; i <= ticks; ++i) {
      q = joints_at(tip_at(i * kDt), q);
      process.advance(kDt);
      Wrench w;
      (void)solver.tick(CoupledArm{robot, ws, state, drift, &process}, q, kDt, w);
      const double x = tip_at(i * kDt).x();
      if (x < 1e-3) before = solver.counters().unconverged;
      if (x < 17e-3) after = solver.counters().unconverged;
    }
    if (steady_unconverged != nullptr) *steady_unconverged = after - before;
    return solver.counters();
  }

  double side;  // +1: the material on -y (down milling), -1: on +y (up milling)
  CellConfig config;
  TrueRobot robot;
  Workspace ws;
  TrueRobotState state;
  PathDrift drift;
  DexelStock stock;
  Matrix3 tcp_r;
  Pose base_T_stock = Pose::Identity();
  MillingProcessConfig process_config;
};

// The wall y = -ae (down milling, `side` +1) or y = ae (up milling, -1), probed at `x` (one station)
// or over the middle of the pass, at mid-depth heights.
WallSpec wall_spec(double side, double x_lo, double x_hi, int points_along) {
  WallSpec s;
  s.normal = WallSpec::Normal::kY;
  s.nominal_m = -side * kAe;
  s.material_below = side > 0.0;
  s.along_lo_m = x_lo;
  s.along_hi_m = x_hi;
  s.z_lo_m = -kAp + 0.75e-3;
  s.z_hi_m = -0.75e-3;
  s.points_along = points_along;
  s.points_up = 4;
  return s;
}

// The independent closed form of the cut's averaged wrench (stock frame: feed x, axis z, M3; the
// material on -y: down milling, the teeth leaving at phi = pi; on +y: up milling, the teeth entering
// at phi = 0) at a radial width and depth.
Vector6 textbook_wrench(double ae, double ap, double side) {
  test::TextbookCut c;
  c.diameter_m = kDiameter;
  c.flutes = kFlutes;
  c.helix_rad = 0.0;  // a revolution's average is the same for any helix on a uniform engagement
  c.fz_m = kFeed * 60.0 / (kRpm * kFlutes);
  c.m3 = true;
  const double sweep = std::acos(1.0 - 2.0 * ae / kDiameter);
  c.entry_rad = side > 0.0 ? kPi - sweep : 0.0;
  c.exit_rad = side > 0.0 ? kPi : sweep;
  c.z_lo_m = 0.0;
  c.z_hi_m = ap;
  const CuttingCoefficients k = al7075();
  c.ktc = k.ktc_n_m2;
  c.krc = k.krc_n_m2;
  c.kac = k.kac_n_m2;
  c.kte = k.kte_n_m;
  c.kre = k.kre_n_m;
  c.kae = k.kae_n_m;
  return test::textbook_average(c, 36000, 1);
}

// The tool's deflection (stock frame) with its chip's feedback: the first-order compliance of the
// lumped arm at the joints `q` under the wrench of the true width and depth, which the deflection
// itself sets (ae = ae0 - side dy, ap = ap0 - dz), to a fixed point. `no_feedback`: the first step.
Vector3 closed_form_deflection(CutRig& rig, const JointVector& q, Vector3* no_feedback = nullptr) {
  const Matrix3 r = rig.base_T_stock.linear();
  Workspace ws(rig.robot.true_model());
  Vector3 d = Vector3::Zero();
  for (int it = 0; it < 40; ++it) {
    const Vector6 w_stock = textbook_wrench(kAe - rig.side * d.y(), kAp - d.z(), rig.side);
    Wrench w_base;
    w_base << r * w_stock.head<3>(), r * w_stock.tail<3>();
    const Vector3 next = r.transpose() * tcp_deflection(rig.robot.true_model(), ws, q, w_base).head<3>();
    if (it == 0 && no_feedback != nullptr) *no_feedback = next;
    if ((next - d).norm() < 1e-12) return next;
    d = next;
  }
  ADD_FAILURE() << "the closed form's fixed point did not converge";
  return d;
}

TEST(MillingCell, ARigidArmMachinesTheWallExactly) {
  // 3000 times stiffer (its stiffest joint at 9e9 Nm/rad, inside the 1e10 Nm/rad deflex accepts): some
  // 0.05 um at the cut's 100 N, where the arm as built yields 155 um.
  CutRig rig(3000.0, 0.0);
  MillingProcess process(rig.process_config, rig.stock);
  const CoupledTickCounters counters = rig.cut(process);
  EXPECT_EQ(counters.unconverged, 0u);  // a rigid arm takes the force without moving
  EXPECT_EQ(process.tilted_ticks(), 0u);
  PartProbe probe(0.0, 1);
  const WallProfile wall = probe.wall(rig.stock, wall_spec(rig.side, 1e-3, kLength - 1e-3, 45));
  ASSERT_EQ(wall.missing, 0);
  ASSERT_EQ(wall.points, 180);
  // The stock's resolution on a wall is the dexels' (float ends: nanometres); a cell's 0.1 mm would be
  // a height map's. The wall is where it was programmed, to the 3000-times stiffer arm's 0.05 um
  // (155 um / 3000; the profile zone is twice the largest deviation), far below either.
  EXPECT_LT(wall.profile_m, 0.2e-6) << wall.mean_m;
  // The floor the end face left under the cut (x away from the ends, y inside the 2 mm strip).
  FloorSpec f;
  f.nominal_m = -kAp;
  f.x_lo_m = 1e-3;
  f.x_hi_m = kLength - 1e-3;
  f.y_lo_m = -kAe + 0.2e-3;
  f.y_hi_m = -0.2e-3;
  const FloorFlatness floor = probe.floor(rig.stock, f);
  EXPECT_LT(floor.flatness_m, 0.2e-6);
  EXPECT_LT(std::abs(floor.mean_m), 0.2e-6);
  // The tool took ae x ap over the block's length (and the entry's and exit's half discs).
  EXPECT_GT(rig.stock.removed_volume_m3(), kAe * kAp * kLength);
}

TEST(MillingCell, ARunoutCutsTheWallDeeperByItsSize) {
  constexpr double kRunout = 10e-6;
  CutRig rig(3000.0, kRunout);
  MillingProcess process(rig.process_config, rig.stock);
  (void)rig.cut(process);
  PartProbe probe(0.0, 1);
  const WallProfile wall = probe.wall(rig.stock, wall_spec(rig.side, 1e-3, kLength - 1e-3, 20));
  ASSERT_EQ(wall.points, 80);
  EXPECT_NEAR(wall.mean_m, -kRunout, 0.2e-6);  // the stiff arm's 0.05 um beside the runout
  EXPECT_LT(wall.peak_to_valley_m, 0.2e-6);
}

// The built-in arm cuts the wall uncompensated; the wall is probed at three stations against the
// closed form of its deflection there.
void compliant_cut_against_closed_form(bool climb) {
  CutRig rig(1.0, 0.0, climb);
  MillingProcess process(rig.process_config, rig.stock);
  std::uint64_t steady_unconverged = 0;
  const CoupledTickCounters counters = rig.cut(process, &steady_unconverged);
  // Down milling: every tick of the stretch the walls are probed on settles; the entry and the exit,
  // where the engagement changes fastest, leave a few at the solver's cap (the force steps by newtons
  // between trial positions a fraction of a micrometre apart there). Up milling leaves about one tick
  // in six at the cap, along the probed walls too; what steps its force is not pinned down (clipping
  // the arcs to a minimum chip thickness of 1-3 um, or taking the feed over 1 to 20 ticks, leaves as
  // many). Counted, and bounded here so that a change that spreads them is seen.
  if (climb) {
    EXPECT_EQ(steady_unconverged, 0u);
    EXPECT_LT(counters.unconverged, counters.ticks / 40);
  } else {
    EXPECT_LT(counters.unconverged, counters.ticks / 5);
  }
  EXPECT_EQ(process.tilted_ticks(), 0u);
  PartProbe probe(0.0, 1);
  // Stations where the full arc was in the material when the tool's centre passed (it leaves the
  // wall beside its centre; its front leaves the block 3-4 mm before the end).
  for (const double x : {4e-3, 10e-3, 16e-3}) {
    const WallProfile wall = probe.wall(rig.stock, wall_spec(rig.side, x, x, 1));
    ASSERT_EQ(wall.points, 4);
    Vector3 no_feedback;
    const JointVector q = rig.joints_at(rig.tip_at((x - rig.tip_at(0.0).x()) / kFeed), start_pose());
    const Vector3 d = closed_form_deflection(rig, q, &no_feedback);
    // How far the tool stands off the wall (away from the material): the material it leaves.
    const double off = rig.side * d.y();
    ASSERT_GT(std::abs(off), 10e-6) << "a cut that hardly moves the tool tests nothing";
    // The cell's arm is solved at its deflected configuration (the closed form is first order):
    // 1 % of the deflection covers it; up milling's unsettled ticks (above) ask 2 %.
    const double tolerance = (climb ? 0.01 : 0.02) * std::abs(off);
    EXPECT_NEAR(wall.mean_m, off, tolerance) << (climb ? "climb" : "conventional") << ", x " << x * 1e3 << " mm";
    EXPECT_LT(wall.peak_to_valley_m, 0.1e-6);
    // Down milling pushes the tool off the wall with most of its force, so there the chip's feedback
    // matters: leaving it out misses by more than the tolerance.
    if (climb) {
      EXPECT_GT(std::abs(rig.side * no_feedback.y() - off), 2.0 * tolerance);
    }
  }
}

TEST(MillingCell, ACompliantArmLeavesADownMilledWallWhereTheClosedFormPutsIt) {
  compliant_cut_against_closed_form(true);
}

TEST(MillingCell, ACompliantArmLeavesAnUpMilledWallWhereTheClosedFormPutsIt) {
  compliant_cut_against_closed_form(false);
}

TEST(MillingCell, TheProbesNoiseIsWhatItSaysAndBadSpecsAreRefused) {
  DexelStock stock = DexelStock::box(Vector3(0.0, -10e-3, -10e-3), Vector3(20e-3, 0.0, 0.0), 0.1e-3, 0.5e-3);
  WallSpec s;
  s.normal = WallSpec::Normal::kY;
  s.nominal_m = 0.0;
  s.along_lo_m = 1e-3;
  s.along_hi_m = 19e-3;
  s.z_lo_m = -9e-3;
  s.z_hi_m = -1e-3;
  s.points_along = 50;
  s.points_up = 8;
  constexpr double kNoise = 2e-6;
  PartProbe probe(kNoise, 3);
  const WallProfile wall = probe.wall(stock, s);
  ASSERT_EQ(wall.points, 400);
  // The RMS of 400 normal draws about the true (untouched) face: within 10 % of sigma (5 standard
  // errors of the RMS, sigma / sqrt(2 n) = 3.5 %, over 3).
  EXPECT_NEAR(wall.rms_m, kNoise, 0.1 * kNoise);
  EXPECT_NEAR(wall.mean_m, 0.0, 5.0 * kNoise / 20.0);
  // The face at x = 0 has its material above it: the same wall seen from the other side.
  WallSpec x0 = s;
  x0.normal = WallSpec::Normal::kX;
  x0.nominal_m = 0.0;
  x0.material_below = false;
  x0.along_lo_m = -9e-3;
  x0.along_hi_m = -1e-3;
  PartProbe exact(0.0, 3);
  const WallProfile face = exact.wall(stock, x0);
  EXPECT_EQ(face.points, 400);
  EXPECT_LT(face.profile_m, 1e-9);
  const WidthMeasure width = PartProbe::width(face, x0, exact.wall(stock, s), s);
  EXPECT_NEAR(width.width_m, 0.0, 1e-9);  // both faces are planes through the origin, at right angles
  WallSpec far = s;
  far.nominal_m = 5e-3;  // no face within the 2 mm search
  EXPECT_EQ(exact.wall(stock, far).missing, 400);
  WallSpec bad = s;
  bad.points_along = 0;
  EXPECT_THROW((void)exact.wall(stock, bad), InputError);
  EXPECT_THROW(PartProbe(-1e-6, 1), InputError);
  bad.points_along = 100000;
  EXPECT_THROW((void)exact.wall(stock, bad), InputError);
  FloorSpec f;
  f.nx = 1;
  f.ny = 1;
  EXPECT_THROW((void)exact.floor(stock, f), InputError);
  f.nx = f.ny = 1 << 20;  // the product would overflow an int
  EXPECT_THROW((void)exact.floor(stock, f), InputError);
}

TEST(MillingCell, BadProcessSettingsAreRefused) {
  DexelStock stock = DexelStock::box(Vector3::Zero(), Vector3(0.01, 0.01, 0.01), 0.5e-3, 0.5e-3);
  MillingProcessConfig c;
  c.cutter.diameter_m = kDiameter;
  c.cutter.flutes = kFlutes;
  c.k = al7075();
  EXPECT_NO_THROW(MillingProcess(c, stock));
  MillingProcessConfig bad = c;
  bad.runout_m = 2e-3;
  EXPECT_THROW(MillingProcess(bad, stock), InputError);
  bad = c;
  bad.spindle_rpm = 0.0;
  EXPECT_THROW(MillingProcess(bad, stock), InputError);
  bad = c;
  bad.k.ktc_n_m2 = std::nan("");
  EXPECT_THROW(MillingProcess(bad, stock), InputError);
  EXPECT_THROW((void)draw_true_coefficients(al7075(), -0.1, 1), InputError);
  // The drawn set: the published one at zero spread; a seed's set differs from another's.
  const CuttingCoefficients same = draw_true_coefficients(al7075(), 0.0, 5);
  EXPECT_DOUBLE_EQ(same.ktc_n_m2, al7075().ktc_n_m2);
  EXPECT_NE(draw_true_coefficients(al7075(), 0.15, 1).ktc_n_m2, draw_true_coefficients(al7075(), 0.15, 2).ktc_n_m2);
}

TEST(MillingCell, TheTrueCoefficientsSpreadAsStated) {
  // Log-normal draws: log(k / k_published) has mean 0 and standard deviation sigma. Over 2000 seeds
  // the sample's mean lies within 3 standard errors (sigma / sqrt(n)) of 0 and its standard deviation
  // within 3 of sigma (sigma / sqrt(2 n): 1.6 %).
  constexpr double kSigma = 0.15;
  constexpr int kDraws = 2000;
  const CuttingCoefficients k0 = al7075();
  double sum = 0.0, sum2 = 0.0;
  for (int seed = 0; seed < kDraws; ++seed) {
    const double l =
        std::log(draw_true_coefficients(k0, kSigma, static_cast<std::uint64_t>(seed)).kre_n_m / k0.kre_n_m);
    sum += l;
    sum2 += l * l;
  }
  const double mean = sum / kDraws, sd = std::sqrt((sum2 - kDraws * mean * mean) / (kDraws - 1));
  EXPECT_NEAR(mean, 0.0, 3.0 * kSigma / std::sqrt(kDraws));
  EXPECT_NEAR(sd, kSigma, 3.0 * kSigma / std::sqrt(2.0 * kDraws));
}

}  // namespace
}  // namespace deflex::cell
