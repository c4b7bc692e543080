"""Calibration-board poses that cover the image, tilt up to ~45 deg and keep the board inside both images.

The board frame (OpenCV's calibration object frame): origin at the first inner corner, x along the
pattern's columns, y along its rows, z into the board (away from a camera that sees its printed face).
Inner corner (i, j) sits at ``(i * square_m, j * square_m, 0)``. Poses are ``T_left_board`` (4x4, metres).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from s2r.errors import RenderError
from s2r.profile import SimulationSettings, StereoProfile
from s2r.render.distortion import project_points

__all__ = ["BoardGeometry", "distance_range_m", "sample_board_poses"]

FloatArray = NDArray[np.float64]

#: Fraction of the image the board (with its margin) spans at the nearest / farthest sampled distance.
FILL_NEAR, FILL_FAR, FILL_MAX = 0.60, 0.40, 0.90
#: Smallest square, pixels: on a fronto-parallel board, and after tilt in any sampled view.
MIN_FRONTAL_SQUARE_PX, MIN_SQUARE_PX = 12.0, 8.0
MIN_TILT_DEG, MAX_TILT_DEG, MAX_VIEW_ANGLE_DEG = 30.0, 45.0, 70.0
#: In-plane roll range: never near 0, because pixel-aligned edges alias worst (no anti-aliasing).
MIN_ROLL_DEG, MAX_ROLL_DEG = 8.0, 30.0
_EDGE_MARGIN_PX = 3.0
_SHRINK_STEPS, _RELAX_STEPS = 21, 30


@dataclass(frozen=True)
class BoardGeometry:
    """A chessboard of ``pattern`` inner corners (columns, rows), ``square_m`` squares and a light margin."""

    pattern: tuple[int, int]
    square_m: float
    border_squares: float

    @property
    def extent_m(self) -> tuple[float, float, float, float]:
        """``(x0, y0, x1, y1)`` of the whole board (squares plus margin) in the board frame, metres."""
        s, b = self.square_m, self.border_squares
        return (-(1 + b) * s, -(1 + b) * s, (self.pattern[0] + b) * s, (self.pattern[1] + b) * s)

    @property
    def size_m(self) -> tuple[float, float]:
        """Board width and height with the margin, metres."""
        x0, y0, x1, y1 = self.extent_m
        return x1 - x0, y1 - y0

    def corners(self) -> FloatArray:
        """Inner corners ``(cols * rows, 3)`` in OpenCV's order (row by row), board frame, metres."""
        cols, rows = self.pattern
        j, i = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
        return np.column_stack([i.ravel(), j.ravel(), np.zeros(i.size)]).astype(np.float64) * self.square_m

    def outline(self, per_edge: int = 8) -> FloatArray:
        """Points ``(4 * per_edge, 3)`` along the board's outer edge, board frame, metres."""
        x0, y0, x1, y1 = self.extent_m
        t = np.linspace(0.0, 1.0, per_edge, endpoint=False)
        xs = np.concatenate([x0 + (x1 - x0) * t, np.full_like(t, x1), x1 - (x1 - x0) * t, np.full_like(t, x0)])
        ys = np.concatenate([np.full_like(t, y0), y0 + (y1 - y0) * t, np.full_like(t, y1), y1 - (y1 - y0) * t])
        return np.column_stack([xs, ys, np.zeros_like(xs)])

    def centre(self) -> FloatArray:
        """Centre of the squares area in the board frame, metres."""
        return np.array([(self.pattern[0] - 1) / 2.0, (self.pattern[1] - 1) / 2.0, 0.0]) * self.square_m


def clip_planes(profile: StereoProfile) -> tuple[float, float]:
    """``(near, far)`` clip planes in metres: the profile's simulation settings or the defaults."""
    sim = profile.simulation if profile.simulation is not None else SimulationSettings()
    return sim.clip_near_m, sim.clip_far_m


def distance_range_m(profile: StereoProfile, board: BoardGeometry) -> tuple[float, float]:
    """Nearest and farthest board distance (metres) to sample, from fill, square size and clip planes."""
    cam = profile.left
    bw, bh = board.size_m
    fill_1m = max(bw * cam.fx_px / cam.width_px, bh * cam.fy_px / cam.height_px)  # image fraction at 1 m
    d_square = board.square_m * min(cam.fx_px, cam.fy_px) / MIN_FRONTAL_SQUARE_PX
    if fill_1m / d_square > FILL_MAX:
        raise RenderError(
            f"a {board.pattern[0]}x{board.pattern[1]} board of {board.square_m * 1000:g} mm squares spans "
            f"{100 * fill_1m / d_square:.0f}% of the image where its squares are {MIN_FRONTAL_SQUARE_PX:g} px; "
            "it cannot fit the view at any distance with refinable corners",
            field="pattern", hint="use fewer corners (--pattern) or a higher-resolution profile",
        )
    near_d, far_d = fill_1m / FILL_NEAR, min(fill_1m / FILL_FAR, d_square)
    near_d = min(near_d, far_d)
    near, far = clip_planes(profile)
    half = 0.5 * math.hypot(bw, bh)
    lo, hi = max(near_d, 1.2 * near + half), min(far_d, 0.9 * far - half)
    if lo > hi:
        if 0.9 * far - half < near_d:
            raise RenderError(
                f"the far clip plane ({far:g} m) cuts off the board, which must be {near_d:.2f}-{far_d:.2f} m away",
                field="simulation.clip_far_m", hint=f"raise clip_far_m above {(near_d + half) / 0.9:.2f} m",
            )
        raise RenderError(
            f"the near clip plane ({near:g} m) cuts off the board, which must be {near_d:.2f}-{far_d:.2f} m away",
            field="simulation.clip_near_m", hint=f"lower clip_near_m below {(far_d - half) / 1.2:.3f} m",
        )
    return lo, hi


