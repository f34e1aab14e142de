// The fault table of docs/online.md ("Faults and exit codes"), row by row, for each link it applies
// to, against stand-ins that behave as the real controllers do (fault_bench.hpp): silences of any
// length, restarts with and without silence, a stalled deflex, a controller that stops, a stale
// force, a slow consumer. In every test the two invariants are checked on what went on the wire:
// every command within the bound of the nominal deflex held, and no step between two commands above
// the per-cycle limit the test computes itself; and every stop has a named reason and its exit code.
#include <gtest/gtest.h>

#include "deflex/fanuc/fanuc_j519_link.hpp"
#include "support/poses.hpp"

#include "links/fault_bench.hpp"

namespace deflex {
namespace {

using runtime::LinkKind;
using runtime::StopReason;
using test::FaultBench;

using test::pose_deg;

const JointVector kStart = pose_deg(0, 20, 10, 0, 60, 0);

// A 20 s sweep: moving all the time, a few degrees a second on the big joints (a 50 mm/s TCP path).
std::shared_ptr<const JointTrajectory> sweep(double seconds = 20.0) {
  return test::sweep_program(test::bench_robot(), kStart, pose_deg(20, -8, 12, 25, -15, 40), seconds);
}

// Every command the controller received is one deflex sent (in order), and what it says is what the
// record says was sent.
void expect_wire_is_what_was_sent(FaultBench& b) {
  b.session->service();
  std::vector<const LinkCycleRecord*> sent;
  for (const LinkCycleRecord& r : b.session->collected()) {
    if (r.replied) sent.push_back(&r);
  }
  std::size_t at = 0;
  for (const standin::WireCommand& c : b.wire()) {
    bool found = false;
    for (; at < sent.size() && !found; ++at) {
      const LinkCycleRecord& r = *sent[at];
      if (b.kind == LinkKind::kEgmJoint) {
        found = (r.q_command - c.joints).cwiseAbs().maxCoeff() < 1e-12;
      } else if (b.kind == LinkKind::kMotoros2Rt) {
        // The command position the increment moved the controller to: reported + increment.
        found = (r.q_command - c.joints).cwiseAbs().maxCoeff() < 1e-12;
      } else if (b.kind == LinkKind::kUrRtde) {
        // The script hands the newest registers to servoj every cycle: a target may repeat.
        found = (r.q_command - c.joints).cwiseAbs().maxCoeff() < 1e-12;
        if (found) --at;
      } else if (b.kind == LinkKind::kFanucJ519) {
        found = (r.q_command - c.joints).cwiseAbs().maxCoeff() < 1e-9;  // float32 degrees on the wire
      } else if (b.kind == LinkKind::kRsi) {
        found = ((r.q_command - r.q_nominal) - c.joints).cwiseAbs().maxCoeff() < 1e-9;
      } else {
        found = true;  // path correction's offsets are in the tool frame: checked by norm below
      }
    }
    ASSERT_TRUE(found) << "a command on the wire that deflex never recorded sending";
  }
}

void expect_invariants(FaultBench& b, const char* what) {
  EXPECT_LE(b.worst_step_fraction(), 1.0) << what << ": a step on the wire beyond the per-cycle limit";
  EXPECT_LE(b.worst_bound_fraction(), 1.0) << what << ": a command beyond the bound of the nominal";
  expect_wire_is_what_was_sent(b);
}

// ---- egm-joint: silence, stalled deflex, restarts, controller stops, stale force ----------------

TEST(FaultTable, EgmJointOutagesOfAnyLengthNeverStepTheTargetAndTheProgramWaits) {
  for (const double outage : {0.02, 0.1, 0.3, 0.45, 0.9}) {
    FaultBench b(LinkKind::kEgmJoint, sweep());
    b.run_for(3.0);
    const double program_before = b.session->link().last_cycle().program_time_s;
    const std::size_t wire_before = b.wire().size();
    b.standin->outage(outage);
    b.run_for(outage + 2.0);
    ASSERT_FALSE(b.session->ended()) << outage << " s: " << b.session->finish().reason_text;
    expect_invariants(b, "outage");
    // The program never ran ahead of what the controller took: it went on where it stopped.
    b.session->service();
    const auto& records = b.session->collected();
    double after = -1.0;
    for (const LinkCycleRecord& r : records) {
      if (r.replied && r.program_time_s > program_before + 1e-9) {
        after = r.program_time_s;
        break;
      }
    }
    EXPECT_NEAR(after, program_before + 0.004, 1e-9) << outage << " s";
    // The TCP: the controller's targets around the outage moved by a normal step only (the 22.8 mm of
    // the old program clock is what this guards).
    Workspace ws(b.robot);
    const Vector3 p0 = tcp_pose(b.robot, ws, b.wire()[wire_before - 1].joints).translation();
    const Vector3 p1 = tcp_pose(b.robot, ws, b.wire()[wire_before].joints).translation();
    EXPECT_LT((p1 - p0).norm(), 0.5e-3) << outage << " s: the first target after the outage steps the TCP";
    if (outage > 0.05) {
      EXPECT_GE(b.session->link().counters().silences, 1u);
      EXPECT_NEAR(b.session->link().counters().longest_silence_s, outage, 0.01) << outage;
    }
    EXPECT_EQ(b.session->link().counters().guard_trips, 0u);
  }
}

TEST(FaultTable, EgmJointAStalledDeflexNeverStepsTheTargetAfterwards) {
  for (const double stall : {0.05, 0.3, 0.45}) {
    FaultBench b(LinkKind::kEgmJoint, sweep());
    b.run_for(3.0);
    b.standin->stall(true);  // the controller goes on (its messages queue up), deflex does not read
    b.run_for(stall);
    b.standin->stall(false);
    b.run_for(2.0);
    ASSERT_FALSE(b.session->ended());
    expect_invariants(b, "stall");
    EXPECT_GT(b.session->link().counters().superseded, 0u);  // the queued messages: only the newest answered
    EXPECT_FALSE(b.standin->egm()->counters().timed_out);
  }
}

TEST(FaultTable, EgmJointARestartAfterASilenceAppliesTheCorrectionOnce) {
  FaultBench b(LinkKind::kEgmJoint, sweep());
  b.run_for(3.0);
  const JointVector dtheta = b.session->link().last_cycle().dtheta;
  ASSERT_GT(dtheta.cwiseAbs().maxCoeff(), 1e-5);
  // 1.2 s of silence: the controller's EGM times out (1 s) and the arm holds where it is, some way
  // behind deflex's last target (its dead time); then EGMRunJoint again, its reference where the arm
  // is, its sequence from 1.
  b.standin->outage(1.2);
  b.run_for(1.7);
  ASSERT_TRUE(b.standin->egm()->counters().timed_out);
  const std::size_t before = b.wire().size();
  b.standin->restart(true);
  b.run_for(3.0);
  ASSERT_FALSE(b.session->ended()) << b.session->finish().reason_text;
  EXPECT_EQ(b.session->link().counters().restarts, 1u);
  // On the wire: within each session no step above the limit, and the new session's first command is
  // where the controller's new reference is (the arm), not a step from it.
  EXPECT_LE(b.worst_step_fraction(before + 1), 1.0);
  EXPECT_LE(b.worst_bound_fraction(), 1.0);
  b.session->service();
  JointVector q(6);
  bool after = false;
  for (const LinkCycleRecord& r : b.session->collected()) {
    if (r.session_start && r.sequence == 1) {
      after = true;
      // The first command is the reference the controller holds (the arm, which holds), less the
      // correction's own change this cycle (at most its rate bound): the blend is that reference less
      // the program less the correction, so the correction counts once.
      const double one_step = b.config.online.max_correction_rate_rad_s * b.config.online.period_s + 1e-9;
      EXPECT_LE((r.q_command - r.q_feedback).cwiseAbs().maxCoeff(), one_step);
      b.program->sample(r.program_time_s, q);
      EXPECT_LE((r.q_blend - (r.q_feedback - (q - r.dtheta))).cwiseAbs().maxCoeff(), one_step);
    }
    // After the ramp-in (1 s) the command is the program less the correction, exactly.
    if (after && r.replied && r.program_time_s > 3.0 + 1.05) {
      b.program->sample(r.program_time_s, q);
      EXPECT_LT((r.q_command - (q - r.dtheta)).cwiseAbs().maxCoeff(), 1e-12);
    }
  }
  EXPECT_TRUE(after);
}

TEST(FaultTable, EgmJointARestartWithoutSilenceKeepsTheStreamAndNeverSteps) {
  // The controller restarts its sequence (a quick EGMRunJoint again) still following deflex's stream:
  // the stream goes on, and no step on the wire, across the restart included, is beyond the limit.
  FaultBench b(LinkKind::kEgmJoint, sweep());
  b.run_for(3.0);
  b.standin->restart(false);
  b.run_for(3.0);
  ASSERT_FALSE(b.session->ended()) << b.session->finish().reason_text;
  EXPECT_EQ(b.session->link().counters().restarts, 1u);
  expect_invariants(b, "restart without silence");
}

TEST(FaultTable, EgmJointAQuickRestartOntoTheMovingArmIsNotResumedAndNothingSteps) {
  // The controller restarts without a silence and resets its reference to where the arm is, some 48 ms
  // of motion behind deflex's last command. deflex cannot tell a real reset from a controller still
  // following what it last sent: a command within the step limit of both does not exist, so nothing
  // more is sent, and the stop names why. Before, the stream was re-anchored on the reported
  // reference and the wire stepped by 3.5-4.3 limits (0.11-0.13 deg) while the log recorded none.
  FaultBench b(LinkKind::kEgmJoint, sweep(5.0));  // about 8 deg/s on joint 4: 48 ms of it is several limits
  b.run_for(2.0);
  b.standin->restart(true);
  b.run_for(1.0);
  ASSERT_TRUE(b.session->ended());
  const runtime::SessionSummary& s = b.session->finish();
  EXPECT_EQ(s.reason, StopReason::kControllerStopped);
  EXPECT_EQ(s.exit_code, 6);
  EXPECT_NE(s.reason_text.find("restarted without a silence"), std::string::npos) << s.reason_text;
  EXPECT_LE(b.worst_step_fraction(0), 1.0) << "a step on the wire across the restart";
  EXPECT_LE(b.worst_bound_fraction(), 1.0);
  expect_wire_is_what_was_sent(b);
}

TEST(FaultTable, EgmJointDatagramsOvertakenInTheNetworkAreLateNotARestart) {
  // Three EgmRobot messages overtaken by the one after them arrive behind it: they are late (their time
  // stamps are older than the newest taken), never a new session, however many continue each other.
  for (const int overtaken : {1, 3, 8}) {
    FaultBench b(LinkKind::kEgmJoint, sweep());
    b.run_for(3.0);
    b.standin->reorder(overtaken);
    b.run_for(2.0);
    ASSERT_FALSE(b.session->ended()) << overtaken << ": " << b.session->finish().reason_text;
    const LinkCounters& c = b.session->link().counters();
    EXPECT_EQ(c.restarts, 0u) << overtaken;
    EXPECT_GE(c.out_of_order, static_cast<std::uint64_t>(overtaken)) << overtaken;
    EXPECT_LE(b.worst_step_fraction(0), 1.0) << overtaken;
    EXPECT_LE(b.worst_bound_fraction(), 1.0) << overtaken;
    expect_wire_is_what_was_sent(b);
  }
}

// A planned stop while the arm moves (SIGINT, SIGTERM, the time limit): the program comes to rest on its
// path over the stop ramp, every step within the limit, and the session ends as planned, saying so.
TEST(FaultTable, EgmJointAStopRequestWhileMovingRampsTheProgramToAStandstill) {
  FaultBench b(LinkKind::kEgmJoint, sweep());
  b.run_for(3.0);
  const std::size_t at = b.wire().size();
  b.session->request_stop();
  b.run_for(2.0);
  ASSERT_TRUE(b.session->ended());
  const runtime::SessionSummary& s = b.session->finish();
  EXPECT_EQ(s.reason, StopReason::kUserStop);
  EXPECT_EQ(s.exit_code, 0);
  EXPECT_NE(s.reason_text.find("standstill"), std::string::npos) << s.reason_text;
  expect_invariants(b, "stop ramp");
  // The ramp took its time (0.5 s of 4 ms cycles), and the steps fell to nothing: the last two commands
  // differ by the correction's own change at most, where before the stop they moved at the program's
  // speed (the sweep moves every joint).
  const auto& w = b.wire();
  const std::size_t after = w.size() - at;
  EXPECT_NEAR(static_cast<double>(after), b.config.stop_ramp_s / b.config.online.period_s, 3.0);
  const JointVector limit = b.joint_step_limit();
  const double before_step = ((w[at - 1].joints - w[at - 2].joints).cwiseAbs().array() / limit.array()).maxCoeff();
  const double last_step = ((w.back().joints - w[w.size() - 2].joints).cwiseAbs().array() / limit.array()).maxCoeff();
  EXPECT_GT(before_step, 0.05);
  EXPECT_LT(last_step, 0.1 * before_step);
  // The speed fell steadily: no step after the request is larger than the one before it by more than
  // the correction's own change.
  const double correction_step = b.config.online.max_correction_rate_rad_s * b.config.online.period_s;
  for (std::size_t k = at + 1; k < w.size(); ++k) {
    EXPECT_LE((w[k].joints - w[k - 1].joints).cwiseAbs().maxCoeff(),
              (w[k - 1].joints - w[k - 2].joints).cwiseAbs().maxCoeff() + 2.0 * correction_step + 1e-9)
        << k - at;
  }
}

TEST(FaultTable, AStopRequestedTwiceEndsAtOnce) {
  FaultBench b(LinkKind::kEgmJoint, sweep());
  b.run_for(3.0);
  const std::size_t at = b.wire().size();
  b.session->request_stop();
  b.run_for(0.1);
  b.session->request_stop();
  b.run_for(1.0);
  ASSERT_TRUE(b.session->ended());
  EXPECT_EQ(b.session->finish().reason, StopReason::kUserStop);
  EXPECT_LE(b.wire().size() - at, 0.1 / 0.004 + 2);
  expect_invariants(b, "second stop request");
}

TEST(FaultTable, CorrectingLinksRampTheirCorrectionOutOnAStopRequest) {
  for (const LinkKind kind : {LinkKind::kRsi, LinkKind::kEgmPath}) {
    FaultBench b(kind, sweep());
    b.run_for(3.0);
    const double before =
        kind == LinkKind::kRsi ? b.wire().back().joints.cwiseAbs().maxCoeff() : b.wire().back().offset_m.norm();
    ASSERT_GT(before, 0.0);
    const std::size_t at = b.wire().size();
    b.session->request_stop();
    b.run_for(3.0);
    ASSERT_TRUE(b.session->ended()) << runtime::link_kind(kind).name;
    const runtime::SessionSummary& s = b.session->finish();
    EXPECT_EQ(s.reason, StopReason::kUserStop) << s.reason_text;
    EXPECT_NE(s.reason_text.find("ramped to zero"), std::string::npos) << s.reason_text;
    for (int k = 0; k < 20; ++k) b.standin->tick();  // the controller reads the last answer in flight
    expect_invariants(b, "stop ramp");
    // The last answer carries no correction, reached over several answers (a ramp, not a step).
    const double last =
        kind == LinkKind::kRsi ? b.wire().back().joints.cwiseAbs().maxCoeff() : b.wire().back().offset_m.norm();
    EXPECT_EQ(last, 0.0) << runtime::link_kind(kind).name;
    EXPECT_LE(b.worst_step_fraction(0), 1.0) << runtime::link_kind(kind).name;  // the last answer too
    const double per_answer = kind == LinkKind::kRsi ? b.joint_step_limit().minCoeff()
                                                     : b.config.online.max_tcp_rate_m_s * b.config.online.period_s;
    EXPECT_GE(static_cast<double>(b.wire().size() - at) + 1e-9, before / per_answer) << runtime::link_kind(kind).name;
  }
}

TEST(FaultTable, AStopRequestWhileTheControllerIsSilentEndsWithoutWaitingForIt) {
  // Nothing can be ramped when nothing is taken: the planned stop ends after a few silent cycles, not
  // after the stop silence as a fault.
  for (const LinkKind kind : {LinkKind::kEgmJoint, LinkKind::kRsi}) {
    FaultBench b(kind, sweep());
    b.run_for(2.0);
    b.standin->outage(10.0);
    b.run_for(0.02);
    b.session->request_stop();
    const double t0 = b.t_s();
    b.run_for(2.0);
    ASSERT_TRUE(b.session->ended()) << runtime::link_kind(kind).name;
    const runtime::SessionSummary& s = b.session->finish();
    EXPECT_EQ(s.reason, StopReason::kUserStop) << s.reason_text;
    EXPECT_NE(s.reason_text.find("fell silent"), std::string::npos) << s.reason_text;
    EXPECT_LT(b.t_s() - t0, 0.1) << runtime::link_kind(kind).name;
  }
}

TEST(FaultTable, SimpleMessageAStopRequestRampsThenStopsTheMotion) {
  FaultBench b(LinkKind::kSimpleMessage, sweep());
  b.run_for(3.0);
  const std::size_t at = b.wire().size();
  b.session->request_stop();
  b.run_for(3.0);
  ASSERT_TRUE(b.session->ended());
  const runtime::SessionSummary& s = b.session->finish();
  EXPECT_EQ(s.reason, StopReason::kUserStop) << s.reason_text;
  EXPECT_NE(s.reason_text.find("standstill"), std::string::npos) << s.reason_text;
  for (int k = 0; k < 100; ++k) {
    b.standin->tick();
    (void)b.session->link().poll(0.0);
  }
  EXPECT_EQ(b.standin->server()->counters().stops, 1u);
  expect_invariants(b, "simple message stop ramp");
  // The last point moved by a tenth of a full cycle's step (the ramp's last share: five 100 ms points
  // over 0.5 s), where the points before the request moved by a whole one.
  const auto& w = b.wire();
  ASSERT_GE(w.size(), 3u);
  const double before = (w[at - 1].joints - w[at - 2].joints).cwiseAbs().maxCoeff();
  EXPECT_GT(before, 0.0);
  EXPECT_LT((w.back().joints - w[w.size() - 2].joints).cwiseAbs().maxCoeff(), 0.15 * before);
}

TEST(FaultTable, EgmJointAControllerThatStopsEndsTheSessionWithItsReason) {
  {  // EGM ended before the program's end: exit 6, named, at the next message
    FaultBench b(LinkKind::kEgmJoint, sweep());
    b.run_for(2.0);
    b.standin->end_session(2);
    const double t0 = b.t_s();
    b.run_for(1.0);
    ASSERT_TRUE(b.session->ended());
    const runtime::SessionSummary& s = b.session->finish();
    EXPECT_EQ(s.reason, StopReason::kControllerStopped);
    EXPECT_EQ(s.exit_code, 6);
    EXPECT_NE(s.reason_text.find("ended EGM (mciState STOPPED)"), std::string::npos) << s.reason_text;
    EXPECT_LE(b.t_s() - t0, 0.0121);  // within three 4 ms cycles
    expect_invariants(b, "EGM ended");
  }
  {  // the motors off (an emergency stop): exit 6
    FaultBench b(LinkKind::kEgmJoint, sweep());
    b.run_for(2.0);
    b.standin->motors_off();
    b.run_for(1.0);
    const runtime::SessionSummary& s = b.session->finish();
    EXPECT_EQ(s.exit_code, 6);
    EXPECT_NE(s.reason_text.find("motors off"), std::string::npos) << s.reason_text;
  }
  {  // EGM ended after the program's end: the planned end, exit 0
    FaultBench b(LinkKind::kEgmJoint, sweep(2.0));
    b.run_for(3.5);
    ASSERT_EQ(b.session->link().state(), LinkState::kFinished);
    b.standin->end_session(2);
    b.run_for(0.1);
    const runtime::SessionSummary& s = b.session->finish();
    EXPECT_EQ(s.reason, StopReason::kProgramEnd);
    EXPECT_EQ(s.exit_code, 0);
  }
  {  // silent for longer than the stop silence (3 s): exit 5, within a cycle of it
    FaultBench b(LinkKind::kEgmJoint, sweep());
    b.run_for(2.0);
    b.standin->outage(10.0);
    const double t0 = b.t_s();
    b.run_for(5.0);
    ASSERT_TRUE(b.session->ended());
    const runtime::SessionSummary& s = b.session->finish();
    EXPECT_EQ(s.reason, StopReason::kControllerSilent);
    EXPECT_EQ(s.exit_code, 5);
    EXPECT_NEAR(b.t_s() - t0, 3.0, 0.01);
    EXPECT_NE(s.reason_text.find("no usable message from the controller for 3.0"), std::string::npos) << s.reason_text;
  }
}

TEST(FaultTable, EgmJointAStaleForceRampsTheCorrectionOutAtTheRateBound) {
  FaultBench b(LinkKind::kEgmJoint, sweep());
  b.run_for(3.0);
  const double before = b.session->link().last_cycle().dtheta.cwiseAbs().maxCoeff();
  b.standin->sensor_silent(true);
  b.run_for(1.0);
  expect_invariants(b, "stale force");
  b.session->service();
  int ramp = 0;
  double previous = before;
  for (const LinkCycleRecord& r : b.session->collected()) {
    if (r.status != CycleStatus::kStaleForce) continue;
    const double now = r.dtheta.cwiseAbs().maxCoeff();
    EXPECT_LE(previous - now, b.config.online.max_correction_rate_rad_s * 0.004 * (1 + 1e-9) + 1e-15);
    if (now > 0.0) ++ramp;
    previous = now;
  }
  EXPECT_EQ(previous, 0.0);
  EXPECT_GE(ramp, 2);  // a ramp over cycles, not a step
}

// ---- egm-path: silence, restart, stale force, the controller's end ---------------------------------

TEST(FaultTable, EgmPathAStaleForceRampsTheOffsetOutOverSeveralAnswers) {
  FaultBench b(LinkKind::kEgmPath, sweep());
  b.run_for(4.0);
  const double offset = b.wire().back().offset_m.norm();
  ASSERT_GT(offset, 2e-4);
  const std::size_t at = b.wire().size();
  b.standin->sensor_silent(true);
  b.run_for(2.0);
  expect_invariants(b, "stale force");
  // Zero at the end, reached over at least |offset| / (TCP rate x period) answers: a ramp.
  std::size_t answers = 0;
  for (std::size_t k = at; k < b.wire().size() && b.wire()[k].offset_m.norm() > 1e-9; ++k) ++answers;
  EXPECT_EQ(b.wire().back().offset_m.norm(), 0.0);
  EXPECT_GE(static_cast<double>(answers) + 1.0, offset / (b.config.online.max_tcp_rate_m_s * b.config.online.period_s));
  EXPECT_GE(answers, 2u);
}

TEST(FaultTable, EgmPathOutagesAndARestartNeverStepTheOffset) {
  FaultBench b(LinkKind::kEgmPath, sweep());
  b.run_for(3.0);
  b.standin->outage(0.45);
  b.run_for(2.0);
  b.standin->stall(true);
  b.run_for(0.3);
  b.standin->stall(false);
  b.run_for(1.0);
  b.standin->restart();  // a new EGMActMove: its correction from zero
  b.run_for(2.0);
  ASSERT_FALSE(b.session->ended()) << b.session->finish().reason_text;
  expect_invariants(b, "egm-path faults");
  EXPECT_EQ(b.session->link().counters().restarts, 1u);
}

TEST(FaultTable, EgmPathTheControllersEndIsPlannedAndSilenceIsNot) {
  {
    FaultBench b(LinkKind::kEgmPath, sweep());
    b.run_for(1.0);
    b.standin->outage(10.0);
    b.run_for(4.0);
    EXPECT_EQ(b.session->finish().exit_code, 5);
  }
  {
    FaultBench b(LinkKind::kEgmPath, sweep(),
                 [](runtime::SessionConfig& c, standin::StandInConfig&) { c.end_on_silence = true; });
    b.run_for(1.0);
    b.standin->outage(10.0);
    b.run_for(4.0);
    const runtime::SessionSummary& s = b.session->finish();
    EXPECT_EQ(s.exit_code, 0) << s.reason_text;
    EXPECT_EQ(s.reason, StopReason::kProgramEnd);
  }
}

// ---- rsi: outage, stalled deflex (the Timeout), restart, stale force ------------------------------

TEST(FaultTable, RsiAnOutageShorterThanTheTimeoutIsRiddenThrough) {
  FaultBench b(LinkKind::kRsi, sweep());
  b.run_for(2.0);
  b.standin->outage(0.2);  // 50 cycles late: below the Timeout of 100
  b.run_for(2.0);
  ASSERT_FALSE(b.session->ended()) << b.session->finish().reason_text;
  EXPECT_TRUE(b.standin->rsi()->running());
  expect_invariants(b, "rsi outage");
  // The controller counted the cycles it got no answer in: 50, less the one in flight when it ended.
  EXPECT_NEAR(static_cast<double>(b.session->link().counters().controller_late), 50.0, 1.0);
}

TEST(FaultTable, RsiStoppedOnItsTimeoutByAStalledDeflexIsNamedWithinTwoCycles) {
  FaultBench b(LinkKind::kRsi, sweep());
  b.run_for(2.0);
  b.standin->stall(true);
  b.run_for(0.6);  // 150 cycles unanswered: RSI stops at its 100th late answer
  ASSERT_FALSE(b.standin->rsi()->running());
  const double stopped_at = b.t_s();
  b.standin->stall(false);
  b.run_for(1.0);
  ASSERT_TRUE(b.session->ended());
  const runtime::SessionSummary& s = b.session->finish();
  EXPECT_EQ(s.reason, StopReason::kControllerStopped);
  EXPECT_EQ(s.exit_code, 6);
  EXPECT_NE(s.reason_text.find("RSI stopped: the controller's late count reached its Timeout of 100"),
            std::string::npos)
      << s.reason_text;
  EXPECT_LE(b.t_s() - stopped_at, 0.0121);
  expect_invariants(b, "rsi timeout");
}

TEST(FaultTable, RsiARestartStartsTheCorrectionFromZeroAndNothingSteps) {
  FaultBench b(LinkKind::kRsi, sweep());
  b.run_for(2.0);
  ASSERT_GT(b.wire().back().joints.cwiseAbs().maxCoeff(), 1e-5);
  b.standin->restart(true, 0.3);  // RSI_OFF for 0.3 s and RSI_ON: a new session, its AXISCORR from zero
  const std::size_t at = b.wire().size();
  b.run_for(2.0);
  ASSERT_FALSE(b.session->ended()) << b.session->finish().reason_text;
  EXPECT_EQ(b.session->link().counters().restarts, 1u);
  // The first answer of the new session steps from zero (what AXISCORR applies), by at most the limit,
  // and is far from the correction the last session ended with.
  ASSERT_GT(b.wire().size(), at);
  EXPECT_LE((b.wire()[at].joints.cwiseAbs().array() / b.joint_step_limit().array()).maxCoeff(), 1.0);
  EXPECT_LT(b.wire()[at].joints.cwiseAbs().maxCoeff(), 0.5 * b.wire()[at - 1].joints.cwiseAbs().maxCoeff());
  EXPECT_LE(b.worst_step_fraction(at + 1), 1.0);
  EXPECT_LE(b.worst_bound_fraction(), 1.0);
  EXPECT_EQ(b.standin->rsi()->counters().clamped, 0u);
}

TEST(FaultTable, RsiAnIpocThatWrapsOrCrosses2To32IsTheNextCycleNotARestart) {
  // No public source states the KR C4's IPOC width: deflex takes a 32-bit counter across its wrap and a
  // 64-bit one across 2^32 alike. Before, the wrap was taken as a restart and AK dropped 0.038 deg in
  // one answer (3 limits).
  for (const int bits : {32, 64}) {
    FaultBench b(LinkKind::kRsi, sweep(), [bits](runtime::SessionConfig&, standin::StandInConfig& s) {
      s.rsi.ipoc_bits = bits;
      s.rsi.first_ipoc = (std::uint64_t{1} << 32) - 2000;  // 2 s before the wrap
    });
    b.run_for(4.0);
    ASSERT_FALSE(b.session->ended()) << bits << ": " << b.session->finish().reason_text;
    ASSERT_EQ(b.standin->rsi()->last_ipoc() < (std::uint64_t{1} << 32), bits == 32) << bits;
    EXPECT_EQ(b.session->link().counters().restarts, 0u) << bits;
    EXPECT_EQ(b.session->link().counters().clock_jumps, 0u) << bits;
    EXPECT_LE(b.worst_step_fraction(0), 1.0) << bits;
    EXPECT_LE(b.worst_bound_fraction(), 1.0) << bits;
    expect_wire_is_what_was_sent(b);
  }
}

TEST(FaultTable, RsiAStaleForceRampsAtTheRateBound) {
  FaultBench b(LinkKind::kRsi, sweep());
  b.run_for(2.0);
  b.standin->sensor_silent(true);
  b.run_for(1.0);
  expect_invariants(b, "rsi stale");
  EXPECT_EQ(b.wire().back().joints.cwiseAbs().maxCoeff(), 0.0);
}

// ---- simple message: a slow consumer, a stale force ------------------------------------------------

TEST(FaultTable, SimpleMessageASlowControllerIsReportedAndStoppedPastTheLimit) {
  FaultBench b(LinkKind::kSimpleMessage, sweep(), [](runtime::SessionConfig&, standin::StandInConfig& s) {
    s.server.read_period_s = 0.15;  // the robot program takes a point every 150 ms; the program's cycle is 100 ms
  });
  b.run_for(20.0);
  ASSERT_TRUE(b.session->ended());
  const runtime::SessionSummary& s = b.session->finish();
  EXPECT_EQ(s.reason, StopReason::kTooSlow);
  EXPECT_EQ(s.exit_code, 8);
  EXPECT_NE(s.reason_text.find("behind the program's 100 ms a point (limit 2.00 s)"), std::string::npos)
      << s.reason_text;
  // It ran at two thirds of the program's speed until then: 2 s behind after some 6 s.
  EXPECT_NEAR(b.t_s(), 6.0, 0.6);
  EXPECT_NE(s.text.find("behind its schedule"), std::string::npos);
  for (int k = 0; k < 100; ++k) {  // the server reads what is left; deflex flushes its STOP_TRAJECTORY
    b.standin->tick();
    (void)b.session->link().poll(0.0);
  }
  EXPECT_EQ(b.standin->server()->counters().stops, 1u);  // the motion stopped with STOP_TRAJECTORY
  expect_invariants(b, "slow consumer");
}

TEST(FaultTable, SimpleMessageAStaleForceRampsAtTheRateBound) {
  FaultBench b(LinkKind::kSimpleMessage, sweep());
  b.run_for(3.0);
  b.standin->sensor_silent(true);
  b.run_for(2.0);
  ASSERT_FALSE(b.session->ended()) << b.session->finish().reason_text;
  expect_invariants(b, "simple message stale");
}

// ---- fanuc-j519: a controller that stops itself at the first fault ----------------------------------
// FANUC's controller keeps a short queue of commands and stops the stream (MOTN-603) when it runs dry,
// and checks every target's velocity, acceleration and jerk (MOTN-609..611): an outage or a stall of
// more than an interval ends the session on the controller's side, and deflex names it. What it sent
// until then holds both invariants, and no alarm ever comes from its own stream.

void expect_no_motion_alarm(FaultBench& b, const char* what) {
  EXPECT_EQ(b.standin->fanuc()->alarm().find("MOTN-61"), std::string::npos)
      << what << ": " << b.standin->fanuc()->alarm();
}

TEST(FaultTable, FanucJ519RunsTheProgramToItsEndWithLastDataAndNoAlarm) {
  FaultBench b(LinkKind::kFanucJ519, sweep(6.0));
  b.run_for(10.0);
  ASSERT_TRUE(b.session->ended());
  const runtime::SessionSummary& s = b.session->finish();
  EXPECT_EQ(s.reason, StopReason::kProgramEnd) << s.reason_text;
  EXPECT_EQ(s.exit_code, 0);
  for (int k = 0; k < 10; ++k) b.standin->tick();
  EXPECT_TRUE(b.standin->fanuc()->ended());
  EXPECT_EQ(b.standin->fanuc()->alarm(), "");
  // The stand-in's threshold tables (3 a joint) were read before the stream began.
  const auto* link = dynamic_cast<const FanucJ519Link*>(&b.session->link());
  ASSERT_NE(link, nullptr);
  EXPECT_EQ(link->thresholds().read, 18u);
  EXPECT_EQ(b.standin->fanuc()->counters().threshold_replies, 18u);
  expect_invariants(b, "fanuc to the end");
}

TEST(FaultTable, FanucJ519OutagesAndStallsStopTheControllerAndDeflexNamesIt) {
  for (const double fault : {0.02, 0.1, 0.5}) {
    for (const bool stall : {false, true}) {
      SCOPED_TRACE(testing::Message() << (stall ? "stall " : "outage ") << fault << " s");
      FaultBench b(LinkKind::kFanucJ519, sweep());
      b.run_for(2.0);
      if (stall) {
        b.standin->stall(true);
        b.run_for(fault);
        b.standin->stall(false);
      } else {
        b.standin->outage(fault);
      }
      b.run_for(3.0);
      ASSERT_TRUE(b.session->ended());
      const runtime::SessionSummary& s = b.session->finish();
      EXPECT_EQ(s.reason, StopReason::kControllerStopped) << s.reason_text;
      EXPECT_EQ(s.exit_code, 6);
      EXPECT_NE(s.reason_text.find("ready bit"), std::string::npos) << s.reason_text;
      EXPECT_NE(b.standin->fanuc()->alarm().find("MOTN-603"), std::string::npos) << b.standin->fanuc()->alarm();
      expect_no_motion_alarm(b, "fault");
      expect_invariants(b, "fanuc fault");
    }
  }
}

TEST(FaultTable, FanucJ519AStopRequestBringsTheProgramToRestAndEndsWithLastData) {
  FaultBench b(LinkKind::kFanucJ519, sweep());
  b.run_for(3.0);
  b.session->request_stop();
  b.run_for(3.0);
  ASSERT_TRUE(b.session->ended());
  const runtime::SessionSummary& s = b.session->finish();
  EXPECT_EQ(s.reason, StopReason::kUserStop) << s.reason_text;
  for (int k = 0; k < 10; ++k) b.standin->tick();
  EXPECT_TRUE(b.standin->fanuc()->ended());
  EXPECT_EQ(b.standin->fanuc()->alarm(), "");
  expect_invariants(b, "fanuc stop request");
}

TEST(FaultTable, FanucJ519AnEStopOrARestartEndsTheSession) {
  for (const bool estop : {true, false}) {
    FaultBench b(LinkKind::kFanucJ519, sweep());
    b.run_for(2.0);
    const std::size_t sent = b.wire().size();
    if (estop) {
      b.standin->motors_off();
    } else {
      b.standin->restart();
    }
    b.run_for(2.0);
    ASSERT_TRUE(b.session->ended());
    EXPECT_EQ(b.session->finish().reason, StopReason::kControllerStopped) << b.session->finish().reason_text;
    EXPECT_LE(b.wire().size(), sent + 2) << "deflex went on sending after the controller stopped";
    expect_invariants(b, estop ? "fanuc e-stop" : "fanuc restart");
  }
}

TEST(FaultTable, FanucJ519AStaleForceRampsTheCorrectionOutWithoutAnAlarm) {
  FaultBench b(LinkKind::kFanucJ519, sweep());
  b.run_for(3.0);
  ASSERT_GT(b.session->link().last_cycle().dtheta.cwiseAbs().maxCoeff(), 1e-5);
  b.standin->sensor_silent(true);
  b.run_for(3.0);
  ASSERT_FALSE(b.session->ended()) << b.session->finish().reason_text;
  EXPECT_LT(b.session->link().last_cycle().dtheta.cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_EQ(b.standin->fanuc()->alarm(), "");
  expect_invariants(b, "fanuc stale force");
}

// ---- motoros2-rt: lock-step increments; the controller drops its session, deflex resends -----------
// MotoROS2 answers each command once, applies nothing while no command comes, answers a command it
// took again without applying it, and drops its session on a sequence jump, a second sender or its
// own timeout; its safety unit may truncate increments. What went on the wire is the command
// position each increment moved the controller to (reported + increment): within the bound of the
// nominal, and no increment beyond the per-cycle step limit.

TEST(FaultTable, Motoros2RtRunsTheProgramToItsEnd) {
  FaultBench b(LinkKind::kMotoros2Rt, sweep(6.0));
  b.run_for(8.0);
  ASSERT_TRUE(b.session->ended());
  const runtime::SessionSummary& s = b.session->finish();
  EXPECT_EQ(s.reason, StopReason::kProgramEnd) << s.reason_text;
  EXPECT_EQ(s.exit_code, 0);
  EXPECT_EQ(b.standin->motoros2()->dropped(), "");
  EXPECT_GT(b.wire().size(), 1500u);
  expect_invariants(b, "motoros2 to the end");
}

TEST(FaultTable, Motoros2RtOutagesAndStallsAreRiddenThroughAndNothingSteps) {
  for (const double fault : {0.02, 0.1, 0.3}) {
    for (const bool stall : {false, true}) {
      SCOPED_TRACE(testing::Message() << (stall ? "stall " : "outage ") << fault << " s");
      FaultBench b(LinkKind::kMotoros2Rt, sweep());
      b.run_for(2.0);
      if (stall) {
        b.standin->stall(true);
        b.run_for(fault);
        b.standin->stall(false);
      } else {
        b.standin->outage(fault);
      }
      b.run_for(2.0);
      ASSERT_FALSE(b.session->ended()) << b.session->finish().reason_text;
      EXPECT_EQ(b.standin->motoros2()->dropped(), "");
      EXPECT_EQ(b.standin->motoros2()->counters().skipped, 0u);
      expect_invariants(b, "motoros2 outage or stall");
    }
  }
}

// Beyond the stop silence (an outage) or the controller's own timeout (a stalled PC: the controller
// drops its session), the session ends, named.
TEST(FaultTable, Motoros2RtALongOutageOrAStallBeyondTheControllersTimeoutEndsTheSession) {
  for (const bool stall : {false, true}) {
    SCOPED_TRACE(stall ? "stall" : "outage");
    FaultBench b(LinkKind::kMotoros2Rt, sweep(),
                 [](runtime::SessionConfig&, standin::StandInConfig& sc) { sc.motoros2.timeout_s = 1.0; });
    b.run_for(2.0);
    const std::size_t sent = b.wire().size();
    if (stall) {
      b.standin->stall(true);
      b.run_for(1.5);
      b.standin->stall(false);
    } else {
      b.standin->outage(3.0);
    }
    b.run_for(4.0);
    ASSERT_TRUE(b.session->ended());
    const runtime::SessionSummary& s = b.session->finish();
    EXPECT_EQ(s.reason, StopReason::kControllerSilent) << s.reason_text;
    EXPECT_EQ(s.exit_code, exit_code(StopReason::kControllerSilent));
    if (stall) {
      EXPECT_EQ(b.standin->motoros2()->dropped(), "no command for timeout_for_rt_msg");
      // The increment in flight as deflex stalled, and none after.
      EXPECT_EQ(b.wire().size(), sent + 1) << "the controller applied an increment after its session ended";
    }
    expect_invariants(b, "motoros2 long fault");
  }
}

TEST(FaultTable, Motoros2RtAStopRequestBringsTheProgramToRest) {
  FaultBench b(LinkKind::kMotoros2Rt, sweep());
  b.run_for(3.0);
  b.session->request_stop();
  b.run_for(3.0);
  ASSERT_TRUE(b.session->ended());
  const runtime::SessionSummary& s = b.session->finish();
  EXPECT_EQ(s.reason, StopReason::kUserStop) << s.reason_text;
  EXPECT_EQ(b.standin->motoros2()->dropped(), "");
  expect_invariants(b, "motoros2 stop request");
}

// A stopped controller (an e-stop, stop_traj_mode) answers nothing more; a restarted one (a new real-time
// session) waits for a command numbered 0, drops deflex's next and answers nothing: both end the session
// on the silence, and nothing moves the arm after.
TEST(FaultTable, Motoros2RtAStoppedOrRestartedControllerEndsTheSession) {
  for (const bool estop : {true, false}) {
    SCOPED_TRACE(estop ? "stopped" : "restarted");
    FaultBench b(LinkKind::kMotoros2Rt, sweep());
    b.run_for(2.0);
    const std::size_t sent = b.wire().size();
    if (estop) {
      b.standin->motors_off();
    } else {
      b.standin->restart();
    }
    b.run_for(2.0);
    ASSERT_TRUE(b.session->ended());
    EXPECT_EQ(b.session->finish().reason, StopReason::kControllerSilent) << b.session->finish().reason_text;
    EXPECT_EQ(b.wire().size(), sent) << "the controller applied an increment after it stopped";
    expect_invariants(b, estop ? "motoros2 stopped" : "motoros2 restarted");
  }
}

TEST(FaultTable, Motoros2RtAnEStopOnTheStatusChannelEndsTheSessionAtOnce) {
  FaultBench b(LinkKind::kMotoros2Rt, sweep(),
               [](runtime::SessionConfig& c, standin::StandInConfig&) { c.motoros2_rt.status_port = 22001; });
  b.run_for(2.0);
  const std::size_t sent = b.wire().size();
  b.standin->motors_off();
  b.run_for(0.05);
  ASSERT_TRUE(b.session->ended());
  const runtime::SessionSummary& s = b.session->finish();
  EXPECT_EQ(s.reason, StopReason::kControllerStopped) << s.reason_text;
  EXPECT_EQ(s.exit_code, 6);
  EXPECT_NE(s.reason_text.find("emergency stop"), std::string::npos) << s.reason_text;
  EXPECT_EQ(b.wire().size(), sent);
  expect_invariants(b, "motoros2 e-stop on the status channel");
}

TEST(FaultTable, Motoros2RtAStaleForceRampsTheCorrectionOut) {
  FaultBench b(LinkKind::kMotoros2Rt, sweep());
  b.run_for(3.0);
  ASSERT_GT(b.session->link().last_cycle().dtheta.cwiseAbs().maxCoeff(), 1e-5);
  b.standin->sensor_silent(true);
  b.run_for(3.0);
  ASSERT_FALSE(b.session->ended()) << b.session->finish().reason_text;
  EXPECT_LT(b.session->link().last_cycle().dtheta.cwiseAbs().maxCoeff(), 1e-9);
  expect_invariants(b, "motoros2 stale force");
}

// The safety unit's speed limit below the program's speed: its truncations run on beyond the link's
// limit, and the session ends naming the safety unit. Every increment deflex sent was within the step
// limit and every absolute within the bound (the truncated positions are the controller's, not sent).
TEST(FaultTable, Motoros2RtASafetyUnitThatKeepsTruncatingEndsTheSession) {
  const auto program = sweep(10.0);
  const double fsu = 0.5 * test::sampled_peak_speed(*program).maxCoeff();
  FaultBench b(LinkKind::kMotoros2Rt, program,
               [&](runtime::SessionConfig&, standin::StandInConfig& sc) { sc.motoros2.fsu_speed_rad_s = fsu; });
  b.run_for(12.0);
  ASSERT_TRUE(b.session->ended());
  const runtime::SessionSummary& s = b.session->finish();
  EXPECT_EQ(s.reason, StopReason::kControllerStopped) << s.reason_text;
  EXPECT_EQ(s.exit_code, 6);
  EXPECT_NE(s.reason_text.find("Functional Safety Unit"), std::string::npos) << s.reason_text;
  EXPECT_GT(b.standin->motoros2()->counters().truncated, 25u);
  const JointVector limit = b.joint_step_limit();
  for (const JointVector& inc : b.standin->motoros2()->increments()) {
    ASSERT_LE((inc.array() / limit.array()).abs().maxCoeff(), 1.0);
  }
  EXPECT_LE(b.worst_bound_fraction(), 1.0);
}

// ---- ur-rtde: one target an output package over TCP; the script's watchdog and the safety system ----
// RTDE's TCP loses nothing: an outage is a stall of the connection both ways, the controller's packages
// arriving together at its end (deflex answers the newest). The script servos to the newest registers
// every 2 ms and stops the program when the counter does not change for its watchdog's 0.1 s; the
// safety system's protective stop and e-stop show in safety_mode. What went on the wire is each target
// the script handed to servoj.

TEST(FaultTable, UrRtdeRunsTheProgramToItsEnd) {
  FaultBench b(LinkKind::kUrRtde, sweep(6.0));
  b.run_for(8.0);
  ASSERT_TRUE(b.session->ended());
  const runtime::SessionSummary& s = b.session->finish();
  EXPECT_EQ(s.reason, StopReason::kProgramEnd) << s.reason_text;
  EXPECT_EQ(s.exit_code, 0);
  for (int k = 0; k < 250; ++k) b.standin->tick();  // the script holds the last target, then ends
  EXPECT_EQ(b.standin->ur()->stopped(), "the program ended (the stream's end)");
  EXPECT_GT(b.wire().size(), 2900u);
  expect_invariants(b, "ur to the end");
}

TEST(FaultTable, UrRtdeStallsShorterThanTheWatchdogAreRiddenThroughAndNothingSteps) {
  for (const double fault : {0.02, 0.06}) {
    for (const bool stall : {false, true}) {
      SCOPED_TRACE(testing::Message() << (stall ? "stalled PC " : "TCP stall ") << fault << " s");
      FaultBench b(LinkKind::kUrRtde, sweep());
      b.run_for(2.0);
      if (stall) {
        b.standin->stall(true);
        b.run_for(fault);
        b.standin->stall(false);
      } else {
        b.standin->outage(fault);
      }
      b.run_for(2.0);
      ASSERT_FALSE(b.session->ended()) << b.session->finish().reason_text;
      EXPECT_EQ(b.standin->ur()->stopped(), "");
      expect_invariants(b, "ur short stall");
    }
  }
}

// Longer than the watchdog: the script stops the program and the arm halts; deflex, reading again,
// ends the session naming the program's state.
TEST(FaultTable, UrRtdeAStallBeyondTheWatchdogStopsTheProgramAndEndsTheSession) {
  for (const bool stall : {false, true}) {
    SCOPED_TRACE(stall ? "stalled PC" : "TCP stall");
    FaultBench b(LinkKind::kUrRtde, sweep());
    b.run_for(2.0);
    if (stall) {
      b.standin->stall(true);
      b.run_for(0.3);
      b.standin->stall(false);
    } else {
      b.standin->outage(0.3);
    }
    b.run_for(1.0);
    ASSERT_TRUE(b.session->ended());
    const runtime::SessionSummary& s = b.session->finish();
    EXPECT_EQ(s.reason, StopReason::kControllerStopped) << s.reason_text;
    EXPECT_EQ(s.exit_code, 6);
    EXPECT_NE(s.reason_text.find("runtime_state 1"), std::string::npos) << s.reason_text;
    EXPECT_NE(b.standin->ur()->stopped().find("watchdog"), std::string::npos) << b.standin->ur()->stopped();
    expect_invariants(b, "ur long stall");
  }
}

TEST(FaultTable, UrRtdeAStopRequestBringsTheProgramToRest) {
  FaultBench b(LinkKind::kUrRtde, sweep());
  b.run_for(3.0);
  b.session->request_stop();
  b.run_for(3.0);
  ASSERT_TRUE(b.session->ended());
  const runtime::SessionSummary& s = b.session->finish();
  EXPECT_EQ(s.reason, StopReason::kUserStop) << s.reason_text;
  for (int k = 0; k < 250; ++k) b.standin->tick();
  EXPECT_EQ(b.standin->ur()->stopped(), "the program ended (the stream's end)");
  expect_invariants(b, "ur stop request");
}

// An e-stop, a program stopped on the pendant, a protective stop from the safety system's joint
// speed limit below the program's speed: each ends the session at once, named, exit 6.
TEST(FaultTable, UrRtdeAnEStopAStoppedProgramOrALimitExceededEndsTheSessionNamingIt) {
  const auto program = sweep(10.0);
  const double limit = 0.5 * test::sampled_peak_speed(*program).maxCoeff();
  for (int fault = 0; fault < 3; ++fault) {
    SCOPED_TRACE(fault);
    FaultBench b(LinkKind::kUrRtde, program, [&](runtime::SessionConfig&, standin::StandInConfig& sc) {
      if (fault == 2) sc.ur.max_speed_rad_s = limit;
    });
    b.run_for(fault == 2 ? 0.0 : 2.0);
    if (fault == 0) b.standin->motors_off();
    if (fault == 1) b.standin->ur()->stop_program();
    b.run_for(fault == 2 ? 10.0 : 0.05);
    ASSERT_TRUE(b.session->ended());
    const runtime::SessionSummary& s = b.session->finish();
    EXPECT_EQ(s.reason, StopReason::kControllerStopped) << s.reason_text;
    EXPECT_EQ(s.exit_code, 6);
    const char* named = fault == 0 ? "emergency stop" : fault == 1 ? "runtime_state 1" : "protective stop";
    EXPECT_NE(s.reason_text.find(named), std::string::npos) << s.reason_text;
    expect_invariants(b, "ur stopped");
  }
}

TEST(FaultTable, UrRtdeAStaleForceRampsTheCorrectionOut) {
  FaultBench b(LinkKind::kUrRtde, sweep());
  b.run_for(3.0);
  ASSERT_GT(b.session->link().last_cycle().dtheta.cwiseAbs().maxCoeff(), 1e-5);
  b.standin->sensor_silent(true);
  b.run_for(3.0);
  ASSERT_FALSE(b.session->ended()) << b.session->finish().reason_text;
  EXPECT_LT(b.session->link().last_cycle().dtheta.cwiseAbs().maxCoeff(), 1e-9);
  expect_invariants(b, "ur stale force");
}

}  // namespace
}  // namespace deflex
