"""Shared helpers of the deflex Python tests: the C++ command-line program (`deflex ... --json`), the
source tree's data files, and independent references (finite differences, rotation vectors).

ctest sets DEFLEX_CLI (the built program), DEFLEX_SOURCE_DIR and PYTHONPATH (the built module)."""

import json
import os
import pathlib
import re
import subprocess

import numpy as np
import pytest

SOURCE_DIR = pathlib.Path(os.environ.get("DEFLEX_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
CLI = os.environ.get("DEFLEX_CLI", str(SOURCE_DIR / "build" / "bin" / "deflex"))


def run_cli(*args, check=True):
    """Runs the deflex program; returns the CompletedProcess (text)."""
    result = subprocess.run([CLI, *map(str, args)], capture_output=True, text=True, timeout=300)
    if check and result.returncode != 0:
        raise AssertionError(f"deflex {' '.join(map(str, args))} failed ({result.returncode}): {result.stderr}")
    return result


def cli_json(*args):
    """The JSON document of `deflex ARGS --json`."""
    return json.loads(run_cli(*args, "--json").stdout)


def deg_list(q_rad):
    return ",".join(repr(float(np.degrees(v))) for v in q_rad)


def yaml_list(path, key):
    """A flow list `key: [a, b, ...]` of a YAML file, read with a regular expression (no YAML library)."""
    text = pathlib.Path(path).read_text()
    match = re.search(rf"^{key}:\s*\[([^\]]*)\]", text, re.MULTILINE)
    assert match, f"{path}: no {key}"
    return np.array([float(v) for v in match.group(1).split(",")])


def rotation_vector(R):
    """The rotation vector (axis * angle, rad) of a rotation matrix, for small and moderate angles."""
    angle = np.arccos(np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0))
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]]) / 2.0
    if angle < 1e-12:
        return w
    return w * angle / np.sin(angle)


def fd_jacobian(fk, q, h=1e-6):
    """6 x dof geometric Jacobian by central differences of a 4x4 FK function: linear rows from the
    position, angular rows from the rotation vector of R(q+h) R(q-h)^T."""
    q = np.asarray(q, dtype=float)
    J = np.zeros((6, q.size))
    for j in range(q.size):
        dq = np.zeros_like(q)
        dq[j] = h
        Tp, Tm = fk(q + dq), fk(q - dq)
        J[:3, j] = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
        J[3:, j] = rotation_vector(Tp[:3, :3] @ Tm[:3, :3].T) / (2 * h)
    return J


@pytest.fixture(scope="session")
def builtin_stiffness():
    """The built-in robot's joint stiffness read from its YAML file (not through deflex)."""
    return yaml_list(SOURCE_DIR / "data" / "robots" / "abb_irb6700_300_270.yaml", "joint_stiffness_Nm_per_rad")


@pytest.fixture(scope="session")
def rng():
    return np.random.default_rng(15)


def random_configurations(robot, n, rng, margin=0.05):
    lo, hi = robot.lower_limits + margin, robot.upper_limits - margin
    return lo + (hi - lo) * rng.random((n, robot.dof))
