"""OpenCV's real stereo chessboard set (../shared/data): figures against plain OpenCV's reference."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from s2r.cli import main
from s2r.formats.s2r_yaml import load_profile_file
from tests.conftest import shared_data

pytestmark = pytest.mark.slow


def test_real_set_calibrates_like_opencv(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    data = shared_data("opencv_stereo_chessboard")
    out = tmp_path / "real.yaml"
    code = main(["calibrate", str(data), "--pattern", "9x6", "--square", "0.025", "-o", str(out), "--json",
                 "--jobs", "2"])
    figures = json.loads(capsys.readouterr().out)
    assert code == 0
    assert not [d for d in figures["dropped"] if not d["reason"].startswith("outlier")]  # every pair detected
    profile = load_profile_file(out)
    q = profile.provenance.calibration
    assert q is not None and q.rms_stereo_px is not None and q.rms_stereo_px <= 0.45
    assert abs(profile.left.fx_px - 536.07) <= 0.005 * 536.07
    assert abs(profile.baseline_m - 0.0836) <= 0.01 * 0.0836
    assert profile.left.std is not None and profile.left.std.fx_px is not None and profile.left.std.fx_px > 0
    assert profile.extrinsics.baseline_std_m is not None and profile.extrinsics.baseline_std_m > 0
    assert profile.provenance.origin == "real" and len(profile.provenance.sources) == 26
    assert q.epipolar_rms_px is not None and q.epipolar_rms_px < 0.5
    assert profile.T[0] < 0  # right camera to the right of the left one (OpenCV convention)
