"""A plane in a camera frame, its total-least-squares fit and its depth along pixel rays (numpy only)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["MIN_FIT_PIXELS", "Plane", "fit_plane", "plane_depth"]

FloatArray = NDArray[np.float64]
#: Fewest inlier ROI pixels for a plane fit (fewer: the frame is not scored).
MIN_FIT_PIXELS = 50


@dataclass(frozen=True)
class Plane:
    """A plane ``normal . P = offset_m`` in a camera frame (metres), ``normal`` a unit vector with
    ``offset_m > 0`` (the camera lies on the side the normal points away from)."""

    normal: tuple[float, float, float]
    offset_m: float

    @property
    def n(self) -> FloatArray:
        """The unit normal as a (3,) array."""
        return np.asarray(self.normal, dtype=np.float64)

    def tilt_deg(self) -> float:
        """Angle between the plane's normal and the optical axis, degrees (0 = fronto-parallel)."""
        return float(np.degrees(np.arccos(min(1.0, abs(self.n[2])))))



def plane_depth(plane: Plane, rays: FloatArray) -> FloatArray:
    """Depth (metres along the optical axis) where each ray ``(N, 2)`` normalised ``(x, y)`` meets ``plane``;
    NaN where the ray is parallel to it or meets it behind the camera."""
    n = plane.n
    denom = rays[:, 0] * n[0] + rays[:, 1] * n[1] + n[2]
    with np.errstate(divide="ignore", invalid="ignore"):
        z = plane.offset_m / denom
    return np.where(np.isfinite(z) & (z > 0), z, np.nan)


def fit_plane(points: FloatArray) -> Plane:
    """Total-least-squares plane through ``(N, 3)`` points (metres), N >= 3."""
    centre = points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - centre, full_matrices=False)
    normal = vt[2]
    offset = float(normal @ centre)
    if offset < 0:
        normal, offset = -normal, -offset
    return Plane((float(normal[0]), float(normal[1]), float(normal[2])), offset)
