"""The online runtime from Python: deflex.StandIn (a session against an in-memory stand-in of the
controller, faults on request) and deflex.Session (a real UDP link, here against the Python stand-in of
an EGM controller in examples/online/). What went on the wire is checked against limits computed here
from the program and the settings, not taken from deflex."""

import subprocess
import sys
import time

import numpy as np
import pytest

import deflex
from conftest import SOURCE_DIR

Q0 = np.radians([0.0, 20.0, 10.0, 0.0, 60.0, 0.0])
DQ = np.radians([20.0, -8.0, 12.0, 25.0, -15.0, 40.0])


def sweep(seconds=20.0, points=41):
    """A cosine sweep from Q0 by DQ: moving all the time, at rest at both ends."""
    t = np.linspace(0.0, seconds, points)
    u = 0.5 - 0.5 * np.cos(np.pi * t / seconds)
    return t, Q0 + np.outer(u, DQ)


def step_limit(t, q, period_s, rate_rad_s, ramp_in_s=1.0, tolerance_rad=np.radians(1.0)):
    """The per-cycle step limit of a joint target, per joint: the program's peak speed (from the
    cosine's closed form, pi/2 x DQ / duration), the blend's and the correction's, over one period."""
    peak = np.abs(DQ) * np.pi / (2.0 * (t[-1] - t[0]))
    return period_s * (peak * 1.02 + 1.5 * tolerance_rad / ramp_in_s + rate_rad_s) + 1e-7


def test_an_outage_never_steps_the_target_on_the_wire():
    robot = deflex.Robot.builtin()
    t, q = sweep()
    rate = 0.05
    s = deflex.StandIn(robot, "egm-joint", (t, q), force_base_N=[0.0, 0.0, -650.0], max_correction_rate_rad_s=rate)
    s.run_for(3.0)
    s.outage(0.45)
    s.run_for(2.0)
    wire = s.wire["joints_rad"]
    assert wire.shape[0] > 1000
    steps = np.abs(np.diff(wire, axis=0))
    assert np.all(steps <= step_limit(t, q, 0.004, rate)), steps.max(axis=0)
    log = s.cycle_log()
    sent = log["replied"] == 1.0
    # Every command sent is within the bound of the nominal held: the program (sampled here by the
    # cycle's program time) plus the blend.
    bound = 0.01 * (1 + 1e-9) + 1e-12
    assert np.all(np.abs(log["q_command_rad"][sent] - log["q_nominal_rad"][sent] - log["q_blend_rad"][sent]) <= bound)
    summary = s.finish()
    assert summary["stop_reason"] == "user-stop" and summary["exit_code"] == 0
    assert summary["counters"]["silences"] == 1
    assert summary["counters"]["longest_silence_s"] == pytest.approx(0.45, abs=0.01)


def test_a_controller_that_stops_is_named_with_its_exit_code():
    robot = deflex.Robot.builtin()
    s = deflex.StandIn(robot, "egm-joint", sweep(), force_base_N=[0.0, 0.0, -400.0])
    s.run_for(1.0)
    s.motors_off()
    s.run_for(0.5)
    assert s.ended
    summary = s.finish()
    assert summary["stop_reason"] == "controller-stopped" and summary["exit_code"] == 6
    assert "motors off" in summary["reason"]


def test_rsi_restart_starts_the_correction_from_zero():
    robot = deflex.Robot.builtin()
    s = deflex.StandIn(robot, "rsi", sweep(), force_base_N=[0.0, 0.0, -650.0])
    s.run_for(2.0)
    assert np.abs(s.wire["joints_rad"][-1]).max() > 1e-5
    s.restart(off_s=0.3)  # RSI_OFF for 0.3 s, then RSI_ON
    before = len(s.wire["t_s"])
    s.run_for(1.0)
    first = s.wire["joints_rad"][before]
    # From zero (what AXISCORR applies in a new session), by at most one rate step (0.05 rad/s x 4 ms).
    assert np.abs(first).max() <= 0.05 * 0.004 + 1e-7
    assert s.finish()["counters"]["restarts"] == 1


