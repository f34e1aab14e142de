// The toolpath job against values computed here without it: the milling force along a real G-code
// slot against the textbook's closed form (it turns with the feed), the compensated G-code of a
// straight slot against the exact form computed with KDL, the spindle angle against a brute-force
// sweep, the rate bound, and the refusals that name the program's line.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <regex>
#include <sstream>

#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainjnttojacsolver.hpp>

#include "deflex/force/force_spec.hpp"
#include "deflex/machining/milling_force_model.hpp"
#include "deflex/machining/stock_spec.hpp"
#include "deflex/offline/toolpath_job.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/toolpath/gcode_reader.hpp"
#include "machining/textbook_milling.hpp"
#include "model/kdl_chain.hpp"
#include "support/error_of.hpp"

namespace deflex {
namespace {

const std::string kSrc = DEFLEX_SOURCE_DIR;

RobotModel spindle_robot() { return load_robot(kSrc + "/examples/machining/irb6700_spindle.yaml"); }

Pose workpiece_at(double x_mm, double y_mm, double z_mm) {
  Pose p = Pose::Identity();
  p.translation() = Vector3(x_mm, y_mm, z_mm) * 1e-3;
  return p;
}

MillingSpec al7075(std::optional<double> ae_mm = std::nullopt, std::optional<double> ap_mm = std::nullopt) {
  MillingSpec s;
  s.coefficients.k = {767e6, 168.8e6, 222e6, 27.7e3, 26.6e3, 0.7e3};
  if (ae_mm) s.ae_m = *ae_mm * 1e-3;
  if (ap_mm) s.ap_m = *ap_mm * 1e-3;
  return s;
}

Cutter end_mill() { return parse_cutter_spec("diameter_mm=10,flutes=3,helix_deg=30"); }

struct JobRun {
  ToolpathJobResult result;
  std::vector<ToolpathJobPoint> points;
};

JobRun run_text(const RobotModel& model, const std::string& gcode, const MillingForceModel& force, Stock* stock,
                ToolpathJobOptions options, const ToolpathOptions& reading = {}) {
  GcodeReader reader(gcode, "t.nc", reading);
  JobRun run;
  ToolpathSinks sinks;
  sinks.keep = &run.points;
  run.result = run_toolpath_job(model, reader, force, stock, options, sinks);
  return run;
}

/// The textbook's slot, averaged over a tooth period by its own per-tooth sum: force and moment
/// about the tip, feed +x, axis +z (textbook_milling.hpp's frame).
Vector6 textbook_average(double ae_mm, double ap_mm, bool climb) {
  test::TextbookCut c;
  c.helix_rad = deg_to_rad(30.0);
  c.fz_m = 0.1e-3;
  c.z_hi_m = ap_mm * 1e-3;
  const double a = std::acos(1.0 - 2.0 * std::min(ae_mm, 10.0) / 10.0);
  if (ae_mm < 10.0) {
    c.entry_rad = climb ? kPi - a : 0.0;
    c.exit_rad = climb ? kPi : a;
  }
  Vector6 sum = Vector6::Zero();
  const int n = 720;
  for (int k = 0; k < n; ++k) sum += test::textbook_wrench(c, 2.0 * kPi / 3.0 * (k + 0.5) / n, 400);
  return sum / n;
}

const char* const kSquareSlot =
    "G21 G90 G94 G17\n"
    "S9000 M3\n"
    "G0 X-30 Y-30 Z5\n"
    "G1 Z-4 F900\n"
    "G1 X30 F2700\n"
    "G1 Y30\n"
    "G1 X-30\n"
    "G1 Y-31\n"
    "G0 Z5\n"
    "M5\n";

// A full slot 4 mm deep cut round a square, feed per tooth 0.1 mm: half-way along each side the tool
// is in a full slot of fresh material, and the force there is the textbook's slot force turned with
// the feed (feed +x, +y, -x, -y on lines 5 to 8).
TEST(ToolpathForce, TurnsWithTheFeedAlongASquareSlot) {
  const RobotModel model = spindle_robot();
  const MillingForceModel force(al7075(), end_mill());
  const std::unique_ptr<Stock> stock = parse_stock_spec("box:min_mm=-50;-50;-20,max_mm=50;50;0,cell_mm=0.1");
  ToolpathJobOptions o;
  o.base_T_workpiece = workpiece_at(2000, 0, 800);
  o.spin.optimize = false;
  ToolpathOptions reading;
  reading.max_linear_step_m = 1e-3;
  const JobRun run = run_text(model, kSquareSlot, force, stock.get(), o, reading);
  const Vector6 slot = textbook_average(10.0, 4.0, true);
  // The closed form (docs/machining.md): along the feed -N ap (fz Krc / 4 + Kre / pi), ...
  EXPECT_NEAR(slot[0], -3 * 4 * (0.1 * 168.8 / 4 + 26.6 / kPi), 0.5);
  const Vector3 feeds[] = {Vector3::UnitX(), Vector3::UnitY(), -Vector3::UnitX(), -Vector3::UnitY()};
  for (int side = 0; side < 4; ++side) {
    const std::size_t line = 5 + static_cast<std::size_t>(side);
    const ToolpathJobPoint* mid = nullptr;
    for (const ToolpathJobPoint& p : run.points) {
      const Vector3 at = p.source.position_m * 1e3;
      const double along = feeds[side].x() != 0.0 ? at.x() : at.y();
      if (p.source.line == line && std::abs(along) < 0.5) mid = &p;
    }
    ASSERT_NE(mid, nullptr) << "line " << line;
    ASSERT_EQ(mid->force.state, MillingPointState::kCut);
    const Vector3 f = feeds[side], n = Vector3::UnitZ().cross(f);
    const Vector3 expected = slot[0] * f + slot[1] * n + slot[2] * Vector3::UnitZ();
    const Vector3 got = mid->force.wrench.head<3>();
    // A wall on the height map lies within half a cell of where it was cut; here the query's circle is
    // the one that cut the slot's walls, and the entry and exit come out at 0 and 180 degrees.
    EXPECT_LT((got - expected).norm(), 0.005 * expected.norm())
        << "line " << line << ": " << got.transpose() << " against " << expected.transpose();
    EXPECT_NEAR(mid->force.ae_m, 10e-3, 0.2e-3);
    EXPECT_NEAR(mid->force.ap_m, 4e-3, 1e-6);
  }
  EXPECT_GT(run.result.removed_volume_m3, 0.9 * 4 * 120 * 10 * 1e-9);  // four 60 mm sides, 10 x 4 mm
}

// Without a stock, ae_mm= and ap_mm= make every feed move a cut of that engagement: the force is the
// textbook's whatever the stock would say, turned with the feed, and the moment about the tip too.
TEST(ToolpathForce, OverridesGiveTheTextbookWrenchOnEveryFeedMove) {
  const RobotModel model = spindle_robot();
  MillingSpec spec = al7075(3.0, 5.0);
  const MillingForceModel force(spec, end_mill());
  ToolpathJobOptions o;
  o.base_T_workpiece = workpiece_at(2000, 0, 800);
  o.spin.optimize = false;
  const JobRun run = run_text(model, kSquareSlot, force, nullptr, o);
  const Vector6 climb = textbook_average(3.0, 5.0, true);
  const Vector3 feeds[] = {Vector3::UnitX(), Vector3::UnitY(), -Vector3::UnitX(), -Vector3::UnitY()};
  int checked = 0;
  for (const ToolpathJobPoint& p : run.points) {
    if (p.source.line < 5 || p.source.line > 8) continue;
    const Vector3 f = feeds[p.source.line - 5], n = Vector3::UnitZ().cross(f), z = Vector3::UnitZ();
    Matrix3 r;
    r << f, n, z;
    EXPECT_LT((p.force.wrench.head<3>() - r * climb.head<3>()).norm(), 1e-3 * climb.head<3>().norm());
    EXPECT_LT((p.force.wrench.tail<3>() - r * climb.tail<3>()).norm(), 1e-3 * climb.tail<3>().norm());
    ++checked;
  }
  EXPECT_EQ(checked, 4);
}

double gcode_number(const std::string& line, char letter) {
  const std::regex word(std::string(1, letter) + R"(([-+]?[0-9]*\.?[0-9]*))");
  std::smatch m;
  if (!std::regex_search(line, m, word)) return std::nan("");
  return std::stod(m[1]);
}

// A straight slot with a known, constant force (ae and ap given): the compensated program's tip is
// where the exact form sends it, q_cmd = q_des - K^-1 J(q_des)^T W, with J and the forward kinematics
// from KDL, and its correction is the model's first-order deflection J K^-1 J^T W turned around.
TEST(ToolpathGcode, StraightSlotIsCompensatedByTheExactForm) {
  const RobotModel model = spindle_robot();
  const std::string dir = ::testing::TempDir();
  const std::string source = dir + "/deflex_slot.nc", output = dir + "/deflex_slot_out.nc";
  {
    std::ofstream f(source);
    f << "G21 G90 G94 G17\nS9000 M3\nG0 X-20. Y0. Z5.\nG1 Z-4. F900.\nG1 X20. F2700.\nG0 Z5.\nM5\n";
  }
  const MillingForceModel force(al7075(10.0, 4.0), end_mill());
  ToolpathJobOptions o;
  o.base_T_workpiece = workpiece_at(2000, 100, 750);
  o.spin = parse_tool_spin_spec("fixed:30");
  ToolpathOptions reading;
  reading.max_linear_step_m = 10e-3;
  std::vector<ToolpathJobPoint> points;
  {
    auto reader = open_toolpath(source, reading);
    GcodeWriteBack gcode(source, output, reading);
    ToolpathSinks sinks;
    sinks.keep = &points;
    sinks.gcode = &gcode;
    const ToolpathJobResult r = run_toolpath_job(model, *reader, force, nullptr, o, sinks);
    gcode.finish();
    EXPECT_EQ(r.counts.cut, 4u);
  }
  // The slot's wrench from the textbook's sum: feed +x of the workpiece, which is the base's.
  const Vector6 w = textbook_average(10.0, 4.0, true);
  const KDL::Chain chain = test::kdl_chain_from_dh(model);
  KDL::ChainFkSolverPos_recursive fk(chain);
  KDL::ChainJntToJacSolver jac(chain);
  std::ifstream in(output);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  int checked = 0;
  for (const ToolpathJobPoint& p : points) {
    if (p.force.state != MillingPointState::kCut) continue;
    KDL::JntArray q(6), q_cmd(6);
    for (int j = 0; j < 6; ++j) q(j) = p.compensated.q_desired[j];
    // The desired pose: the tip at the programmed point, TCP z down the tool, x the workpiece's x turned
    // by 30 deg about TCP z (the convention, written out here).
    KDL::Frame at;
    fk.JntToCart(q, at);
    const Vector3 tip_base = o.base_T_workpiece * p.source.position_m;
    EXPECT_LT((Vector3(at.p.x(), at.p.y(), at.p.z()) - tip_base).norm(), 1e-9);
    const double c = std::cos(deg_to_rad(30.0)), s = std::sin(deg_to_rad(30.0));
    EXPECT_LT((Vector3(at.M.UnitZ().x(), at.M.UnitZ().y(), at.M.UnitZ().z()) - Vector3(0, 0, -1)).norm(), 1e-9);
    EXPECT_LT((Vector3(at.M.UnitX().x(), at.M.UnitX().y(), at.M.UnitX().z()) - Vector3(c, -s, 0)).norm(), 1e-9);
    KDL::Jacobian j(6);
    jac.JntToJac(q, j);
    Eigen::Matrix<double, 6, 6> jm;
    for (int r = 0; r < 6; ++r)
      for (int k = 0; k < 6; ++k) jm(r, k) = j(static_cast<unsigned>(r), static_cast<unsigned>(k));
    const Vector6 dtheta = model.compliance().head<6>().asDiagonal() * (jm.transpose() * w);
    for (int k = 0; k < 6; ++k) q_cmd(k) = q(k) - dtheta[k];
    KDL::Frame cmd;
    fk.JntToCart(q_cmd, cmd);
    const Vector3 tip_cmd = o.base_T_workpiece.inverse() * Vector3(cmd.p.x(), cmd.p.y(), cmd.p.z());
    EXPECT_LT((tip_cmd - p.command_tip_workpiece_m).norm(), 1e-9);
    // First order, the correction is the deflection J K^-1 J^T W turned around.
    const Vector3 deflection = (jm * dtheta).head<3>();
    const Vector3 correction = tip_cmd - p.source.position_m;
    EXPECT_LT((correction + deflection).norm(), 0.01 * deflection.norm());
    EXPECT_GT(deflection.norm(), 0.05e-3);
    // The written program: the point's line (a G1 split in 10 mm steps) carries it to 0.001 mm.
    bool found = false;
    for (const std::string& l : lines) {
      if (l.rfind("G1", 0) != 0 && l.rfind("X", 0) != 0) continue;
      const double x = gcode_number(l, 'X'), y = gcode_number(l, 'Y'), z = gcode_number(l, 'Z');
      if (std::abs(x - tip_cmd.x() * 1e3) < 6e-4 && std::abs(y - tip_cmd.y() * 1e3) < 6e-4 &&
          std::abs(z - tip_cmd.z() * 1e3) < 6e-4) {
        found = true;
      }
    }
    EXPECT_TRUE(found) << "no line of the program at " << (tip_cmd * 1e3).transpose() << " mm";
    ++checked;
  }
  EXPECT_EQ(checked, 4);
  std::filesystem::remove(source);
  std::filesystem::remove(output);
}

/// The mean predicted deflection over the cutting points of a run at a fixed spindle angle.
double fixed_run(const RobotModel& model, const std::string& text, const MillingForceModel& force, ToolpathJobOptions o,
                 double deg, const ToolpathOptions& reading) {
  o.spin = parse_tool_spin_spec(fmt::format("fixed:{}", deg));
  return run_text(model, text, force, nullptr, o, reading).result.mean_cutting_deflection_m;
}

// On a short slot the choice is held to a brute-force sweep of every whole degree, each a full run at
// that fixed angle with the exact predicted deflection: the optimised run is within 0.5 % of the best
// of them, and the angle it holds is within one candidate step of that best.
TEST(ToolSpin, MatchesABruteForceSweepOnAShortPath) {
  const RobotModel model = spindle_robot();
  const std::string text = "G21 G90 G94\nS9000 M3\nG0 X-20 Y0 Z5\nG1 Z-4 F900\nG1 X20 F2700\nG0 Z5\nM5\n";
  const MillingForceModel force(al7075(10.0, 4.0), end_mill());
  ToolpathJobOptions o;
  o.base_T_workpiece = workpiece_at(1900, -200, 700);
  o.first.configuration = ArmConfiguration{0, 0, 0, 0};
  ToolpathOptions reading;
  reading.max_linear_step_m = 1e-3;
  double best = HUGE_VAL, best_deg = 0.0;
  for (int deg = -180; deg < 180; ++deg) {
    double mean = HUGE_VAL;
    try {
      mean = fixed_run(model, text, force, o, deg, reading);
    } catch (const InputError&) {
      continue;  // out of reach in this configuration at that angle
    }
    if (mean < best) {
      best = mean;
      best_deg = deg;
    }
  }
  ASSERT_LT(best, HUGE_VAL);
  const JobRun opt = run_text(model, text, force, nullptr, o, reading);
  EXPECT_LE(opt.result.mean_cutting_deflection_m, best * 1.005);
  for (const ToolpathJobPoint& p : opt.points) {
    if (p.force.state != MillingPointState::kCut) continue;
    EXPECT_LE(std::abs(std::remainder(rad_to_deg(p.spin_rad) - best_deg, 360.0)), 10.0 + 1e-9) << p.source.line;
  }
}

// Round a square the force turns by 90 degrees at every corner: the spin follows no faster than the
// rate bound, measured on the path length the planner counts (moves longer than 15 mm count 15 mm).
TEST(ToolSpin, TurnsNoFasterThanTheRateBound) {
  const RobotModel model = spindle_robot();
  const MillingForceModel force(al7075(3.0, 5.0), end_mill());
  ToolpathJobOptions o;
  o.base_T_workpiece = workpiece_at(2000, 0, 800);
  o.spin = parse_tool_spin_spec("optimize:rate_deg_per_mm=2,step_deg=5");
  ToolpathOptions reading;
  reading.max_linear_step_m = 0.5e-3;
  const JobRun run = run_text(model, kSquareSlot, force, nullptr, o, reading);
  double turned = 0.0;
  for (std::size_t i = 1; i < run.points.size(); ++i) {
    const double move = std::min((run.points[i].source.position_m - run.points[i - 1].source.position_m).norm(), 15e-3);
    const double step = std::abs(std::remainder(run.points[i].spin_rad - run.points[i - 1].spin_rad, 2.0 * kPi));
    EXPECT_LE(step, deg_to_rad(2.0) * move * 1e3 + 1e-9) << "line " << run.points[i].source.line;
    turned += step;
  }
  EXPECT_GT(turned, 0.0);  // it does use the freedom here
}

// Decided with a short lag and with the whole path in view, the choice differs little, and a tiny
// buffer (stages forced, the angle held across them) still gives every point a feasible angle.
TEST(ToolSpin, ShortLagAndForcedStagesStayCloseToTheFullView) {
  const RobotModel model = spindle_robot();
  const MillingForceModel force(al7075(3.0, 5.0), end_mill());
  ToolpathJobOptions o;
  o.base_T_workpiece = workpiece_at(2000, 0, 800);
  ToolpathOptions reading;
  reading.max_linear_step_m = 0.5e-3;
  o.spin.lag_stages = 1000;
  const double full = run_text(model, kSquareSlot, force, nullptr, o, reading).result.mean_cutting_deflection_m;
  o.spin.lag_stages = 3;
  const double short_lag = run_text(model, kSquareSlot, force, nullptr, o, reading).result.mean_cutting_deflection_m;
  o.spin.max_buffered_points = 20;
  const JobRun forced = run_text(model, kSquareSlot, force, nullptr, o, reading);
  EXPECT_LE(short_lag, full * 1.02);
  EXPECT_GT(forced.result.spin.forced_stages, 0u);
  EXPECT_LE(forced.result.mean_cutting_deflection_m, full * 1.10);
  EXPECT_EQ(forced.points.size(), run_text(model, kSquareSlot, force, nullptr, o, reading).points.size());
}

/// One example's run: the figure of merit of the optimised spin and of each of the twelve fixed
/// angles 0, 30, ..., 330 deg that is feasible (no error, within the margins everywhere).
struct SpinContest {
  double optimised = 0.0, best_fixed = HUGE_VAL, fixed_zero = HUGE_VAL;
  int feasible = 0;
};

SpinContest contest(const std::string& file, const std::string& force_spec, const std::string& stock_spec) {
  const RobotModel model = spindle_robot();
  ForceSpecContext context;
  context.milling = milling_force_specs(end_mill());
  const auto models = parse_force_specs(force_spec, context);
  const auto& force = dynamic_cast<const MillingForceModel&>(*models.front());
  ToolpathJobOptions o;
  o.base_T_workpiece = workpiece_at(2000, 0, 800);
  ToolpathOptions reading;
  reading.max_linear_step_m = 1e-3;
  const auto run = [&](const std::string& spin) {
    o.spin = parse_tool_spin_spec(spin);
    std::unique_ptr<Stock> stock = stock_spec.empty() ? nullptr : parse_stock_spec(stock_spec);
    auto reader = open_toolpath(kSrc + "/examples/machining/" + file, reading);
    return run_toolpath_job(model, *reader, force, stock.get(), o, ToolpathSinks{});
  };
  SpinContest c;
  c.optimised = run("optimize").mean_cutting_deflection_m;
  for (int deg = 0; deg < 360; deg += 30) {
    try {
      const ToolpathJobResult r = run(fmt::format("fixed:{}", deg));
      if (r.spin.margin_violations > 0) continue;
      ++c.feasible;
      c.best_fixed = std::min(c.best_fixed, r.mean_cutting_deflection_m);
      if (deg == 0) c.fixed_zero = r.mean_cutting_deflection_m;
    } catch (const InputError&) {
      // out of reach at that angle somewhere: out of the contest
    }
  }
  return c;
}

// The rule the choice is held to: on the shipped examples it never loses to the best of the twelve
// fixed angles by more than 2 % (mean predicted deflection over the cutting points, the exact
// fixed-point prediction of every run). The gains are printed for the docs.
TEST(ToolSpin, NeverLosesToTheBestFixedAngleByMoreThanTwoPercentOnTheExamples) {
  const SpinContest pocket = contest("pocket_contour.nc", "milling:file=" + kSrc + "/data/machining/al7075-t6.yaml",
                                     "box:min_mm=-50;-40;-20,max_mm=50;40;0,cell_mm=0.25");
  const SpinContest swarf =
      contest("swarf_wall.apt", "milling:file=" + kSrc + "/data/machining/al7075-t6.yaml,ae_mm=0.5,ap_mm=20", "");
  for (const auto& [name, c] : {std::pair{"pocket", pocket}, std::pair{"swarf", swarf}}) {
    ASSERT_GE(c.feasible, 6) << name;
    EXPECT_LE(c.optimised, 1.02 * c.best_fixed) << name;
    std::cout << fmt::format(
        "{}: optimised {:.4f} mm, best of {} fixed angles {:.4f} mm ({:+.1f} %), fixed 0 deg {:.4f} "
        "mm ({:+.1f} %)\n",
        name, c.optimised * 1e3, c.feasible, c.best_fixed * 1e3, 100.0 * (c.optimised / c.best_fixed - 1.0),
        c.fixed_zero * 1e3, 100.0 * (c.optimised / c.fixed_zero - 1.0));
  }
}

/// The numbers of a text in order (signs and decimals as written).
std::vector<double> numbers_in(const std::string& text) {
  std::vector<double> out;
  const std::regex number(R"([-+]?[0-9]+\.?[0-9]*(E[+-]?[0-9]+)?)");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), number); it != std::sregex_iterator(); ++it) {
    out.push_back(std::stod(it->str()));
  }
  return out;
}

