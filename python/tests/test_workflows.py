"""The command-line program's workflows from Python, each checked against what `deflex ... --json`
prints or the files it writes for the same inputs: several loads on one path, its CSV, RAPID module
and joint trajectories, force models evaluated along a path, an existing RAPID and KRL program
compensated, payload identification, the case study's traces and report from a case given as a
dict, and the arm's joint frames (against finite differences and the chain's own flange)."""

import csv
import json
import pickle

import numpy as np
import pytest

import deflex
from conftest import SOURCE_DIR, cli_json, fd_jacobian, run_cli

LDBB = "ldbb:phi_deg=30,force_N=125;325;650"


def numeric_rows(path):
    """The rows of a CSV as floats (comment lines and the header left out)."""
    rows = []
    with open(path) as f:
        for row in csv.reader(line for line in f if not line.startswith("#")):
            try:
                rows.append([float(v) for v in row])
            except ValueError:
                continue  # the header
    return np.array(rows)


def test_several_loads_and_their_files_match_the_cli(tmp_path):
    robot = deflex.Robot.builtin()
    results = deflex.compensate_loads(robot, deflex.Circle(), LDBB)
    doc = cli_json("offline", "--circle", "default", "--force", LDBB, "-o", tmp_path / "cli.csv", "--rapid",
                   tmp_path / "cli.mod", "--joint-trajectory", tmp_path / "cli_traj.csv", "--nominal-trajectory",
                   tmp_path / "cli_nominal.csv", "--speed-mm-s", 20)
    assert len(results) == len(doc["runs"]) == 3
    with pytest.raises(deflex.InputError, match="compensate_loads"):
        deflex.compensate_path(robot, deflex.Circle(), LDBB)
    for res, run in zip(results, doc["runs"]):
        assert res.force_description == run["force"]
        assert res.max_deflection_m * 1e3 == pytest.approx(run["max_deflection_mm"], rel=1e-12)
        assert res.mean_deflection_m * 1e3 == pytest.approx(run["mean_deflection_mm"], rel=1e-12)
        assert np.degrees(res.max_joint_correction_rad) == pytest.approx(run["max_joint_correction_deg"], rel=1e-12)
        # The per-point CSV: the same numbers (the CLI streams it, Python writes it from the result).
        mine = tmp_path / "mine.csv"
        res.write_csv(mine)
        np.testing.assert_allclose(numeric_rows(mine), numeric_rows(run["csv"]), rtol=1e-9, atol=1e-9)
        # The RAPID module: the same module but for the header's note, which names the CLI's options.
        cli_lines = [l for l in open(run["rapid"]).read().splitlines() if "Path:" not in l]
        module = run["rapid"].rsplit("/", 1)[1].replace("cli_", "DeflexOffline_").replace(".mod", "")
        text = res.rapid_module(module=module, speed_mm_s=20)
        assert [l for l in text.splitlines() if "Path:" not in l] == cli_lines
        # The compensated joint trajectory at 20 mm/s, as the CLI wrote it (deg in the file, rad here).
        t, q = res.joint_trajectory(robot, speed_mm_s=20)
        file_t, file_q = deflex.read_joint_trajectory(run["joint_trajectory"], robot)
        np.testing.assert_allclose(t, file_t, atol=1e-9)
        np.testing.assert_allclose(q, file_q, atol=1e-9)
    t, q = results[0].joint_trajectory(robot, speed_mm_s=20, nominal=True)
    file_t, file_q = deflex.read_joint_trajectory(tmp_path / "cli_nominal.csv", robot)
    np.testing.assert_allclose(q, file_q, atol=1e-9)
    # Written from Python and read back: the same trajectory, checked as the CLI checks it.
    deflex.write_joint_trajectory(tmp_path / "py_traj.csv", robot, t, q, comment="from Python")
    t2, q2 = deflex.read_joint_trajectory(tmp_path / "py_traj.csv", robot)
    np.testing.assert_allclose(q2, q, atol=1e-9)
    bad_q = q.copy()
    bad_q[3, 0] = 10.0  # beyond joint 1's limit
    with pytest.raises(deflex.InputError):
        deflex.write_joint_trajectory(tmp_path / "bad.csv", robot, t, bad_q)
    assert not (tmp_path / "bad.csv").exists()
    # A list gives one load an item to compensate_loads; to compensate_path a nested list is a table.
    mixed = deflex.compensate_loads(robot, deflex.Circle(points=5), ["constant:fz_N=-300", [0, 0, -300, 0, 0, 0]])
    np.testing.assert_allclose(mixed[0].q_command, mixed[1].q_command, atol=1e-12)
    table = deflex.compensate_path(robot, deflex.Circle(points=5), [[0, 0, -300, 0, 0, 0]] * 5)
    np.testing.assert_allclose(table.q_command, mixed[0].q_command, atol=1e-12)
    # Results pickle (e.g. to a worker process) with every point.
    copy = pickle.loads(pickle.dumps(results[1]))
    np.testing.assert_array_equal(copy.q_command, results[1].q_command)


