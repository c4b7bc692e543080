"""Device depth's noise, fill and dropout, measured on a chessboard recording (numpy, scipy, OpenCV).

Per frame, inside the board's region (the quadrilateral of its outer inner corners, :mod:`s2r.quality.board`):

- disparity noise: the valid depths as disparity ``d = f B / Z``; a plane's disparity is affine in the undistorted
  normalised coordinates, ``d = a x + b y + c``, fitted by least squares twice (the second time on the pixels
  within 4 robust sigmas, 1.4826 MAD, of the first: mismatches and flying pixels left out); the inliers' residual
  standard deviation, with the depth's own rounding taken out (``(f B q / Z^2)^2 / 12`` for a depth step ``q``,
  1 mm in uint16 PNGs), is sigma_d at the board's distance (the PnP plane's median depth over the region);
- fill rate: the share of region pixels with depth;
- hole correlation: the share of neighbouring region pixels of which exactly one has depth; for a standard normal
  field thresholded at the fill rate this share fixes the field's lag-1 correlation, and so the Gaussian scale
  that correlates it (:func:`s2r.sensor.depth.hole_field`);
- edge dropout, over the whole frame: the depth edges of the (5x5 median of the) depth with holes filled from
  the nearest pixel with depth (:func:`s2r.sensor.depth.depth_edges`); the pixels without depth within
  :data:`BAND_REACH_PX` of an edge beyond the share missing 6-12 px from the edges, divided by the edges' length
  (from the area of that shell), is the band's width.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray
from scipy.optimize import brentq
from scipy.special import ndtri
from scipy.stats import multivariate_normal

from s2r.quality.board import BoardView, normalised_rays, roi_mask
from s2r.quality.metrics import plane_depth
from s2r.sensor.depth import depth_edges, hole_kernel

__all__ = ["BAND_REACH_PX", "DepthFrame", "depth_frame", "hole_scale_px"]

FloatArray = NDArray[np.float64]
#: Distance from a depth edge (px) within which missing depth counts towards the edge's dropout band.
BAND_REACH_PX = 6.0
_LENGTH_SHELL_PX = (6.0, 12.0)
_MIN_PIXELS = 50


@dataclass(frozen=True)
class DepthFrame:
    """One frame's measurements (module docstring); None where the frame could not give the figure.

    ``band_missing_px`` and ``edge_length_px``: excess pixels without depth near the depth edges and the edges'
    length (px), summed over frames for the band width."""

    name: str
    distance_m: float
    sigma_d_px: float | None
    fill_pct: float
    transitions: float | None
    band_missing_px: float | None
    edge_length_px: float | None


def _depth_step_m(z: FloatArray) -> float:
    """The depth's rounding step (metres): 1 mm when every depth is a whole number of millimetres, else 0."""
    mm = z * 1000.0
    return 0.001 if z.size and bool(np.all(np.abs(mm - np.round(mm)) < 1e-3)) else 0.0


def _disparity_sigma(z: FloatArray, xy: FloatArray, fb: float) -> float | None:
    """Residual sigma (px) of disparity about its best affine plane (module docstring)."""
    d = fb / z
    design = np.column_stack([xy, np.ones(len(d))])
    keep = np.ones(len(d), bool)
    for _ in range(2):
        coef, *_ = np.linalg.lstsq(design[keep], d[keep], rcond=None)
        resid = d - design @ coef
        mad = 1.4826 * float(np.median(np.abs(resid[keep] - np.median(resid[keep]))))
        keep = np.abs(resid) <= max(4.0 * mad, 1e-9)
        if keep.sum() < _MIN_PIXELS:
            return None
    coef, *_ = np.linalg.lstsq(design[keep], d[keep], rcond=None)
    resid = d[keep] - design[keep] @ coef
    var = float(resid @ resid) / (keep.sum() - 3)
    step = _depth_step_m(z)
    var -= float(np.mean((fb * step / z[keep] ** 2) ** 2)) / 12.0
    return math.sqrt(max(var, 0.0))


def _transitions(valid: NDArray[np.bool_], mask: NDArray[np.bool_]) -> float | None:
    """Share of neighbouring pairs (right, down) inside ``mask`` of which exactly one pixel is valid."""
    pairs = [(valid[:, 1:] != valid[:, :-1])[mask[:, 1:] & mask[:, :-1]],
             (valid[1:] != valid[:-1])[mask[1:] & mask[:-1]]]
    n = sum(p.size for p in pairs)
    return float(sum(int(p.sum()) for p in pairs)) / n if n else None


