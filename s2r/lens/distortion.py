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

__all__ = ["distort_normalised", "is_pinhole", "normalised_rays", "project_points", "undistort_pixels"]

FloatArray = NDArray[np.float64]

#: OpenCV's iterative undistortion gives the start; Newton steps on the forward model polish it.
_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 10, 1e-12)
_NEWTON_STEPS = 2
_STEP = 1e-7
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


def distort_normalised(camera: Camera, x: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray]:
    """OpenCV's forward lens model on normalised coordinates (same formulas as ``cv2.projectPoints`` and
    ``cv2.fisheye.projectPoints``, vectorised): returns distorted normalised ``(xd, yd)``."""
    D = camera.D
    if camera.distortion.model == "equidistant":
        r = np.hypot(x, y)
        theta = np.arctan(r)
        t2 = theta * theta
        theta_d = theta * (1 + t2 * (D[0] + t2 * (D[1] + t2 * (D[2] + t2 * D[3]))))
        scale = np.where(r > 1e-12, theta_d / np.maximum(r, 1e-12), 1.0)
        return x * scale, y * scale
    k = np.zeros(8)
    k[: len(D)] = D
    r2 = x * x + y * y
    radial = (1 + r2 * (k[0] + r2 * (k[1] + r2 * k[4]))) / (1 + r2 * (k[5] + r2 * (k[6] + r2 * k[7])))
    xd = x * radial + 2 * k[2] * x * y + k[3] * (r2 + 2 * x * x)
    yd = y * radial + k[2] * (r2 + 2 * y * y) + 2 * k[3] * x * y
    return xd, yd


def _newton(camera: Camera, norm: FloatArray, target: FloatArray) -> FloatArray:
    """Polish undistorted ``norm`` (N, 2) so that distorting it gives ``target`` (N, 2), both normalised."""
    x, y = norm[:, 0].copy(), norm[:, 1].copy()
    tx, ty = target[:, 0], target[:, 1]
    for _ in range(_NEWTON_STEPS):
        fx, fy = distort_normalised(camera, x, y)
        ax, ay = distort_normalised(camera, x + _STEP, y)
        bx, by = distort_normalised(camera, x, y + _STEP)
        j11, j21, j12, j22 = (ax - fx) / _STEP, (ay - fy) / _STEP, (bx - fx) / _STEP, (by - fy) / _STEP
        det = j11 * j22 - j12 * j21
        det = np.where(np.abs(det) > 1e-12, det, 1e-12)
        ex, ey = fx - tx, fy - ty
        x -= (j22 * ex - j12 * ey) / det
        y -= (-j21 * ex + j11 * ey) / det
    return np.column_stack([x, y])


def undistort_pixels(camera: Camera, pixels: FloatArray) -> FloatArray:
    """Normalised undistorted coordinates ``(N, 2)`` of distorted pixels ``(N, 2)`` of ``camera``.

    OpenCV's iterative inverse (``cv2.undistortPoints`` / ``cv2.fisheye.undistortPoints``) gives the start,
    Newton steps on the forward model make the round trip exact (< 1e-3 px, checked). Raises RenderError
    when the lens model cannot be inverted over the image (e.g. a rational model folding back on itself).
    """
    pts = np.ascontiguousarray(pixels, dtype=np.float64).reshape(-1, 1, 2)
    if camera.distortion.model == "equidistant":
        und = cv2.fisheye.undistortPoints(pts, camera.K, camera.D, criteria=_CRITERIA)
    else:
        und = cv2.undistortPoints(pts, camera.K, camera.D, criteria=_CRITERIA)
    flat = pts.reshape(-1, 2)
    f, c = np.array([camera.fx_px, camera.fy_px]), np.array([camera.cx_px, camera.cy_px])
    target = (flat - c) / f
    norm = _newton(camera, np.asarray(und, dtype=np.float64).reshape(-1, 2), target)
    xd, yd = distort_normalised(camera, norm[:, 0], norm[:, 1])
    check = np.column_stack([xd, yd]) * f + c
    err = float(np.max(np.abs(check - flat))) if len(norm) else 0.0
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