def test_force_models_along_a_path_match_the_cli_csv(tmp_path):
    robot = deflex.Robot.builtin()
    loads = deflex.force_along_path(robot, deflex.Circle(), LDBB)
    assert len(loads) == 3 and all(d["moment_about"] == "wap" for d in loads)
    doc = cli_json("offline", "--circle", "default", "--force", LDBB, "-o", tmp_path / "cli.csv")
    for load, run in zip(loads, doc["runs"]):
        assert load["description"] == run["force"]
        rows = numeric_rows(run["csv"])
        # fx_N..mz_Nm are columns 31..36 of the CLI's CSV (base frame, moment about the WAP).
        np.testing.assert_allclose(load["wrench"], rows[:, 31:37], rtol=1e-9, atol=1e-9)
        lo, hi = run["bar_length_mm"]
        assert load["bar_length_m"].min() * 1e3 == pytest.approx(lo, rel=1e-12)
        assert load["bar_length_m"].max() * 1e3 == pytest.approx(hi, rel=1e-12)
        lo, hi = run["bar_inclination_deg"]
        assert np.degrees(load["bar_inclination_rad"]).min() == pytest.approx(lo, rel=1e-9)
    # Wrench arrays come back as given; a constant model's moment moves to the WAP as documented.
    w = deflex.force_along_path(robot, deflex.Circle(points=5), [0, 0, -100, 1, 2, 3])[0]["wrench"]
    np.testing.assert_array_equal(w, np.tile([0, 0, -100, 1, 2, 3], (5, 1)))


KRL_TOOLS = ["TOOL_DATA[1]={X 250,Y 0,Z 0,A 0,B 0,C 0}", "TOOL_DATA[2]={X 320,Y 0,Z 40,A 0,B -10,C 0}"]
KRL_BASES = ["BASE_DATA[1]={X 1800,Y -300,Z 500,A 0,B 0,C 0}"]


