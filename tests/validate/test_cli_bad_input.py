"""Bad input to ``s2r validate``: one ``error: ...`` line naming what is wrong, exit code 2, nothing written."""

from __future__ import annotations

from pathlib import Path

import pytest

from s2r.cli import main
from s2r.formats.s2r_yaml import dump_profile
from s2r.profile import MatcherSettings
from tests.conftest import make_rig

REAL = "realsense_d435_848x480"


def _error(capsys: pytest.CaptureFixture[str], argv: list[str]) -> str:
    assert main(argv) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    errors = [line for line in lines if line.startswith("error: ")]
    assert len(errors) == 1 and lines[-1] == errors[0]  # warnings may precede it
    return errors[0]


def test_unknown_profile_lists_known_ones(capsys: pytest.CaptureFixture[str]) -> None:
    err = _error(capsys, ["validate", "no_such_rig", REAL])
    assert "unknown profile name 'no_such_rig'" in err and REAL in err


def test_tolerances_file_with_unknown_keys(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "tol.yaml"
    path.write_text("focal: 0.02\nfov_deg: 2\n")
    err = _error(capsys, ["validate", REAL, "--tolerances", str(path)])
    assert str(path) in err and "unknown tolerance key(s) focal" in err and "focal_rel" in err


def test_matcher_that_cannot_see_the_distances(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # 16 disparities on a 640 px, 10 cm rig: nothing nearer than fx B / 15 = 3.7 m
    rig = make_rig(name="short_sighted").model_copy(update={"matcher": MatcherSettings(num_disparities=16)})
    path = dump_profile(rig, tmp_path / "short_sighted.yaml")
    err = _error(capsys, ["validate", str(path), "--quick"])
    assert "short_sighted" in err and "16 disparities" in err and "sees 3.70-55.4 m" in err
    assert "not 0.75, 1.5, 2.5 m" in err


def test_distances_beyond_the_preset(capsys: pytest.CaptureFixture[str]) -> None:
    err = _error(capsys, ["validate", REAL, "--preset", "seed-sgbm", "--distances", "0.1,1"])
    assert "seed-sgbm" in err and "not 0.1 m" in err
    err = _error(capsys, ["validate", REAL, "--distances", "1,x"])
    assert "--distances" in err


def test_unwritable_report_folder(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    blocker = tmp_path / "file.txt"
    blocker.write_text("not a folder")
    err = _error(capsys, ["validate", REAL, "--quick", "--report", str(blocker / "report")])
    assert str(blocker) in err and "is a file, expected a folder" in err  # names what is in the way


def test_report_folder_holding_files_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "old.html").write_text("keep me")
    err = _error(capsys, ["validate", REAL, "--quick", "--report", str(tmp_path)])
    assert "--force" in err and (tmp_path / "old.html").read_text() == "keep me"


def test_unknown_preset_and_bad_jobs(capsys: pytest.CaptureFixture[str]) -> None:
    assert "unknown preset 'nope'" in _error(capsys, ["validate", REAL, "--preset", "nope"])
    assert "--jobs" in _error(capsys, ["validate", REAL, "--jobs", "0"])
