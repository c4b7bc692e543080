"""Lens models for the renderer: project points through a profile camera and invert its distortion.

PyBullet renders ideal pinhole images only. A camera with distortion is emulated by rendering a wider
pinhole image in the same optical frame and remapping it: for every output (distorted) pixel we find the
undistorted normalised ray with OpenCV's own inverse (``cv2.undistortPoints`` / ``cv2.fisheye``), so
rendered images obey the profile's K and D as ``cv2.projectPoints`` defines them.

Pixel coordinates are OpenCV's: 0-based, pixel centres at integers. Normalised coordinates are
``(X / Z, Y / Z)`` in the camera's optical frame (z forward, x right, y down).
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.errors import RenderError
from s2r.profile import Camera

__all__ = ["is_pinhole", "normalised_rays", "project_points", "undistort_pixels"]

FloatArray = NDArray[np.float64]

#: Stop criteria of OpenCV's iterative undistortion (enough for 1e-6 px round trips on usual lenses).
_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 60, 1e-12)
#: Largest accepted round-trip error of the inverse distortion, pixels.
_MAX_ROUNDTRIP_PX = 1e-3


def is_pinhole(camera: Camera) -> bool:
    """True when the camera is an ideal pinhole without skew (rendered directly, no remap)."""
    return camera.distortion.is_zero and camera.skew == 0.0


def project_points(camera: Camera, points_cam: FloatArray) -> FloatArray:
    """Pixels ``(N, 2)`` of points ``(N, 3)`` in the camera's optical frame (metres), with its distortion."""
    pts = np.ascontiguousarray(points_cam, dtype=np.float64).reshape(-1, 1, 3)
    zero = np.zeros(3)
    if camera.distortion.model == "equidistant":
        out, _ = cv2.fisheye.projectPoints(pts, zero, zero, camera.K, camera.D)
    else:
        out, _ = cv2.projectPoints(pts, zero, zero, camera.K, camera.D)
    return np.asarray(out, dtype=np.float64).reshape(-1, 2)


def undistort_pixels(camera: Camera, pixels: FloatArray) -> FloatArray:
    """Normalised undistorted coordinates ``(N, 2)`` of distorted pixels ``(N, 2)`` of ``camera``.

    Raises RenderError if OpenCV's iterative inverse does not reproduce the pixels (a lens model too strong
    to invert over the image, e.g. a rational model folding back on itself).
    """
    pts = np.ascontiguousarray(pixels, dtype=np.float64).reshape(-1, 1, 2)
    if camera.distortion.model == "equidistant":
        und = cv2.fisheye.undistortPoints(pts, camera.K, camera.D, criteria=_CRITERIA)
    else:
        und = cv2.undistortPoints(pts, camera.K, camera.D, criteria=_CRITERIA)
    norm = np.asarray(und, dtype=np.float64).reshape(-1, 2)
    check = project_points(camera, np.column_stack([norm, np.ones(len(norm))]))
    err = float(np.max(np.abs(check - pts.reshape(-1, 2)))) if len(norm) else 0.0
    if not np.isfinite(err) or err > _MAX_ROUNDTRIP_PX:
        raise RenderError(
            f"the lens distortion cannot be inverted over the image (round trip {err:.3g} px)",
            field="distortion.coefficients", hint="check the distortion coefficients and model",
        )
    return norm


def normalised_rays(camera: Camera, width: int, height: int) -> tuple[FloatArray, FloatArray]:
    """Undistorted normalised ``(x, y)`` grids ``(height, width)`` of every pixel centre of ``camera``."""
    u, v = np.meshgrid(np.arange(width, dtype=np.float64), np.arange(height, dtype=np.float64))
    if is_pinhole(camera):
        return (u - camera.cx_px) / camera.fx_px, (v - camera.cy_px) / camera.fy_px
    norm = undistort_pixels(camera, np.column_stack([u.ravel(), v.ravel()]))
    return norm[:, 0].reshape(height, width), norm[:, 1].reshape(height, width)
