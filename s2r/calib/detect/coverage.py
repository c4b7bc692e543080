"""Coverage of a calibration set: which image regions the corners reached, and the spread of board
tilt and distance (the figures behind ROS camera_calibration's X / Y / size / skew bars), with advice
on which views to add.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

__all__ = ["GRID", "Coverage", "PoseSpread", "coverage_of", "coverage_warnings", "pose_spread"]

#: Coverage grid (columns, rows) of image cells.
GRID = (8, 6)
_REGION_NAMES = (("top-left", "top", "top-right"), ("left", "centre", "right"),
                 ("bottom-left", "bottom", "bottom-right"))


#: Pixels per cell of the board-footprint map.
FOOTPRINT_CELL_PX = 8


@dataclass(frozen=True)
class Coverage:
    """Where the boards were seen in one camera.

    ``counts``: corners per image cell (GRID[1] rows x GRID[0] cols, for the region advice);
    ``footprint``: number of views whose board (convex hull of its corners) covers each
    FOOTPRINT_CELL_PX-pixel cell; ``fraction``: share of the image inside at least one board's footprint
    (the honest "covered" figure: a board that fills 5 % of the image covers 5 %, not the cells its
    corners touch); x/y ranges: extent of the corners as image fractions.
    """

    counts: NDArray[np.int64]
    fraction: float
    x_range: tuple[float, float]
    y_range: tuple[float, float]
    footprint: NDArray[np.int64] | None = None


@dataclass(frozen=True)
class PoseSpread:
    """Spread of the solved board poses: tilt to the optical axis (degrees), distance (metres), and the
    board's share of the image area (size)."""

    tilt_deg: tuple[float, float]
    distance_m: tuple[float, float]
    size_fraction: tuple[float, float]


def coverage_of(corners: Sequence[NDArray[np.float32]], size: tuple[int, int], *,
                grid: tuple[int, int] = GRID) -> Coverage:
    """Count the corners (each (N, 2) px) falling into each of ``grid`` cells of a ``size`` (w, h) image."""
    w, h = size
    counts = np.zeros((grid[1], grid[0]), np.int64)
    cell = FOOTPRINT_CELL_PX
    foot = np.zeros((max(1, -(-h // cell)), max(1, -(-w // cell))), np.int64)
    if not corners:
        return Coverage(counts=counts, fraction=0.0, x_range=(0.0, 0.0), y_range=(0.0, 0.0), footprint=foot)
    pts = np.vstack([c.reshape(-1, 2) for c in corners]).astype(np.float64)
    cx = np.clip((pts[:, 0] + 0.5) * grid[0] / w, 0, grid[0] - 1).astype(int)
    cy = np.clip((pts[:, 1] + 0.5) * grid[1] / h, 0, grid[1] - 1).astype(int)
    np.add.at(counts, (cy, cx), 1)
    for c in corners:
        hull = cv2.convexHull(((c.reshape(-1, 2).astype(np.float64) + 0.5) / cell * 16).round().astype(np.int32))
        mask = np.zeros(foot.shape, np.uint8)
        cv2.fillConvexPoly(mask, hull, 1, lineType=cv2.LINE_8, shift=4)
        foot += mask
    return Coverage(counts=counts, fraction=float(np.mean(foot > 0)),
                    x_range=(float(pts[:, 0].min() / w), float(pts[:, 0].max() / w)),
                    y_range=(float(pts[:, 1].min() / h), float(pts[:, 1].max() / h)), footprint=foot)


def pose_spread(rvecs: Sequence[NDArray[np.float64]], tvecs: Sequence[NDArray[np.float64]],
                corners: Sequence[NDArray[np.float32]], *, pattern: tuple[int, int], square_m: float,
                size: tuple[int, int]) -> PoseSpread:
    """Tilt (angle between board normal and optical axis, degrees), distance of the board centre (metres)
    and the image-area share of the corners' convex hull, each as (min, max) over the views."""
    centre = np.array([(pattern[0] - 1) * square_m / 2, (pattern[1] - 1) * square_m / 2, 0.0])
    tilts, dists, sizes = [], [], []
    for rvec, tvec, pts in zip(rvecs, tvecs, corners, strict=True):
        R, _ = cv2.Rodrigues(np.asarray(rvec, np.float64))
        tilts.append(float(np.degrees(np.arccos(min(1.0, abs(float(R[2, 2])))))))
        dists.append(float(np.linalg.norm(R @ centre + np.asarray(tvec, np.float64).reshape(3))))
        hull = cv2.convexHull(pts.reshape(-1, 1, 2).astype(np.float32))
        sizes.append(float(cv2.contourArea(hull)) / (size[0] * size[1]))
    if not tilts:
        return PoseSpread((0.0, 0.0), (0.0, 0.0), (0.0, 0.0))
    return PoseSpread((min(tilts), max(tilts)), (min(dists), max(dists)), (min(sizes), max(sizes)))


def _region_fraction(counts: NDArray[np.int64], row: int, col: int) -> float:
    rows, cols = counts.shape
    r0, r1 = row * rows // 3, (row + 1) * rows // 3
    c0, c1 = col * cols // 3, (col + 1) * cols // 3
    return float(np.mean(counts[r0:r1, c0:c1] > 0))


def coverage_warnings(camera: str, coverage: Coverage, spread: PoseSpread | None = None) -> list[str]:
    """Plain-language advice in at most ONE line per camera: image regions (thirds) with corners in less
    than half of their GRID cells, too little tilt or distance variation (empty list when the set covers everything)."""
    regions = [_REGION_NAMES[row][col] for row in range(3) for col in range(3)
               if _region_fraction(coverage.counts, row, col) < 0.5]
    parts = []
    if regions:
        where = ", ".join(regions)
        parts.append(f"few or no corners in the {where} of the image (add views with the board there)")
    if spread is not None:
        if spread.tilt_deg[1] - spread.tilt_deg[0] < 15.0:
            parts.append(f"board tilt only spans {spread.tilt_deg[0]:.0f}-{spread.tilt_deg[1]:.0f} deg (add views "
                         "with the board tilted 20-45 deg left/right and up/down)")
        if spread.distance_m[1] < 1.3 * spread.distance_m[0]:
            parts.append(f"board distance only spans {spread.distance_m[0]:.2f}-{spread.distance_m[1]:.2f} m "
                         "(add views with the board nearer and farther)")
    return [f"{camera} camera: " + "; ".join(parts)] if parts else []
