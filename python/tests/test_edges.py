"""The module's edges a researcher meets: every array a property hands out is read-only, every config
and result object pickles, the documented positional forms work, tracker points pair by name as
`deflex register` pairs them, the case study's tables are recomputed from its traces with
split_laps and mean_reference, a partial case dict is merged over the paper's case, messages name
the Python arguments, a 3-axis sensor's (N, 3) log replays, and joints beyond their limits are a
status, not a command."""

import pickle
import re

import numpy as np
import pytest

import deflex
from conftest import SOURCE_DIR, cli_json


def objects_of_every_class(tmp_path):
    """An instance of each class that has array properties, made the way a user makes it."""
    robot = deflex.Robot.builtin()
    circle = deflex.Circle()
    circle.centre_m = [1.6, 0.0, 0.8]
    circle.points = 12
    plan = deflex.plan_calibration(robot, [1.4, -0.3, 0.6], [1.8, 0.3, 1.0], poses=4)
    q = np.array([0.1, 0.5, 0.2, 0.3, 0.9, 0.1])
    oc = deflex.OnlineCompensator(robot)
    oc.push_force(0.0, [0, 0, 300, 0, 0, 0])
    estimate = deflex.identify_stiffness(
        deflex.Robot.from_file(SOURCE_DIR / "examples" / "robots" / "kuka_kr210_r2700.yaml"),
        SOURCE_DIR / "examples" / "identify" / "kr210_synthetic_measurements.csv")
    return {
        "Robot": robot,
        "Circle": circle,
        "CalibrationPlan": plan,
        "StiffnessEstimate": estimate,
        "Deflection": robot.deflect(q, [0, 0, -500, 0, 0, 0]),
        "IkResult": robot.ik(robot.fk(q))[0],
        "OfflineResult": deflex.compensate_path(robot, circle, "constant:fz_N=-400"),
        "CycleOutput": oc.step(0.004, q),
        "SensorConfig": deflex.SensorConfig(),
        "OnlineConfig": deflex.OnlineConfig(),
    }


def test_every_array_property_is_read_only(tmp_path):
    checked = 0
    for name, obj in objects_of_every_class(tmp_path).items():
        for attr in dir(type(obj)):
            if attr.startswith("_") or not isinstance(getattr(type(obj), attr), property):
                continue
            value = getattr(obj, attr)
            if isinstance(value, np.ndarray):
                checked += 1
                assert not value.flags.writeable, f"{name}.{attr} is writeable"
                with pytest.raises(ValueError, match="read-only"):
                    value.reshape(-1)[0] = 1.0
    assert checked >= 30


def test_every_config_and_result_object_pickles(tmp_path):
    objects = objects_of_every_class(tmp_path)
    sensor = objects["SensorConfig"]
    sensor.name = "ati omega160"
    sensor.components = 3
    sensor.lowpass_cutoff_hz = 12.5
    sensor.bias_sensor = [1, 2, 3, 0.1, 0.2, 0.3]
    sensor.gravity_base_m_s2 = [0, 0.5, -9.8]
    sensor.flange_T_sensor = deflex.pose([0, 0, 0.05], [0, 1, 0, 0])
    config = objects["OnlineConfig"]
    config.period_s = 0.012
    config.max_tcp_rate_m_s = 0.02
    config.jacobian_at = "feedback"
    for name, obj in objects.items():
        back = pickle.loads(pickle.dumps(obj))
        assert type(back) is type(obj), name
        for attr in dir(type(obj)):
            if attr.startswith("_") or not isinstance(getattr(type(obj), attr), property):
                continue
            a, b = getattr(obj, attr), getattr(back, attr)
            if isinstance(a, np.ndarray):
                np.testing.assert_array_equal(a, b, err_msg=f"{name}.{attr}")
            elif not callable(a):
                assert a == b or (a != a and b != b), f"{name}.{attr}: {a!r} != {b!r}"
    assert pickle.loads(pickle.dumps(sensor)).to_yaml() == sensor.to_yaml()


def test_the_documented_positional_forms_of_identify_stiffness():
    robot = deflex.Robot.from_file(SOURCE_DIR / "examples" / "robots" / "kuka_kr210_r2700.yaml")
    csv = SOURCE_DIR / "examples" / "identify" / "kr210_synthetic_measurements.csv"
    m = deflex.read_stiffness_measurements(csv)
    by_file = deflex.identify_stiffness(robot, str(csv))
    forms = [
        deflex.identify_stiffness(robot, csv),
        deflex.identify_stiffness(robot, csv_path=csv),
        deflex.identify_stiffness(robot, data=str(csv)),
        deflex.identify_stiffness(robot, m["q"], m["wrench"], m["dp"], m["drot"]),
        deflex.identify_stiffness(robot, m["q"], m["wrench"], m["dp"], m["drot"], m["weight"]),
        deflex.identify_stiffness(robot, q=m["q"], wrench=m["wrench"], dp=m["dp"], drot=m["drot"], weight=m["weight"]),
    ]
    for est in forms:
        np.testing.assert_allclose(est.stiffness_nm_per_rad, by_file.stiffness_nm_per_rad, rtol=1e-12)
    with pytest.raises(deflex.InputError, match="given twice"):
        deflex.identify_stiffness(robot, m["q"], m["wrench"], m["dp"], csv_path=csv)


