"""docs/python.md's tables against the module: every call form they write (`robot.fk(q, point="tcp",
threads=0)`, `identify_stiffness(robot, q, wrench, dp, drot=None, ...)`) names parameters the function
has, in the order it has them; and every form is called as written: the arguments without a default
positionally, in the documented order, with a value of the kind the table says, and those with one by
keyword with the documented default, so a form the docs show and the module refuses fails here."""

import functools
import math
import re

import numpy as np
import pytest

import deflex
from conftest import SOURCE_DIR

FORM = re.compile(r"`((?:deflex\.)?(?:robot\.|Robot\.)?[A-Za-z_][A-Za-z_0-9]*)\(([^`]*)\)`")


def documented_forms():
    """(callable name, [(parameter, default text or None)]) of every call in the API table's first column."""
    text = (SOURCE_DIR / "docs" / "python.md").read_text(encoding="utf-8")
    forms = []
    for line in text.splitlines():
        if not line.startswith("| `"):
            continue
        first_cell = line.split(" | ")[0]
        for name, args in FORM.findall(first_cell):
            params = []
            depth = 0
            current = ""
            for ch in args + ",":
                if ch in "([{":
                    depth += 1
                elif ch in ")]}":
                    depth -= 1
                if ch == "," and depth == 0:
                    if current.strip() and current.strip() != "..." and not current.strip().startswith("**"):
                        key, _, default = current.strip().partition("=")
                        params.append((key.strip(), default.strip() or None))
                    current = ""
                else:
                    current += ch
            forms.append((name, params))
    return forms


def resolve(name):
    name = name.removeprefix("deflex.")
    if name.startswith("robot.") or name.startswith("Robot."):
        return getattr(deflex.Robot, name.split(".", 1)[1])
    return getattr(deflex, name)


def signature_params(fn):
    """Parameter names (self dropped) of each overload in a pybind11 docstring's signature lines."""
    overloads = []
    for line in (fn.__doc__ or "").splitlines():
        m = re.match(r"^(?:\d+\. )?\w+\((.*)\) ->", line.strip())
        if not m:
            continue
        names = [p.split(":")[0].strip() for p in re.split(r",\s*(?![^\[]*\])", m.group(1)) if p.strip()]
        overloads.append([n for n in names if n not in ("self", "*")])
    return overloads


FORMS = documented_forms()


def test_the_table_documents_many_calls():
    assert len(FORMS) >= 30


@pytest.mark.parametrize("name,params", FORMS, ids=[f"{n}({','.join(p for p, _ in ps)})" for n, ps in FORMS])
def test_a_documented_form_names_the_parameters_in_order(name, params):
    fn = resolve(name)
    if isinstance(fn, type):  # a class: its constructor
        fn = fn.__init__
    overloads = signature_params(fn)
    assert overloads, f"{name}: no signature in its docstring"
    wanted = [p for p, _ in params]
    for names in overloads:
        it = iter(names)
        if all(any(p == n for n in it) for p in wanted):
            return
    pytest.fail(f"{name}({', '.join(wanted)}): the function takes {overloads}")


EXAMPLES = SOURCE_DIR / "examples"
ROBOT = deflex.Robot.builtin()
Q = np.array([0.1, 0.5, 0.2, 0.3, 0.9, 0.1])


@functools.lru_cache(maxsize=None)
def trace(z_offset=0.0):
    """A circle's TCP positions as an (N, 4) trace [t_s, x_m, y_m, z_m], two laps."""
    circle = deflex.Circle(centre_m=[1.6, 0.0, 0.8 + z_offset], radius_m=0.1, points=4000)
    p = ROBOT.fk(deflex.solve_path_ik(ROBOT, circle)[0])[:, :3, 3]
    p = np.vstack([p, p])
    return np.column_stack([0.02 * np.arange(len(p)), p])