/// The swarf pass compensated into a robot program of `kind`, its text, and the job's points.
std::string robot_program(ToolpathOutputKind kind, const Pose& workpiece, std::vector<ToolpathJobPoint>& points) {
  const RobotModel model = spindle_robot();
  const MillingForceModel force(al7075(0.5, 20.0), end_mill());
  const std::string path = ::testing::TempDir() + (kind == ToolpathOutputKind::kRapid ? "/swarf.mod" : "/swarf.src");
  {
    OutputFile file(path);
    ToolpathProgramOptions p;
    p.base_T_workpiece = workpiece;
    ToolpathProgramWriter program(file, kind, p, model);
    ToolpathJobOptions o;
    o.base_T_workpiece = workpiece;
    auto reader = open_toolpath(kSrc + "/examples/machining/swarf_wall.apt");
    ToolpathSinks sinks;
    sinks.program = &program;
    sinks.keep = &points;
    (void)run_toolpath_job(model, *reader, force, nullptr, o, sinks);
    program.finish("the end");
    file.commit();
  }
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  std::filesystem::remove(path);
  return text.str();
}

// The RAPID module moves through every compensated pose in the work object the workpiece placement
// declares, at the program's feed: each robtarget is base_T_workpiece^-1 tcp_command.
TEST(ToolpathProgram, RapidTargetsAreTheCompensatedPosesInTheWorkpieceFrame) {
  Pose workpiece = workpiece_at(1950, -100, 780);
  workpiece.linear() = Eigen::AngleAxisd(deg_to_rad(30.0), Vector3::UnitZ()).toRotationMatrix();
  std::vector<ToolpathJobPoint> points;
  const std::string text = robot_program(ToolpathOutputKind::kRapid, workpiece, points);
  EXPECT_NE(text.find("PERS wobjdata wobjDeflex:=[FALSE,TRUE,\"\",[[1950.0000,-100.0000,780.0000],[0.96592583,"
                      "0.00000000,0.00000000,0.25881905]]"),
            std::string::npos);
  std::vector<std::string> moves;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) {
    if (l.rfind("    Move", 0) == 0) moves.push_back(l);
  }
  ASSERT_EQ(moves.size(), points.size());
  EXPECT_EQ(moves.front().rfind("    MoveJ [[", 0), 0u);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::vector<double> n = numbers_in(moves[i].substr(moves[i].find('[')));
    const Pose target = workpiece.inverse() * points[i].compensated.tcp_command;
    EXPECT_LT((Vector3(n[0], n[1], n[2]) - target.translation() * 1e3).norm(), 1e-4) << moves[i];
    const Eigen::Quaterniond q(target.linear());
    EXPECT_NEAR(std::abs(q.w() * n[3] + q.x() * n[4] + q.y() * n[5] + q.z() * n[6]), 1.0, 1e-7) << moves[i];
    const ToolpathPoint& s = points[i].source;
    if (i > 0 && s.motion != MotionKind::kRapid) {
      EXPECT_NE(moves[i].find(fmt::format("\\V:={:.4f},", s.feed_m_s * 1e3)), std::string::npos) << moves[i];
    }
    EXPECT_NE(moves[i].find(fmt::format("! line {}", s.line)), std::string::npos);
  }
  EXPECT_NE(text.find("  ! the end\nENDMODULE\n"), std::string::npos);
}

