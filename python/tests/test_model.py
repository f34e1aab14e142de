"""deflex.Robot against the C++ command-line program's JSON, finite differences of FK and the closed
form of the lumped compliance model computed here in NumPy."""

import subprocess
import sys

import numpy as np
import pytest

import deflex
from conftest import SOURCE_DIR, cli_json, deg_list, fd_jacobian, random_configurations, yaml_list

CONFIGS_DEG = [[0, 30, 10, 0, 50, 0], [20, -10, 35, 40, -60, 90], [-75, 45, -20, -120, 30, -200]]
KR210 = SOURCE_DIR / "examples" / "robots" / "kuka_kr210_r2700.yaml"
FANUC_URDF = SOURCE_DIR / "examples" / "robots" / "ros-industrial" / "fanuc_m10ia.urdf"


def test_issue_line_runs_in_a_fresh_interpreter():
    out = subprocess.run([sys.executable, "-c",
                          "import deflex; print(deflex.Robot.builtin().fk([0,0.5,0.2,0,0.9,0]))"],
                         capture_output=True, text=True, check=True)
    assert out.stdout.count("[") == 5  # a printed 4x4 array


@pytest.mark.parametrize("robot_file", [None, KR210, FANUC_URDF])
def test_fk_single_and_batch_match_cli(robot_file):
    robot = deflex.Robot.builtin() if robot_file is None else deflex.Robot.from_file(str(robot_file))
    extra = [] if robot_file is None else ["--robot", robot_file]
    q = np.radians(np.array(CONFIGS_DEG, dtype=float))
    batch = robot.fk(q)
    assert batch.shape == (len(q), 4, 4)
    for i, qi in enumerate(q):
        doc = cli_json("fk", "--joints-deg", deg_list(qi), *extra)
        T = robot.fk(qi)
        assert T.shape == (4, 4)
        np.testing.assert_allclose(T[:3, 3], doc["position_m"], atol=1e-12)
        np.testing.assert_allclose(T[:3, :3], doc["rotation_matrix"], atol=1e-12)
        np.testing.assert_allclose(T[3], [0, 0, 0, 1])
        np.testing.assert_allclose(batch[i], T, atol=1e-15)


def test_jacobian_against_finite_differences(rng):
    robot = deflex.Robot.builtin()
    q = random_configurations(robot, 20, rng)
    batch = robot.jacobian(q)
    assert batch.shape == (20, 6, 6)
    for point in ("tcp", "flange"):
        for i in range(0, 20, 4):
            J_fd = fd_jacobian(lambda x: robot.fk(x, point), q[i])
            J = robot.jacobian(q[i], point)
            np.testing.assert_allclose(J, J_fd, atol=2e-7)
    for i in range(20):
        np.testing.assert_allclose(batch[i], fd_jacobian(robot.fk, q[i]), atol=2e-7)


def test_deflect_matches_cli():
    robot = deflex.Robot.builtin()
    wrench = [120.0, -300.0, -650.0, 15.0, 0.0, -8.0]
    for q_deg in CONFIGS_DEG:
        doc = cli_json("deflect", "--joints-deg", ",".join(map(str, q_deg)), "--wrench", ",".join(map(str, wrench)))
        d = robot.deflect(np.radians(q_deg), wrench)
        np.testing.assert_allclose(d.dtheta_rad, doc["dtheta_rad"], rtol=1e-12, atol=1e-18)
        np.testing.assert_allclose(d.tcp_deflection, doc["tcp_deflection_m"], rtol=1e-12, atol=1e-18)
        np.testing.assert_allclose(robot.cartesian_compliance(np.radians(q_deg)), doc["cartesian_compliance"],
                                   rtol=1e-12, atol=1e-20)


def test_deflect_closed_form_from_the_yaml_stiffness(rng, builtin_stiffness):
    """dtheta = K^-1 J_wap^T W and dx = J_tcp dtheta, with K read from the robot file here; linear in W."""
    robot = deflex.Robot.builtin()
    q = random_configurations(robot, 50, rng)
    W = rng.normal(0.0, 400.0, (50, 6))
    batch = robot.deflect(q, W)
    one_wrench = robot.deflect(q, W[0])
    for i in range(50):
        J_wap = fd_jacobian(lambda x: robot.fk(x, "wap"), q[i])
        J_tcp = fd_jacobian(robot.fk, q[i])
        dtheta = (J_wap.T @ W[i]) / builtin_stiffness
        scale = np.abs(dtheta).max()
        np.testing.assert_allclose(batch.dtheta_rad[i], dtheta, atol=1e-6 * scale)
        np.testing.assert_allclose(batch.tcp_deflection[i], J_tcp @ dtheta, atol=1e-6 * np.abs(J_tcp @ dtheta).max())
        np.testing.assert_allclose(one_wrench.dtheta_rad[i], (J_wap.T @ W[0]) / builtin_stiffness,
                                   atol=1e-6 * np.abs((J_wap.T @ W[0]) / builtin_stiffness).max())
    doubled = robot.deflect(q, 2.0 * W)
    np.testing.assert_allclose(doubled.dtheta_rad, 2.0 * batch.dtheta_rad, rtol=1e-13, atol=1e-20)
    np.testing.assert_allclose(doubled.tcp_deflection, 2.0 * batch.tcp_deflection, rtol=1e-13, atol=1e-20)


