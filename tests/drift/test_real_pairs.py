"""Real pairs (OpenCV's sample stereo set): the profile calibrated on them passes; 0.3 deg of roll added to it
is flagged, and the check recovers it."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from s2r.cli import main
from s2r.drift.check import check_drift
from s2r.drift.source import StereoSource, read_pairs
from s2r.profile import Extrinsics
from s2r.registry import load_profile

DATA = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "opencv_stereo_chessboard"
pytestmark = pytest.mark.skipif(not DATA.is_dir(), reason=f"shared real data not found at {DATA}")


@pytest.mark.slow
def test_calibrated_profile_passes_and_an_added_roll_is_flagged(tmp_path: Path) -> None:
    real = tmp_path / "real.yaml"
    assert main(["-q", "calibrate", str(DATA), "--pattern", "9x6", "--square", "0.025", "-o", str(real)]) == 0
    profile = load_profile(real)
    own = check_drift(profile, read_pairs(StereoSource(folder=DATA)))
    assert own.verdict == "good", own.reasons
    assert abs(own.omega_deg[0]) < 0.05 and abs(own.omega_deg[2]) < 0.05  # pitch and roll
    dR = Rotation.from_rotvec(np.radians([0.0, 0.0, 0.3])).as_matrix()
    rolled = profile.model_copy(update={"extrinsics": Extrinsics(
        rotation=tuple(tuple(float(v) for v in row) for row in dR @ profile.R),  # type: ignore[arg-type]
        translation_m=tuple(float(v) for v in profile.T.reshape(3)))})  # type: ignore[arg-type]
    drifted = check_drift(rolled, read_pairs(StereoSource(folder=DATA)))
    assert drifted.verdict == "drifted"
    # the rig is really at R_profile without the added roll: dR = -0.3 deg roll, on top of the calibration's own
    assert drifted.omega_deg[2] - own.omega_deg[2] == pytest.approx(-0.3, abs=0.04)
