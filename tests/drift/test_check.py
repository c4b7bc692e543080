"""s2r check on rigs turned by a known dR (independent ray-cast scenes) and on a real set."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from s2r.cli import main
from s2r.drift.check import AXES, check_drift
from s2r.drift.source import StereoSource, read_pairs
from tests.drift.conftest import rig, write_recording


def _check(capsys: pytest.CaptureFixture[str], argv: list[str]) -> tuple[int, dict[str, object]]:
    code = main(["check", *argv, "--json"])
    return code, json.loads(capsys.readouterr().out)


@pytest.mark.slow
def test_a_turned_rig_is_flagged_and_its_rotation_recovered(capsys: pytest.CaptureFixture[str],
                                                            drift_rig_file: Path, recordings: dict[str, Path]) -> None:
    code, result = _check(capsys, [str(drift_rig_file), str(recordings["turned"])])
    assert code == 1 and result["verdict"] == "drifted"
    assert "R_true = dR @ R_profile" in str(result["convention"])
    got = result["rotation_error_deg"]
    assert isinstance(got, dict)
    for axis, truth in zip(AXES, (0.2, -0.3, 0.15), strict=True):
        assert abs(got[axis] - truth) <= max(0.03, 0.1 * abs(truth)), (axis, got[axis])
    assert "baseline" in str(result["blind_spots"])


@pytest.mark.slow
def test_the_profiles_own_rotation_passes(capsys: pytest.CaptureFixture[str], drift_rig_file: Path,
                                          recordings: dict[str, Path]) -> None:
    code, result = _check(capsys, [str(drift_rig_file), str(recordings["same"])])
    assert code == 0 and result["verdict"] == "good", result["reasons"]
    assert all(abs(v) < 0.02 for v in result["rotation_error_deg"].values())  # type: ignore[attr-defined]


@pytest.mark.slow
def test_a_turn_with_the_profiles_translation_kept_is_recovered_too(tmp_path: Path) -> None:
    """The other reading of "turned" (T_true = T_profile): the depth-dependent term is in the sigma."""
    folder = write_recording(tmp_path / "rec", rig(), (0.0, 0.25, -0.3), frames=2, keep="translation", seed=5)
    result = check_drift(rig(), read_pairs(StereoSource(folder=folder)))
    for value, truth in zip(result.omega_deg, (0.0, 0.25, -0.3), strict=True):
        assert abs(value - truth) <= max(0.03, 0.1 * abs(truth))
    assert result.verdict == "drifted"


@pytest.mark.slow
def test_fix_writes_a_profile_that_then_passes(tmp_path: Path, drift_rig_file: Path,
                                               recordings: dict[str, Path], capsys: pytest.CaptureFixture[str]) -> None:
    fixed = tmp_path / "fixed.yaml"
    assert main(["-q", "check", str(drift_rig_file), str(recordings["turned"]), "--fix", "-o", str(fixed)]) == 1
    out = capsys.readouterr().out
    assert "next: s2r check" in out and "--fix -o fixed.yaml" in out  # what to do after DRIFTED
    assert "frames it did not fit" in out and ": GOOD," in out  # the written profile re-checked on held-out frames
    from s2r.registry import load_profile

    profile = load_profile(fixed)
    assert profile.baseline_m == pytest.approx(rig().baseline_m, abs=1e-12)
    assert np.allclose(profile.left.K, rig().left.K)
    assert "s2r check --fix" in profile.provenance.notes
    again = check_drift(profile, read_pairs(StereoSource(folder=recordings["turned"])))
    assert again.verdict == "good", again.reasons


def test_a_textureless_recording_cannot_tell(tmp_path: Path) -> None:
    import cv2

    for side in ("left", "right"):
        (tmp_path / side).mkdir()
        for k in range(2):
            cv2.imwrite(str(tmp_path / side / f"{k}.png"), np.full((360, 480), 128, np.uint8))
    result = check_drift(rig(), read_pairs(StereoSource(folder=tmp_path)))
    assert result.verdict == "cannot tell" and "usable matches" in result.reasons[0]


def test_bad_inputs_are_one_line(capsys: pytest.CaptureFixture[str], tmp_path: Path, drift_rig_file: Path) -> None:
    assert main(["check", str(drift_rig_file), str(tmp_path / "none")]) == 2
    assert capsys.readouterr().err.strip().startswith("error: ")
    assert main(["check", str(drift_rig_file)]) == 2
    assert "give one recording" in capsys.readouterr().err
    assert main(["check", str(drift_rig_file), str(tmp_path), "--tolerance", "nan"]) == 2
    assert "--tolerance" in capsys.readouterr().err
