"""PyBullet cameras built exactly from a profile camera, and the per-process PyBullet connection.

Conventions (measured, see REFERENCE.md "PyBullet as a camera simulator"; each is pinned by a test):

- Projection from K: ``P00 = 2 fx / W``, ``P11 = 2 fy / H``, ``P02 = 1 - 2 (cx + ox) / W``,
  ``P12 = 2 (cy + oy) / H - 1``, ``P22 = -(far + near) / (far - near)``, ``P23 = -2 far near / (far - near)``,
  ``P32 = -1``, with TinyRenderer's pixel offset ``(ox, oy) = (0, +1)``; pybullet takes the transpose flattened.
- View: ``diag(1, -1, -1, 1) @ T_cam_world`` with ``T_cam_world`` an OpenCV world-to-optical-frame pose.
- Depth buffer ``d`` to metric z along the optical axis: ``z = far near / (far - (far - near) d)``.

The renderer's world frame is the LEFT optical frame of the profile (z forward, x right, y down, metres).
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from s2r.render._pybullet import p

__all__ = [
    "PIXEL_OFFSET",
    "PinholeView",
    "client",
    "depth_buffer_to_z",
    "projection_matrix",
    "render_pinhole",
    "view_matrix",
]

FloatArray = NDArray[np.float64]

#: TinyRenderer's pixel offset (ox, oy) that makes rendered images obey an OpenCV K.
PIXEL_OFFSET: tuple[float, float] = (0.0, 1.0)
#: Depth-buffer values at or above this count as "nothing hit" (the far plane).
_BACKGROUND_FRACTION = 0.999

_CLIENT: dict[int, int] = {}


def client() -> int:
    """This process's PyBullet DIRECT connection, created on first use (one per process, fork-safe)."""
    pid = os.getpid()
    if pid not in _CLIENT:
        _CLIENT.clear()
        _CLIENT[pid] = int(p.connect(p.DIRECT))
    return _CLIENT[pid]


def projection_matrix(
    K: FloatArray, width: int, height: int, near: float, far: float, *, offset: tuple[float, float] = PIXEL_OFFSET
) -> FloatArray:
    """4x4 OpenGL projection (row-major) of a pinhole with camera matrix ``K`` (pixels) and clip planes (m)."""
    fx, fy, cx, cy = K[0, 0], K[1, 1], K[0, 2], K[1, 2]
    ox, oy = offset
    P = np.zeros((4, 4))
    P[0, 0] = 2.0 * fx / width
    P[1, 1] = 2.0 * fy / height
    P[0, 2] = 1.0 - 2.0 * (cx + ox) / width
    P[1, 2] = 2.0 * (cy + oy) / height - 1.0
    P[2, 2] = -(far + near) / (far - near)
    P[2, 3] = -2.0 * far * near / (far - near)
    P[3, 2] = -1.0
    return P


def view_matrix(T_cam_world: FloatArray) -> FloatArray:
    """4x4 OpenGL view matrix (row-major) of an OpenCV world-to-optical-frame pose ``T_cam_world``."""
    return np.diag([1.0, -1.0, -1.0, 1.0]) @ np.asarray(T_cam_world, dtype=np.float64)


def depth_buffer_to_z(depth: NDArray[np.floating], near: float, far: float) -> NDArray[np.float64]:
    """Metric z (metres along the optical axis) of OpenGL depth-buffer values in [0, 1]; NaN at the far plane."""
    d = np.asarray(depth, dtype=np.float64)
    z = far * near / (far - (far - near) * d)
    z[z >= _BACKGROUND_FRACTION * far] = np.nan
    return z


@dataclass(frozen=True)
class PinholeView:
    """An ideal pinhole render camera.

    Attributes:
        K: 3x3 camera matrix in pixels (OpenCV convention, no skew).
        width, height: image size in pixels.
        T_cam_world: 4x4 pose mapping world (= left optical frame) points to this camera's optical frame.
        near, far: clip planes in metres.
    """

    K: FloatArray
    width: int
    height: int
    T_cam_world: FloatArray
    near: float
    far: float


def render_pinhole(view: PinholeView) -> tuple[NDArray[np.uint8], NDArray[np.float32]]:
    """Render the current PyBullet world through ``view``.

    Returns:
        ``(rgb, depth_buffer)``: ``(H, W, 3)`` uint8 RGB with flat (ambient-only) shading, and the ``(H, W)``
        float32 OpenGL depth buffer in [0, 1] (:func:`depth_buffer_to_z` turns it into metres).
    """
    P = projection_matrix(view.K, view.width, view.height, view.near, view.far)
    V = view_matrix(view.T_cam_world)
    _, _, rgba, depth, _ = p.getCameraImage(
        view.width, view.height, viewMatrix=V.T.ravel().tolist(), projectionMatrix=P.T.ravel().tolist(),
        renderer=p.ER_TINY_RENDERER, flags=p.ER_NO_SEGMENTATION_MASK, shadow=0,
        lightAmbientCoeff=1.0, lightDiffuseCoeff=0.0, lightSpecularCoeff=0.0, physicsClientId=client(),
    )
    rgba = np.ascontiguousarray(np.asarray(rgba, dtype=np.uint8).reshape(view.height, view.width, 4))
    rgb = cv2.cvtColor(rgba, cv2.COLOR_RGBA2RGB)  # the alpha dropped: 10x faster than numpy's strided copy
    return np.asarray(rgb, np.uint8), np.asarray(depth, dtype=np.float32).reshape(view.height, view.width)


def pose_to_pybullet(T_world_obj: FloatArray) -> tuple[list[float], list[float]]:
    """Position (m) and quaternion (x, y, z, w) of a 4x4 pose, as pybullet wants them."""
    T = np.asarray(T_world_obj, dtype=np.float64)
    quat = Rotation.from_matrix(T[:3, :3]).as_quat()
    return T[:3, 3].tolist(), [float(q) for q in quat]