def test_compensated_configuration_is_the_exact_form(builtin_stiffness):
    robot = deflex.Robot.builtin()
    q = np.radians(CONFIGS_DEG[1])
    w = np.array([0.0, 0.0, -625.0, 0.0, 0.0, 0.0])
    J_wap = fd_jacobian(lambda x: robot.fk(x, "wap"), q)
    expected = q - (J_wap.T @ w) / builtin_stiffness
    np.testing.assert_allclose(robot.compensated_configuration(q, w), expected, atol=1e-11)
    # The arm commanded there deflects back onto q (the fixed point of the lumped model).
    np.testing.assert_allclose(robot.deflected_configuration(robot.compensated_configuration(q, w), w), q, atol=1e-11)


def test_ik_all_solutions_contain_the_cli_solution():
    robot = deflex.Robot.builtin()
    q = np.radians(CONFIGS_DEG[1])
    T = robot.fk(q)
    quat = deflex_quaternion(T[:3, :3])
    doc = cli_json("ik", "--position-mm", ",".join(repr(v * 1e3) for v in T[:3, 3]), "--quaternion-wxyz",
                   ",".join(map(repr, quat)), "--seed-deg", ",".join(map(str, CONFIGS_DEG[1])))
    solutions = robot.ik(T, seed=q)
    assert 1 <= len(solutions) <= 8 * 4
    cli_q = np.radians(doc["joints_deg"])
    assert min(np.abs(s.q - cli_q).max() for s in solutions) < 1e-9
    assert any(list(s.configuration) == doc["config"] for s in solutions)
    for s in solutions:
        assert s.ok and s.analytic
        np.testing.assert_allclose(robot.fk(s.q), T, atol=1e-9)
        assert robot.within_limits(s.q)
    assert robot.ik(deflex.pose([9.0, 0.0, 0.0], [1, 0, 0, 0])) == []
    one = robot.inverse_kinematics(deflex.pose([9.0, 0.0, 0.0], [1, 0, 0, 0]))
    assert not one.ok and one.status == "unreachable"


def deflex_quaternion(R):
    """Unit quaternion (w, x, y, z) of a rotation matrix (Shepperd's method, written here)."""
    t = np.trace(R)
    if t > 0:
        s = 2.0 * np.sqrt(1.0 + t)
        return [s / 4, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s]
    i = int(np.argmax(np.diag(R)))
    j, k = (i + 1) % 3, (i + 2) % 3
    s = 2.0 * np.sqrt(1.0 + R[i, i] - R[j, j] - R[k, k])
    q = np.zeros(4)
    q[0] = (R[k, j] - R[j, k]) / s
    q[1 + i] = s / 4
    q[1 + j] = (R[j, i] + R[i, j]) / s
    q[1 + k] = (R[k, i] + R[i, k]) / s
    return list(q)


def test_robot_properties_from_the_file():
    robot = deflex.Robot.from_file(str(KR210))
    assert robot.dof == 6 and robot.has_stiffness
    np.testing.assert_allclose(robot.stiffness, yaml_list(KR210, "joint_stiffness_Nm_per_rad"))
    stiffer = robot.with_stiffness(2 * robot.stiffness)
    q = np.radians(CONFIGS_DEG[0])
    w = [0, 0, -500, 0, 0, 0]
    np.testing.assert_allclose(stiffer.deflect(q, w).dtheta_rad, robot.deflect(q, w).dtheta_rad / 2, rtol=1e-13)
    again = deflex.Robot.from_yaml(robot.to_yaml(), str(KR210.parent))
    np.testing.assert_allclose(again.fk(q), robot.fk(q), atol=1e-12)


def test_batch_calls_from_several_threads_at_once(rng):
    """The batch calls release the GIL and use a workspace of their own: threads sharing one Robot get the
    single-threaded answer (itself checked against the CLI above)."""
    from concurrent.futures import ThreadPoolExecutor

    robot = deflex.Robot.builtin()
    q = random_configurations(robot, 20000, rng)
    expected_T, expected_J = robot.fk(q), robot.jacobian(q)
    with ThreadPoolExecutor(4) as pool:
        results = list(pool.map(lambda k: robot.fk(q) if k % 2 else robot.jacobian(q), range(8)))
    for k, r in enumerate(results):
        np.testing.assert_array_equal(r, expected_T if k % 2 else expected_J)
