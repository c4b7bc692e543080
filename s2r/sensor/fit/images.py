"""Image noise and blur of a camera, measured on chessboard images (numpy, scipy, OpenCV).

- Noise, from repeated frames of a still pose (board corners within :data:`STILL_PX` RMS of each other): each
  flat board pixel's variance across the frames, averaged over the board, in grey levels. Without repeats, from
  the flat squares: inside each square, away from its edges by three blur sigmas plus two pixels, the residual
  variance about a fitted plane ``a + b x + c y`` (lighting gradients), the median over the squares (chi-square
  scaled). A square touching 0 or 255 (clipped) gives the sigma of a normal distribution censored there
  (maximum likelihood, a constant level); still frames leave clipped pixels out. Rounding to integers adds
  1/12 DN^2, which is taken out.
- Blur, from the board's edges: along every edge between two neighbouring inner corners (its middle 60 %), the
  grey level against the signed distance from the edge line is fitted with ``a + b Phi((d - delta) / s)``; the
  median ``s`` over the edges is the edge spread (see :mod:`s2r.sensor.model`). It includes whatever the pixel's
  footprint adds: measured on 6 boards imaged by area-averaging 4x4 samples per pixel then blurred by sigma,
  ``s`` was sigma +8 % at 0.6 px and +0.5 % at 2 px; imaged by one sample per pixel (aliased), -6 % at 0.8 px
  and -24 % at 0.5 px (a discrete blur of an aliased edge is narrower than the blur).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray
from scipy.optimize import curve_fit, minimize
from scipy.special import ndtr
from scipy.stats import chi2

__all__ = ["ROUNDING_VAR", "STILL_PX", "BoardImage", "edge_spread_px", "image_blur_px",
           "image_noise_dn", "still_groups", "temporal_noise_var"]

FloatArray = NDArray[np.float64]
#: Board corners within this RMS distance (px) of a group's first frame: the same still pose.
STILL_PX = 0.3
#: Variance of rounding to integer grey levels (DN^2).
ROUNDING_VAR = 1.0 / 12.0
_MIN_SQUARE_PIXELS = 20
_MIN_EDGE_PX = 8.0


@dataclass(frozen=True)
class BoardImage:
    """One 8-bit grey image (H, W) and its chessboard's inner corners (N, 2) px, row-major over the pattern."""

    name: str
    grey: NDArray[np.uint8]
    corners: NDArray[np.float32]
    pattern: tuple[int, int]

    def grid(self) -> NDArray[np.float64]:
        """Corners as (rows, cols, 2)."""
        cols, rows = self.pattern
        return np.asarray(self.corners, np.float64).reshape(rows, cols, 2)


def _chi2_scaled_median(variances: Sequence[float], dof: float) -> float:
    """Median of sample variances with ``dof`` degrees of freedom, scaled to estimate the variance."""
    return float(np.median(variances)) * dof / float(chi2.median(dof))


def still_groups(images: Sequence[BoardImage]) -> list[list[int]]:
    """Indices of images grouped by still pose (same corners within :data:`STILL_PX` RMS), groups of two or more."""
    groups: list[list[int]] = []
    for i, img in enumerate(images):
        for group in groups:
            ref = images[group[0]].corners
            if ref.shape == img.corners.shape and math.sqrt(float(np.mean(np.sum(
                    (ref.astype(np.float64) - img.corners) ** 2, axis=1)))) < STILL_PX:
                group.append(i)
                break
        else:
            groups.append([i])
    return [g for g in groups if len(g) >= 2]


def _board_mask(img: BoardImage) -> NDArray[np.bool_]:
    grid = img.grid()
    quad = np.array([grid[0, 0], grid[0, -1], grid[-1, -1], grid[-1, 0]])
    mask = np.zeros(img.grey.shape[:2], np.uint8)
    cv2.fillConvexPoly(mask, np.round(quad * 16).astype(np.int32), 1, lineType=cv2.LINE_8, shift=4)
    return mask.astype(bool)


