"""The traps a researcher fell into (issue: Python without silent traps), each closed and tested:
in-place edits, where a wrench's moment is taken, ik's seed, replayed force samples, batches, None
for absent values, os.PathLike, pickling, keyword construction, reprs, errors, units."""

import multiprocessing
import pathlib
import pickle

import numpy as np
import pytest

import deflex
from conftest import SOURCE_DIR

URDF = SOURCE_DIR / "examples" / "robots" / "ros-industrial" / "kuka_kr120r2500pro.urdf"
KR210 = SOURCE_DIR / "examples" / "robots" / "kuka_kr210_r2700.yaml"
Q = np.array([0.3, 0.4, 0.2, 0.5, 0.9, 0.7])


def robot_with_wap(offset_m=0.3):
    """The built-in IRB 6700 with its wrench application point 0.3 m beyond the TCP along the tool z axis."""
    text = deflex.Robot.builtin().to_yaml()
    text += f"\nwap_frame: {{position: [0, 0, {offset_m}], quaternion_wxyz: [1, 0, 0, 0]}}\n"
    return deflex.Robot.from_yaml(text)


# 1. Edits in place: every array a property returns is read-only, so an edit raises; assignment works.

def test_in_place_edits_raise_and_assignment_changes_the_object():
    c = deflex.Circle()
    with pytest.raises(ValueError, match="read-only"):
        c.centre_m[2] = 0.9
    c.centre_m = [1.5, 0.0, 0.9]
    assert c.centre_m[2] == 0.9
    s = deflex.SensorConfig()
    with pytest.raises(ValueError, match="read-only"):
        s.flange_T_sensor[2, 3] = 0.05
    with pytest.raises(ValueError, match="read-only"):
        s.bias_sensor[2] = 10
    T = np.eye(4)
    T[2, 3] = 0.05
    s.flange_T_sensor = T
    b = np.zeros(6)
    b[2] = 10
    s.bias_sensor = b
    assert s.flange_T_sensor[2, 3] == 0.05 and s.bias_sensor[2] == 10


def array_properties(obj):
    for name in dir(type(obj)):
        if name.startswith("_") or not isinstance(getattr(type(obj), name), property):
            continue
        value = getattr(obj, name)
        if isinstance(value, np.ndarray):
            yield name, value


def test_every_array_property_of_every_object_is_read_only():
    robot = deflex.Robot.builtin()
    result = deflex.compensate_path(robot, deflex.Circle(points=9), "constant:fz_N=-500")
    est = deflex.identify_stiffness(deflex.Robot.from_file(KR210),
                                    SOURCE_DIR / "examples" / "identify" / "kr210_synthetic_measurements.csv")
    oc = deflex.OnlineCompensator(robot)
    oc.push_force(0.0, [0, 0, -100, 0, 0, 0])
    out = oc.step(0.004, Q)
    objects = [robot, deflex.Circle(), deflex.SensorConfig(), result, est, out, robot.deflect(Q, [0, 0, -500, 0, 0, 0]),
               robot.ik(robot.fk(Q))[0]]
    seen = 0
    for obj in objects:
        for name, value in array_properties(obj):
            seen += 1
            assert not value.flags.writeable, f"{type(obj).__name__}.{name} is writeable: an edit would be lost"
    assert seen >= 25


# 2. One wrench, one meaning: the moment about the WAP in every call (moment_about="tcp" to give it
#    about the TCP), checked against K^-1 J_wap^T W computed here in NumPy.

