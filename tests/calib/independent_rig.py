"""Independent known-answer stereo rigs: chessboard corners projected with plain numpy (no s2r, no OpenCV).

A rig: two 640x480 cameras with random plumb_bob lenses (k1, k2, small k3, tangential p1 p2 up to
5e-4), the right camera about 6-12 cm to the right of the left one (``X_right = R X_left + T``, metres,
OpenCV optical frames: x right, y down, z forward) and slightly rotated; ``views`` board poses that keep
every corner of a 9x6 board (25 mm squares) inside both images, spread over the image, 0.3-0.9 m away
and tilted up to about 40 degrees. Corners get Gaussian noise of ``noise_px`` per coordinate.

The projection here is written from the plumb_bob formulas (Brown-Conrady, as documented by OpenCV and
ROS camera_info) and shares no code with s2r, so it checks s2r's solver from outside.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]
SIZE = (640, 480)
PATTERN = (9, 6)
SQUARE_M = 0.025


@dataclass(frozen=True)
class Lens:
    """Pinhole + plumb_bob: fx fy cx cy (px), dist = (k1, k2, p1, p2, k3)."""

    fx: float
    fy: float
    cx: float
    cy: float
    dist: tuple[float, float, float, float, float]


@dataclass(frozen=True)
class Rig:
    """Known rig and its noisy observations: ``left[i]``/``right[i]`` (N, 2) px of ``board`` (N, 3) m."""

    left_lens: Lens
    right_lens: Lens
    R: Array
    T: Array
    board: Array
    left: list[Array]
    right: list[Array]

    @property
    def baseline_m(self) -> float:
        return float(np.linalg.norm(self.T))


def rotation(axis_angle: Array) -> Array:
    """Rotation matrix of an axis-angle vector (radians), Rodrigues' formula written out."""
    theta = float(np.linalg.norm(axis_angle))
    if theta < 1e-12:
        return np.eye(3)
    k = axis_angle / theta
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(theta) * kx + (1 - np.cos(theta)) * (kx @ kx)


def project(lens: Lens, pts_cam: Array) -> Array:
    """Pixels (N, 2) of camera-frame points (N, 3): perspective division, then plumb_bob distortion."""
    x = pts_cam[:, 0] / pts_cam[:, 2]
    y = pts_cam[:, 1] / pts_cam[:, 2]
    k1, k2, p1, p2, k3 = lens.dist
    r2 = x * x + y * y
    radial = 1 + k1 * r2 + k2 * r2 ** 2 + k3 * r2 ** 3
    xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    return np.stack([lens.fx * xd + lens.cx, lens.fy * yd + lens.cy], axis=1)


def board_points() -> Array:
    """Inner corners of the 9x6 board, row-major (x along the 9 columns), metres, z = 0."""
    cols, rows = PATTERN
    return np.array([[c * SQUARE_M, r * SQUARE_M, 0.0] for r in range(rows) for c in range(cols)])


def random_lens(rng: np.random.Generator, *, k3_max: float = 0.02, tangential_max: float = 5e-4) -> Lens:
    f = rng.uniform(450.0, 650.0)
    return Lens(fx=f, fy=f * rng.uniform(0.995, 1.005), cx=320.0 + rng.uniform(-15, 15),
                cy=240.0 + rng.uniform(-12, 12),
                dist=(float(rng.uniform(-0.3, 0.05)), float(rng.uniform(-0.05, 0.15)),
                      float(rng.uniform(-tangential_max, tangential_max)),
                      float(rng.uniform(-tangential_max, tangential_max)), float(rng.uniform(-k3_max, k3_max))))


def _inside(px: Array, margin: float = 8.0) -> bool:
    return bool(np.all((px[:, 0] > margin) & (px[:, 0] < SIZE[0] - 1 - margin) & (px[:, 1] > margin)
                       & (px[:, 1] < SIZE[1] - 1 - margin)))


def _random_pose(rng: np.random.Generator, lens: Lens) -> tuple[Array, Array]:
    """Board pose in the left camera: aim the board centre at a random image point, random distance/tilt."""
    board = board_points()
    centre = board.mean(axis=0)
    dist = rng.uniform(0.3, 0.9)
    u, v = rng.uniform(0.1, 0.9) * SIZE[0], rng.uniform(0.1, 0.9) * SIZE[1]
    ray = np.array([(u - lens.cx) / lens.fx, (v - lens.cy) / lens.fy, 1.0])
    target = ray / np.linalg.norm(ray) * dist
    tilt = rng.uniform(-0.7, 0.7, size=2)
    R = rotation(np.array([tilt[0], tilt[1], rng.uniform(-0.4, 0.4)]))
    return R, target - R @ centre


def bent_board(bend_m: tuple[float, float]) -> Array:
    """The board's corners bent into a parabola along each axis: z = bx (1 - u^2) + by (1 - v^2) metres, with
    u, v running -1..1 across the corners (the bend at the centre, as mrcal models a board's warp)."""
    board = board_points()
    u = 2 * board[:, 0] / board[:, 0].max() - 1
    v = 2 * board[:, 1] / board[:, 1].max() - 1
    board[:, 2] = bend_m[0] * (1 - u ** 2) + bend_m[1] * (1 - v ** 2)
    return board


def make_rig(seed: int, *, views: int = 20, noise_px: float = 0.07, k3_max: float = 0.02,
             tangential_max: float = 5e-4, bend_m: tuple[float, float] = (0.0, 0.0)) -> Rig:
    """A random rig with ``views`` noisy board observations in both cameras (seeded); ``bend_m``: the printed
    board is not flat (see :func:`bent_board`)."""
    rng = np.random.default_rng(seed)
    left, right = random_lens(rng, k3_max=k3_max, tangential_max=tangential_max), \
        random_lens(rng, k3_max=k3_max, tangential_max=tangential_max)
    R = rotation(rng.uniform(-0.02, 0.02, size=3))
    centre_right = np.array([rng.uniform(0.06, 0.12), rng.uniform(-0.003, 0.003), rng.uniform(-0.003, 0.003)])
    T = -R @ centre_right
    board = bent_board(bend_m)
    obs_l: list[Array] = []
    obs_r: list[Array] = []
    tries = 0
    while len(obs_l) < views:
        tries += 1
        if tries > 100 * views:
            raise RuntimeError("could not place boards")
        Rb, tb = _random_pose(rng, left)
        pts_l = board @ Rb.T + tb
        pts_r = pts_l @ R.T + T
        if np.any(pts_l[:, 2] < 0.1) or np.any(pts_r[:, 2] < 0.1):
            continue
        pl, pr = project(left, pts_l), project(right, pts_r)
        if not (_inside(pl) and _inside(pr)):
            continue
        obs_l.append(pl + rng.normal(0.0, noise_px, pl.shape))
        obs_r.append(pr + rng.normal(0.0, noise_px, pr.shape))
    return Rig(left, right, R, T, board, obs_l, obs_r)