def rotation(axis, angle):
    """Rodrigues' formula, in NumPy."""
    k = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def test_register_frames_pairs_named_points_by_name_as_the_cli_does(tmp_path):
    rng = np.random.default_rng(3)
    base = rng.uniform(-1.0, 1.0, (6, 3)) + [1.5, 0.0, 0.8]
    R, t = rotation([0.2, -0.3, 1.0], 0.8), np.array([0.3, -2.0, 0.1])
    tracker = (base - t) @ R  # p_base = R p_tracker + t
    names = [f"REF{i}" for i in range(6)]
    order = [0, 4, 2, 3, 1, 5]  # two rows swapped in the tracker's list
    swapped, swapped_names = tracker[order], [names[i] for i in order]
    by_order = deflex.register_frames(tracker, base)
    by_name = deflex.register_frames(swapped, base, tracker_names=swapped_names, base_names=names)
    for r in (by_order, by_name):
        np.testing.assert_allclose(r["base_T_tracker"][:3, :3], R, atol=1e-12)
        np.testing.assert_allclose(r["base_T_tracker"][:3, 3], t, atol=1e-12)
        assert r["rms_m"] < 1e-12
    assert by_name["names"] == swapped_names
    # Swapped rows without names pair by order: refused by the RMS bound, not a silent error of metres.
    with pytest.raises(deflex.Error, match="RMS"):
        deflex.register_frames(swapped, base)
    # What read_tracker_file returns pairs by name, the target's own name against a bare one, as `deflex
    # register --tracker FILE --base FILE` pairs them.
    lines = ["// Working Frame: Tracker", "// Units: Millimeters", "// Columns: Collection Group Target X Y Z"]
    lines += [f"Job Nests {n} {p[0] * 1e3:.9f} {p[1] * 1e3:.9f} {p[2] * 1e3:.9f}" for n, p in zip(swapped_names, swapped)]
    (tmp_path / "tracker.txt").write_text("\n".join(lines) + "\n")
    measured = deflex.read_tracker_file(tmp_path / "tracker.txt")
    assert measured["names"][1] == "Job::Nests::REF4"
    r = deflex.register_frames(measured, {"points": base, "names": names})
    np.testing.assert_allclose(r["base_T_tracker"][:3, 3], t, atol=1e-9)
    assert r["names"] == swapped_names
    cli = cli_json("register", "--tracker", tmp_path / "tracker.txt", "--base", write_base(tmp_path, base, names),
                   "-o", tmp_path / "frame.yaml")
    assert cli["rms_mm"] == pytest.approx(r["rms_m"] * 1e3, abs=1e-6)
    # A name without a partner is refused, naming it and where it is.
    with pytest.raises(deflex.DataError, match=r"tracker.txt:5: point 'Job::Nests::REF4' is not in"):
        deflex.register_frames(measured, {"points": base, "names": names[:4] + ["REF9", "REF5"]})
    with pytest.raises(deflex.DataError, match="REF9.*is not in"):
        deflex.register_frames(swapped, base, tracker_names=names[:-1] + ["REF9"], base_names=names)


