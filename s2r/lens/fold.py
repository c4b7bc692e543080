"""Whether a solved lens model can serve its whole image: a loud check on what the fit figures cannot see.

OpenCV's pinhole distortion moves a point at undistorted normalised radius ``r`` (``sqrt(x^2 + y^2)`` with
``x = X / Z``, ``y = Y / Z`` in the camera's optical frame) to the distorted radius

    r_d(r) = r (1 + k1 r^2 + k2 r^4 + k3 r^6) / (1 + k4 r^2 + k5 r^4 + k6 r^6)

(plumb_bob: k4 = k5 = k6 = 0; the tangential p1 p2 are small and left out). A pixel at distorted radius ``q``
(from the principal point, in focal lengths) is undistorted by finding ``r`` with ``r_d(r) = q`` on the branch
that starts at the axis. That fails when, before ``r_d`` reaches the farthest image corner:

- **it folds over**: ``r_d`` stops growing with the ray's angle (its slope ``d r_d / d r`` falls under
  :data:`MIN_SLOPE`: near there a pixel spans 20 or more times its share of rays, and the tangential terms
  left out here fold it outright), so two rays land on one pixel and pixels beyond have no ray;
- **it never gets there**: still short of the corner for rays at 89.5 degrees;
- **it stretches beyond a pinhole lens**: the radial factor ``r_d / r`` at the corner is outside
  :data:`STRETCH_RANGE` (a near-cancelling rational model whose denominator reaches zero maps the whole image
  into a few degrees; OpenCV's iterative undistortion then misses by tens of pixels).

The fit cannot see any of this when no board reached that part of the image: its residuals, held-out error
and even the lens-model comparison are measured where the boards were. On seven real sets the default
k1k2p1p2 fits pass (the closest fold at 103 % of the way to the farthest corner, radial factors 0.81-1.31),
while ``--distortion rational`` fails on three of six single-camera fits (coefficients of 8-750 whose numerator
and denominator nearly cancel), unseen by every other figure: folds at 79 % and 93 % of the way, and a
stretch of 2.6x where numerator and denominator share a root inside the image.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from s2r.profile import Camera

__all__ = ["FOLD_MODELS", "MIN_SLOPE", "STRETCH_RANGE", "corner_radius", "fold_radius", "fold_warnings",
           "radial_problem"]

#: The profile distortion models whose radial mapping is checked (the equidistant fisheye model is another
#: mapping and is not).
FOLD_MODELS = ("plumb_bob", "rational_polynomial")
#: Smallest slope ``d r_d / d r`` counted as still growing.
MIN_SLOPE = 0.05
#: Radial factors ``r_d / r`` at the farthest corner accepted: the default fits of seven real sets span 0.81
#: (OpenCV's sample camera, barrel) to 1.31; a lens beyond 0.4 is better served by the fisheye model. A
#: near-cancelling rational fit whose numerator and denominator share a root inside the image reads 2.6.
STRETCH_RANGE = (0.4, 2.0)
#: Rays sampled evenly in angle from the axis to this many degrees.
_MAX_ANGLE_DEG = 89.5
_SAMPLES = 40_000

FloatArray = NDArray[np.float64]


def _radial(coefficients: Sequence[float]) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Undistorted radii (evenly spaced in angle), the numerator and denominator factors, and r_d there."""
    k = [float(c) for c in coefficients] + [0.0] * 8
    k1, k2, k3, k4, k5, k6 = k[0], k[1], k[4], k[5], k[6], k[7]
    r = np.tan(np.linspace(0.0, math.radians(_MAX_ANGLE_DEG), _SAMPLES))
    r2 = r * r
    num = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
    den = 1 + r2 * (k4 + r2 * (k5 + r2 * k6))
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        rd = r * num / den
    return r, num, den, rd


def _first(mask: NDArray[np.bool_]) -> int | None:
    return int(np.argmax(mask)) if mask.any() else None


def fold_radius(coefficients: Sequence[float]) -> float | None:
    """The distorted normalised radius at which the radial mapping of OpenCV coefficients ``k1 k2 p1 p2 [k3
    [k4 k5 k6]]`` folds over (its slope falls under :data:`MIN_SLOPE`: within 0.1 % of the radius where it
    stops growing); None when it grows all the way to 89.5 degrees or up to a denominator zero (where it
    grows without bound)."""
    r, _, den, rd = _radial(coefficients)
    return _fold(r, rd, _first(den <= 0))