def _fits(profile: StereoProfile, board: BoardGeometry, T: FloatArray) -> bool:
    """True when the whole board lies inside both images, in front, facing them, with big enough squares."""
    near, far = clip_planes(profile)
    outline, corners = board.outline(), board.corners()
    for cam, R, t in ((profile.left, np.eye(3), np.zeros(3)), (profile.right, profile.R, profile.T)):
        T_cam = np.eye(4)
        T_cam[:3, :3], T_cam[:3, 3] = R @ T[:3, :3], R @ T[:3, 3] + t
        pts = outline @ T_cam[:3, :3].T + T_cam[:3, 3]
        if np.any(pts[:, 2] < 1.2 * near) or np.any(pts[:, 2] > 0.9 * far):
            return False
        centre = T_cam[:3, :3] @ board.centre() + T_cam[:3, 3]
        cos_view = float(T_cam[:3, 2] @ centre / np.linalg.norm(centre))
        if cos_view < math.cos(math.radians(MAX_VIEW_ANGLE_DEG)):
            return False
        uv = project_points(cam, pts)
        m = _EDGE_MARGIN_PX
        if np.any(uv < m) or np.any(uv[:, 0] > cam.width_px - 1 - m) or np.any(uv[:, 1] > cam.height_px - 1 - m):
            return False
        grid = project_points(cam, corners @ T_cam[:3, :3].T + T_cam[:3, 3])
        grid = grid.reshape(board.pattern[1], board.pattern[0], 2)
        step = min(np.linalg.norm(np.diff(grid, axis=0), axis=2).min(), np.linalg.norm(np.diff(grid, axis=1),
                                                                                       axis=2).min())
        if step < MIN_SQUARE_PX:
            return False
    return True


def _candidate(profile: StereoProfile, board: BoardGeometry, target: FloatArray, d: float, tilt: FloatArray,
               roll: float) -> FloatArray:
    cam = profile.left
    ray = np.array([(target[0] - cam.cx_px) / cam.fx_px, (target[1] - cam.cy_px) / cam.fy_px, 1.0])
    R = Rotation.from_rotvec(tilt).as_matrix() @ Rotation.from_euler("z", roll).as_matrix()
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = d * ray - R @ board.centre()
    return T


def _schedule(d0: float, hi: float) -> Iterator[tuple[float, float, float]]:
    """Fallbacks ``(shrink, distance, relax)`` for a view that does not fit: at each pull toward the image
    centre (``shrink`` 1 -> 0) first try moving the board back a little (the stereo overlap widens with
    distance; far boards constrain the focal length less, so only a third of the way),
    then reduce tilt and roll (``relax``) at the centre and the farthest distance."""
    steps = [d0 + (hi - d0) * t for t in (0.0, 1 / 3)]
    for shrink in np.linspace(1.0, 0.0, _SHRINK_STEPS):
        for d in steps:
            yield float(shrink), d, 1.0
    for k in range(1, _RELAX_STEPS + 1):
        yield 0.0, hi, 0.9**k


def sample_board_poses(profile: StereoProfile, board: BoardGeometry, *, views: int, seed: int) -> list[FloatArray]:
    """``views`` poses ``T_left_board`` (4x4, metres), deterministic for ``seed``.

    View k aims the board centre at one of 9 image positions (corners, edge midpoints, centre; shuffled by
    the seed, with jitter), at a log-stratified distance, tilted by a stratified angle up to 45 deg about a
    random in-plane axis and rolled 8-30 deg either way. A candidate that does not fit both images is moved
    back and pulled toward the image centre, then un-tilted, until it fits (see :func:`_schedule`).
    """
    lo, hi = distance_range_m(profile, board)
    rng = np.random.default_rng(seed)
    grid = np.array([(x, y) for y in (-1.0, 0.0, 1.0) for x in (-1.0, 0.0, 1.0)])
    order = rng.permutation(len(grid))
    cam = profile.left
    half = np.array([cam.width_px / 2.0, cam.height_px / 2.0])
    centre = np.array([cam.cx_px, cam.cy_px])
    poses: list[FloatArray] = []
    for k in range(views):
        pos = grid[order[k % len(grid)]] + rng.uniform(-0.1, 0.1, 2)
        frac = (k * 0.6180339887 + rng.uniform(0.0, 0.15)) % 1.0
        d0 = lo * (hi / lo) ** frac
        band = k % 3
        angle = math.radians(MIN_TILT_DEG + rng.uniform(band, band + 1) * (MAX_TILT_DEG - MIN_TILT_DEG) / 3.0)
        phi = rng.uniform(0.0, 2.0 * math.pi)
        axis = np.array([math.cos(phi), math.sin(phi), 0.0])
        roll = math.radians(rng.uniform(MIN_ROLL_DEG, MAX_ROLL_DEG) * rng.choice([-1.0, 1.0]))
        for shrink, d, relax in _schedule(d0, hi):
            T = _candidate(profile, board, centre + shrink * pos * half, d, angle * relax * axis, roll * relax)
            if _fits(profile, board, T):
                poses.append(T)
                break
        else:
            raise RenderError(
                f"view {k}: the board does not fit inside both images at any sampled pose",
                field="pattern", hint="use a smaller board (--pattern / --square) or check the profile's extrinsics",
            )
    return poses