def test_fanuc_streams_within_its_controllers_jerk_limit_and_ends_with_last_data():
    robot = deflex.Robot.builtin()
    t, q = sweep(6.0)
    s = deflex.StandIn(robot, "fanuc-j519", (t, q), force_base_N=[0.0, 0.0, -650.0],
                       fanuc_limits="120,265,1240")
    s.run_for(2.0)
    s.set_force([0.0, 300.0, -650.0])  # a step in the force while the arm moves
    s.run_for(8.0)
    summary = s.finish()
    assert summary["stop_reason"] == "program-end" and summary["exit_code"] == 0, summary["reason"]
    assert "last-data" in summary["reason"]
    # The controller's check, done here on what it received: finite differences at its 8 ms interval.
    wire = np.degrees(s.wire["joints_rad"])
    assert wire.shape[0] > 700
    period = 0.008
    velocity = np.abs(np.diff(wire, 1, axis=0)) / period
    acceleration = np.abs(np.diff(wire, 2, axis=0)) / period**2
    jerk = np.abs(np.diff(wire, 3, axis=0)) / period**3
    assert velocity.max() <= 120.0
    assert acceleration.max() <= 265.0
    assert jerk.max() <= 1240.0, jerk.max()
    assert jerk.max() > 1.0  # the correction moved the stream


def test_motoros2_streams_increments_within_the_step_limit_and_reaches_the_programs_end():
    robot = deflex.Robot.builtin()
    t, q = sweep(6.0)
    rate = 0.05
    s = deflex.StandIn(robot, "motoros2-rt", (t, q), force_base_N=[0.0, 0.0, -650.0],
                       max_correction_rate_rad_s=rate)
    s.run_for(8.0)
    summary = s.finish()
    assert summary["stop_reason"] == "program-end" and summary["exit_code"] == 0, summary["reason"]
    # The command position each increment moved the controller to: the program's 1501 points at 4 ms.
    wire = s.wire["joints_rad"]
    assert wire.shape[0] == 1501
    assert (np.abs(np.diff(wire, axis=0)) <= step_limit(t, q, 0.004, rate)).all()
    # It ends at the program's last point less the correction, within the 0.01 rad bound.
    correction = np.abs(wire[-1] - q[-1])
    assert correction.max() <= 0.01 and correction.max() > 1e-5


def test_ur_rtde_servoes_targets_within_the_step_limit_and_reaches_the_programs_end():
    robot = deflex.Robot.builtin()
    t, q = sweep(6.0)
    rate = 0.05
    s = deflex.StandIn(robot, "ur-rtde", (t, q), force_base_N=[0.0, 0.0, -650.0],
                       max_correction_rate_rad_s=rate, ur_lookahead_s=0.05)
    s.run_for(8.0)
    summary = s.finish()
    assert summary["stop_reason"] == "program-end" and summary["exit_code"] == 0, summary["reason"]
    # Each target the servo program handed to servoj, one a 2 ms cycle: the program's 3001 points, then
    # the last one held while servoj reaches it.
    wire = s.wire["joints_rad"]
    assert wire.shape[0] >= 3001
    assert (np.abs(np.diff(wire, axis=0)) <= step_limit(t, q, 0.002, rate)).all()
    correction = np.abs(wire[-1] - q[-1])
    assert correction.max() <= 0.01 and correction.max() > 1e-5
    with pytest.raises(deflex.InputError, match="ur-lookahead-ms"):
        deflex.StandIn(robot, "ur-rtde", sweep(), ur_lookahead_s=0.01)


def test_settings_are_checked_and_named():
    robot = deflex.Robot.builtin()
    with pytest.raises(deflex.InputError, match="setting 'egm_prot' is not one of"):
        deflex.StandIn(robot, "egm-joint", sweep(), egm_prot=1)
    with pytest.raises(deflex.InputError, match=r"setting period_s \(--period-ms\): expects a number"):
        deflex.StandIn(robot, "egm-joint", sweep(), period_s="fast")
    with pytest.raises(deflex.InputError, match="argument link: 'fanuc' is not one of"):
        deflex.StandIn(robot, "fanuc", sweep())
    with pytest.raises(deflex.InputError, match="protocol version 2 is not 1, 3 or 4"):
        deflex.StandIn(robot, "fanuc-j519", sweep(), fanuc_version=2)
    with pytest.raises(deflex.InputError, match="is not VEL,ACC,JERK"):
        deflex.StandIn(robot, "fanuc-j519", sweep(), fanuc_limits="120;265")
    with pytest.raises(deflex.InputError, match="motoros2-group"):
        deflex.StandIn(robot, "motoros2-rt", sweep(), motoros2_group=8)
    with pytest.raises(deflex.InputError, match=r"setting tare \(--tare\): a stand-in has its own sensor"):
        deflex.StandIn(robot, "egm-joint", sweep(), tare=True)
    with pytest.raises(deflex.InputError, match="rate bound allows"):
        deflex.StandIn(robot, "egm-joint", sweep(), max_correction_rate_rad_s=0.5, period_s=0.1)


