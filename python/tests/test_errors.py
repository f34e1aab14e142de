"""Errors: deflex's exceptions arrive as Python exceptions with the C++ program's message text, and no
bad array (shape, dtype, NaN, memory layout) crashes or is silently misread."""

import os
import stat

import numpy as np
import pytest

import deflex
from conftest import SOURCE_DIR, run_cli

Q = np.radians([0.0, 30.0, 10.0, 0.0, 50.0, 0.0])


def test_exception_hierarchy():
    assert issubclass(deflex.ModelError, deflex.Error) and issubclass(deflex.DataError, deflex.Error)
    assert issubclass(deflex.InputError, deflex.Error) and issubclass(deflex.InputError, ValueError)
    assert issubclass(deflex.Error, RuntimeError)


@pytest.mark.parametrize("q, expected", [
    ([0.0, 0.1, 0.2], "argument q: expected shape (6,) or (N, 6), got (3,)"),
    (np.zeros((4, 5)), "argument q: expected shape (6,) or (N, 6), got (4, 5)"),
    (np.zeros((2, 3, 6)), "argument q: expected shape (6,) or (N, 6), got (2, 3, 6)"),
    (np.zeros(0), "got (0,)"),
])
def test_wrong_shape_names_argument_and_shape(q, expected):
    robot = deflex.Robot.builtin()
    for call in (robot.fk, robot.jacobian, lambda x: robot.deflect(x, np.zeros(6))):
        with pytest.raises(deflex.InputError) as info:
            call(q)
        assert expected in str(info.value)


@pytest.mark.parametrize("q", [np.array(["a"] * 6), np.zeros(6, dtype=complex), np.array([None] * 6),
                               [[0, 1], [2]], "012345", None])
def test_wrong_dtype_is_refused(q):
    with pytest.raises(ValueError, match="argument q"):
        deflex.Robot.builtin().fk(q)


def test_nan_names_the_row():
    q = np.zeros((10, 6))
    q[7, 2] = np.nan
    with pytest.raises(deflex.InputError, match=r"argument q: row 7 has a non-finite value \(nan at column 2\)"):
        deflex.Robot.builtin().fk(q)
    with pytest.raises(deflex.InputError, match="argument wrench: element 3 is not finite"):
        deflex.Robot.builtin().deflect(Q, [0, 0, 1, np.inf, 0, 0])
    with pytest.raises(deflex.InputError, match=r"argument wrench: expected shape \(6,\) or \(10, 6\)"):
        deflex.Robot.builtin().deflect(np.zeros((10, 6)), np.zeros((9, 6)))


def test_non_contiguous_integer_and_fortran_arrays_are_read_correctly(rng):
    robot = deflex.Robot.builtin()
    q = rng.uniform(-1, 1, (8, 6))
    expected = np.stack([robot.fk(row) for row in q.tolist()])
    wide = np.zeros((8, 12))
    wide[:, ::2] = q
    assert not wide[:, ::2].flags.c_contiguous
    np.testing.assert_array_equal(robot.fk(wide[:, ::2]), expected)
    np.testing.assert_array_equal(robot.fk(np.asfortranarray(q)), expected)
    np.testing.assert_array_equal(robot.fk(q[::-1]), expected[::-1])
    np.testing.assert_array_equal(robot.fk(q.astype(np.float32)), robot.fk(q.astype(np.float32).astype(float)))
    np.testing.assert_array_equal(robot.fk(np.zeros(6, dtype=np.int64)), robot.fk(np.zeros(6)))


def test_bad_robot_file_message_is_the_cli_message(tmp_path):
    text = (SOURCE_DIR / "examples" / "robots" / "kuka_kr210_r2700.yaml").read_text()
    bad = tmp_path / "bad.yaml"
    bad.write_text(text.replace("joint_stiffness_Nm_per_rad: [3.5e6,", "joint_stiffness_Nm_per_rad: [-3.5e6,"))
    with pytest.raises(deflex.ModelError) as info:
        deflex.Robot.from_file(str(bad))
    message = str(info.value)
    assert str(bad) in message and "stiffness" in message
    cli = run_cli("fk", "--robot", bad, "--joints-deg", "0,0,0,0,0,0", check=False)
    assert cli.returncode == 2
    assert message in cli.stderr


def test_missing_file_and_robot_without_stiffness():
    with pytest.raises(deflex.Error, match="no_such_robot.yaml"):
        deflex.Robot.from_file("no_such_robot.yaml")
    urdf = deflex.Robot.from_file(str(SOURCE_DIR / "examples" / "robots" / "ros-industrial" / "fanuc_m10ia.urdf"))
    assert not urdf.has_stiffness
    with pytest.raises(deflex.ModelError, match="stiffness"):
        urdf.deflect(np.zeros(6), np.zeros(6))


def test_bad_csv_message_is_the_cli_message(tmp_path):
    src = (SOURCE_DIR / "examples" / "identify" / "kr210_synthetic_measurements.csv").read_text().splitlines()
    src[5] = src[5].replace(",800,", ",abc,", 1)
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join(src) + "\n")
    robot = deflex.Robot.from_file(str(SOURCE_DIR / "examples" / "robots" / "kuka_kr210_r2700.yaml"))
    with pytest.raises(deflex.DataError) as info:
        deflex.identify_stiffness(robot, str(bad))
    message = str(info.value)
    assert f"{bad}:6:" in message and "abc" in message
    cli = run_cli("identify", "--robot", SOURCE_DIR / "examples" / "robots" / "kuka_kr210_r2700.yaml", "--data", bad,
                  check=False)
    assert cli.returncode != 0 and message in cli.stderr


