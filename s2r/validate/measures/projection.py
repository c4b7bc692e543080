"""Projection difference between two profiles, as mrcal's ``mrcal-show-projection-diff`` frames it.

A table of parameter deltas misleads because parameters are correlated (a focal change and a principal
point change can cancel in part); what matters is where each camera sees the same 3D point. For a grid of
pixels over the REAL left image (the sim camera first scaled to the real resolution with
:meth:`Camera.scaled` when sizes differ), each pixel is unprojected with the real left camera to a point at
the working depth (metres along the left optical axis) and projected with the sim camera. The left shift
compares the two left cameras; the right shift compares where the two right cameras (placed by each
profile's own extrinsics) see that same point, so baseline and rotation differences show there, scaled by
the working distance.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from s2r.lens.distortion import project_points, undistort_pixels
from s2r.profile import Camera, StereoProfile

__all__ = ["ProjectionDiff", "projection_difference"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class ProjectionDiff:
    """Pixel shift between the sim and real cameras over a grid of the real image.

    ``shift_px`` has shape (rows, cols): the distance in pixels (real resolution) between where the sim and
    the real camera see each grid point's 3D point; ``u_px``/``v_px`` the grid's pixel columns/rows;
    ``outside_fraction`` the share of the points the real camera sees in its image that fall outside the sim
    camera's image (for the right camera, points outside the real right image - the stereo pair's own
    non-overlap - are left out: they are no sim-vs-real difference).
    """

    camera: str
    image_size: tuple[int, int]
    distance_m: float
    u_px: FloatArray
    v_px: FloatArray
    shift_px: FloatArray
    outside_fraction: float

    @property
    def mean_px(self) -> float:
        """Mean shift over the grid, pixels."""
        return float(np.mean(self.shift_px))

    @property
    def p95_px(self) -> float:
        """95th percentile shift over the grid, pixels."""
        return float(np.percentile(self.shift_px, 95))

    @property
    def max_px(self) -> float:
        """Largest shift over the grid, pixels."""
        return float(np.max(self.shift_px))

    def as_dict(self) -> dict[str, Any]:
        """Summary figures and the grid for JSON."""
        return {"camera": self.camera, "image_size": list(self.image_size), "distance_m": self.distance_m,
                "mean_px": self.mean_px, "p95_px": self.p95_px, "max_px": self.max_px,
                "outside_fraction": self.outside_fraction, "u_px": self.u_px.tolist(), "v_px": self.v_px.tolist(),
                "shift_px": np.round(self.shift_px, 4).tolist()}


def _common(cam: Camera, size: tuple[int, int]) -> Camera:
    return cam if cam.image_size == size else cam.scaled(*size)


def _outside(cam: Camera, pixels: FloatArray) -> NDArray[np.bool_]:
    u, v = pixels[:, 0], pixels[:, 1]
    return (u < -0.5) | (u > cam.width_px - 0.5) | (v < -0.5) | (v > cam.height_px - 0.5)


def projection_difference(sim: StereoProfile, real: StereoProfile, *, distance_m: float = 2.0,
                          grid: tuple[int, int] = (30, 40)) -> list[ProjectionDiff]:
    """Left and right projection differences over a ``grid`` = (rows, cols) of the real left image.

    Args:
        sim, real: the profiles; the sim cameras are scaled to the real image size when they differ.
        distance_m: working depth (metres along the real left optical axis) of the 3D points.
        grid: number of grid rows and columns spanning pixel centres 0 .. W-1, 0 .. H-1.
    """
    size = real.image_size
    sim_left, sim_right = _common(sim.left, size), _common(sim.right, size)
    u = np.linspace(0.0, size[0] - 1.0, grid[1])
    v = np.linspace(0.0, size[1] - 1.0, grid[0])
    uu, vv = np.meshgrid(u, v)
    pixels = np.stack([uu.ravel(), vv.ravel()], axis=1)
    rays = undistort_pixels(real.left, pixels)
    points = np.concatenate([rays * distance_m, np.full((len(rays), 1), distance_m)], axis=1)

    sim_px = project_points(sim_left, points)
    left = ProjectionDiff("left", size, distance_m, u, v, np.linalg.norm(sim_px - pixels, axis=1).reshape(grid),
                          float(np.mean(_outside(sim_left, sim_px))))
    real_r = project_points(real.right, points @ real.R.T + real.T)
    sim_r = project_points(sim_right, points @ sim.R.T + sim.T)
    # only points the REAL right camera sees count: the rest is the pair's own non-overlap, not a sim-real difference
    real_sees = ~_outside(real.right, real_r)
    missed = float(np.mean(_outside(sim_right, sim_r)[real_sees])) if real_sees.any() else 0.0
    right = ProjectionDiff("right", size, distance_m, u, v, np.linalg.norm(sim_r - real_r, axis=1).reshape(grid),
                           missed)
    return [left, right]
