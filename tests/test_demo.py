"""The whole migration story of ``make demo``, in quick mode, in a temporary folder."""

from __future__ import annotations

from pathlib import Path

import pytest

from s2r.cli.demo import REPO, UNIT_TRUTH, DemoPaths, calibration_errors, run_demo
from s2r.formats.s2r_yaml import load_profile_file


@pytest.mark.slow
def test_demo_flow_ends_with_a_passing_validation(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.chdir(REPO)
    paths = DemoPaths(out=tmp_path / "out", report=tmp_path / "report", sample=tmp_path / "sample")
    paths.out.mkdir()
    outcome = run_demo(paths, quick=True)
    printed = capsys.readouterr().out
    assert outcome.codes["lint seed rig"] == 1 and "baseline-axis" in printed
    assert outcome.codes["validate sim vs real"] == 1
    assert outcome.codes["validate closed loop"] == 0, printed[-3000:]
    assert outcome.calibration_ok and outcome.ok
    # the calibrated profile matches the sample unit's truth within the calibration issue's tolerances
    rows = calibration_errors(load_profile_file(paths.real), load_profile_file(UNIT_TRUTH))
    assert all(ok for *_, ok in rows), rows
    assert (paths.report / "validation.html").stat().st_size > 10_000
    assert (paths.report / "closed_loop" / "validation.html").is_file()
