"""Tracker sessions from Python: SA exports read back, registration against a rotation built with NumPy,
and a clock offset recovered; the same figures as `deflex register --json`."""

import math

import numpy as np
import pytest

import deflex
from conftest import cli_json


def rotation(axis, angle):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


def test_sa_export_round_trip(tmp_path):
    t = np.linspace(0.0, 1.0, 101)
    trace = np.column_stack([t, 1.9 + 0.1 * np.cos(t), 0.1 * np.sin(t), np.full_like(t, 0.9)])
    deflex.write_sa_export(tmp_path / "run.txt", trace, frame="Tracker")
    f = deflex.read_tracker_file(tmp_path / "run.txt", expect_frame="Tracker")
    assert f["format"] == "sa" and f["frame"] == "Tracker" and f["has_time"]
    np.testing.assert_allclose(f["points"], trace, atol=1e-9)
    with pytest.raises(deflex.Error, match="names no length unit"):
        (tmp_path / "bare.txt").write_text("P1 1 2 3\n")
        deflex.read_tracker_file(tmp_path / "bare.txt")


def test_registration_matches_numpy_rotation_and_the_cli(tmp_path):
    r = rotation([0.3, -0.4, 0.87], 0.7)
    p = np.array([-3.2, 1.5, -0.4])
    base = np.array([[1.5, -0.5, 0.5], [2.2, -0.4, 0.7], [1.8, 0.6, 0.4], [2.0, 0.0, 1.5], [1.6, 0.3, 1.2]])
    tracker = (base - p) @ r  # p_t = R^T (p_b - p)
    out = deflex.register_frames(tracker, base)
    np.testing.assert_allclose(out["base_T_tracker"][:3, :3], r, atol=1e-12)
    np.testing.assert_allclose(out["base_T_tracker"][:3, 3], p, atol=1e-12)
    for name, pts in (("tracker.txt", tracker), ("base.txt", base)):
        (tmp_path / name).write_text("// Units: Meters\n" + "".join(f"P{i} {x!r} {y!r} {z!r}\n" for i, (x, y, z) in enumerate(pts)))
    doc = cli_json("register", "--tracker", str(tmp_path / "tracker.txt"), "--base", str(tmp_path / "base.txt"),
                   "-o", str(tmp_path / "frame.yaml"))
    np.testing.assert_allclose(np.array(doc["position_mm"]) * 1e-3, p, atol=1e-9)
    with pytest.raises(deflex.Error, match="on one line"):
        deflex.register_frames(base[:, :] * [1, 0, 0], base * [1, 0, 0])


def test_align_time_recovers_a_clock_offset():
    t = np.arange(0.0, 20.0, 0.004)
    phase = 2 * np.pi * (t / 20 - np.sin(2 * np.pi * t / 20) / (2 * np.pi))
    commanded = np.column_stack([t, 1.9 + 0.1 * np.cos(3 * phase), 0.1 * np.sin(3 * phase), np.full_like(t, 0.9)])
    tracker_t = np.arange(1000.0, 1019.0, 0.001)
    program_t = tracker_t - 999.5
    ph = 2 * np.pi * (program_t / 20 - np.sin(2 * np.pi * program_t / 20) / (2 * np.pi))
    measured = np.column_stack([tracker_t, 1.9 + 0.1 * np.cos(3 * ph), 0.1 * np.sin(3 * ph), np.full_like(ph, 0.9)])
    a = deflex.align_time(measured, commanded)
    assert abs(a["offset_s"] + 999.5) < 1e-4


def test_align_time_refuses_traces_without_times():
    t = np.arange(0.0, 5.0, 0.01)
    timed = np.column_stack([t, 1.9 + 0.1 * np.cos(t), 0.1 * np.sin(t), np.full_like(t, 0.9)])
    # Row numbers are not seconds: an (N, 3) array is refused, naming the argument.
    with pytest.raises(deflex.Error, match="argument measured: .N, 3. positions carry no times"):
        deflex.align_time(timed[:, 1:], timed)
    with pytest.raises(deflex.Error, match="argument commanded"):
        deflex.align_time(timed, timed[:, 1:])
    with pytest.raises(deflex.Error, match="argument loaded"):
        deflex.time_synchronous_deviation(timed[:, 1:], timed)
    a = deflex.align_time(timed, timed)
    assert abs(a["offset_s"]) < 1e-3 and a["reference_t_s"] == pytest.approx(2.495, abs=0.01)


def test_registration_refuses_a_mirror_image_and_a_large_rms():
    r = rotation([0.3, -0.4, 0.87], 0.7)
    base = np.array([[1.5, -0.5, 0.5], [2.2, -0.4, 0.7], [1.8, 0.6, 0.4], [2.0, 0.0, 1.5], [1.6, 0.3, 1.2]])
    tracker = base @ r
    with pytest.raises(deflex.Error, match="mirror image"):
        deflex.register_frames(tracker, base * [1, -1, 1], max_rms_m=10.0)
    moved = base.copy()
    moved[2, 0] += 0.005
    with pytest.raises(deflex.Error, match="above the limit of 1.0000 mm"):
        deflex.register_frames(tracker, moved)
    assert deflex.register_frames(tracker, moved, max_rms_m=0.005)["rms_m"] > 1e-3


def test_tracker_csv_ignores_text_columns_and_refuses_time_going_back(tmp_path):
    (tmp_path / "run.csv").write_text("point,t_s,x_mm,y_mm,z_mm,note\nA,0,1500,0,900,ok\nB,0.01,1501,0,900,\"a, b\"\n")
    f = deflex.read_tracker_file(tmp_path / "run.csv")
    np.testing.assert_allclose(f["points"][1], [0.01, 1.501, 0.0, 0.9])
    (tmp_path / "back.csv").write_text("t_s,x_mm,y_mm,z_mm\n0.02,1500,0,900\n0.01,1501,0,900\n")
    with pytest.raises(deflex.Error, match="back.csv:3: column 't_s': time goes backwards"):
        deflex.read_tracker_file(tmp_path / "back.csv")


def test_a_windows_1252_export_reads_its_frame_as_utf8(tmp_path):
    (tmp_path / "cp.txt").write_bytes(b"// Working Frame: Caf\xe9 \xb0\n// Units: Millimeters\nP1 1500 0 900\n")
    f = deflex.read_tracker_file(tmp_path / "cp.txt", expect_frame="Café °")
    assert f["frame"] == "Café °"
