"""Synthetic stereo sets with known parameters, generated once per test session (seeded)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from s2r.calib.solve.synth import write_stereo_set
from s2r.profile import StereoProfile
from tests.conftest import make_rig


def distorted_truth() -> StereoProfile:
    """The known rig: 640x480, fx 554.26, barrel distortion, slightly rotated right camera, 10 cm baseline."""
    return make_rig(name="truth", distortion=(-0.12, 0.05, 0.0, 0.0, 0.0), rotation_deg=(0.3, -0.5, 0.2),
                    cx=322.0, cy=238.5)


@pytest.fixture(scope="session")
def synthetic_set(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, StereoProfile]:
    """30 board pairs of the distorted rig in left/ and right/ (PNG), noise sigma 1.5 grey levels."""
    folder = tmp_path_factory.mktemp("synthetic") / "set"
    truth = distorted_truth()
    write_stereo_set(truth, folder, views=30, seed=7)
    return folder, truth


def copy_pairs(src: Path, dst: Path, indices: range | list[int]) -> Path:
    """Copy pairs ``indices`` of a left/ right/ set into ``dst`` (same layout); returns ``dst``."""
    for side in ("left", "right"):
        (dst / side).mkdir(parents=True, exist_ok=True)
        for i in indices:
            shutil.copy(src / side / f"{i:02d}.png", dst / side / f"{i:02d}.png")
    return dst


@pytest.fixture
def small_set(tmp_path: Path, synthetic_set: tuple[Path, StereoProfile]) -> Path:
    """Eight pairs of the synthetic set in ``tmp_path/set`` (left/, right/), free to damage."""
    return copy_pairs(synthetic_set[0], tmp_path / "set", range(8))