// The KRL program: $BASE is the placement (A about z: 30 deg), one PTP then a LIN a point, $VEL.CP
// the feed in m/s where it changes, the poses the compensated ones as Z-Y-X Euler angles.
TEST(ToolpathProgram, KrlMovesThroughTheCompensatedPosesInBase) {
  Pose workpiece = workpiece_at(1950, -100, 780);
  workpiece.linear() = Eigen::AngleAxisd(deg_to_rad(30.0), Vector3::UnitZ()).toRotationMatrix();
  std::vector<ToolpathJobPoint> points;
  const std::string text = robot_program(ToolpathOutputKind::kKrl, workpiece, points);
  EXPECT_NE(text.find("$BASE = {X 1950.0000,Y -100.0000,Z 780.0000,A 30.0000,B 0.0000,C 0.0000}"), std::string::npos);
  std::vector<std::string> moves;
  std::istringstream in(text);
  double vel = 0.25;
  for (std::string l; std::getline(in, l);) {
    if (l.rfind("  $VEL.CP = ", 0) == 0) vel = std::stod(l.substr(12));
    if (l.rfind("  PTP {", 0) != 0 && l.rfind("  LIN {", 0) != 0) continue;
    const std::size_t i = moves.size();
    ASSERT_LT(i, points.size());
    moves.push_back(l);
    const std::vector<double> n = numbers_in(l.substr(l.find('{')));
    const Pose target = workpiece.inverse() * points[i].compensated.tcp_command;
    EXPECT_LT((Vector3(n[0], n[1], n[2]) - target.translation() * 1e3).norm(), 1e-4) << l;
    const Matrix3 r =
        (Eigen::AngleAxisd(deg_to_rad(n[3]), Vector3::UnitZ()) * Eigen::AngleAxisd(deg_to_rad(n[4]), Vector3::UnitY()) *
         Eigen::AngleAxisd(deg_to_rad(n[5]), Vector3::UnitX()))
            .toRotationMatrix();
    EXPECT_LT((r - target.linear()).norm(), 1e-5) << l;
    const ToolpathPoint& s = points[i].source;
    const double expected = s.motion == MotionKind::kRapid ? 0.25 : s.feed_m_s;
    if (i > 0) {
      EXPECT_NEAR(vel, expected, 1e-5 * expected) << l;  // six significant digits (a KRL REAL)
    }
  }
  EXPECT_EQ(moves.size(), points.size());
  EXPECT_EQ(moves.front().rfind("  PTP {", 0), 0u);
  EXPECT_NE(moves.front().find(",S 'B"), std::string::npos);
}

