"""MuJoCo itself as the anchor for the MJCF reader: what the compiled model says about two cameras.

Shares no code with s2r: MuJoCo compiles the file (includes, defaults, compiler settings, frames, every pose form),
``mj_forward`` places the cameras (``data.cam_xpos`` / ``cam_xmat``; a keyframe is applied with
``mj_resetDataKeyframe``), and the pixel intrinsics come from ``model.cam_fovy`` or ``model.cam_intrinsic`` and
``model.cam_sensorsize`` exactly as MuJoCo's renderer builds its frustum (engine_vis_visualize.c ``getFrustum``:
the optical axis sits ``principal`` to the LEFT of and ABOVE the image centre, which test_mjcf_render.py checks by
rendering).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

os.environ.setdefault("MUJOCO_GL", "egl")  # headless rendering (test_mjcf_render.py); read when mujoco is imported
mujoco = pytest.importorskip("mujoco", reason="the mujoco extra is not installed (pip install -e '.[mujoco]')")

#: MuJoCo's camera frame (-z forward, +y up) to OpenCV's optical frame (z forward, y down).
FLIP = np.diag([1.0, -1.0, -1.0])


@dataclass(frozen=True)
class Truth:
    """One camera as MuJoCo has it: pixel intrinsics (0-based centres) and the optical frame in the world."""

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    T_world_optical: np.ndarray


def _size(model: object, cam: int) -> tuple[int, int]:
    res = [int(v) for v in model.cam_resolution[cam]]  # type: ignore[attr-defined]
    if res == [1, 1]:
        glob = model.vis.global_  # type: ignore[attr-defined]
        return int(glob.offwidth), int(glob.offheight)
    return res[0], res[1]


def camera_truth(path: Path, name: str, *, keyframe: int | None = None) -> Truth:
    """Compile ``path`` with MuJoCo and read camera ``name``."""
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    if keyframe is not None:
        mujoco.mj_resetDataKeyframe(model, data, keyframe)
    mujoco.mj_forward(model, data)
    cam = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, name)
    assert cam >= 0, name
    width, height = _size(model, cam)
    sensor = model.cam_sensorsize[cam]
    if sensor[1] > 0:
        k = model.cam_intrinsic[cam]
        fx, fy = k[0] / sensor[0] * width, k[1] / sensor[1] * height
        cx = (width - 1) / 2 - k[2] / sensor[0] * width
        cy = (height - 1) / 2 - k[3] / sensor[1] * height
    else:
        fy = (height / 2) / math.tan(math.radians(model.cam_fovy[cam]) / 2)
        fx, cx, cy = fy, (width - 1) / 2, (height - 1) / 2
    T = np.eye(4)
    T[:3, :3] = data.cam_xmat[cam].reshape(3, 3) @ FLIP
    T[:3, 3] = data.cam_xpos[cam]
    return Truth(width, height, float(fx), float(fy), float(cx), float(cy), T)


def pair_truth(path: Path, left: str, right: str, *, keyframe: int | None = None) -> tuple[Truth, Truth, np.ndarray]:
    """Both cameras and ``T_left_right``: the right optical frame in the left one (metres)."""
    a = camera_truth(path, left, keyframe=keyframe)
    b = camera_truth(path, right, keyframe=keyframe)
    return a, b, np.linalg.inv(a.T_world_optical) @ b.T_world_optical
