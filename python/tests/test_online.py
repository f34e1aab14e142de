"""The online compensator's step() in a loop run from Python, against the closed form
dtheta = K^-1 J_wap^T W of a constant force, and its status values."""

import numpy as np
import pytest

import deflex
from conftest import fd_jacobian

Q = np.radians([10.0, 25.0, 15.0, 30.0, 45.0, -20.0])


def compensator_with_sensor_at_the_tcp(robot):
    """The sensor frame placed at the TCP (= the WAP of the built-in robot), so a pure force in it
    is a pure force at the WAP."""
    sensor = deflex.SensorConfig()
    sensor.flange_T_sensor = np.linalg.inv(robot.fk(Q, "flange")) @ robot.fk(Q, "tcp")
    config = deflex.OnlineConfig()
    config.period_s = 0.004
    return deflex.OnlineCompensator(robot, sensor, config), sensor


def test_constant_force_settles_on_the_closed_form(builtin_stiffness):
    robot = deflex.Robot.builtin()
    comp, sensor = compensator_with_sensor_at_the_tcp(robot)
    first = comp.step(0.0, Q)
    assert first.status == "no_force_yet" and first.usable
    np.testing.assert_array_equal(first.q_command, Q)
    force_sensor = np.array([150.0, -100.0, 300.0, 0.0, 0.0, 0.0])
    t = 0.0
    for cycle in range(1, 400):  # 1.6 s: the 25 Hz low-pass and the rate bound have settled
        for k in range(4):
            comp.push_force(t + k * 0.001, force_sensor)
        t = cycle * 0.004
        out = comp.step(t, Q)
    assert out.status == "ok" and not out.size_limited and not out.rate_limited
    R = robot.fk(Q)[:3, :3]  # sensor axes = TCP axes
    wrench_base = np.concatenate([R @ force_sensor[:3], np.zeros(3)])
    np.testing.assert_allclose(out.wrench_base, wrench_base, atol=1e-6)
    J_wap = fd_jacobian(lambda x: robot.fk(x, "wap"), Q)
    dtheta = (J_wap.T @ wrench_base) / builtin_stiffness
    np.testing.assert_allclose(out.dtheta, dtheta, atol=1e-6 * np.abs(dtheta).max())
    np.testing.assert_allclose(out.q_command, Q - out.dtheta, atol=1e-15)
    assert comp.counters["samples_ok"] == 4 * 399


def test_stale_and_fault_force_ramp_to_zero():
    robot = deflex.Robot.builtin()
    comp, sensor = compensator_with_sensor_at_the_tcp(robot)
    comp.push_force(0.0, [0, 0, 400.0, 0, 0, 0])
    assert comp.step(0.004, Q).status == "ok"
    out = comp.step(0.2, Q)  # no sample for longer than the watchdog
    assert out.status == "stale_force"
    comp.push_force(0.2, [0, 0, 9000.0, 0, 0, 0])  # above the 5000 N fault threshold
    out = comp.step(0.204, Q)
    assert out.status == "force_fault"
    assert comp.counters["samples_fault"] == 1


def test_step_arguments_are_checked():
    comp = deflex.OnlineCompensator(deflex.Robot.builtin())
    with pytest.raises(deflex.InputError, match="argument q_planned"):
        comp.step(0.0, [0.0, np.nan, 0, 0, 0, 0])
    with pytest.raises(deflex.InputError, match="argument wrench_sensor"):
        comp.push_force(0.0, [1.0, 2.0, 3.0])
    config = deflex.OnlineConfig()
    config.period_s = -1.0
    with pytest.raises(deflex.InputError):
        deflex.OnlineCompensator(deflex.Robot.builtin(), deflex.SensorConfig(), config)