def _fold(r: FloatArray, rd: FloatArray, end: int | None) -> float | None:
    """:func:`fold_radius` of the sampled curve ``rd(r)`` whose denominator first reaches zero at ``end``."""
    with np.errstate(divide="ignore", invalid="ignore"):
        slope = np.diff(rd[:end]) / np.diff(r[:end])
    i = _first(~(slope >= MIN_SLOPE))  # NaN counts as not growing
    return None if i is None else float(rd[i])


def corner_radius(cam: Camera) -> float:
    """The largest distorted normalised radius of the image's four corner pixels (``(u - cx) / fx`` etc.)."""
    us = np.array([0.0, cam.width_px - 1.0])
    vs = np.array([0.0, cam.height_px - 1.0])
    x, y = (us - cam.cx_px) / cam.fx_px, (vs - cam.cy_px) / cam.fy_px
    return float(np.max(np.hypot(x[:, None], y[None, :])))


def radial_problem(coefficients: Sequence[float], corner: float) -> str:
    """What keeps the radial mapping from serving every pixel out to the distorted radius ``corner`` (see the
    module docstring), in words without the remedy; '' when nothing does."""
    r, num, den, rd = _radial(coefficients)
    end = _first(den <= 0)
    fold = _fold(r, rd, end)
    if fold is not None and fold < corner:
        return (f"folds over at {math.floor(100 * fold / corner)} % of the way from the principal point to the "
                "farthest image corner (its distortion stops growing with the ray's angle: two rays land on one "
                "pixel, so pixels beyond cannot be undistorted or rectified)")
    reach = _first(rd[:end] >= corner)
    if reach is not None:
        r_corner = float(r[reach])
    elif end is not None and num[end - 1] > 0:  # r_d grows without bound towards the denominator's zero
        r_corner = float(r[end])
    else:
        top = float(np.nanmax(rd[:end]))  # the denominator is 1 on the axis: end is None or at least 1
        return (f"reaches only {math.floor(100 * top / corner)} % of the way from the principal point to the "
                "farthest image corner even for rays at 89.5 degrees (pixels beyond have no ray)")
    stretch = corner / max(r_corner, 1e-12)
    if STRETCH_RANGE[0] <= stretch <= STRETCH_RANGE[1]:
        return ""
    why = ("its coefficients nearly cancel, and undistortion there is unreliable" if stretch > STRETCH_RANGE[1]
           else "a lens this wide is beyond the pinhole model")
    return (f"stretches the image {stretch:.3g}x at its farthest corner (the radial distortion factor; the pinhole "
            f"model serves lenses within {STRETCH_RANGE[0]:g}-{STRETCH_RANGE[1]:g}x): {why}")


def _remedy(coefficients: Sequence[float]) -> str:
    """What to do: drop the higher terms a fit extrapolated (k3, or the rational k4 k5 k6) when it has them, or
    cover the corners (a lens whose two-term model cannot serve its image is wide: fisheye may suit it)."""
    if any(float(c) != 0.0 for c in coefficients[4:]):
        return "use fewer lens terms (--distortion k1k2p1p2) or add views with the board near the image corners"
    return "add views with the board near the image corners; a lens this wide may need --lens fisheye"


def fold_warnings(cameras: Sequence[tuple[str, Camera]]) -> list[str]:
    """One line per camera (``(label, camera)``, label e.g. ``left``) whose lens model cannot serve its whole
    image (:func:`radial_problem`), saying how and what to do; [] when every one can (or is not a pinhole
    polynomial model)."""
    out = []
    for label, cam in cameras:
        if cam.distortion.model not in FOLD_MODELS:
            continue
        corner = corner_radius(cam)
        problem = radial_problem(cam.distortion.coefficients, corner)
        if problem:
            out.append(f"{label} camera: the {cam.distortion.model} lens model {problem}; "
                       f"{_remedy(cam.distortion.coefficients)}")
    return out