@pytest.mark.parametrize("program,robot_file,force,tools,bases", [
    ("deburr_housing.mod", None, "tool:fz_N=-150,fx_N=40", [], []),
    ("deburr_bracket.src", "kuka_kr210_r3100_2_flange.yaml", "tool:fx_N=-150", KRL_TOOLS, KRL_BASES),
])
def test_programs_in_and_out_match_the_cli(tmp_path, program, robot_file, force, tools, bases):
    robot = deflex.Robot.from_file(SOURCE_DIR / "examples" / "robots" / robot_file) if robot_file else deflex.Robot.builtin()
    extra = [a for t in tools for a in ("--tooldata", t)] + [a for b in bases for a in ("--wobjdata", b)] + (
        ["--robot", SOURCE_DIR / "examples" / "robots" / robot_file] if robot_file else [])
    src = SOURCE_DIR / "examples" / "programs" / program
    out_cli = tmp_path / ("cli_" + program)
    out_py = tmp_path / ("py_" + program)
    doc = cli_json("offline", "--program-in", src, "--force", force, "--program-out", out_cli, *extra)
    mine = deflex.compensate_program(robot, force, src, out_py, tooldata=tools, wobjdata=bases)
    assert mine["language"] == doc["language"] and mine["force"] == doc["force"]
    assert len(mine["targets"]) == len(doc["targets"]) > 0
    for a, b in zip(mine["targets"], doc["targets"]):
        assert (a["line"], a["instruction"], a["target"], a["action"]) == (b["line"], b["instruction"], b["target"], b["action"])
        assert a["correction_m"] * 1e3 == pytest.approx(b["correction_mm"], rel=1e-12)
        assert np.degrees(a["joint_correction_rad"]) == pytest.approx(b["joint_correction_deg"], rel=1e-12)
    assert mine["unresolved"] == doc["unresolved"]
    for cli_path, py_path in zip(doc["outputs"], mine["outputs"]):
        assert open(cli_path).read() == open(py_path).read()
    # write=False: the texts, no file; the input is never an output.
    dry = deflex.compensate_program(robot, force, src, tmp_path / ("dry_" + program), tooldata=tools, wobjdata=bases, write=False)
    assert not (tmp_path / ("dry_" + program)).exists() and len(dry["texts"]) == len(dry["outputs"])
    with pytest.raises(deflex.Error):
        deflex.compensate_program(robot, force, src, src, tooldata=tools, wobjdata=bases)


def test_payload_identification_matches_the_cli(tmp_path):
    data = SOURCE_DIR / "examples" / "online" / "payload_poses.csv"
    doc = cli_json("identify-payload", "--data", data, "-o", tmp_path / "payload.yaml")
    mine = deflex.identify_payload(data)
    assert mine["mass_kg"] == pytest.approx(doc["mass_kg"], rel=1e-12)
    np.testing.assert_allclose(mine["cog_sensor_m"], doc["cog_sensor_m"], rtol=1e-12)
    np.testing.assert_allclose(mine["bias_sensor"], doc["bias_sensor"], rtol=1e-12)
    assert mine["mass_kg"] == pytest.approx(8.5, abs=0.05)  # the file's synthetic payload
    text = (tmp_path / "payload.yaml").read_text()
    assert mine["sensor"].to_yaml().splitlines()[-5:] == text.splitlines()[-5:]
    # From arrays: base_R_sensor from the file's quaternions, the readings as they are.
    rows = numeric_rows(data)
    R = np.array([deflex.pose([0, 0, 0], r[:4])[:3, :3] for r in rows])
    arrays = deflex.identify_payload(R, wrench_sensor=rows[:, 4:10])
    assert arrays["mass_kg"] == pytest.approx(doc["mass_kg"], rel=1e-9)


def test_the_case_study_from_a_dict_gives_the_cli_traces_and_report(tmp_path):
    from test_study import small_case
    case_file = small_case(tmp_path)
    import yaml  # python3-yaml: the same case as the dict a researcher would build
    case = yaml.safe_load(case_file.read_text())
    result = deflex.run_case_study(case, quick=True, seeds=1, speed_sweep=False, error_budget=False, threads=2,
                                   traces=True)
    run_cli("case-study", "--case", case_file, "--quick", "--seeds", 1, "--no-sweep", "--no-budget", "--no-progress",
            "--threads", 2, "--out", tmp_path / "cli_out", "--write-traces", tmp_path / "cli_traces")
    names = sorted(p.name[:-4] for p in (tmp_path / "cli_traces").glob("*.csv"))
    assert names and sorted(result.traces) == names
    for name, trace in result.traces.items():
        rows = numeric_rows(tmp_path / "cli_traces" / (name + ".csv"))
        np.testing.assert_allclose(trace[:, 1:] * 1e3, rows[:, 1:], atol=1e-6)  # the CSV holds mm to 1 nm
        np.testing.assert_allclose(trace[:, 0], rows[:, 0], atol=1e-9)
    result.write_report(tmp_path / "py_out")
    for f in ("tables.csv", "tables.md"):
        assert (tmp_path / "py_out" / f).read_text() == (tmp_path / "cli_out" / f).read_text(), f
    cli = json.loads((tmp_path / "cli_out" / "results.json").read_text())
    mine = json.loads((tmp_path / "py_out" / "results.json").read_text())
    cli.pop("wall_time_s", None)
    mine.pop("wall_time_s", None)
    assert mine == cli
    assert "<svg" in (tmp_path / "py_out" / "report.html").read_text()
    result.write_traces(tmp_path / "py_traces")
    assert sorted(p.name for p in (tmp_path / "py_traces").iterdir()) == sorted(
        p.name for p in (tmp_path / "cli_traces").iterdir())
    with pytest.raises(deflex.ModelError):
        deflex.run_case_study({"name": "x", "no_such_key": 1}, quick=True)