def test_pose_arguments_are_checked():
    robot = deflex.Robot.builtin()
    T = robot.fk(Q)
    T[0, 0] += 0.1
    with pytest.raises(deflex.InputError, match="argument pose: the top-left 3x3 block is not a rotation matrix"):
        robot.ik(T)
    with pytest.raises(deflex.InputError, match=r"argument pose: expected shape \(4, 4\)"):
        robot.ik(np.eye(3))
    with pytest.raises(deflex.InputError, match="not a unit quaternion"):
        deflex.pose([1, 0, 1], [1, 1, 0, 0])
    with pytest.raises(deflex.InputError, match="argument point"):
        robot.fk(Q, "elbow")


def test_values_outside_their_documented_range_are_refused():
    robot = deflex.Robot.builtin()
    # Forces and moments to +-1e6 N and Nm, joints to +-63 rad: the table the program and files use.
    with pytest.raises(deflex.InputError, match=r"argument wrench: element 2: -1e\+308 N is outside -1e\+06\.\.1e\+06 N"):
        robot.deflect(Q, [0, 0, -1e308, 0, 0, 0])
    with pytest.raises(deflex.InputError, match=r"argument wrench: row 1, column 4: 2e\+06 Nm is outside"):
        robot.deflect(np.zeros((2, 6)), [[0, 0, 1, 0, 0, 0], [0, 0, 1, 0, 2e6, 0]])
    with pytest.raises(deflex.InputError, match=r"argument q: row 3, column 0: 100 rad is outside -63\.\.63 rad"):
        robot.fk(np.vstack([np.zeros((3, 6)), [100, 0, 0, 0, 0, 0]]))
    with pytest.raises(deflex.InputError, match="argument q_desired: element 1"):
        robot.compensated_configuration([0, 1e3, 0, 0, 0, 0], np.zeros(6))
    with pytest.raises(deflex.InputError, match="argument force: element 0"):
        deflex.compensate_path(robot, deflex.Circle(), [2e6, 0, 0, 0, 0, 0])
    # Counts and loads of the calibration planner and ISO 9283, bounded as the program's options are.
    with pytest.raises(deflex.InputError, match=r"poses must be 1\.\.100000"):
        deflex.plan_calibration(robot, [1.3, -0.4, 0.5], [1.9, 0.4, 1.1], poses=10**9)
    with pytest.raises(deflex.InputError, match=r"the load: 1e\+12 N is outside"):
        deflex.plan_calibration(robot, [1.3, -0.4, 0.5], [1.9, 0.4, 1.1], load_n=1e12)
    circle = robot.fk(np.zeros((5, 6)))[:, :3, 3]
    with pytest.raises(deflex.InputError, match=r"1000000000 evaluation points \(need 1\.\.100000\)"):
        deflex.iso9283_path([circle], circle, evaluation_points=10**9)
    # In range, the deflection is the model's: doubling the load doubles it.
    one = robot.deflect(Q, [0, 0, -1e6, 0, 0, 0]).dtheta_rad
    half = robot.deflect(Q, [0, 0, -5e5, 0, 0, 0]).dtheta_rad
    np.testing.assert_allclose(one, 2 * half, rtol=1e-12)


def test_inputs_must_be_regular_files_within_their_size(tmp_path):
    # A device: refused at once, not read until the memory runs out (it took 4 GiB).
    with pytest.raises(deflex.Error, match="/dev/zero: is a character device"):
        deflex.load_sensor_config("/dev/zero")
    fifo = tmp_path / "robot.yaml"
    os.mkfifo(fifo)
    with pytest.raises(deflex.Error, match="is a FIFO"):  # no writer: a blocking open would hang
        deflex.Robot.from_file(str(fifo))
    with pytest.raises(deflex.Error, match="is a directory"):
        deflex.read_tracker_csv(str(tmp_path))
    big = tmp_path / "big.yaml"
    with open(big, "wb") as f:
        f.truncate((16 << 20) + 1)
    with pytest.raises(deflex.Error, match=r"16777217 bytes; deflex reads a robot file of up to 16777216 bytes"):
        deflex.Robot.from_file(str(big))


def test_write_csv_never_leaves_half_a_file(tmp_path):
    robot = deflex.Robot.builtin()
    result = deflex.compensate_path(robot, deflex.Circle(), [0, 0, -300, 0, 0, 0])
    out = tmp_path / "out.csv"
    out.write_text("the user's file\n")
    inode = out.stat().st_ino
    (tmp_path / "afile").write_text("a user's file\n")
    with pytest.raises(deflex.Error, match="afile' is not a directory"):
        result.write_csv(str(tmp_path / "afile" / "out.csv"))
    result.write_csv(str(tmp_path / "made" / "for" / "it.csv"))  # a missing folder is made, as by the CLI
    assert (tmp_path / "made" / "for" / "it.csv").read_text().startswith("index,q1_des_deg")
    with pytest.raises(deflex.Error, match="/dev/full"):
        result.write_csv("/dev/full")
    assert os.path.exists("/dev/full") and stat.S_ISCHR(os.lstat("/dev/full").st_mode)
    result.write_csv(str(out))
    assert out.read_text().startswith("index,q1_des_deg")
    assert out.stat().st_ino != inode  # replaced whole by a rename, never truncated in place
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile", "made", "out.csv"]  # no temporary file left
