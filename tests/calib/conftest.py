"""Synthetic stereo sets with known parameters, generated once per test session (seeded)."""

from __future__ import annotations

from pathlib import Path

import pytest

from s2r.calib.synth import write_stereo_set
from s2r.profile import StereoProfile
from tests.conftest import make_rig


def distorted_truth() -> StereoProfile:
    """The known rig: 640x480, fx 554.26, barrel distortion, slightly rotated right camera, 10 cm baseline."""
    return make_rig(name="truth", distortion=(-0.12, 0.05, 0.0, 0.0, 0.0), rotation_deg=(0.3, -0.5, 0.2),
                    cx=322.0, cy=238.5)


@pytest.fixture(scope="session")
def synthetic_set(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, StereoProfile]:
    """24 board pairs of the distorted rig in left/ and right/ (PNG), noise sigma 1.5 grey levels."""
    folder = tmp_path_factory.mktemp("synthetic") / "set"
    truth = distorted_truth()
    write_stereo_set(truth, folder, views=24, seed=7)
    return folder, truth