def temporal_noise_var(images: Sequence[BoardImage], group: Sequence[int]) -> float | None:
    """Noise variance (DN^2, rounding included) of one still group: each flat board pixel's variance across the
    frames (unbiased), averaged. Flat: the frames' mean image spans under a fifth of the board's contrast within
    5x5 px (edges left out: a still pose's sub-pixel jitter would read as noise there); clipped pixels left out."""
    mean64, var, unclipped = _running_moments(images, group)
    board = _board_mask(images[group[0]])
    mean = mean64.astype(np.float32)
    kernel = np.ones((5, 5), np.uint8)
    span = cv2.dilate(mean, kernel) - cv2.erode(mean, kernel)
    lo, hi = np.percentile(mean[board], [5, 95]) if board.any() else (0.0, 0.0)
    mask = board & unclipped & (span < 0.2 * (hi - lo))
    if mask.sum() < _MIN_SQUARE_PIXELS:
        return None
    return float(np.mean(var[mask]))


def _running_moments(images: Sequence[BoardImage], group: Sequence[int]
                     ) -> tuple[FloatArray, FloatArray, NDArray[np.bool_]]:
    """Per-pixel mean, unbiased variance (DN, DN^2) and "never clipped" of a still group's frames, summed one frame
    at a time (Welford): two (H, W) float64 arrays, where a float64 stack of 300 frames at 848x480 took 2.2 GB."""
    first = images[group[0]].grey
    mean = np.zeros(first.shape, np.float64)
    m2 = np.zeros(first.shape, np.float64)
    unclipped = np.ones(first.shape, bool)
    for n, i in enumerate(group, start=1):
        x = images[i].grey.astype(np.float64)
        unclipped &= (x > 0) & (x < 255)
        delta = x - mean
        mean += delta / n
        m2 += delta * (x - mean)
    return mean, m2 / max(len(group) - 1, 1), unclipped


