"""Offline compensation and paths against `deflex offline`'s CSV and the exact compensation form
q_cmd = q_des - K^-1 J_wap(q_des)^T W computed here."""

import numpy as np
import pytest

import deflex
from conftest import cli_json, fd_jacobian, run_cli


def read_offline_csv(path, dof=6):
    table = np.genfromtxt(path, delimiter=",", names=True, comments="#")
    q_des = np.radians(np.column_stack([table[f"q{j}_des_deg"] for j in range(1, dof + 1)]))
    q_cmd = np.radians(np.column_stack([table[f"q{j}_cmd_deg"] for j in range(1, dof + 1)]))
    wrench = np.column_stack([table[c] for c in ("fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm")])
    return q_des, q_cmd, wrench, table["deflection_mm"]


def test_circle_ldbb_matches_cli(tmp_path):
    robot = deflex.Robot.builtin()
    result = deflex.compensate_path(robot, deflex.Circle(), "ldbb:phi_deg=30,force_N=400")
    out = tmp_path / "circle.csv"
    doc = cli_json("offline", "--circle", "default", "--force", "ldbb:phi_deg=30,force_N=400", "-o", out)
    q_des, q_cmd, wrench, deflection_mm = read_offline_csv(out)
    assert result.q_command.shape == (81, 6)
    # The CSV holds 10 significant digits.
    np.testing.assert_allclose(result.q_desired, q_des, atol=1e-9)
    np.testing.assert_allclose(result.q_command, q_cmd, atol=1e-9)
    np.testing.assert_allclose(result.wrench, wrench, rtol=1e-8, atol=1e-8)
    np.testing.assert_allclose(np.linalg.norm(result.predicted_deflection[:, :3], axis=1) * 1e3, deflection_mm,
                               rtol=1e-6)
    run = doc["runs"][0]
    assert abs(result.max_deflection_m * 1e3 - run["max_deflection_mm"]) < 1e-9
    assert abs(result.mean_deflection_m * 1e3 - run["mean_deflection_mm"]) < 1e-9


def test_exact_form_and_residual(builtin_stiffness):
    robot = deflex.Robot.builtin()
    poses = deflex.line_path([1.4, -0.2, 0.9], [1.6, 0.2, 1.1], points=7)
    assert poses.shape == (7, 4, 4)
    w = np.array([150.0, -80.0, -500.0, 0.0, 0.0, 0.0])
    result = deflex.compensate_path(robot, poses, w)
    np.testing.assert_allclose(robot.fk(result.q_desired), poses, atol=1e-9)
    for qd, qc in zip(result.q_desired, result.q_command):
        J_wap = fd_jacobian(lambda x: robot.fk(x, "wap"), qd)
        np.testing.assert_allclose(qc, qd - (J_wap.T @ w) / builtin_stiffness, atol=1e-11)
    assert result.max_residual_m < 1e-9
    # The same wrench as a spec string and as one row a point.
    spec = deflex.compensate_path(robot, poses, "constant:fx_N=150,fy_N=-80,fz_N=-500")
    table = deflex.compensate_path(robot, poses, np.tile(w, (7, 1)))
    np.testing.assert_allclose(spec.q_command, result.q_command, atol=1e-15)
    np.testing.assert_allclose(table.q_command, result.q_command, atol=1e-15)
    with pytest.raises(deflex.InputError, match="has 7 points, the path 8"):
        deflex.compensate_path(robot, deflex.line_path([1.4, -0.2, 0.9], [1.6, 0.2, 1.1], points=8), np.tile(w, (7, 1)))


def test_path_ik_error_names_the_point():
    robot = deflex.Robot.builtin()
    with pytest.raises(deflex.InputError, match="path point 0"):
        deflex.solve_path_ik(robot, deflex.line_path([5.0, 0, 1.0], [5.2, 0, 1.0], points=3))
    q, configuration = deflex.solve_path_ik(robot, deflex.Circle())
    assert q.shape == (81, 6) and len(configuration) == 4
    cli = run_cli("ik", "--position-mm", "1600,0,1000", "--quaternion-wxyz", "0,0,1,0", "--json")
    assert cli.returncode == 0
