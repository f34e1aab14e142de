"""Stiffness identification and calibration planning against the command-line program's JSON and
CSV, the shipped example's true stiffness, and the compliance model's closed form."""

import numpy as np

import deflex
from conftest import SOURCE_DIR, cli_json, fd_jacobian, yaml_list

EXAMPLE = SOURCE_DIR / "examples" / "identify"
KR210 = SOURCE_DIR / "examples" / "robots" / "kuka_kr210_r2700.yaml"
MEASUREMENTS = EXAMPLE / "kr210_synthetic_measurements.csv"


def read_measurements_here(path):
    """The measurement CSV read with NumPy alone, converted to SI units."""
    table = np.genfromtxt(path, delimiter=",", names=True, comments="#")
    q = np.radians(np.column_stack([table[f"q{j}_deg"] for j in range(1, 7)]))
    wrench = np.column_stack([table[c] for c in ("fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm")])
    dp = np.column_stack([table[c] for c in ("dx_mm", "dy_mm", "dz_mm")]) * 1e-3
    return q, wrench, dp, table["weight"]


def test_identify_from_csv_matches_cli_and_the_truth():
    robot = deflex.Robot.from_file(str(KR210))
    est = deflex.identify_stiffness(robot, str(MEASUREMENTS))
    doc = cli_json("identify", "--robot", KR210, "--data", MEASUREMENTS)
    np.testing.assert_allclose(est.stiffness_nm_per_rad, doc["stiffness_Nm_per_rad"], rtol=1e-9)
    np.testing.assert_allclose(est.std_error_nm_per_rad, doc["std_error_Nm_per_rad"], rtol=1e-9)
    assert est.measurements == doc["measurements"]
    assert abs(est.condition_number - doc["condition_number"]) < 1e-9 * doc["condition_number"]
    assert est.unidentifiable_joints == doc["unidentifiable_joints"] and est.warnings == doc["warnings"]
    truth = yaml_list(EXAMPLE / "kr210_true_stiffness.yaml", "joint_stiffness_Nm_per_rad")
    z = (est.stiffness_nm_per_rad - truth) / est.std_error_nm_per_rad
    assert np.all(np.abs(z) < 4), z
    assert np.all(est.std_error_nm_per_rad > 0)


def test_identify_from_arrays_equals_csv_and_reads_the_same_rows():
    robot = deflex.Robot.from_file(str(KR210))
    q, wrench, dp, weight = read_measurements_here(MEASUREMENTS)
    from_arrays = deflex.identify_stiffness(robot, q=q, wrench=wrench, dp=dp, weight=weight)
    from_csv = deflex.identify_stiffness(robot, str(MEASUREMENTS))
    np.testing.assert_allclose(from_arrays.stiffness_nm_per_rad, from_csv.stiffness_nm_per_rad, rtol=1e-9)
    data = deflex.read_stiffness_measurements(str(MEASUREMENTS))
    np.testing.assert_allclose(data["q"], q, atol=1e-12)
    np.testing.assert_allclose(data["dp"], dp, atol=1e-15)
    assert data["drot"] is None


def test_identify_noise_free_recovers_the_stiffness_exactly():
    """Measurements made here from the closed form dp = J_tcp K^-1 J_wap^T W (finite-difference Jacobians)."""
    truth = deflex.Robot.from_file(str(EXAMPLE / "kr210_true_stiffness.yaml"))
    k = truth.stiffness
    q, wrench, _, _ = read_measurements_here(MEASUREMENTS)
    dp = np.array([(fd_jacobian(truth.fk, qi) @ ((fd_jacobian(lambda x: truth.fk(x, "wap"), qi).T @ wi) / k))[:3]
                   for qi, wi in zip(q, wrench)])
    est = deflex.identify_stiffness(deflex.Robot.from_file(str(KR210)), q=q, wrench=wrench, dp=dp, robust=False)
    np.testing.assert_allclose(est.stiffness_nm_per_rad, k, rtol=1e-5)
    fixed = deflex.identify_stiffness(deflex.Robot.from_file(str(KR210)), q=q, wrench=wrench, dp=dp,
                                      fixed_stiffness_nm_per_rad=[None, None, None, None, None, k[5]])
    assert fixed.fixed_joints == [6]


def test_plan_calibration_matches_cli_and_the_closed_form(tmp_path):
    robot = deflex.Robot.from_file(str(KR210))
    # The region as the program computes it from --region-mm (mm times 1e-3): mirror-image poses give the
    # design the same information, and the last bit of a grid coordinate decides between them.
    region_min, region_max = np.array([1300.0, -400.0, 500.0]) * 1e-3, np.array([1900.0, 400.0, 1100.0]) * 1e-3
    plan = deflex.plan_calibration(robot, region_min, region_max, load_n=800, poses=8, loads_per_pose=2)
    out = tmp_path / "plan.csv"
    doc = cli_json("plan-calibration", "--robot", KR210, "--region-mm", "1300,1900,-400,400,500,1100", "--load-N", 800,
                   "--poses", 8, "--loads-per-pose", 2, "-o", out)
    table = np.genfromtxt(out, delimiter=",", names=True, comments="#")
    np.testing.assert_allclose(plan.q, np.radians(np.column_stack([table[f"q{j}_deg"] for j in range(1, 7)])),
                               atol=1e-8)
    np.testing.assert_allclose(plan.wrench[:, :3], np.column_stack([table[c] for c in ("fx_N", "fy_N", "fz_N")]),
                               atol=1e-6)
    assert abs(plan.condition_number - doc["condition_number"]) < 1e-6 * doc["condition_number"]
    assert len(plan.pose) == 16 and max(plan.pose) == 8
    for qi, wi, dpi, Ti in zip(plan.q, plan.wrench, plan.expected_dp, plan.base_T_tcp):
        dtheta = (fd_jacobian(lambda x: robot.fk(x, "wap"), qi).T @ wi) / robot.stiffness
        np.testing.assert_allclose(dpi, (fd_jacobian(robot.fk, qi) @ dtheta)[:3], atol=1e-6 * np.abs(dpi).max())
        np.testing.assert_allclose(Ti, robot.fk(qi), atol=1e-9)