def test_the_same_wrench_gives_the_same_correction_through_every_call():
    robot = robot_with_wap(0.3)
    w = np.array([300.0, -200.0, -800.0, 10.0, 20.0, 5.0])
    k = robot.stiffness
    expected = np.linalg.solve(np.diag(k), robot.jacobian(Q, point="wap").T @ w)
    via_deflect = robot.deflect(Q, w).dtheta_rad
    via_command = Q - robot.compensated_configuration(Q, w)
    pose = robot.fk(Q)
    res = deflex.compensate_path(robot, pose[None], w, seed=Q)
    via_path = res.q_desired[0] - res.q_command[0]
    res_table = deflex.compensate_path(robot, np.stack([pose, pose]), np.stack([w, w]), seed=Q)
    for got in (via_deflect, via_command, via_path, res_table.q_desired[1] - res_table.q_command[1]):
        np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(res.wrench[0], w, atol=1e-12)
    assert res.moment_about == "wap"
    # The same force given about the TCP: the moment moves by (p_tcp - p_wap) x F, here by hand.
    r = robot.fk(Q, point="tcp")[:3, 3] - robot.fk(Q, point="wap")[:3, 3]
    assert np.linalg.norm(r) == pytest.approx(0.3)
    w_tcp = w.copy()
    w_tcp[3:] -= np.cross(r, w[:3])  # the moment about the TCP of the wrench w (about the WAP)
    for got in (robot.deflect(Q, w_tcp, moment_about="tcp").dtheta_rad,
                Q - robot.compensated_configuration(Q, w_tcp, moment_about="tcp"),
                (lambda rr: rr.q_desired[0] - rr.q_command[0])(
                    deflex.compensate_path(robot, pose[None], w_tcp, seed=Q, moment_about="tcp"))):
        np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-15)
    # A force spec's moments are about the TCP (as on the command line): constant:... equals moment_about="tcp".
    spec = "constant:fx_N={},fy_N={},fz_N={},mx_Nm={},my_Nm={},mz_Nm={}".format(*w_tcp)
    np.testing.assert_allclose(
        deflex.compensate_path(robot, pose[None], spec, seed=Q).q_command[0], Q - expected, atol=1e-12)
    # Taken about the wrong point the correction differs: the convention matters on this robot.
    assert np.abs(robot.deflect(Q, w_tcp).dtheta_rad - expected).max() > 0.1 * np.abs(expected).max()
    with pytest.raises(deflex.InputError, match="moment_about"):
        robot.deflect(Q, w, moment_about="flange")


# 3. ik honours its seed: [0] is the solution with each joint at the turn nearest the seed.

def test_ik_with_a_seed_returns_the_nearest_turn_first():
    robot = deflex.Robot.builtin()
    q = Q.copy()
    q[5] = 2.0
    sols = robot.ik(robot.fk(q), seed=q)
    assert len(sols) > 1
    np.testing.assert_allclose(sols[0].q, q, atol=1e-7)
    q_turned = q.copy()
    q_turned[5] -= 2 * np.pi  # the same pose, joint 6 a turn away: the seed there picks that turn
    first = robot.ik(robot.fk(q), seed=q_turned)[0]
    np.testing.assert_allclose(first.q, q_turned, atol=1e-7)
    distances = [np.abs(s.q - q).max() for s in sols]
    assert distances == sorted(distances)


# 4. Replayed force samples: a push into a full queue raises; replay() consumes a recorded log whole.

def test_a_400_sample_replay_is_consumed_or_refused_never_dropped():
    robot = deflex.Robot.builtin()
    t_force = np.arange(400) * 1e-3  # 400 samples at 1 kHz
    w = np.tile([0.0, 0.0, -400.0, 0.0, 0.0, 0.0], (400, 1))
    oc = deflex.OnlineCompensator(robot)
    assert oc.queue_capacity >= 64
    with pytest.raises(deflex.Error, match="queue is full"):
        for t, wi in zip(t_force, w):
            oc.push_force(t, wi)
    assert oc.counters["samples_dropped"] == 0
    oc = deflex.OnlineCompensator(robot)
    t_cycle = np.arange(1, 101) * 0.004
    out = oc.replay(t_force, w, t_cycle, Q)
    assert out["samples_used"].sum() == 400
    assert oc.counters["samples_dropped"] == 0
    assert out["status"][-1] == "ok" and out["usable"][-1]
    assert out["q_command"].shape == (100, 6)
    # 400 samples before one cycle are more than the queue holds: refused, not thinned.
    with pytest.raises(deflex.Error, match="more than the queue"):
        deflex.OnlineCompensator(robot).replay(t_force, w, [0.5], Q)


# 5. Batches for every per-configuration call, spread over threads.

