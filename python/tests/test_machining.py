"""Machining from Python against the command line and values computed here: compensate_toolpath
against `deflex offline --toolpath`'s JSON and CSV and the exact form with a finite-difference
Jacobian; milling_force against the textbook's full-slot closed form; fit_cutting_coefficients
recovering the coefficients that made noisy slot forces."""

import numpy as np
import pytest

import deflex
from conftest import SOURCE_DIR, cli_json, fd_jacobian, yaml_list

ROBOT = SOURCE_DIR / "examples" / "machining" / "irb6700_spindle.yaml"
POCKET = SOURCE_DIR / "examples" / "machining" / "pocket_contour.nc"
SWARF = SOURCE_DIR / "examples" / "machining" / "swarf_wall.apt"
COEFFS = SOURCE_DIR / "data" / "machining" / "al7075-t6.yaml"
WORKPIECE = "x_mm=2000,y_mm=0,z_mm=800"
CUTTER = "diameter_mm=10,flutes=3,helix_deg=30"
STOCK = "box:min_mm=-50;-40;-20,max_mm=50;40;0,cell_mm=0.5"
# Al7075-T6 (reference/machining.md), N/mm^2 and N/mm.
K = dict(Ktc=767.0, Krc=168.8, Kac=222.0, Kte=27.7, Kre=26.6, Kae=0.7)
SPEC = "milling:" + ",".join(f"{k}_N_mm{'2' if k.endswith('c') else ''}={v}" for k, v in K.items())


def test_toolpath_matches_the_command_line(tmp_path):
    robot = deflex.Robot.from_file(ROBOT)
    out = tmp_path / "pocket.csv"
    result = deflex.compensate_toolpath(robot, POCKET, WORKPIECE, CUTTER, f"milling:file={COEFFS}", stock=STOCK,
                                        csv=out)
    doc = cli_json("offline", "--robot", ROBOT, "--toolpath", POCKET, "--workpiece", WORKPIECE, "--cutter", CUTTER,
                   "--force", f"milling:file={COEFFS}", "--stock", STOCK)
    assert result["points"] == doc["points"]
    assert result["cutting_points"] == doc["cutting_points"]
    assert result["mean_cutting_deflection_m"] * 1e3 == pytest.approx(doc["mean_cutting_deflection_mm"], rel=1e-12)
    p = result["point"]
    table = np.genfromtxt(out, delimiter=",", names=True, comments="#")
    np.testing.assert_allclose(np.radians(table["tool_spin_deg"]), p["spin_rad"], atol=1e-9)
    np.testing.assert_allclose(table["ae_mm"], p["ae_m"] * 1e3, atol=1e-9)
    np.testing.assert_array_equal(table["cutting"].astype(bool), p["cutting"])
    assert p["q_command"].shape == (result["points"], 6)


def test_toolpath_command_is_the_exact_form():
    robot = deflex.Robot.from_file(ROBOT)
    stiffness = yaml_list(ROBOT, "joint_stiffness_Nm_per_rad")
    result = deflex.compensate_toolpath(robot, SWARF, WORKPIECE, CUTTER, SPEC + ",ae_mm=0.5,ap_mm=20",
                                        tool_spin="fixed:20")
    p = result["point"]
    cutting = np.flatnonzero(p["cutting"])
    assert cutting.size > 50
    for i in cutting[:: cutting.size // 8]:
        q = p["q_desired"][i]
        J = fd_jacobian(robot.fk, q)
        # The wrench is about the TCP (the WAP of this robot): the exact form with J from differences.
        expected = q - (J.T @ p["wrench"][i]) / stiffness
        np.testing.assert_allclose(p["q_command"][i], expected, atol=1e-9)
        # The desired TCP: the tip on the program's point, z down the tool.
        T = robot.fk(q)
        np.testing.assert_allclose(T[:3, 2], -p["tool_axis"][i], atol=1e-9)


def test_milling_force_full_slot_is_the_closed_form():
    N, ap_mm, fz_mm = 3, 5.0, 0.1
    f = deflex.milling_force(CUTTER, SPEC, ae_m=10e-3, ap_m=ap_mm * 1e-3, feed_mm_min=fz_mm * 9000 * N,
                             spindle_rpm=9000)
    along = -N * ap_mm * (fz_mm * K["Krc"] / 4 + K["Kre"] / np.pi)
    normal = N * ap_mm * (fz_mm * K["Ktc"] / 4 + K["Kte"] / np.pi)
    axial = -N * ap_mm * (fz_mm * K["Kac"] / np.pi + K["Kae"] / 2)
    np.testing.assert_allclose(f["force_n"], [along, normal, axial], rtol=1e-9)
    assert f["tooth_passing_hz"] == pytest.approx(N * 9000 / 60)
    assert f["peak_force_n"] > np.linalg.norm(f["force_n"])


def test_fit_recovers_the_coefficients_from_noisy_slot_forces(rng):
    N = 3
    fz = np.array([0.03, 0.06, 0.09, 0.12, 0.15, 0.18]) * 1e-3
    ap = np.full(fz.size, 4e-3)
    mm = fz * 1e3
    a = ap * 1e3
    means = np.column_stack([
        -N * a * (mm * K["Krc"] / 4 + K["Kre"] / np.pi),
        N * a * (mm * K["Ktc"] / 4 + K["Kte"] / np.pi),
        -N * a * (mm * K["Kac"] / np.pi + K["Kae"] / 2),
    ])
    fit = deflex.fit_cutting_coefficients(fz, ap, means + rng.normal(0.0, 0.5, means.shape), flutes=N)
    for key, true in K.items():
        name = f"{key}_N_mm{'2' if key.endswith('c') else ''}"
        assert abs(fit["coefficients"][name] - true) <= 4 * fit["standard_error"][name] + 1e-9, name


def test_bad_toolpath_names_its_line_and_writes_nothing(tmp_path):
    robot = deflex.Robot.from_file(ROBOT)
    bad = tmp_path / "bad.nc"
    bad.write_text(POCKET.read_text().replace("N120 G1 X22.", "N120 G1 X200000"))
    out = tmp_path / "out.nc"
    with pytest.raises(deflex.DataError, match=r"bad\.nc:18: word 'X200000'"):
        deflex.compensate_toolpath(robot, bad, WORKPIECE, CUTTER, SPEC, stock=STOCK, program_out=out)
    assert not out.exists()
    with pytest.raises(deflex.InputError, match="never touches the stock"):
        deflex.compensate_toolpath(robot, POCKET, WORKPIECE, CUTTER, SPEC,
                                   stock="box:min_mm=500;500;-20,max_mm=600;600;0,cell_mm=0.5", program_out=out)
    assert not out.exists()