TEST(ToolpathJob, PointOutOfReachIsNamedByItsLine) {
  const RobotModel model = spindle_robot();
  const MillingForceModel force(al7075(3.0, 5.0), end_mill());
  ToolpathJobOptions o;
  o.base_T_workpiece = workpiece_at(2000, 0, 800);
  const std::string text = "G21 G90 G94\nS9000 M3\nG0 X0 Y0 Z5\nG1 Z-4 F900\nG1 X20 F2700\nG1 X3000\nG0 Z5\nM5\n";
  for (const char* spin : {"optimize", "fixed:0"}) {
    o.spin = parse_tool_spin_spec(spin);
    const std::string e = test::error_of([&] { (void)run_text(model, text, force, nullptr, o); });
    EXPECT_NE(e.find("t.nc: line 6"), std::string::npos) << spin << ": " << e;
    EXPECT_NE(e.find("any"), std::string::npos) << spin << ": " << e;
  }
}

TEST(ToolpathJob, StockTheToolNeverTouchesIsRefused) {
  const RobotModel model = spindle_robot();
  const MillingForceModel force(al7075(), end_mill());
  const std::unique_ptr<Stock> stock = parse_stock_spec("box:min_mm=200;200;-20,max_mm=300;300;0,cell_mm=0.5");
  ToolpathJobOptions o;
  o.base_T_workpiece = workpiece_at(2000, 0, 800);
  const std::string e = test::error_of([&] { (void)run_text(model, kSquareSlot, force, stock.get(), o); });
  EXPECT_NE(e.find("never touches the stock"), std::string::npos) << e;
  EXPECT_NE(e.find("t.nc"), std::string::npos) << e;
}

TEST(ToolpathJob, TiltedToolAxisWithAStockIsRefusedNamingTheLine) {
  const RobotModel model = spindle_robot();
  const MillingForceModel force(al7075(), end_mill());
  const std::unique_ptr<Stock> stock = parse_stock_spec("box:min_mm=-50;-50;-20,max_mm=50;50;0,cell_mm=0.5");
  ToolpathJobOptions o;
  o.base_T_workpiece = workpiece_at(2000, 0, 800);
  const std::string text =
      "G21 G90 G94\nS9000 M3\nG43.5 H1\nG0 X-30 Y0 Z5 I0 J0 K1\nG1 Z-4 F900 I0 J0 K1\nG1 X0 F2700 I0 J0.2 K0.98\nM5\n";
  const std::string e = test::error_of([&] { (void)run_text(model, text, force, stock.get(), o); });
  EXPECT_NE(e.find("t.nc: line 6"), std::string::npos) << e;
  EXPECT_NE(e.find("tilted"), std::string::npos) << e;
  EXPECT_NE(e.find("ae_mm="), std::string::npos) << e;
}

}  // namespace
}  // namespace deflex