def test_a_session_on_udp_against_the_python_egm_standin(tmp_path):
    robot = deflex.Robot.builtin()
    t, q = sweep(10.0)
    program = tmp_path / "program.csv"
    program.write_text("t_s,q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg\n" +
                       "".join(f"{ti}," + ",".join(f"{v!r}" for v in np.degrees(qi)) + "\n" for ti, qi in zip(t, q)))
    session = deflex.Session(robot, "egm-joint", f"csv:{SOURCE_DIR}/examples/online/force_replay.csv",
                             program=str(program), loop=True, egm_port=0, duration_s=3.0)
    port = int(session.where.rsplit(":", 1)[1])
    standin = subprocess.Popen([sys.executable, str(SOURCE_DIR / "examples/online/egm_position_guidance_standin.py"),
                                "--port", str(port), "--program", str(program), "--seconds", "2"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        reason = session.run()
    finally:
        out, err = standin.communicate(timeout=30)
    assert reason == "duration", err
    summary = session.finish()
    assert summary["exit_code"] == 0
    assert summary["answers"] > 200, summary["text"]
    log = session.cycle_log()
    sent = log["replied"] == 1.0
    assert np.all(np.abs(log["q_command_rad"][sent] - log["q_nominal_rad"][sent] - log["q_blend_rad"][sent])
                  <= np.radians(0.5) + 1e-12)
    assert np.all(log["step_fraction"][sent] <= 1.0)
    # The nominal recorded is the program at the cycle's program time.
    nominal = np.array([[np.interp(p, t, q[:, j]) for j in range(6)] for p in log["program_t_s"][sent]])
    assert np.abs(nominal - log["q_nominal_rad"][sent]).max() < np.radians(0.05)  # the CSV's cubic vs linear
    assert "answers taken" in out


def test_the_command_line_and_python_refuse_the_same_settings_with_the_same_words(tmp_path):
    """Both front ends hand their settings to the library's table (runtime/session_settings.hpp): the same
    bad value, once as `deflex online`'s option in its unit and once as Python's keyword in SI, is
    refused with the same sentence."""
    from conftest import run_cli

    robot = deflex.Robot.builtin()
    force = f"csv:{SOURCE_DIR / 'examples/online/force_replay.csv'}"
    cases = [  # (link, Python keywords, the command line's options)
        ("egm-joint", {"max_joint_correction_rad": 1.0}, ["--max-joint-correction-deg", "57.29577951308232"]),
        ("egm-joint", {"period_s": 2.0}, ["--period-ms", "2000"]),
        ("rsi", {"buffer_depth": 2}, ["--buffer-depth", "2"]),
        ("simple-message", {"period_s": 0.004}, ["--period-ms", "4"]),
        ("egm-joint", {"jacobian_at": "sideways"}, ["--jacobian-at", "sideways"]),
        ("egm-joint", {"rt_cpu": 1}, ["--rt-cpu", "1"]),
        ("egm-joint", {"tare_window_s": 0.5}, ["--tare-window-s", "0.5"]),
        ("fanuc-j519", {"fanuc_correction_share": 1.5}, ["--fanuc-correction-share", "1.5"]),
        ("egm-path", {"stop_ramp_s": 20.0}, ["--stop-ramp-s", "20"]),
        ("rsi", {"rsi_sentype": "9lives"}, ["--rsi-sentype", "9lives"]),
    ]
    for link, keywords, options in cases:
        with pytest.raises(deflex.InputError) as python_error:
            deflex.Session(robot, link, force, **keywords)
        cli = run_cli("online", "--link", link, "--force-source", force, *options, check=False)
        assert cli.returncode == 2, cli.stderr
        words = str(python_error.value)
        assert words.startswith("setting "), words
        assert f"deflex online: error: {words}\n" in cli.stderr, (words, cli.stderr)
        # controller-setup writes the controller's side from the same settings: it refuses them alike
        # (before writing anything).
        if options[0] in CONTROLLER_SETUP_SHARES and link != "simple-message":
            out = tmp_path / f"setup_{link}_{options[0].strip('-')}"
            setup = run_cli("controller-setup", "--link", link, "--sensor-ip", "10.0.0.2", "-o", str(out),
                            *options, check=False)
            assert setup.returncode == 2, setup.stderr
            assert f"deflex controller-setup: error: {words}\n" in setup.stderr, (words, setup.stderr)
            assert not out.exists()


# The options `deflex controller-setup` shares with `deflex online` (checked by the same table).
CONTROLLER_SETUP_SHARES = {"--max-joint-correction-deg", "--period-ms", "--fanuc-correction-share", "--rsi-sentype"}
