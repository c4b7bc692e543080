"""Recordings of ordinary scenes through rigs turned by a known dR, from tests/drift/scene_gen.py."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from s2r.formats.s2r_yaml import dump_profile
from s2r.profile import StereoProfile
from tests.conftest import make_rig
from tests.drift.scene_gen import turned_pair
from tests.raycast import Lens

SIZE = (480, 360)


def rig() -> StereoProfile:
    """480x360, 8 cm baseline, the right camera already turned a little (the profile's own R)."""
    return make_rig(name="drift_rig", width=SIZE[0], height=SIZE[1], hfov_rad=1.1, baseline_m=0.08,
                    rotation_deg=(0.3, -0.5, 0.2), origin="real")


def lens(profile: StereoProfile) -> Lens:
    cam = profile.left
    return Lens(cam.width_px, cam.height_px, cam.fx_px, cam.fy_px, cam.cx_px, cam.cy_px, "plumb_bob", (0.0,) * 5)


def write_recording(folder: Path, profile: StereoProfile, turn_deg: tuple[float, float, float], *, frames: int,
                    keep: str = "centre", seed: int = 0) -> Path:
    """``folder/left/NN.png``, ``folder/right/NN.png``: ``frames`` scenes with the right camera really at
    ``dR @ R`` (dR from the rotation vector ``turn_deg`` about the right optical axes)."""
    dR = Rotation.from_rotvec(np.radians(turn_deg)).as_matrix()
    for side in ("left", "right"):
        (folder / side).mkdir(parents=True, exist_ok=True)
    for k in range(frames):
        left, right = turned_pair(lens(profile), lens(profile), profile.R, profile.T.reshape(3), dR,
                                  seed=seed + 7 * k, keep=keep)
        cv2.imwrite(str(folder / "left" / f"{k:02d}.png"), left)
        cv2.imwrite(str(folder / "right" / f"{k:02d}.png"), right)
    return folder


@pytest.fixture(scope="session")
def drift_rig_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("drift_profile") / "rig.yaml"
    dump_profile(rig(), path)
    return path


@pytest.fixture(scope="session")
def recordings(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """``same``: through the profile's own rotation; ``turned``: 0.2 deg pitch, -0.3 yaw, 0.15 roll."""
    base = tmp_path_factory.mktemp("drift_recordings")
    return {"same": write_recording(base / "same", rig(), (0.0, 0.0, 0.0), frames=4, seed=1),
            "turned": write_recording(base / "turned", rig(), (0.2, -0.3, 0.15), frames=4, seed=2)}