def sample(function, name, tmp_path):
    """A value for argument `name` of `function`, of the kind docs/python.md says."""
    files = {
        ("Robot.from_file", "path"): EXAMPLES / "robots" / "kuka_kr210_r2700.yaml",
        ("read_stiffness_measurements", "path"): EXAMPLES / "identify" / "kr210_synthetic_measurements.csv",
        ("read_tracker_csv", "path"): EXAMPLES / "evaluate" / "unloaded.csv",
        ("load_sensor_config", "path"): EXAMPLES / "online" / "sensor_3axis.yaml",
        ("read_joint_trajectory", "path"): written_trajectory(tmp_path),
        ("write_joint_trajectory", "path"): tmp_path / "written.csv",
        ("compensate_program", "program_in"): EXAMPLES / "programs" / "deburr_housing.mod",
        ("compensate_program", "program_out"): tmp_path / "out.mod",
        ("identify_payload", "data"): EXAMPLES / "online" / "payload_poses.csv",
        ("read_tracker_file", "path"): EXAMPLES / "evaluate" / "session" / "unloaded.sa.txt",
        ("write_sa_export", "path"): tmp_path / "written.sa.txt",
    }
    if (function, name) in files:
        return files[(function, name)]
    measured = deflex.read_stiffness_measurements(EXAMPLES / "identify" / "kr210_synthetic_measurements.csv")
    values = {
        "robot": deflex.Robot.from_file(EXAMPLES / "robots" / "kuka_kr210_r2700.yaml")
        if function == "identify_stiffness" else ROBOT,
        "text": ROBOT.to_yaml(), "stiffness_nm_per_rad": [3e6, 2.5e6, 1.8e6, 6e5, 5e5, 3e5], "note": "documented",
        "q": measured["q"] if function == "identify_stiffness" else Q, "q_desired": Q, "q_command": Q,
        "wrench": measured["wrench"] if function == "identify_stiffness" else [0, 0, -500, 0, 0, 0],
        "dp": measured["dp"], "csv_path": EXAMPLES / "identify" / "kr210_synthetic_measurements.csv",
        "pose": ROBOT.fk(Q), "position_m": [1.6, 0, 0.8], "quaternion_wxyz": [0, 0, 1, 0],
        "region_min_m": [1.4, -0.3, 0.6], "region_max_m": [1.8, 0.3, 1.0],
        "start_m": [1.5, -0.1, 0.8], "end_m": [1.7, 0.1, 0.8], "points": 11, "orientation_wxyz": [0, 0, 1, 0],
        "path": deflex.Circle(centre_m=[1.6, 0.0, 0.8], radius_m=0.1), "force": "constant:fz_N=-400",
        "t_s": np.array([0.0, 1.0]), "loaded": trace(1e-4), "reference": trace(), "runs": [trace(1e-4)],
        "uc": 0.6, "c": 0.1, "link": "egm-path", "trace": trace(), "traces": trace(),
        "tracker_points": trace()[:4000:500, 1:] + 0.5, "base_points": trace()[:4000:500, 1:],
        "measured": trace() + [0.04, 0, 0, 0], "commanded": trace(),
        "force_source": f"csv:{EXAMPLES / 'online' / 'force_replay.csv'}",
    }
    machining = milling_sample(function, name, tmp_path)
    if machining is not None:
        return machining
    if function == "StandIn" and name == "link":
        return "egm-joint"
    if function == "StandIn" and name == "program":
        return (np.array([0.0, 1.0]), np.vstack([Q, Q]))
    if function == "write_joint_trajectory" and name == "q":
        return np.vstack([Q, Q + 0.01])
    return values[name]


# The milling calls' arguments: the Al7075-T6 set written out with an engagement for the whole run, a
# short straight slot as G-code, and full-slot mean forces from the textbook's closed forms.
KC = {"Ktc_N_mm2": 767.0, "Krc_N_mm2": 168.8, "Kac_N_mm2": 222.0, "Kte_N_mm": 27.7, "Kre_N_mm": 26.6,
      "Kae_N_mm": 0.7}
MILLING = "milling:" + ",".join(f"{k}={v}" for k, v in KC.items()) + ",ae_mm=2,ap_mm=3"


