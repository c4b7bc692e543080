"""Gazebo camera conventions: intrinsics from ``horizontal_fov`` and Gazebo's distortion units.

Intrinsics (REFERENCE.md), W x H pixels, ``f = W / (2 tan(hfov / 2))`` in every convention:

- ``gazebo-classic`` (gazebo_ros camera plugins): fx = fy = f, cx = (W + 1) / 2, cy = (H + 1) / 2.
- ``gz-sim``: fx = fy = f, cx = W / 2, cy = H / 2, unless ``<lens><intrinsics>`` gives fx, fy, cx, cy, s.
- ``exact``: fx = fy = f, cx = (W - 1) / 2, cy = (H - 1) / 2: the true centre of the rendered image in
  OpenCV's 0-based pixel-centre convention.

A centred render therefore *publishes* a principal point :data:`CENTRE_OFFSET_PX` pixels right of and
below the exact one; the profile records which convention its numbers follow.

Distortion (gazebo-classic issue 3003): Gazebo applies Brown's model to texture coordinates, i.e. to
``x_n = (u - c_u) / W`` and ``y_n = (v - c_v) / H`` (image-size-normalised, per axis), while OpenCV
applies it to focal-normalised ``x = (u - cx) / fx``, ``y = (v - cy) / fy``. With ``a = fx / W = fy / H``
(square pixels AND a square image, or matching aspect) the conversion is exact:
``k1_cv = k1_gz a^2``, ``k2_cv = k2_gz a^4``, ``k3_cv = k3_gz a^6``, ``p_cv = p_gz a``. Otherwise no
5-term OpenCV model equals Gazebo's, so both directions here are linear least-squares fits of the
pixel displacement over the image (both models are linear in their coefficients) and report the
residual in pixels: that residual is the documented limit of the conversion.

Which units each simulator uses (read from their source, 2026-11):

- Gazebo classic 11 (gazebo/rendering/Distortion.cc, ``Distortion::Distort``): the image-size-normalised model
  above by default; ``<ignition:legacy_mode>false</ignition:legacy_mode>`` inside ``<distortion>`` (PR 3009)
  multiplies texture offsets by ``W / f`` first. Both normalise x and y by the same length on a texture that is
  stretched to W x H, so neither is OpenCV's model on a non-square image: they differ only in the coefficients'
  units. The gazebo_ros camera plugins (gazebo_ros_camera_utils.cpp, ``GazeboRosCameraUtils::Init``) crop
  barrel-distorted images (k1 < 0) to hide the black border unless ``<borderCrop>false</borderCrop>``; the crop
  magnifies the image and changes the focal length.
- gz-sim (gz-rendering ogre/src/OgreDistortionPass.cc, ``OgreDistortionPass::Distort``): always the scaled form,
  ``n' = (t - center) * S / F`` with ``S = max(W, H)`` and ``F = S / (2 tan(fov / 2))``, ``fov`` =
  ``FOVy * aspect`` (W >= H) or ``FOVy`` (H > W), where Ogre's ``FOVy = 2 atan(tan(hfov / 2) / aspect)``
  (ogre/src/OgreCamera.cc ``SetHFOV``). So gz-sim coefficients are the image-normalised ones divided by
  ``s^2, s^4, s^6`` (k1, k2, k3) and ``s`` (p1, p2) with ``s = 2 tan(fov / 2)``
  (:func:`gz_sim_distortion_scale`). Only the ogre (1.x) engine has a distortion pass; gz-sensors' default ogre2
  renders undistorted (``ImageBrownDistortionModel::SetCamera``: "not supported"); the pass always crops k1 < 0.
- Both honour ``<lens><intrinsics>`` (classic ``Camera::LoadCameraIntrinsics``; gz-sensors
  ``CameraSensor::UpdateLensIntrinsicsAndProjection``) with the principal point in continuous pixel coordinates
  (the image's left edge at 0): OpenCV's 0-based ``cx`` + 0.5.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from s2r.errors import SourceError
from s2r.profile import CENTRE_OFFSET_PX
from s2r.sources.description import FloatArray, LensIntrinsics

__all__ = [
    "CENTRE_OFFSET_PX",
    "CONVENTIONS",
    "LENS_OFFSET_PX",
    "DistortionFit",
    "Intrinsics",
    "check_convention",
    "classic_distortion_scale",
    "crop_magnification",
    "focal_from_hfov",
    "gazebo_to_opencv_distortion",
    "gz_sim_distortion_scale",
    "hfov_from_focal",
    "intrinsics_for",
    "opencv_to_gazebo_distortion",
    "scale_distortion",
    "texture_center",
]

CONVENTIONS = ("gazebo-classic", "gz-sim", "exact")
#: ``<lens><intrinsics>`` cx, cy minus OpenCV's 0-based principal point, pixels (continuous coordinates).
LENS_OFFSET_PX = 0.5
# CENTRE_OFFSET_PX (published principal point minus the exact centre) lives in s2r.profile, re-exported here.


class Intrinsics(NamedTuple):
    """Pinhole intrinsics in pixels (in the convention they were computed for)."""

    fx: float
    fy: float
    cx: float
    cy: float
    skew: float = 0.0


class DistortionFit(NamedTuple):
    """Converted coefficients and how far the converted model is from the original, in pixels."""

    coefficients: tuple[float, float, float, float, float]
    rms_px: float
    max_px: float


def check_convention(convention: str) -> str:
    """Return ``convention`` if known; SourceError listing the known ones otherwise."""
    if convention not in CONVENTIONS:
        raise SourceError(f"unknown convention {convention!r}", field="--convention",
                          hint=f"use one of {', '.join(CONVENTIONS)}")
    return convention


def focal_from_hfov(width_px: int, hfov_rad: float) -> float:
    """Focal length in pixels of a ``width_px`` wide image with horizontal FOV ``hfov_rad``."""
    return width_px / (2.0 * math.tan(hfov_rad / 2.0))


def hfov_from_focal(width_px: int, fx_px: float) -> float:
    """Exact inverse of :func:`focal_from_hfov`: ``2 atan(W / (2 fx))`` radians."""
    return 2.0 * math.atan(width_px / (2.0 * fx_px))


def intrinsics_for(width_px: int, height_px: int, hfov_rad: float, convention: str,
                   lens: LensIntrinsics | None = None) -> Intrinsics:
    """Intrinsics a camera of this size and FOV renders with, its principal point expressed in ``convention``.

    ``<lens><intrinsics>`` wins when given (both simulators render with it; its cx, cy are OpenCV's + 0.5)."""
    check_convention(convention)
    offset = CENTRE_OFFSET_PX[convention]
    if lens is not None:
        shift = offset - LENS_OFFSET_PX
        return Intrinsics(lens.fx, lens.fy, lens.cx + shift, lens.cy + shift, lens.s)
    f = focal_from_hfov(width_px, hfov_rad)
    return Intrinsics(f, f, (width_px - 1) / 2.0 + offset, (height_px - 1) / 2.0 + offset)


def gz_sim_distortion_scale(width_px: int, height_px: int, hfov_rad: float) -> float:
    """``s = 2 tan(fov / 2)``: gz-rendering's distortion units are the image-normalised ones scaled by ``s``
    (k1 by ``s^2``, k2 ``s^4``, k3 ``s^6``, p1 p2 ``s``): ``k_image = k_gz * s^2``. ``fov`` as
    OgreDistortionPass computes it from Ogre's vertical FOV (see the module docstring)."""
    aspect = width_px / height_px
    fovy = 2.0 * math.atan(math.tan(hfov_rad / 2.0) / aspect)
    fov = fovy * aspect if width_px >= height_px else fovy
    return 2.0 * math.tan(fov / 2.0)


def classic_distortion_scale(width_px: int, height_px: int, hfov_rad: float) -> float:
    """Gazebo classic with ``<ignition:legacy_mode>false``: ``s = 2 tan(fov / 2)`` with its own ``fov`` (HFOV,
    or the VFOV ``2 atan(tan(hfov / 2) H / W)`` when H > W; Distortion::SetCamera): ``W / f`` for W >= H."""
    fov = hfov_rad if width_px >= height_px else 2.0 * math.atan(math.tan(hfov_rad / 2.0) * height_px / width_px)
    return 2.0 * math.tan(fov / 2.0)


def scale_distortion(coefficients: tuple[float, ...], s: float) -> tuple[float, float, float, float, float]:
    """Gazebo ``(k1, k2, k3, p1, p2)`` in image-normalised units -> units scaled by ``s``
    (divide by ``s^2, s^4, s^6, s, s``); pass ``1 / s`` for the way back."""
    k1, k2, k3, p1, p2 = coefficients
    return (k1 / s**2, k2 / s**4, k3 / s**6, p1 / s, p2 / s)


def _grid(width: int, height: int, steps: int = 24) -> tuple[FloatArray, FloatArray]:
    """Pixel offsets from the exact image centre on a grid covering the whole image."""
    u = np.linspace(0.0, width - 1.0, steps + 1) - (width - 1) / 2.0
    v = np.linspace(0.0, height - 1.0, steps + 1) - (height - 1) / 2.0
    du, dv = np.meshgrid(u, v)
    return du.ravel(), dv.ravel()


def _design(x: FloatArray, y: FloatArray, sx: float, sy: float) -> FloatArray:
    """Pixel displacement per unit coefficient, columns (k1, k2, k3, p1, p2), rows u then v."""
    r2 = x * x + y * y
    cols_u = [x * r2, x * r2**2, x * r2**3, 2 * x * y, r2 + 2 * x * x]
    cols_v = [y * r2, y * r2**2, y * r2**3, r2 + 2 * y * y, 2 * x * y]
    return np.vstack([np.column_stack(cols_u) * sx, np.column_stack(cols_v) * sy])


def _models(width: int, height: int, fx: float, fy: float, center: tuple[float, float],
            principal: tuple[float, float] | None = None) -> tuple[FloatArray, FloatArray]:
    """Design matrices of the OpenCV model (about the principal point ``principal``, exact 0-based pixels;
    default the image centre) and of Gazebo's (about ``center`` in texture coordinates) on one pixel grid."""
    du, dv = _grid(width, height)
    cx, cy = principal if principal is not None else ((width - 1) / 2.0, (height - 1) / 2.0)
    x_cv = (du + (width - 1) / 2.0 - cx) / fx
    y_cv = (dv + (height - 1) / 2.0 - cy) / fy
    a_cv = _design(x_cv, y_cv, fx, fy)
    xn, yn = du / width + 0.5 - center[0], dv / height + 0.5 - center[1]
    return a_cv, _design(xn, yn, float(width), float(height))


def texture_center(width: int, height: int, cx: float, cy: float) -> tuple[float, float]:
    """Gazebo's ``<distortion><center>`` (texture coordinates, 0.5 0.5 = image centre) of a principal point
    ``(cx, cy)`` in exact 0-based pixel-centre coordinates: ``((cx + 0.5) / W, (cy + 0.5) / H)``."""
    return (cx + 0.5) / width, (cy + 0.5) / height


def _fit(source: FloatArray, target: FloatArray, coeffs: FloatArray) -> tuple[FloatArray, float, float]:
    wanted = source @ coeffs
    solved = np.asarray(np.linalg.lstsq(target, wanted, rcond=None)[0], dtype=np.float64)
    diff = (target @ solved - wanted).reshape(2, -1)
    err = np.hypot(diff[0], diff[1])
    return solved, float(np.sqrt(np.mean(err**2))), float(np.max(err))


def _fit_used(source: FloatArray, target: FloatArray, coeffs: FloatArray) -> tuple[FloatArray, float, float]:
    """:func:`_fit` over only the terms ``coeffs`` (k1, k2, k3, p1, p2) uses: k1, k2 when k2 or k3 is set, k3 when
    set, both tangential terms when either is set. Free extra terms would only chase the aspect-ratio residual
    and make the converted model non-invertible near the image corners."""
    _, k2, k3, p1, p2 = (float(v) for v in coeffs)
    used = [True, k2 != 0.0 or k3 != 0.0, k3 != 0.0, p1 != 0.0 or p2 != 0.0, p1 != 0.0 or p2 != 0.0]
    cols = [i for i, keep in enumerate(used) if keep]
    solved_used, rms, worst = _fit(source, target[:, cols], coeffs)
    solved = np.zeros(5)
    solved[cols] = solved_used
    return solved, rms, worst


def gazebo_to_opencv_distortion(k1: float, k2: float, k3: float, p1: float, p2: float, *, width: int, height: int,
                                fx: float, fy: float, center: tuple[float, float] = (0.5, 0.5),
                                principal: tuple[float, float] | None = None) -> DistortionFit:
    """OpenCV plumb_bob ``(k1, k2, p1, p2, k3)`` closest to Gazebo's ``<distortion>`` on a W x H image.

    ``principal``: the OpenCV principal point (exact 0-based pixels) the coefficients will be used with;
    default the image centre. Only the terms the Gazebo model uses are fitted (see :func:`_fit_used`)."""
    a_cv, a_gz = _models(width, height, fx, fy, center, principal)
    solved = _fit_used(a_gz, a_cv, np.array([k1, k2, k3, p1, p2]))
    c = [float(v) for v in solved[0]]
    return DistortionFit((c[0], c[1], c[3], c[4], c[2]), solved[1], solved[2])


def opencv_to_gazebo_distortion(coefficients: tuple[float, ...], *, width: int, height: int, fx: float,
                                fy: float, principal: tuple[float, float] | None = None) -> DistortionFit:
    """Gazebo ``(k1, k2, k3, p1, p2)`` closest to OpenCV plumb_bob ``(k1, k2, p1, p2, k3)``, with Gazebo's
    distortion centre at the principal point (:func:`texture_center` of ``principal``; default the image centre).

    Only the terms the OpenCV model uses are fitted (see :func:`_fit_used`)."""
    k1, k2, p1, p2, k3 = (tuple(coefficients) + (0.0,) * 5)[:5]
    cx, cy = principal if principal is not None else ((width - 1) / 2.0, (height - 1) / 2.0)
    a_cv, a_gz = _models(width, height, fx, fy, texture_center(width, height, cx, cy), (cx, cy))
    solved, rms, worst = _fit_used(a_cv, a_gz, np.array([k1, k2, k3, p1, p2]))
    c = [float(v) for v in solved]
    return DistortionFit((c[0], c[1], c[2], c[3], c[4]), rms, worst)


def crop_magnification(coefficients: tuple[float, float, float, float, float],
                       center: tuple[float, float]) -> tuple[float, float]:
    """How much Gazebo's border crop magnifies a barrel-distorted image (x, y), >= 1; (1, 1) when k1 >= 0.

    ``coefficients``: Gazebo ``(k1, k2, k3, p1, p2)`` in image-normalised units; ``center`` in texture
    coordinates. The crop scales the output by the span of the distorted image corners (0, 0) and (1, 1)
    (``Distortion::CalculateAndApplyDistortionScale``), so focal lengths grow by this factor."""
    if coefficients[0] >= 0:
        return 1.0, 1.0

    def distort(u: float, v: float) -> tuple[float, float]:
        k1, k2, k3, p1, p2 = coefficients
        x, y = u - center[0], v - center[1]
        r2 = x * x + y * y
        radial = 1.0 + k1 * r2 + k2 * r2**2 + k3 * r2**3
        return (x * radial + p2 * (r2 + 2 * x * x) + 2 * p1 * x * y,
                y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y)

    (ax, ay), (bx, by) = distort(0.0, 0.0), distort(1.0, 1.0)
    return 1.0 / (bx - ax), 1.0 / (by - ay)