def test_batches_equal_the_loop_and_threads_do_not_change_the_result():
    robot = deflex.Robot.builtin()
    rng = np.random.default_rng(3)
    qs = Q + rng.uniform(-0.3, 0.3, size=(600, 6))
    w = np.array([100.0, 50.0, -500.0, 3.0, 2.0, 1.0])
    batch = robot.compensated_configuration(qs, w)
    for i in (0, 299, 599):
        np.testing.assert_array_equal(batch[i], robot.compensated_configuration(qs[i], w))
    np.testing.assert_array_equal(robot.deflected_configuration(qs[:3], w)[1], robot.deflected_configuration(qs[1], w))
    np.testing.assert_array_equal(robot.cartesian_compliance(qs[:4])[2], robot.cartesian_compliance(qs[2]))
    lim = robot.within_limits(np.vstack([qs[:2], [[10.0] * 6]]))
    assert lim.dtype == bool and list(lim) == [True, True, False]
    np.testing.assert_array_equal(robot.fk(qs, threads=1), robot.fk(qs, threads=2))
    np.testing.assert_array_equal(robot.jacobian(qs, threads=1), robot.jacobian(qs, threads=2))
    np.testing.assert_array_equal(robot.deflect(qs, w, threads=1).dtheta_rad, robot.deflect(qs, w, threads=2).dtheta_rad)
    poses = robot.fk(qs[:5])
    per_pose = robot.ik(poses, seed=qs[:5])
    assert len(per_pose) == 5
    for i, sols in enumerate(per_pose):
        np.testing.assert_allclose(sols[0].q, qs[i], atol=1e-7)
    one_seed = robot.ik(poses, seed=qs[0])  # one seed (dof,) for every pose
    np.testing.assert_allclose(one_seed[0][0].q, qs[0], atol=1e-7)
    one_each = robot.inverse_kinematics(poses, seed=qs[:5])
    np.testing.assert_allclose(np.array([r.q for r in robot.inverse_kinematics(poses, seed=qs[0])])[0], qs[0], atol=1e-7)
    np.testing.assert_allclose(np.array([r.q for r in one_each]), qs[:5], atol=1e-7)
    with pytest.raises(deflex.InputError, match="threads"):
        robot.fk(qs, threads=-1)


# 6. None for absent values, os.PathLike, pickling, keyword construction, reprs, errors, units.

def test_absent_stiffness_is_none_and_paths_may_be_pathlib():
    bare = deflex.Robot.from_file(URDF)
    assert bare.stiffness is None and not bare.has_stiffness
    assert deflex.load_robot(pathlib.Path(KR210)).stiffness is not None
    est = deflex.identify_stiffness(deflex.Robot.from_file(KR210),
                                    pathlib.Path(SOURCE_DIR / "examples" / "identify" / "kr210_synthetic_measurements.csv"))
    assert np.all(np.isfinite(est.stiffness_nm_per_rad))


def _tcp_x(robot):
    return float(robot.fk(Q)[0, 3])


def test_robots_and_results_pickle_and_cross_processes():
    for robot in (deflex.Robot.builtin(), deflex.Robot.from_file(KR210), deflex.Robot.from_file(URDF), robot_with_wap()):
        copy = pickle.loads(pickle.dumps(robot))
        np.testing.assert_array_equal(copy.fk(Q), robot.fk(Q))
        np.testing.assert_array_equal(copy.fk(Q, point="wap"), robot.fk(Q, point="wap"))
        assert copy.name == robot.name and copy.has_stiffness == robot.has_stiffness
    robot = deflex.Robot.builtin()
    d = robot.deflect(Q, [0, 0, -500, 0, 0, 0])
    d2 = pickle.loads(pickle.dumps(d))
    np.testing.assert_array_equal(d2.dtheta_rad, d.dtheta_rad)
    ik = robot.ik(robot.fk(Q), seed=Q)[0]
    ik2 = pickle.loads(pickle.dumps(ik))
    np.testing.assert_array_equal(ik2.q, ik.q)
    assert ik2.configuration == ik.configuration and ik2.status == ik.status
    est = deflex.identify_stiffness(deflex.Robot.from_file(KR210),
                                    SOURCE_DIR / "examples" / "identify" / "kr210_synthetic_measurements.csv")
    est2 = pickle.loads(pickle.dumps(est))
    np.testing.assert_array_equal(est2.stiffness_nm_per_rad, est.stiffness_nm_per_rad)
    np.testing.assert_array_equal(est2.robust_weights, est.robust_weights)
    assert (est2.warnings, est2.measurements, est2.condition_number) == (est.warnings, est.measurements,
                                                                         est.condition_number)
    c = pickle.loads(pickle.dumps(deflex.Circle(radius_m=0.2, points=17)))
    assert c.radius_m == 0.2 and c.points == 17
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        assert pool.map(_tcp_x, [robot, robot]) == [_tcp_x(robot)] * 2


