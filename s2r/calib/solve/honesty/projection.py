"""Projection uncertainty in pixels (mrcal-style): how far a point seen at a pixel may land under other
plausible calibrations, over the image, at a chosen distance.

For a grid of pixels ``q`` the solved camera's rays are taken to points at depth ``distance_m`` (metres, camera
frame). Each alternative calibration (the jackknife folds' intrinsics) projects those points after the small
camera rotation that best aligns it with the solved camera (a rotation of the camera is absorbed by the board
poses and is no error of the intrinsics; mrcal compensates it the same way). The spread of the projections
(px, worst direction: the square root of the largest eigenvalue of the 2x2 covariance, scaled by (K-1)) is
the uncertainty at ``q``. The covariance of the intrinsics is propagated to first order instead, as mrcal
does: the projection Jacobian with the best-aligning rotation's share removed, ``J C J^T`` per pixel (the
same as drawing samples without their sampling noise: 32 draws scattered the map by about 13 %).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

__all__ = ["DISTANCE_M", "ProjectionMap", "covariance_projection_map", "projection_map"]

FloatArray = NDArray[np.float64]
#: Depth (m) at which the projection uncertainty is reported.
DISTANCE_M = 1.0
_GRID = (16, 10)
Intrinsics = tuple[FloatArray, FloatArray]


@dataclass(frozen=True)
class ProjectionMap:
    """Uncertainty (px) on a grid of pixels ``xs`` x ``ys`` (``sigma[j, i]`` at ``(xs[i], ys[j])``); the
    value at the image centre and the largest at the four image corners; ``source`` what was resampled."""

    xs: FloatArray
    ys: FloatArray
    sigma: FloatArray
    centre_px: float
    corner_px: float
    distance_m: float
    source: str

    def as_dict(self) -> dict[str, object]:
        """JSON-ready summary (the grid itself stays out of the JSON)."""
        return {"centre_px": self.centre_px, "corner_px": self.corner_px, "distance_m": self.distance_m,
                "source": self.source}


def _points(q: FloatArray, K: FloatArray, D: FloatArray, distance_m: float) -> FloatArray:
    norm = cv2.undistortPoints(q.reshape(-1, 1, 2), K, D).reshape(-1, 2)
    return np.column_stack([norm * distance_m, np.full(len(norm), distance_m)])


def _aligned(P: FloatArray, q: FloatArray, K: FloatArray, D: FloatArray) -> FloatArray:
    """Projections (N, 2) of ``P`` by (K, D) after the camera rotation that best matches ``q`` (Gauss-Newton)."""
    rvec, t0 = np.zeros(3), np.zeros(3)
    for _ in range(5):
        pts, jac = cv2.projectPoints(P.reshape(-1, 1, 3), rvec, t0, K, D)
        r = (pts.reshape(-1, 2) - q).reshape(-1)
        J = np.asarray(jac, np.float64)[:, :3]
        step = np.linalg.lstsq(J, -r, rcond=None)[0]
        rvec = rvec + step
        if np.linalg.norm(step) < 1e-12:
            break
    return np.asarray(cv2.projectPoints(P.reshape(-1, 1, 3), rvec, t0, K, D)[0], np.float64).reshape(-1, 2)


def _worst(dev: FloatArray, scale: float) -> FloatArray:
    """Worst-direction std per point from deviations (S, N, 2) around their mean."""
    d = dev - dev.mean(axis=0)
    cov = np.einsum("sni,snj->nij", d, d) * scale
    return np.sqrt(np.maximum(np.linalg.eigvalsh(cov)[:, -1], 0.0))


def _probes(K: FloatArray, D: FloatArray, size: tuple[int, int], distance_m: float
            ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """The grid's ``xs``, ``ys``, the probed pixels ``q`` (the grid, then the image centre last) and the points
    (camera frame, m) the camera (K, D) sees there at depth ``distance_m``."""
    w, h = size
    xs, ys = np.linspace(0, w - 1, _GRID[0]), np.linspace(0, h - 1, _GRID[1])
    q = np.vstack([np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2), [[(w - 1) / 2, (h - 1) / 2]]])
    return xs, ys, q, _points(q, K, D, distance_m)


def projection_map(K: FloatArray, D: FloatArray, size: tuple[int, int], folds: Sequence[Intrinsics], *,
                   distance_m: float = DISTANCE_M) -> ProjectionMap | None:
    """The uncertainty map of camera (K, D) from the jackknife folds' intrinsics ``folds``; None with fewer
    than 2 folds."""
    if len(folds) < 2:
        return None
    xs, ys, q, P = _probes(K, D, size, distance_m)
    dev = np.array([_aligned(P, q, Ks, Ds) - q for Ks, Ds in folds])
    k = len(folds)
    return _map(xs, ys, _worst(dev, (k - 1) / k), distance_m, "jackknife")


def _map(xs: FloatArray, ys: FloatArray, every: FloatArray, distance_m: float, source: str) -> ProjectionMap:
    sigma, centre = every[:-1].reshape(len(ys), len(xs)), every[-1:]
    corners = [sigma[0, 0], sigma[0, -1], sigma[-1, 0], sigma[-1, -1]]
    return ProjectionMap(xs, ys, sigma, float(centre[0]), float(max(corners)), distance_m, source)


def covariance_projection_map(K: FloatArray, D: FloatArray, size: tuple[int, int], cov: FloatArray,
                              free: Sequence[int], *, distance_m: float = DISTANCE_M) -> ProjectionMap | None:
    """The uncertainty map of camera (K, D) from the covariance ``cov`` of ``(fx, fy, cx, cy, D[free])``
    (px^2, coefficient^2), propagated to first order with the best-aligning camera rotation removed; None
    when the covariance is not finite."""
    cov = np.asarray(cov, np.float64)
    if not np.all(np.isfinite(cov)):
        return None
    xs, ys, _, P = _probes(K, D, size, distance_m)
    _, jac = cv2.projectPoints(P.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), K, D)
    J = np.asarray(jac, np.float64)
    J_rot, J_intr = J[:, :3], J[:, [6, 7, 8, 9, *(10 + i for i in free)]]
    # what a small camera rotation absorbs (least squares over every grid point at once) is no error
    J_eff = J_intr - J_rot @ np.linalg.lstsq(J_rot, J_intr, rcond=None)[0]
    per_point = J_eff.reshape(-1, 2, J_eff.shape[1])
    c = np.einsum("nip,pq,njq->nij", per_point, cov, per_point)
    every = np.sqrt(np.maximum(np.linalg.eigvalsh(c)[:, -1], 0.0))
    return _map(xs, ys, every, distance_m, "covariance")
