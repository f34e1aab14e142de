"""The machining study from Python against `deflex machining-study` with the same options (quick, one
seed): the table and the fits must agree to the last digit, and bad arguments are refused."""

import json

import pytest

import deflex
from conftest import run_cli


def test_quick_machining_study_matches_cli(tmp_path):
    result = deflex.run_machining_study(quick=True, seeds=1, threads=2)
    run_cli("machining-study", "--quick", "--seeds", 1, "--threads", 2, "--no-progress", "--out", tmp_path / "out")
    doc = json.loads((tmp_path / "out" / "machining-study.json").read_text())
    assert result.table == doc
    strategies = [row["strategy"] for row in doc["table"]]
    assert strategies == ["uncompensated"] * 2 + ["offline"] * 2 + ["online"] * 2 + ["hybrid"] * 2
    assert "climb wall um" in result.table_text
    report = tmp_path / "report.html"
    result.write_report(report)
    assert "<svg" in report.read_text()


def test_bad_machining_study_arguments_are_refused():
    with pytest.raises(deflex.InputError):
        deflex.run_machining_study(seeds=-1)
    with pytest.raises(deflex.InputError):
        deflex.run_machining_study(seeds=21)
