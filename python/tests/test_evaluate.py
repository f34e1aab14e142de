"""Path metrics against closed forms and `deflex evaluate --json` on the same traces."""

import numpy as np

import deflex
from conftest import cli_json


def line(n=201, length=0.2, offset=(0.0, 0.0, 0.0), t0=0.0):
    t = np.linspace(0.0, 2.0, n) + t0
    p = np.column_stack([np.linspace(0.0, length, n), np.zeros(n), np.zeros(n)]) + np.asarray(offset)
    return np.column_stack([t, p])


def write_tracker(path, trace):
    with open(path, "w") as f:
        f.write("t_s,x_mm,y_mm,z_mm\n")
        for t, x, y, z in trace:
            f.write(f"{t!r},{x * 1e3!r},{y * 1e3!r},{z * 1e3!r}\n")


def test_mean_distance_closed_form():
    reference = line()
    loaded = line(n=101)
    offsets = np.linspace(0.0, 4e-4, 101)
    loaded[:, 2] += offsets  # y displaced by a known amount at each point
    np.testing.assert_allclose(deflex.mean_distance_to_path_m(loaded, reference), offsets.mean(), rtol=1e-12)
    stats = deflex.path_deviation(loaded[:, 1:], reference[:, 1:])  # (N, 3) positions work too
    np.testing.assert_allclose([stats.mean_m, stats.max_m], [offsets.mean(), offsets.max()], rtol=1e-12)
    np.testing.assert_allclose(stats.rms_m, np.sqrt(np.mean(offsets ** 2)), rtol=1e-12)
    np.testing.assert_allclose(stats.std_m, offsets.std(ddof=1), rtol=1e-10)
    assert stats.samples == 101


def test_iso9283_closed_form():
    reference = line()
    shifted = [line(offset=(0.0, 3e-4, 0.0)), line(offset=(0.0, 3e-4, 0.0))]
    iso = deflex.iso9283_path(shifted, reference, evaluation_points=21)
    assert abs(iso.accuracy_m - 3e-4) < 1e-12 and abs(iso.repeatability_m) < 1e-12
    assert iso.evaluation_points == 21 and iso.runs == 2
    spread = [line(offset=(0.0, 2e-4, 0.0)), line(offset=(0.0, -2e-4, 0.0))]
    iso = deflex.iso9283_path(spread, reference, evaluation_points=21)
    assert abs(iso.accuracy_m) < 1e-12 and abs(iso.repeatability_m - 2e-4) < 1e-12


def test_time_synchronous_sees_lag():
    reference = line()
    lagging = line(t0=0.1)  # the same path, 0.1 s late: no distance from the path, a time error
    assert deflex.mean_distance_to_path_m(lagging, reference) < 1e-15
    lag = deflex.time_synchronous_deviation(lagging, reference)
    np.testing.assert_allclose(lag.mean_m, 0.2 / 2.0 * 0.1, rtol=1e-9)


def test_matches_cli_on_files(tmp_path, rng):
    reference = line()
    laps = [line(offset=(0.0, 1e-4, 0.0)) + np.column_stack([np.zeros(201), rng.normal(0, 2e-5, (201, 3))])
            for _ in range(3)]
    write_tracker(tmp_path / "u.csv", reference)
    for i, lap in enumerate(laps):
        write_tracker(tmp_path / f"l{i}.csv", lap)
    args = ["evaluate", "--unloaded", tmp_path / "u.csv"]
    for i in range(3):
        args += ["--loaded", tmp_path / f"l{i}.csv"]
    doc = cli_json(*args)
    read = [deflex.read_tracker_csv(str(tmp_path / f"l{i}.csv")) for i in range(3)]
    np.testing.assert_allclose(read[0], laps[0], rtol=1e-13, atol=1e-16)
    stats = deflex.path_deviation(read, [deflex.read_tracker_csv(str(tmp_path / "u.csv"))])
    np.testing.assert_allclose(stats.mean_m * 1e3, doc["mean_deformation_mm"], rtol=1e-12)
    np.testing.assert_allclose(stats.max_m * 1e3, doc["max_mm"], rtol=1e-12)
    iso = deflex.iso9283_path(read, deflex.read_tracker_csv(str(tmp_path / "u.csv")))
    np.testing.assert_allclose(iso.accuracy_m * 1e3, doc["iso9283_loaded"]["accuracy_mm"], rtol=1e-12)
    np.testing.assert_allclose(iso.repeatability_m * 1e3, doc["iso9283_loaded"]["repeatability_mm"], rtol=1e-12)
    assert deflex.compensation_ratio(0.6, 0.2) == 1 - 0.2 / 0.6
