"""Mismatched pixels on a planar target, told apart from noise (numpy only).

Stereo matching on a repeating pattern (a chessboard) returns some pixels a pattern period off: on the real
OpenCV set SGBM matches 7-20 % of a board's pixels one square off. Such pixels are wrong matches, not noise, and
one of them at 10x the distance outweighs every other pixel of an RMS. Two tests, both in the disparity domain
(``d = f B / z``, pixels), where matching errors live:

1. against the ground truth, when known: ``|d - d_true| >= period / 2`` (half a chessboard square, in pixels
   along the rows) is a pattern-period mismatch. Honest depth errs by far less: a disparity off by half a square
   is a depth error of ``square / (2 B)`` (15 % at 25 mm squares and an 83 mm baseline);
2. against the plane fitted to the rest: beyond ``max(5 sigma, BAND_FLOOR_PX)`` of the median residual, sigma the
   robust standard deviation (1.4826 x the median absolute deviation) of the disparity residuals. Gaussian noise
   puts no pixel there. The plane is refitted on the inliers until they stop changing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from s2r.quality.plane import Plane, fit_plane, plane_depth

__all__ = ["BAND_FLOOR_PX", "BAND_SIGMAS", "PlaneFit", "planarity_problem", "robust_plane", "truth_mismatches"]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
#: Width of the robust band around the fitted plane, in robust standard deviations of the disparity residuals.
BAND_SIGMAS = 5.0
#: Smallest half-width of that band, disparity pixels (keeps near-noiseless or quantised depth from reading as
#: all mismatches; a mismatch a pattern period off is many pixels).
BAND_FLOOR_PX = 0.25
#: Flat-wall mode: tiles per side of the planarity check, and the smallest off-plane tile median (disparity px)
#: that makes a region "not a plane" (SGBM's sub-pixel locking alone moves a plane's residuals by up to 0.2 px).
PLANARITY_TILES = 4
PLANARITY_FLOOR_PX = 0.5
_ITERATIONS = 8


@dataclass(frozen=True)
class PlaneFit:
    """The plane fitted to a frame's inliers, the inlier mask (N,) over the valid pixels, the robust standard
    deviation ``sigma_px`` of their disparity residuals and the band's half-width ``band_px`` (pixels)."""

    plane: Plane
    inliers: BoolArray
    sigma_px: float
    band_px: float


def truth_mismatches(z: FloatArray, z_true: FloatArray | None, *, fb_px_m: float,
                     period_px: float | None) -> BoolArray:
    """(N,) True where the disparity of depth ``z`` (metres) lies half a pattern period (``period_px``, pixels)
    or more off the ground truth's ``z_true`` (metres, NaN unknown); all False without a truth or a period."""
    if z_true is None or period_px is None or not period_px > 0:
        return np.zeros(z.shape, bool)
    with np.errstate(divide="ignore", invalid="ignore"):
        off = np.abs(fb_px_m / z - fb_px_m / z_true)
    return np.asarray(np.isfinite(off) & (off >= 0.5 * period_px), bool)


def _points(z: FloatArray, xy: FloatArray) -> FloatArray:
    return np.column_stack([xy * z[:, None], z])


