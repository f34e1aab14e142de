"""The case study from Python against `deflex case-study --json` with the same options (a quick
run: one seed, one lap each way, no sweep, no budget) on the paper's case cut to one load of the
offline and the online setup at one speed, so it takes seconds: every figure of the tables must agree."""

import math

import deflex
from conftest import SOURCE_DIR, cli_json


def small_case(tmp_path):
    """data/cases/paper.yaml with two setups of one load each, at 50 mm/s."""
    text = (SOURCE_DIR / "data" / "cases" / "paper.yaml").read_text()
    start, end = text.index("setups:\n"), text.index("\ntrue_robot:")
    text = text[:start] + (
        "setups:\n"
        "  - {name: offline, strategy: offline, link: program, sensor: false, loads_N: [625]}\n"
        "  - {name: online, strategy: online, link: egm-joint, sensor: true, loads_N: [650]}\n") + text[end:]
    text = text.replace("speeds_mm_s: [10, 30, 50]", "speeds_mm_s: [50]").replace("  load_index: 2", "  load_index: 0")
    path = tmp_path / "small.yaml"
    path.write_text(text)
    return path


def same(a, b, path="tables"):
    if isinstance(a, dict):
        assert set(a) == set(b), path
        for k in a:
            same(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, list):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            same(x, y, f"{path}[{i}]")
    elif isinstance(a, float) or isinstance(b, float):
        assert a is not None and b is not None and math.isclose(a, b, rel_tol=1e-12, abs_tol=1e-15), (path, a, b)
    else:
        assert a == b, (path, a, b)


def test_quick_case_study_matches_cli(tmp_path):
    case = small_case(tmp_path)
    result = deflex.run_case_study(str(case), quick=True, seeds=1, speed_sweep=False, error_budget=False, threads=2)
    doc = cli_json("case-study", "--case", case, "--quick", "--seeds", 1, "--no-sweep", "--no-budget", "--no-progress", "--threads", 2,
                   "--out", tmp_path / "out")
    tables = result.tables
    tables.pop("wall_time_s", None)
    doc.pop("wall_time_s", None)
    same(tables, doc)
    assert [s["setup"] for s in tables["setups"]] == ["offline", "online"]
    assert tables["speeds_mm_s"] == [50]
    assert result.runs > 0 and result.calibrations > 0 and result.simulated_s > 0
    assert "Table 1" in result.tables_text
    assert all(link["guard_trips"] == 0 for link in result.links)
