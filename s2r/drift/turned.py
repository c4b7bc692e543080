"""A vertical rig (one camera above the other) checked as a side-by-side one: both images and the profile turned
by 90 degrees about the optical axes, so that the second camera sits to the right of the first.

Frames: a camera's optical axes (x right, y down, z forward). The turn ``M`` maps a vector of a camera's old
frame to its new one; the images turn with it (``cv2.rotate``), the intrinsics swap axes, the tangential
distortion coefficients (p1, p2) turn too, and the extrinsics become ``R' = M R M^T``, ``T' = M T``. A small
rotation error found in the turned frame, ``omega'``, is ``M omega`` of the original one.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.profile import Camera, Distortion, Extrinsics, StereoProfile

__all__ = ["Turn", "side_by_side_turn"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Turn:
    """``M`` (3, 3) old -> new camera frame, the ``cv2.rotate`` code of the images, and the turned profile."""

    M: FloatArray
    rotate_code: int
    profile: StereoProfile

    def image(self, image: NDArray[np.uint8]) -> NDArray[np.uint8]:
        """A raw image of the original rig, turned."""
        return np.ascontiguousarray(cv2.rotate(image, self.rotate_code))

    def back(self, omega: FloatArray) -> FloatArray:
        """A rotation vector of the turned frame in the original frame (``M^T omega'``)."""
        return np.asarray(self.M.T @ np.asarray(omega, np.float64), np.float64)

    def back_sigma(self, sigma: FloatArray) -> FloatArray:
        """Per-axis sigmas: ``M`` permutes the axes (with signs), so the sigmas are permuted."""
        return np.asarray(np.abs(self.M.T) @ np.asarray(sigma, np.float64), np.float64)


def _turn_camera(cam: Camera, *, clockwise: bool) -> Camera:
    w, h = cam.width_px, cam.height_px
    coefficients = list(cam.distortion.coefficients)
    if cam.distortion.model != "equidistant":  # (p1, p2) -> (p2, -p1) clockwise, (-p2, p1) counter-clockwise
        p1, p2 = coefficients[2], coefficients[3]
        coefficients[2], coefficients[3] = (p2, -p1) if clockwise else (-p2, p1)
    if clockwise:  # u' = (H - 1) - v, v' = u
        cx, cy = (h - 1) - cam.cy_px, cam.cx_px
    else:  # u' = v, v' = (W - 1) - u
        cx, cy = cam.cy_px, (w - 1) - cam.cx_px
    return cam.model_copy(update={
        "width_px": h, "height_px": w, "fx_px": cam.fy_px, "fy_px": cam.fx_px, "cx_px": cx, "cy_px": cy,
        "distortion": Distortion(model=cam.distortion.model, coefficients=tuple(coefficients))})


def side_by_side_turn(profile: StereoProfile) -> Turn:
    """The 90-degree turn that puts a vertical rig's second camera to the right of the first (``T'_x < 0``)."""
    T = profile.T.reshape(3)
    clockwise = T[1] > 0  # x' = -y: a second camera above the first (T_y > 0) ends on the right
    M = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]) if clockwise else \
        np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    R = M @ profile.R @ M.T
    extrinsics = profile.extrinsics.model_copy(update={
        "rotation": tuple(tuple(float(v) for v in row) for row in R),
        "translation_m": tuple(float(v) for v in M @ T)})
    turned = profile.model_copy(update={
        "left": _turn_camera(profile.left, clockwise=clockwise),
        "right": _turn_camera(profile.right, clockwise=clockwise),
        "extrinsics": Extrinsics.model_validate(extrinsics.model_dump())})
    code = cv2.ROTATE_90_CLOCKWISE if clockwise else cv2.ROTATE_90_COUNTERCLOCKWISE
    return Turn(M=M, rotate_code=code, profile=turned)
