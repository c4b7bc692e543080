"""Perfect depth (a simulator's) turned into a device's: dropout at depth edges, holes against distance, disparity
noise and sub-pixel quantisation, as a :class:`~s2r.sensor.model.SensorModel` describes them. Seeded.

Depth is (H, W) metres along the optical axis in the camera whose focal length ``f`` (px) and the rig's baseline
``B`` (m) give disparity ``d = f B / Z``; NaN, inf or <= 0 mean no data. The steps, in order:

1. depth edges: the depth with holes filled from the nearest valid pixel, pixels whose 3x3 neighbourhood spans
   more than :data:`EDGE_RELATIVE_JUMP` of its nearest depth (a band two pixels wide across each jump);
2. edge dropout: pixels closer than ``edge_dropout_px / 2`` to the jump's midline lose their depth;
3. holes: a standard normal random field, correlated by a Gaussian of ``hole_scale_px``, below
   ``Phi^-1(fill(Z))`` keeps the pixel, so a surface at Z keeps ``fill(Z)`` of its pixels;
4. noise: ``d + N(0, sigma_d(Z))``, rounded to ``disparity_step_px``; ``Z = f B / d`` (d <= 0: no data).
"""

from __future__ import annotations

import math

import cv2
import numpy as np
from numpy.typing import NDArray
from scipy.special import ndtri

from s2r.errors import DepthError
from s2r.sensor.model import SensorModel

__all__ = ["EDGE_RELATIVE_JUMP", "degrade_depth", "depth_edges", "fill_at", "hole_field", "hole_kernel",
           "nearest_fill"]

F32 = NDArray[np.float32]
#: Relative depth span within a 3x3 neighbourhood above which a pixel lies on a depth edge.
EDGE_RELATIVE_JUMP = 0.1


def nearest_fill(depth_m: F32) -> F32:
    """(H, W) depth with every invalid pixel given its nearest valid pixel's depth (all NaN: unchanged)."""
    valid = np.isfinite(depth_m) & (depth_m > 0)
    if valid.all() or not valid.any():
        return np.asarray(depth_m, np.float32)
    _, labels = cv2.distanceTransformWithLabels((~valid).astype(np.uint8), cv2.DIST_L2, 5,
                                                labelType=cv2.DIST_LABEL_PIXEL)
    values = np.zeros(int(labels.max()) + 1, np.float32)
    values[labels[valid]] = depth_m[valid]
    return np.asarray(values[labels], np.float32)


def depth_edges(depth_m: F32, *, smooth: bool = False) -> NDArray[np.bool_]:
    """(H, W) bool: pixels on a depth edge of ``depth_m`` (module docstring, step 1); ``smooth`` takes a 5x5
    median first (measured, noisy depth)."""
    filled = nearest_fill(depth_m)
    if not np.isfinite(filled).any():
        return np.zeros(depth_m.shape, bool)
    filled = np.where(np.isfinite(filled), filled, 0).astype(np.float32)
    if smooth:
        filled = np.asarray(cv2.medianBlur(filled, 5), np.float32)
    kernel = np.ones((3, 3), np.uint8)
    hi = cv2.dilate(filled, kernel)
    lo = cv2.erode(filled, kernel)
    return np.asarray((lo > 0) & (hi - lo > EDGE_RELATIVE_JUMP * lo), bool)


def fill_at(model: SensorModel, distance_m: F32) -> F32:
    """Fill rate (0..1) of the model at each distance (metres; linear between the model's points, constant beyond
    its ends; 1 without points)."""
    points = model.fill_rate_by_distance
    if not points:
        return np.ones_like(distance_m, dtype=np.float32)
    xs = np.array([p.distance_m for p in points])
    ys = np.array([p.fill_rate_pct for p in points]) / 100.0
    order = np.argsort(xs)
    return np.interp(distance_m, xs[order], ys[order]).astype(np.float32)


def hole_kernel(scale_px: float) -> NDArray[np.float64]:
    """The normalised 1-D Gaussian kernel (unit sum of squares) correlating the hole field."""
    size = 2 * math.ceil(4.0 * scale_px) + 1
    k = np.exp(-0.5 * (np.arange(size) - size // 2) ** 2 / scale_px ** 2)
    return np.asarray(k / np.sqrt(np.sum(k * k)), np.float64)


def hole_field(shape: tuple[int, int], scale_px: float, rng: np.random.Generator) -> F32:
    """(H, W) standard normal random field, correlated by a Gaussian of ``scale_px`` px (0: independent)."""
    white = rng.standard_normal(shape).astype(np.float32)
    if scale_px <= 0:
        return white
    k = hole_kernel(scale_px).astype(np.float32)
    return np.asarray(cv2.sepFilter2D(white, -1, k, k, borderType=cv2.BORDER_REFLECT), np.float32)


def _edge_dropout(depth_m: F32, width_px: float | None) -> NDArray[np.bool_]:
    """(H, W) bool: pixels inside the dropout band of ``width_px`` across the depth edges."""
    if not width_px:
        return np.zeros(depth_m.shape, bool)
    edges = depth_edges(depth_m)
    if not edges.any():
        return edges
    dist = cv2.distanceTransform((~edges).astype(np.uint8), cv2.DIST_L2, 5)
    return np.asarray(dist < width_px / 2.0 - 0.5, bool)


def degrade_depth(depth_m: F32, model: SensorModel, *, fb_px_m: float, rng: np.random.Generator) -> F32:
    """The device's depth from perfect ``depth_m`` (module docstring); (H, W) float32 metres, NaN no data.

    Args:
        depth_m: (H, W) perfect depth, metres along the optical axis; NaN, inf or <= 0 no data.
        model: the sensor model (its depth fields; image fields are ignored).
        fb_px_m: focal length (px) times baseline (m) of the depth's camera pair.
        rng: the random generator (seed it for repeatable output).
    """
    if depth_m.ndim != 2:
        raise DepthError(f"depth must be one (H, W) image, got shape {depth_m.shape}", field="depth")
    if not fb_px_m > 0:
        raise DepthError(f"f B must be positive, got {fb_px_m}", field="fb_px_m")
    z = np.asarray(depth_m, np.float32)
    valid = np.isfinite(z) & (z > 0)
    keep = valid & ~_edge_dropout(z, model.edge_dropout_px)
    safe_z = np.where(valid, z, 1.0).astype(np.float32)
    threshold = ndtri(np.clip(fill_at(model, safe_z), 1e-9, 1 - 1e-9)).astype(np.float32)
    keep &= hole_field(z.shape, model.hole_scale_px, rng) < threshold
    sigma = (model.subpixel_sigma_px or 0.0) + model.subpixel_growth_px_per_m * (safe_z - 1.0)
    d = np.float32(fb_px_m) / safe_z + rng.standard_normal(z.shape).astype(np.float32) * np.maximum(sigma, 0.0)
    if model.disparity_step_px:
        d = np.round(d / model.disparity_step_px) * np.float32(model.disparity_step_px)
    keep &= d > 0
    out = np.full(z.shape, np.nan, np.float32)
    out[keep] = np.float32(fb_px_m) / d[keep]
    return out