def _edge_band(depth: NDArray[np.float32]) -> tuple[float, float] | None:
    """(excess missing pixels near depth edges, edge length px) of one frame, or None without depth edges.

    The missing share expected without a band is that of the shell 6-12 px from the edges (both sides, in the
    same proportions as the band), the edges' length that shell's area over twice its width."""
    edges = depth_edges(depth, smooth=True)
    if edges.sum() < 10:
        return None
    dist = cv2.distanceTransform((~edges).astype(np.uint8), cv2.DIST_L2, 5)
    h, w = depth.shape
    inner = np.zeros((h, w), bool)
    m = int(_LENGTH_SHELL_PX[1]) + 1
    inner[m:h - m, m:w - m] = True  # edges cut by the image border would be counted short
    near_edge = edges & inner
    if near_edge.sum() < 10:
        return None
    reach = cv2.distanceTransform((~near_edge).astype(np.uint8), cv2.DIST_L2, 5)
    lo, hi = _LENGTH_SHELL_PX
    shell = (reach >= lo) & (reach < hi) & (dist >= lo)
    length = float(shell.sum()) / (2.0 * (hi - lo))
    if length < 5:
        return None
    missing = ~(np.isfinite(depth) & (depth > 0))
    base = float(missing[shell].mean())
    band = reach < BAND_REACH_PX
    excess = max(float(missing[band].sum()) - band.sum() * base, 0.0) / max(1.0 - base, 1e-3)
    return excess, length


def depth_frame(name: str, depth: NDArray[np.float32], board: BoardView, *, pattern: tuple[int, int],
                K: FloatArray, D: FloatArray, fb_px_m: float) -> DepthFrame | None:
    """The measurements of one frame (module docstring); None when the region holds too few pixels."""
    h, w = depth.shape
    mask = roi_mask(board.corners, pattern, (w, h))
    ys, xs = np.nonzero(mask)
    if xs.size < _MIN_PIXELS:
        return None
    xy = normalised_rays(np.column_stack([xs, ys]).astype(np.float64), K, D)
    truth = plane_depth(board.plane, xy)
    distance = float(np.nanmedian(truth)) if np.isfinite(truth).any() else float("nan")
    z = depth[ys, xs].astype(np.float64)
    valid = np.isfinite(z) & (z > 0)
    fill = float(valid.mean())
    sigma = _disparity_sigma(z[valid], xy[valid], fb_px_m) if valid.sum() >= _MIN_PIXELS else None
    valid_img = np.isfinite(depth) & (depth > 0)
    inner = cv2.erode(mask.astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)
    band = _edge_band(depth) if fill > 0.05 else None
    return DepthFrame(name, distance, sigma, 100.0 * fill, _transitions(valid_img, inner),
                      None if band is None else band[0], None if band is None else band[1])


def _lag1(scale: float) -> float:
    """Lag-1 correlation of the hole field correlated by a Gaussian of ``scale`` px (0 at scale 0)."""
    if scale <= 0:
        return 0.0
    k = hole_kernel(scale)
    return float(np.sum(k[1:] * k[:-1]))


def _transition_share(fill: float, rho: float) -> float:
    """Share of neighbour pairs with exactly one pixel below the ``fill`` quantile of a field with lag-1 corr rho."""
    a = float(ndtri(fill))
    both = float(multivariate_normal(mean=[0.0, 0.0], cov=[[1.0, rho], [rho, 1.0]]).cdf([a, a]))
    return 2.0 * (fill - both)


def hole_scale_px(frames: list[DepthFrame]) -> float | None:
    """The hole field's Gaussian scale (px) that best explains the frames' neighbour transitions, or None when no
    frame has a fill rate between 10 and 95 %."""
    scales = []
    for f in frames:
        p = f.fill_pct / 100.0
        if f.transitions is None or not 0.10 <= p <= 0.95:
            continue
        def gap(scale: float, p: float = p, t: float = f.transitions) -> float:
            return _transition_share(p, _lag1(scale)) - t
        if gap(0.0) <= 0:
            scales.append(0.0)
        elif gap(20.0) >= 0:
            scales.append(20.0)
        else:
            scales.append(float(brentq(gap, 1e-3, 20.0, xtol=1e-3)))
    return float(np.median(scales)) if scales else None