def test_keyword_construction_reprs_and_positional_arrays():
    c = deflex.Circle(centre_m=[1.6, 0.0, 0.8], radius_m=0.1, points=41, clockwise=True)
    assert list(c.centre_m) == [1.6, 0.0, 0.8] and c.points == 41 and c.clockwise
    assert "Circle(centre_m=[1.6, 0, 0.8]" in repr(c)
    with pytest.raises(deflex.InputError, match="radius_m"):
        deflex.Circle(radius_m=-1)
    robot = deflex.Robot.from_file(KR210)
    data = deflex.read_stiffness_measurements(SOURCE_DIR / "examples" / "identify" / "kr210_synthetic_measurements.csv")
    by_keyword = deflex.identify_stiffness(robot, q=data["q"], wrench=data["wrench"], dp=data["dp"])
    positional = deflex.identify_stiffness(robot, data["q"], data["wrench"], data["dp"])
    np.testing.assert_array_equal(by_keyword.stiffness_nm_per_rad, positional.stiffness_nm_per_rad)
    with pytest.raises(deflex.InputError, match="give the measurement CSV's path, or the arrays"):
        deflex.identify_stiffness(robot, data["q"])
    results = [deflex.Robot.builtin(), deflex.compensate_path(deflex.Robot.builtin(), deflex.Circle(points=5), "constant:fz_N=-100"),
               by_keyword, deflex.OnlineCompensator(deflex.Robot.builtin()).step(0.0, Q), deflex.SensorConfig(),
               deflex.OnlineConfig(), deflex.Robot.builtin().ik(deflex.Robot.builtin().fk(Q))[0]]
    for r in results:
        assert " object at 0x" not in repr(r), repr(r)


def test_unidentifiable_joints_say_nan_not_a_value():
    robot = deflex.Robot.from_file(KR210)
    data = deflex.read_stiffness_measurements(SOURCE_DIR / "examples" / "identify" / "kr210_synthetic_measurements.csv")
    # One pose (3 equations) for four free joints: joints 1 and 4 cannot be told apart.
    est = deflex.identify_stiffness(robot, q=data["q"][:1], wrench=data["wrench"][:1], dp=data["dp"][:1], robust=False,
                                    fixed_stiffness_nm_per_rad=[None, None, None, None, 3.5e5, 2e5])
    nan_joints = [j for j in est.unidentifiable_joints if np.isnan(est.stiffness_nm_per_rad[j - 1])]
    assert nan_joints == [1, 4]
    for j in nan_joints:
        assert any(w.startswith(f"joint {j}: not identified (NaN in the estimate)") for w in est.warnings), est.warnings
    assert not any("held at" in w and not w.startswith(("joint 1:", "joint 4:")) for w in est.warnings)
    assert "not identified (NaN): joints 1, 4" in repr(est) and "poorly identified" in repr(est)


def test_errors_are_deflex_errors_and_units_are_not_guessed():
    robot = deflex.Robot.builtin()
    with pytest.raises(deflex.InputError, match="configuration"):
        robot.inverse_kinematics(robot.fk(Q), configuration=("a", 1, 2, 3))
    with pytest.raises(deflex.InputError, match="positions are in m"):
        deflex.mean_distance_to_path_m([[1500.0, 0.0, 1000.0]] * 3, [[1.5, 0.0, 1.0]] * 3)
    with pytest.raises(deflex.Error):
        deflex.Robot.from_file(pathlib.Path("/nonexistent/robot.yaml"))


def test_the_stubs_give_typed_signatures():
    """The .pyi stubs the build writes beside the module (python/make_stubs.py): every argument typed,
    none shown as pybind11's `handle`, static methods static, paths str or os.PathLike."""
    stub = pathlib.Path(deflex.__file__).parent / "_deflex.pyi"
    text = stub.read_text()
    assert "handle" not in text
    assert ("def fk(self, q: numpy.typing.ArrayLike, point: str = ..., threads: int = ...) -> "
            "numpy.typing.NDArray[numpy.float64]: ...") in text
    assert "    @staticmethod\n    def builtin() -> Robot: ..." in text
    assert "def identify_stiffness(robot: Robot, q: typing.Union[str, os.PathLike, numpy.typing.ArrayLike]" in text
    assert "def compensate_path(robot: Robot, path: typing.Union[Circle, numpy.typing.ArrayLike]" in text
    assert "def load_robot(path: typing.Union[str, os.PathLike]) -> Robot: ..." in text
    assert (pathlib.Path(deflex.__file__).parent / "py.typed").exists()