def slot_forces(fz_m, ap_m, flutes):
    """Full-slot means on the tool (feed, normal, axis), N, from the closed forms (mm and N/mm units); a
    clockwise (M3) tool is pushed back against its feed and along its axis away from the spindle."""
    out = []
    for fz, ap in zip(fz_m, ap_m):
        fz_mm, ap_mm = fz * 1e3, ap * 1e3
        out.append([-flutes * ap_mm * (fz_mm * KC["Krc_N_mm2"] / 4 + KC["Kre_N_mm"] / math.pi),
                    flutes * ap_mm * (fz_mm * KC["Ktc_N_mm2"] / 4 + KC["Kte_N_mm"] / math.pi),
                    -flutes * ap_mm * (fz_mm * KC["Kac_N_mm2"] / math.pi + KC["Kae_N_mm"] / 2)])
    return np.array(out)


def milling_sample(function, name, tmp_path):
    """A value for the milling calls' arguments, or None for another call's."""
    if function not in ("compensate_toolpath", "milling_force", "fit_cutting_coefficients"):
        return None
    fz = [3e-5, 6e-5, 9e-5, 1.2e-4]
    if name == "toolpath":
        path = tmp_path / "slot.nc"
        path.write_text("G21 G90 G17\nS12000 M3\nG0 X-10 Y0 Z5\nG1 Z-3 F600\nG1 X20 F1500\nG0 Z5\nM5\n")
        return path
    return {"robot": deflex.Robot.from_file(EXAMPLES / "machining" / "irb6700_spindle.yaml"),
            "workpiece": "x_mm=2000,y_mm=0,z_mm=800", "cutter": "diameter_mm=10,flutes=3,helix_deg=30",
            "force": MILLING, "ae_m": 0.002, "ap_m": 0.003 if function == "milling_force" else [0.004] * 4,
            "feed_mm_min": 1500.0, "spindle_rpm": 12000.0, "fz_m": fz,
            "mean_force_n": slot_forces(fz, [0.004] * 4, 3), "flutes": 3}[name]


def written_trajectory(tmp_path):
    path = tmp_path / "trajectory.csv"
    if not path.exists():
        deflex.write_joint_trajectory(path, ROBOT, [0.0, 1.0], np.vstack([Q, Q + 0.01]))
    return path


# The documented defaults of run_case_study run the whole paper's study (45 s on two cores), and those of
# run_machining_study the whole machining study (40 s of CPU): the form is
# called with its documented keywords, the quick ones of them given quick values.
QUICK = {"run_case_study": {"case": {"protocol": {"speeds_mm_s": [50], "sweep_load_N": 625},
                                     "error_budget": {"load_index": 0},
                                     "setups": [{"name": "offline", "strategy": "offline", "link": "program",
                                                 "sensor": False, "loads_N": [625]}]},
                            "quick": True, "speed_sweep": False, "error_budget": False, "threads": 2},
         "run_machining_study": {"quick": True, "seeds": 1, "threads": 2},
         # A session on a real address: a port of the system's choosing, not EGM's 6511.
         "Session": {"egm_port": 0}}


def default_value(text):
    names = {"None": None, "True": True, "False": False, "SensorConfig()": deflex.SensorConfig(),
             "OnlineConfig()": deflex.OnlineConfig()}
    if text in names:
        return names[text]
    return eval(text, {"math": math})  # numbers, strings, tuples and lists as the docs write them


@pytest.mark.parametrize("name,params", FORMS, ids=[f"{n}({','.join(p for p, _ in ps)})" for n, ps in FORMS])
def test_a_documented_form_is_called_as_written(name, params, tmp_path):
    short = name.removeprefix("deflex.").replace("robot.", "Robot.")
    fn = resolve(name)
    positional = [sample(short, p, tmp_path) for p, default in params if default is None]
    keywords = {p: default_value(d) for p, d in params if d is not None and d != "..."}
    keywords.update(QUICK.get(short, {}))
    if short.startswith("Robot.") and short not in ("Robot.builtin", "Robot.from_file", "Robot.from_yaml"):
        positional.insert(0, ROBOT)  # a method: robot.fk(...) is Robot.fk(robot, ...)
    result = fn(*positional, **keywords)
    assert result is not None or short in ("write_joint_trajectory", "write_sa_export"), name
    if short in ("Session", "StandIn"):
        result.finish()