def test_joint_frames_against_finite_differences_and_the_flange():
    robot = deflex.Robot.builtin()
    q = np.array([0.3, -0.4, 0.5, 0.6, -0.7, 0.8])
    assert robot.frames[:3] == ["tcp", "flange", "wap"] and robot.frames[-1] == "joint6"
    for k in range(1, 7):
        J = robot.jacobian(q, point=f"joint{k}")
        J_fd = fd_jacobian(lambda qq: robot.fk(qq, point=f"joint{k}"), q)
        np.testing.assert_allclose(J, J_fd, atol=1e-7)
        assert np.all(J[:, k:] == 0)
    # The flange rides on joint 6's frame: a fixed transform whatever q is.
    q2 = q + 0.3
    T1 = np.linalg.inv(robot.fk(q, point="joint6")) @ robot.fk(q, point="flange")
    T2 = np.linalg.inv(robot.fk(q2, point="joint6")) @ robot.fk(q2, point="flange")
    np.testing.assert_allclose(T1, T2, atol=1e-12)
    urdf = deflex.Robot.from_file(SOURCE_DIR / "examples" / "robots" / "ros-industrial" / "kuka_kr120r2500pro.urdf")
    name = urdf.joint_names[2]
    np.testing.assert_array_equal(urdf.fk(q, point=name), urdf.fk(q, point="joint3"))
    with pytest.raises(deflex.InputError, match="joint7"):
        robot.fk(q, point="joint7")


def test_the_identified_robot_is_the_one_the_cli_writes(tmp_path):
    robot_file = SOURCE_DIR / "examples" / "robots" / "kuka_kr210_r2700.yaml"
    data = SOURCE_DIR / "examples" / "identify" / "kr210_synthetic_measurements.csv"
    run_cli("identify", "--robot", robot_file, "--data", data, "--write-robot", tmp_path / "identified.yaml")
    written = deflex.Robot.from_file(tmp_path / "identified.yaml")
    robot = deflex.Robot.from_file(robot_file)
    mine = deflex.identified_robot(robot, deflex.identify_stiffness(robot, data), str(data))
    # The file holds 9 significant digits: rounding to them moves a value by up to 5e-9 of itself.
    np.testing.assert_allclose(mine.stiffness, written.stiffness, rtol=1e-8)
    assert mine.to_yaml() == written.to_yaml()
    # A joint not identified keeps the file's value, and the note says so.
    d = deflex.read_stiffness_measurements(data)
    partial = deflex.identify_stiffness(robot, q=d["q"][:1], wrench=d["wrench"][:1], dp=d["dp"][:1], robust=False,
                                        fixed_stiffness_nm_per_rad=[None, None, None, None, 3.5e5, 2e5])
    merged = deflex.identified_robot(robot, partial)
    assert merged.stiffness[0] == robot.stiffness[0] and merged.stiffness[3] == robot.stiffness[3]
    assert "joints 1, 2, 4 kept from the previous file" in merged.to_yaml()
    bare = deflex.Robot.from_file(SOURCE_DIR / "examples" / "robots" / "ros-industrial" / "kuka_kr120r2500pro.urdf")
    with pytest.raises(deflex.InputError, match="joint 1 is not identified"):
        deflex.identified_robot(bare, partial)
