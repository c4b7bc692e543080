"""Shared fixtures: seeded rigs with known parameters and the location of the shared real data."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from s2r.profile import Camera, Distortion, Extrinsics, Provenance, SimulationSettings, StereoProfile

# MuJoCo picks its GL platform when first imported: headless test runs render through EGL whichever test imports it
# first (s2r.render.mujoco.backend chooses the same, but only when it is the first importer).
if not os.environ.get("DISPLAY"):
    import ctypes.util

    only_osmesa = ctypes.util.find_library("EGL") is None and ctypes.util.find_library("OSMesa") is not None
    os.environ.setdefault("MUJOCO_GL", "osmesa" if only_osmesa else "egl")

#: Real recorded data kept outside the repository (see ../shared/data/README.md).
SHARED_DATA = Path(__file__).resolve().parents[2] / "shared" / "data"


def shared_data(*parts: str) -> Path:
    """Path into ../shared/data, skipping the calling test with a reason when it is absent."""
    path = SHARED_DATA.joinpath(*parts)
    if not path.exists():
        pytest.skip(f"real data not available: {path} (see ../shared/data/README.md)")
    return path


def make_rig(
    *,
    name: str = "test_rig",
    width: int = 640,
    height: int = 480,
    hfov_rad: float = 1.047,
    baseline_m: float = 0.1,
    cx: float | None = None,
    cy: float | None = None,
    distortion: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0, 0.0),
    rotation_deg: tuple[float, float, float] = (0.0, 0.0, 0.0),
    origin: str = "sim",
) -> StereoProfile:
    """A stereo profile with known parameters: fx = fy from the FOV, right camera baseline_m to the right."""
    fx = width / (2.0 * math.tan(hfov_rad / 2.0))
    cam = Camera(
        width_px=width, height_px=height, fx_px=fx, fy_px=fx,
        cx_px=(width - 1) / 2.0 if cx is None else cx, cy_px=(height - 1) / 2.0 if cy is None else cy,
        distortion=Distortion(coefficients=distortion),
    )
    R = Rotation.from_euler("xyz", rotation_deg, degrees=True).as_matrix()
    T = -R @ np.array([baseline_m, 0.0, 0.0])
    return StereoProfile(
        name=name, left=cam, right=cam,
        extrinsics=Extrinsics(rotation=tuple(map(tuple, R.tolist())), translation_m=tuple(T.tolist())),
        simulation=SimulationSettings(clip_near_m=0.05, clip_far_m=50.0),
        provenance=Provenance(origin=origin, method="tests.conftest.make_rig", convention="exact"),  # type: ignore[arg-type]
    )


@pytest.fixture
def rig() -> StereoProfile:
    """640x480, 60 deg HFOV (fx 554.26), 10 cm baseline, no distortion."""
    return make_rig()


@pytest.fixture
def distorted_rig() -> StereoProfile:
    """A rig with mild barrel distortion and a slight rotation between the cameras."""
    return make_rig(name="distorted_rig", distortion=(-0.12, 0.05, 0.0, 0.0, 0.0), rotation_deg=(0.3, -0.5, 0.2),
                    cx=322.0, cy=238.5)


#: A xacro file defining a ``cam`` macro (params ``side``, ``y``): a 640x480 Gazebo camera on a link fixed to ``base``.
CAMERA_MACRO_XACRO = """<?xml version="1.0"?>
<robot xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:macro name="cam" params="side y">
    <link name="${side}_link"/>
    <joint name="${side}_joint" type="fixed"><parent link="base"/><child link="${side}_link"/>
      <origin xyz="0 ${y} 0" rpy="0 0 0"/></joint>
    <gazebo reference="${side}_link"><sensor type="camera" name="${side}_cam"><update_rate>30</update_rate>
      <camera><horizontal_fov>1.047</horizontal_fov><image><width>640</width><height>480</height></image>
      </camera></sensor></gazebo>
  </xacro:macro>
</robot>
"""