def disparity_residuals(z: FloatArray, xy: FloatArray, plane: Plane, *, fb_px_m: float) -> FloatArray:
    """(N,) ``f B / z - f B / z_plane`` on each pixel's ray (pixels; NaN where the ray misses the plane)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.asarray(fb_px_m / z - fb_px_m / plane_depth(plane, xy), np.float64)


def robust_plane(z: FloatArray, xy: FloatArray, *, fb_px_m: float, keep: BoolArray | None = None) -> PlaneFit:
    """Plane through the valid pixels' points (depth ``z`` (N,) metres on rays ``xy`` (N, 2)), refitted on the
    pixels inside the robust band (module docstring) until the inliers settle; ``keep`` (N,) pre-excludes pixels
    (truth mismatches), which are never inliers."""
    keep = np.ones(z.shape, bool) if keep is None else np.asarray(keep, bool)
    points = _points(z, xy)
    if keep.sum() < 3:
        return PlaneFit(fit_plane(points), np.zeros(z.shape, bool), float("nan"), float("nan"))
    inliers = keep
    sigma = band = float("nan")
    plane = fit_plane(points[keep])
    for _ in range(_ITERATIONS):
        resid = disparity_residuals(z, xy, plane, fb_px_m=fb_px_m)
        usable = keep & np.isfinite(resid)
        if usable.sum() < 3:
            return PlaneFit(plane, np.zeros(z.shape, bool), sigma, band)
        centre = float(np.median(resid[usable]))
        sigma = 1.4826 * float(np.median(np.abs(resid[usable] - centre)))
        band = max(BAND_SIGMAS * sigma, BAND_FLOOR_PX)
        new = usable & (np.abs(resid - centre) <= band)
        if new.sum() < 3 or np.array_equal(new, inliers):
            break
        inliers = new
        plane = fit_plane(points[inliers])
    return PlaneFit(plane, inliers, sigma, band)


def _pixel_noise(resid: FloatArray) -> float:
    """Robust noise of residuals listed in image order (row-major): 1.4826 x the median absolute difference of
    neighbours / sqrt(2). A second surface or a mis-fitted plane moves neighbours together, so neither inflates
    it (the global spread of the residuals would take the structure for noise)."""
    steps = np.diff(resid)
    steps = steps[np.isfinite(steps)]
    return 1.4826 * float(np.median(np.abs(steps))) / np.sqrt(2.0) if steps.size else 0.0


def planarity_problem(z: FloatArray, xy: FloatArray, fit: PlaneFit, *, fb_px_m: float) -> str:
    """Why the valid pixels (``z`` (N,) metres on rays ``xy`` (N, 2)) are not one plane, or "" when they are.

    The region is cut into ``PLANARITY_TILES`` x ``PLANARITY_TILES`` tiles of equal pixel counts (quantiles of x
    and y); a tile whose median disparity residual to the inlier plane exceeds ``max(PLANARITY_FLOOR_PX, 5
    sigma)``, sigma the pixel-to-pixel noise (:func:`_pixel_noise`), holds another surface (a step, an object, a
    corner of the room)."""
    resid = disparity_residuals(z, xy, fit.plane, fb_px_m=fb_px_m)
    edges_x = np.quantile(xy[:, 0], np.linspace(0, 1, PLANARITY_TILES + 1))
    edges_y = np.quantile(xy[:, 1], np.linspace(0, 1, PLANARITY_TILES + 1))
    col = np.clip(np.searchsorted(edges_x, xy[:, 0], side="right") - 1, 0, PLANARITY_TILES - 1)
    row = np.clip(np.searchsorted(edges_y, xy[:, 1], side="right") - 1, 0, PLANARITY_TILES - 1)
    least = max(20, z.size // (4 * PLANARITY_TILES**2))
    medians: dict[tuple[int, int], float] = {}
    for r in range(PLANARITY_TILES):
        for c in range(PLANARITY_TILES):
            values = resid[(row == r) & (col == c)]
            values = values[np.isfinite(values)]
            if values.size >= least:
                medians[(r, c)] = float(np.median(values))
    if not medians:
        return ""
    limit = max(PLANARITY_FLOOR_PX, BAND_SIGMAS * _pixel_noise(resid))
    where = max(medians, key=lambda k: abs(medians[k]))
    worst = medians[where]
    if abs(worst) <= limit:
        return ""
    return (f"tile (row {where[0] + 1}, column {where[1] + 1}) of a {PLANARITY_TILES}x{PLANARITY_TILES} grid sits "
            f"{worst:+.2f} px of disparity off the best-fit plane (limit {limit:.2f} px): aim at a flat wall or "
            "pass a smaller --roi")