def write_base(tmp_path, base, names):
    """The base points as an SA export with their names (mm)."""
    lines = ["// Working Frame: Robot Base", "// Units: Millimeters", "// Columns: Collection Group Target X Y Z"]
    lines += [f"Job Base {n} {p[0] * 1e3:.9f} {p[1] * 1e3:.9f} {p[2] * 1e3:.9f}" for n, p in zip(names, base)]
    path = tmp_path / "base.txt"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_a_partial_case_dict_runs_and_its_tables_come_back_from_its_traces():
    # Only what differs from the paper's case: one setup, one load, one speed (and the indices that
    # point into the loads); every other key is the paper's.
    case = {
        "protocol": {"speeds_mm_s": [50], "sweep_load_N": 625},
        "error_budget": {"load_index": 0},
        "setups": [{"name": "offline", "strategy": "offline", "link": "program", "sensor": False, "loads_N": [625]}],
    }
    result = deflex.run_case_study(case, quick=True, seeds=1, speed_sweep=False, error_budget=False, threads=2,
                                   traces=True)
    tables = result.tables
    paper_name = re.search(r'^name: "(.*)"', (SOURCE_DIR / "data" / "cases" / "paper.yaml").read_text(), re.M).group(1)
    assert tables["case"] == paper_name and tables["speeds_mm_s"] == [50]
    assert [s["setup"] for s in tables["setups"]] == ["offline"]
    # The figures of the table, recomputed in Python from the traces as the study computes them: the
    # distance to the mean of the unloaded run's laps, the laps split by the angle turned.
    load = tables["setups"][0]["loads"][0]
    unloaded = result.traces["offline-program_unloaded_50mm_s"]
    reference = deflex.mean_reference(unloaded)
    for kind, key in (("offline", "c"), ("uc", "uc")):
        loaded = result.traces[f"offline-program_{kind}_625N_50mm_s"]
        d = deflex.path_deviation(loaded, reference)
        assert d.mean_m * 1e3 == pytest.approx(load[f"{key}_mm"]["50"], rel=1e-12)
        assert d.std_m * 1e3 == pytest.approx(load[f"{key}_std_mm"]["50"], rel=1e-12)
        assert d.max_m * 1e3 == pytest.approx(load[f"{key}_max_mm"]["50"], rel=1e-12)
        sync = deflex.time_synchronous_deviation(loaded, unloaded)
        assert sync.mean_m * 1e3 == pytest.approx(load[f"{key}_sync_mm"]["50"], rel=1e-12)
        laps = deflex.split_laps(loaded)
        assert len(laps) == 2  # quick: one lap each way
        iso = deflex.iso9283_path(laps, reference)
        assert iso.accuracy_m * 1e3 == pytest.approx(load[f"iso_accuracy_{key}_mm"]["50"], rel=1e-12)
        if key == "c":
            assert iso.repeatability_m * 1e3 == pytest.approx(load["iso_repeatability_mm"]["50"], rel=1e-12)
        # Against the noisy unloaded run itself the nearest-point distance comes out lower (biased by
        # the reference's own noise): why the study measures against the laps' mean.
        assert deflex.path_deviation(loaded, unloaded).mean_m < d.mean_m
    with pytest.raises(deflex.ModelError, match="no_such_key"):
        deflex.run_case_study({"protocol": {"no_such_key": 1}}, quick=True)


def test_messages_name_the_python_arguments(tmp_path):
    robot = deflex.Robot.builtin()
    # No lever and a TCP on the flange axis: joint 6 cannot be told apart; the advice names lever_m.
    plan = deflex.plan_calibration(robot, [1.4, -0.3, 0.6], [1.8, 0.3, 1.0], poses=6, lever_m=0.0)
    text = " ".join(plan.warnings)
    assert "lever_m" in text and "--lever-mm" not in text, text
    (tmp_path / "t.txt").write_text("// Units: Millimeters\n// Columns: Collection Group Target X Y Z\nJ G P1 1 2 3\n")
    with pytest.raises(deflex.Error) as error:
        deflex.read_tracker_file(tmp_path / "t.txt", length_unit="furlong")
    assert "length_unit" in str(error.value) and "--tracker-units" not in str(error.value), str(error.value)


def test_a_three_axis_sensors_force_log_replays_as_n_by_3():
    robot = deflex.Robot.builtin()
    sensor = deflex.SensorConfig()
    sensor.components = 3
    q = np.array([0.1, 0.5, 0.2, 0.3, 0.9, 0.1])
    t_force = np.arange(0, 0.4, 0.001)
    forces = np.column_stack([100 * np.sin(t_force), 50 + 0 * t_force, -300 + 0 * t_force])
    t_cycle = np.arange(0.004, 0.4, 0.004)
    three = deflex.OnlineCompensator(robot, sensor).replay(t_force, forces, t_cycle, q)
    padded = np.column_stack([forces, np.zeros_like(forces)])
    six = deflex.OnlineCompensator(robot, sensor).replay(t_force, padded, t_cycle, q)
    np.testing.assert_array_equal(three["q_command"], six["q_command"])
    assert np.abs(three["dtheta"]).max() > 0
    one = deflex.OnlineCompensator(robot, sensor)
    one.push_force(0.0, forces[0])
    with pytest.raises(deflex.InputError, match="wrench_sensor.*6-axis"):
        deflex.OnlineCompensator(robot).replay(t_force, forces, t_cycle, q)


def test_joints_beyond_their_limits_are_a_status_not_a_command():
    robot = deflex.Robot.builtin()
    oc = deflex.OnlineCompensator(robot)
    q = np.array([0.1, 0.5, 0.2, 0.3, 0.9, 0.1])
    for k in range(10):
        oc.push_force(0.004 * k, [0, 0, 300, 0, 0, 0])
        out = oc.step(0.004 * k, q)
    assert out.status == "ok"
    far = q.copy()
    far[0] = 10.0  # joint 1 of the IRB 6700 turns +-170 deg (robot file): 10 rad is beyond
    out = oc.step(0.05, far)
    assert out.status == "outside_limits" and not out.usable
    assert np.abs(out.q_command).max() < 1.0