def _censored_var(values: FloatArray) -> float | None:
    """Noise variance (DN^2) of a flat square whose grey levels are clipped at 0 and/or 255: the maximum-likelihood
    mean and sigma of a normal distribution censored below 0.5 and above 254.5 (None when fewer than a tenth of the
    pixels, or 10, are unclipped)."""
    low, high = values <= 0, values >= 255
    mid = values[~(low | high)]
    if mid.size < max(10, values.size // 10):
        return None
    n_low, n_high = int(low.sum()), int(high.sum())

    def nll(params: FloatArray) -> float:
        mu, log_s = float(params[0]), float(params[1])
        s = math.exp(log_s)
        total = float(np.sum(0.5 * ((mid - mu) / s) ** 2)) + mid.size * log_s
        if n_low:
            total -= n_low * math.log(max(float(ndtr((0.5 - mu) / s)), 1e-300))
        if n_high:
            total -= n_high * math.log(max(float(ndtr((mu - 254.5) / s)), 1e-300))
        return total

    spread = max(1.4826 * float(np.median(np.abs(mid - np.median(mid)))), 0.5)
    result = minimize(nll, np.array([float(np.median(values)), math.log(spread)]), method="Nelder-Mead",
                      options={"xatol": 1e-4, "fatol": 1e-6, "maxiter": 400})
    return math.exp(2.0 * float(result.x[1])) if result.success else None


def _square_vars(img: BoardImage, margin_px: float) -> list[tuple[float, int]]:
    """(noise variance, dof) of each square interior: the residual variance about a plane, or for a clipped
    square the censored normal's (:func:`_censored_var`)."""
    grid, grey = img.grid(), img.grey
    out = []
    for r in range(grid.shape[0] - 1):
        for c in range(grid.shape[1] - 1):
            quad = np.array([grid[r, c], grid[r, c + 1], grid[r + 1, c + 1], grid[r + 1, c]])
            side = min(np.linalg.norm(quad - np.roll(quad, 1, axis=0), axis=1))
            shrink = 1.0 - 2.0 * margin_px / side
            if shrink < 0.2:
                continue
            centre = quad.mean(axis=0)
            inner = centre + shrink * (quad - centre)
            mask = np.zeros(grey.shape[:2], np.uint8)
            cv2.fillConvexPoly(mask, np.round(inner * 16).astype(np.int32), 1, lineType=cv2.LINE_8, shift=4)
            ys, xs = np.nonzero(mask)
            values = grey[ys, xs].astype(np.float64)
            if values.size < _MIN_SQUARE_PIXELS:
                continue
            if values.min() <= 0 or values.max() >= 255:
                var = _censored_var(values)
                if var is not None:
                    out.append((var, values.size - 2))
                continue
            design = np.column_stack([np.ones(values.size), xs, ys]).astype(np.float64)
            coef, *_ = np.linalg.lstsq(design, values, rcond=None)
            resid = values - design @ coef
            out.append((float(resid @ resid) / (values.size - 3), values.size - 3))
    return out


def image_noise_dn(images: Sequence[BoardImage], *, blur_px: float) -> tuple[float | None, str]:
    """Grey-level noise sigma (DN, rounding taken out) and how it was measured (module docstring)."""
    groups = still_groups(images)
    temporal = [v for g in groups if (v := temporal_noise_var(images, g)) is not None]
    if temporal:
        var, how = float(np.median(temporal)), f"temporal, {len(temporal)} still pose(s)"
    else:
        squares = [s for img in images for s in _square_vars(img, 3.0 * blur_px + 2.0)]
        if not squares:
            return None, "no flat square large enough (or all clipped)"
        var = _chi2_scaled_median([v for v, _ in squares], float(np.median([d for _, d in squares])))
        how = f"flat squares, {len(squares)} squares"
    return math.sqrt(max(var - ROUNDING_VAR, 0.0)), how


def _esf(d: FloatArray, a: float, b: float, delta: float, s: float) -> FloatArray:
    return np.asarray(a + b * ndtr((d - delta) / s), np.float64)


def _edge_fit(grey: NDArray[np.uint8], p0: FloatArray, p1: FloatArray) -> float | None:
    """Edge spread sigma (px) across the edge from ``p0`` to ``p1``, or None when it cannot be fitted."""
    length = float(np.linalg.norm(p1 - p0))
    if length < _MIN_EDGE_PX:
        return None
    t = (p1 - p0) / length
    n = np.array([-t[1], t[0]])
    half = min(0.45 * length, 10.0)
    lo, hi = np.floor(np.minimum(p0, p1) - half).astype(int), np.ceil(np.maximum(p0, p1) + half).astype(int)
    h, w = grey.shape[:2]
    if lo[0] < 0 or lo[1] < 0 or hi[0] >= w or hi[1] >= h:
        return None
    ys, xs = np.mgrid[lo[1]:hi[1] + 1, lo[0]:hi[0] + 1]
    rel = np.column_stack([xs.ravel(), ys.ravel()]) - p0
    along, across = rel @ t, rel @ n
    keep = (along > 0.2 * length) & (along < 0.8 * length) & (np.abs(across) <= half)
    d, v = across[keep], grey[ys.ravel()[keep], xs.ravel()[keep]].astype(np.float64)
    dark, light = v[d < -half / 2], v[d > half / 2]
    if dark.size < 3 or light.size < 3 or abs(float(np.median(light) - np.median(dark))) < 20:
        return None
    a0, b0 = float(np.median(dark)), float(np.median(light) - np.median(dark))
    try:
        params, _ = curve_fit(_esf, d, v, p0=(a0, b0, 0.0, 1.0),
                              bounds=([-np.inf, -np.inf, -2.0, 0.05], [np.inf, np.inf, 2.0, half]))
    except (RuntimeError, ValueError):
        return None
    return float(params[3])


def edge_spread_px(images: Sequence[BoardImage], *, max_edges: int = 400) -> list[float]:
    """Edge-spread sigmas (px) of the board edges between neighbouring inner corners (at most ``max_edges``,
    spread evenly over the images)."""
    segments = []
    for img in images:
        grid = img.grid()
        rows, cols = grid.shape[:2]
        segments += [(img.grey, grid[r, c], grid[r, c + 1]) for r in range(rows) for c in range(cols - 1)]
        segments += [(img.grey, grid[r, c], grid[r + 1, c]) for r in range(rows - 1) for c in range(cols)]
    step = max(1, len(segments) // max_edges)
    return [s for grey, p0, p1 in segments[::step] if (s := _edge_fit(grey, p0, p1)) is not None]


def image_blur_px(images: Sequence[BoardImage]) -> tuple[float | None, int]:
    """Edge-spread sigma (px, the median over the board edges) and the number of edges it rests on."""
    spreads = edge_spread_px(images)
    if len(spreads) < 5:
        return None, len(spreads)
    return float(np.median(spreads)), len(spreads)
